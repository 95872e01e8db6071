# Light tracing (--estimator light): paths from the lights, joined to the
# camera and splatted.  Its image is the path tracer's in expectation: on
# scenes where every path it needs has a diffuse vertex the camera sees
# (no glass or mirror between the camera and a diffuse surface), in 16
# blocks of the image, the mean of each block's per-pixel differences
# from MIS's image is 0 within 4.5 standard errors (pixels are
# independent, so the spread of the differences gives the error), and
# over the whole image within 4.  Scenes: the Cornell box (triangle lamp,
# every bounce), a large one-sided lamp close over a floor (lamp.sph,
# direct light), a glowing sphere over a ball on a floor (soft.sph), and
# point lights over diffuse balls, a two-sided triangle lamp over a floor,
# lamps seen only directly, through a glass ball and in a mirror ball
# (nothing diffuse: the camera's half alone); and a moving lamp at the shutter's one
# instant against the lamp put there.  The same bytes on 1 and 3 threads;
# split renders and --adaptive refused.
. tests/lib.sh
. tests/estimators.sh
for r in "cornell.sph -n 256" "lamp.sph -n 64 -d 2" "soft.sph --pt -n 128 -d 3" "points.sph -n 64 -d 3" \
         "twosided.sph -n 64 -d 3" "seen.sph -n 64 -d 6"; do
  set -- $r
  f=$1; shift
  scene=scenes/$f; [ -f "$TMP/$f" ] && scene=$TMP/$f
  ./ray "$scene" "$@" -s 32x32 --seed 3 -o "$TMP/mis.pfm" 2>/dev/null
  ./ray "$scene" "$@" -s 32x32 --seed 4 --estimator light -o "$TMP/light.pfm" 2>/dev/null
  read -r worst whole <<<"$(blocks "$TMP/mis.pfm" "$TMP/light.pfm" 32 32)"
  awk -v b="$worst" -v z="$whole" 'BEGIN { exit !(b != "" && b < 4.5 && z < 4 && z > -4) }' \
    && ok "$f $*: light tracing's image is MIS's in expectation (worst of 16 blocks $worst standard errors, the whole image $whole)" \
    || bad "$f $*: light tracing differs from MIS: worst block '$worst' standard errors, the whole image '$whole'"
done

# a lamp that moves, seen at the shutter's one instant, is the lamp put there
./ray "$TMP/placed.sph" -s 32x32 -n 64 -d 3 --seed 3 -o "$TMP/mis.pfm" 2>/dev/null
./ray "$TMP/moving.sph" -s 32x32 -n 64 -d 3 --seed 4 --estimator light -o "$TMP/light.pfm" 2>/dev/null
read -r worst whole <<<"$(blocks "$TMP/mis.pfm" "$TMP/light.pfm" 32 32)"
awk -v b="$worst" -v z="$whole" 'BEGIN { exit !(b != "" && b < 4.5 && z < 4 && z > -4) }' \
  && ok "a moving lamp at shutter 1 1, light traced, is MIS's lamp put there (worst of 16 blocks $worst standard errors, the whole image $whole)" \
  || bad "a moving lamp at shutter 1 1, light traced, differs from the lamp put there: worst block '$worst', whole image '$whole'"

# the furnace, inside a glowing sphere of albedo .5 and Le 1.5: after 3
# bounces L = Le (1 - a^4) / (1 - a) = 2.8125 (light paths leave the sphere
# inward, since the eye is inside it)
./ray "$TMP/furnace.sph" -s 32x32 -n 64 -d 4 --estimator light -o "$TMP/f.pfm" 2>/dev/null
read -r mean z <<<"$(mean_z "$TMP/f.pfm" 2.8125)"
awk -v z="$z" 'BEGIN { exit !(z != "" && z < 4 && z > -4) }' \
  && ok "the furnace at -d 4: light tracing's mean $mean is 2.8125 within $z standard errors" \
  || bad "the furnace at -d 4: light tracing's mean '$mean' is not 2.8125: '$z' standard errors"

threads_agree "--estimator light" scenes/cornell.sph -s 40x30 -n 8 --estimator light

for opt in "--adaptive 2" "--crop 0,0,8,8" "--samples 0:4" "-o $TMP/x.part"; do
  # shellcheck disable=SC2086
  ./ray scenes/cornell.sph -s 16x16 -n 8 --estimator light -o "$TMP/r.pfm" $opt 2>"$TMP/err"; rc=$?
  [ $rc = 2 ] && grep -q "whole images only" "$TMP/err" \
    && ok "--estimator light with $opt refused, exit 2: $(sed "s|$TMP/||" "$TMP/err")" \
    || bad "--estimator light with $opt: exit $rc, $(cat "$TMP/err")"
done
