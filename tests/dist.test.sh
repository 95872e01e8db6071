# Distribution ray tracing (tests/test_dist.c): the lens's circle of
# confusion, soft shadows against similar triangles and against the path
# tracer, glossy reflection against its lobe; and every effect's scene the
# same bytes on 1 and 2 threads.
. tests/lib.sh
# shellcheck disable=SC2086 # CFLAGS and RAY_PARTS hold several words
$CC $CFLAGS -std=c99 -o "$TMP/test_dist" tests/test_dist.c $RAY_PARTS -lm || { bad "tests/test_dist.c compiles"; exit 1; }
"$TMP/test_dist" "$TMP"

for scene in dof soft glossy; do
  for integrator in --whitted --pt; do
    ./ray -t 1 $integrator -s 48x32 -n 8 -o "$TMP/$scene-1.ppm" "scenes/$scene.sph" 2>/dev/null
    ./ray -t 2 $integrator -s 48x32 -n 8 -o "$TMP/$scene-2.ppm" "scenes/$scene.sph" 2>/dev/null
    if [ -s "$TMP/$scene-1.ppm" ] && cmp -s "$TMP/$scene-1.ppm" "$TMP/$scene-2.ppm"; then
      ok "scenes/$scene.sph $integrator: the same bytes on 1 and 2 threads"
    else
      bad "scenes/$scene.sph $integrator: 1 and 2 threads differ (or it did not render)"
    fi
  done
done
