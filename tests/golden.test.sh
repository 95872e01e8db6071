# Golden images: small renders compared with the references in tests/golden/
# by tools/ppmdiff.  The tolerance (max 1 level, PSNR >= 50 dB) lets a
# compiler that fuses multiply-adds (gcc on arm64 does by default) round a
# few pixels the other way; a real change of the renderer moves far more.
# Those few go either way, so their mean is near 0: the mean difference must
# stay within 0.05 of a level.  A bias of one level that max and PSNR let
# through fails there: truncating in to_byte instead of rounding moves 39-58%
# of the channels down by one, mean -0.39 to -0.58.
# To regenerate after an intended change, run the commands in the loop below
# with -o tests/golden/NAME.ppm and say why in the commit.
. tests/lib.sh
while read -r name args; do
  [ -z "$name" ] && continue
  ./ray $args -o "$TMP/$name.ppm" 2>/dev/null || { bad "golden $name: ray failed"; continue; }
  if res=$(tools/ppmdiff -t 1 --psnr 50 --bias 0.05 "tests/golden/$name.ppm" "$TMP/$name.ppm" 2>&1); then
    ok "golden $name: $res"
  else
    bad "golden $name: $res"
  fi
done <<'LIST'
minray_96_n4         -s 96x96 -n 4 scenes/minray.sph
whitted_160x120_n4   -s 160x120 -n 4 scenes/whitted.sph
whitted_160x120_d1   -s 160x120 -d 1 scenes/whitted.sph
mesh_160x120_n2      -s 160x120 -n 2 scenes/mesh.sph
demo_nff_128x96_n2   -s 128x96 -n 2 scenes/demo.nff
LIST
