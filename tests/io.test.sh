# Output and input at their edges (issue 13): PNG and --gamma, output that is
# neither lost nor left behind, and readers and a command line that say what
# is really wrong.  Every check prints PASS or FAIL (tests/lib.sh).
. tests/lib.sh

# --- PNG: decoded by tests/png2ppm.py (python's zlib inflates it, every CRC
# and the Adler-32 are checked) and compared byte for byte with the PPM of the
# same render: width 1, odd sizes, exactly one and two full stored blocks
# (28x771: 85 x 771 = 65535 bytes of rows), and more than one block.
for size in 1x1 1x9 7x5 33x17 28x771 28x1542 160x140; do
  ./ray -s $size -o "$TMP/p.ppm" scenes/minray.sph && ./ray -s $size -o "$TMP/p.png" scenes/minray.sph \
    && python3 tests/png2ppm.py "$TMP/p.png" > "$TMP/back.ppm" 2> "$TMP/err" && cmp -s "$TMP/back.ppm" "$TMP/p.ppm" \
    && ok "PNG $size decodes to the PPM's bytes" || bad "PNG $size: $(cat "$TMP/err")"
done
./ray -s 9x4 --gamma -o "$TMP/g.ppm" scenes/whitted.sph && ./ray -s 9x4 --gamma -o "$TMP/G.PNG" scenes/whitted.sph \
  && python3 tests/png2ppm.py -c "$TMP/G.PNG" 2> "$TMP/chunks" | cmp -s - "$TMP/g.ppm" \
  && [ "$(head -c 4 "$TMP/G.PNG" | tail -c 3)" = PNG ] && grep -qx sRGB "$TMP/chunks" \
  && ok "-o X.PNG (upper case) writes a PNG; with --gamma it has an sRGB chunk and the --gamma PPM's bytes" \
  || bad "-o X.PNG with --gamma: $(cat "$TMP/chunks")"
python3 tests/png2ppm.py -c "$TMP/p.png" 2> "$TMP/chunks" > /dev/null; ! grep -q sRGB "$TMP/chunks" \
  && ok "PNG without --gamma has no sRGB chunk" || bad "PNG without --gamma says sRGB"
for args in "-o $TMP/x.jpg" "-o $TMP/x.TIFF" "--p3 -o $TMP/x.png"; do
  rm -f "$TMP"/x.*
  ./ray -s 4x4 $args scenes/minray.sph 2> "$TMP/err"; rc=$?
  [ $rc = 2 ] && ! ls "$TMP"/x.* > /dev/null 2>&1 && ok "${args//$TMP\//} refused, exit 2: $(sed "s|$TMP/||" "$TMP/err")" \
    || bad "${args//$TMP\//}: exit $rc, $(cat "$TMP/err")"
done

# --- --gamma: the sRGB curve (IEC 61966-2-1) on a 1x1 image of one colour,
# against python's own evaluation of it; without --gamma the byte is linear.
levels="0 0.001 0.0031308 0.004 0.01 0.18 0.5 0.9 1 1.5"
for g in "" --gamma; do
  for v in $levels; do
    printf 'background %s %s %s\n' $v $v $v > "$TMP/bg.sph"
    ./ray -s 1x1 $g -o - "$TMP/bg.sph" 2>/dev/null | tail -c 1 | od -An -tu1
  done
done | tr -s ' \n' ' ' > "$TMP/got"
python3 -c "
def srgb(v): return 12.92 * v if v <= 0.0031308 else 1.055 * v ** (1 / 2.4) - 0.055
vs = [float(x) for x in '$levels'.split()]
print(' ' + ' '.join(str(min(255, max(0, round(255 * f(v))))) for f in (lambda v: v, srgb) for v in vs) + ' ')
" | tr -d '\n' > "$TMP/want"
cmp -s "$TMP/got" "$TMP/want" && ok "--gamma gives the sRGB curve's bytes, linear without it ($(cat "$TMP/want"))" \
  || bad "--gamma bytes: got$(cat "$TMP/got"), want$(cat "$TMP/want")"
