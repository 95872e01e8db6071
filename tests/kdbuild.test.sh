# The kd-tree's build on fans of thin triangles and on concave polygons, and
# ray.c's ear clipper (tests/test_kdbuild.c).  kdtree.c is compiled with its
# malloc, realloc and free renamed, so that the test counts the bytes it
# holds.
. tests/lib.sh

counted="-Dmalloc=kdb_malloc -Dcalloc=kdb_calloc -Drealloc=kdb_realloc -Dfree=kdb_free"
# shellcheck disable=SC2086
if ! $CC $CFLAGS $counted -c kdtree.c -o "$TMP/kd_counted.o" 2>"$TMP/cc.err" \
   || ! $CC $CFLAGS $counted -c bvh.c -o "$TMP/bvh_counted.o" 2>>"$TMP/cc.err" \
   || ! $CC $CFLAGS -o "$TMP/test_kdbuild" tests/test_kdbuild.c "$TMP/kd_counted.o" "$TMP/bvh_counted.o" $(parts_but kdtree bvh) -lm 2>>"$TMP/cc.err"; then
  bad "test_kdbuild builds: $(head -c 300 "$TMP/cc.err" | tr '\n' ' ')"
  exit 1
fi

# Two parts at a time (the fans take longest); lines printed in a fixed order.
parts="fan polygon ears memory"
for p in $parts; do
  ( "$TMP/test_kdbuild" "$p" >"$TMP/$p.out" 2>"$TMP/$p.err"; echo $? >"$TMP/$p.rc" ) &
  [ "$(jobs -r | wc -l)" -ge 2 ] && wait -n
done
wait
for p in $parts; do
  cat "$TMP/$p.out"
  sed 's/^/    /' "$TMP/$p.err" | head -n 20
  rc=$(cat "$TMP/$p.rc")
  if [ "$rc" != 0 ] && ! grep -q '^FAIL ' "$TMP/$p.out"; then
    bad "test_kdbuild $p exited $rc"
  fi
done
