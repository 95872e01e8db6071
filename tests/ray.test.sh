# Unit tests of ray.c's functions (tests/test_ray.c includes ray.c whole).
. tests/lib.sh
$CC $CFLAGS -std=c99 -o "$TMP/test_ray" tests/test_ray.c kdtree.c bvh.c grid.c -lm || { bad "tests/test_ray.c compiles"; exit 1; }
"$TMP/test_ray"
