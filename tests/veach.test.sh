# Veach's comparison as the README makes it: tools/veach.sh renders
# scenes/veach.sph with each estimator, at depth 2 (the scene's `depth 2`:
# direct light only).  The estimators' means are checked in tests/test_pt.c
# (test_veach), on floats; here, that the one command makes the three.
. tests/lib.sh
VEACH_OUT="$TMP/veach" bash tools/veach.sh -s 48x32 -n 2 >"$TMP/veach.out" 2>&1
for e in bsdf nee mis; do
  check "tools/veach.sh writes the $e picture, a 48x32 PNG" \
    sh -c "python3 tests/png2ppm.py '$TMP/veach/$e.png' | head -n 2 | grep -qx '48 32'"
done
check "tools/veach.sh prints each render's size and time" \
  sh -c "[ \$(grep -c '^[a-z]*: time ' '$TMP/veach.out') = 3 ] && grep -q '^mis: image *48x32, 2 spp, path traced' '$TMP/veach.out'"
check "scenes/veach.sph renders at depth 2: paths of at most 2 rays" \
  sh -c "./ray --stats -s 8x8 -o '$TMP/d.ppm' scenes/veach.sph 2>&1 | grep -q 'length bound 2 rays'"
