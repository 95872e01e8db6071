# The BVH builder's split choice against brute force (tests/test_bvhbuild.c,
# which includes bvh.c whole).
. tests/lib.sh

$CC $CFLAGS -std=c99 -o "$TMP/test_bvhbuild" tests/test_bvhbuild.c -lm 2>"$TMP/cc.err" \
  || { bad "tests/test_bvhbuild.c compiles: $(head -c 300 "$TMP/cc.err" | tr '\n' ' ')"; exit 1; }
"$TMP/test_bvhbuild"
