# Unit tests of ray.c's functions (tests/test_ray.c includes ray.c whole),
# in the double build and, for what it must keep (triangles at every scale,
# watertightness near and far, the tree against the loop), the float build.
. tests/lib.sh
$CC $CFLAGS -std=c99 -o "$TMP/test_ray" tests/test_ray.c $RAY_PARTS -lm || { bad "tests/test_ray.c compiles"; exit 1; }
"$TMP/test_ray"
# scene.c from its source: it rounds what it reads to REAL
# shellcheck disable=SC2046
$CC $CFLAGS -std=c99 -DREAL=float -o "$TMP/test_ray_float" tests/test_ray.c scene.c $(parts_but scene) -lm ||
  { bad "tests/test_ray.c compiles with -DREAL=float"; exit 1; }
"$TMP/test_ray_float"
