# Triangle lights sampled by solid angle (tests/test_light.c): Arvo's
# sampler meets its triangle, is uniform in solid angle (chi-square),
# estimates Lambert's polygon formula, and its pdf is light_pdf's.
. tests/lib.sh
# shellcheck disable=SC2086 # CFLAGS and RAY_PARTS hold several words
$CC $CFLAGS -std=c99 -o "$TMP/test_light" tests/test_light.c $RAY_PARTS -lm || { bad "tests/test_light.c compiles"; exit 1; }
"$TMP/test_light"
