#!/usr/bin/env bash
# make stress: the long runs that make test keeps short.  The kd-tree against
# brute force on 2x the rays, at 4x the scene sizes, with two more seeds;
# the same output from 1, 2 and 3 threads on every SPD scene, when ../shared
# is there.  Ends with "N passed, N failed" like make test.
cd "$(dirname "$0")/.." || exit 2
. tests/lib.sh
pass=0 fail=0
# count < FILE: echo its lines and add up PASS and FAIL (not in a pipe: a
# pipe would run it in a subshell and lose the sums)
count() { while read -r line; do echo "$line"; case $line in PASS*) pass=$((pass+1));; FAIL*) fail=$((fail+1));; esac; done; }
$CC $CFLAGS -o "$TMP/test_kdtree" tests/test_kdtree.c kdtree.c -lm || exit 2
mkdir -p "$TMP/kd"
for seed in 11 12; do
  for s in same mesh grid thirds soup flat; do     # two at a time, one per core
    KD_RAYS=2000000 KD_SCALE=4 KD_SEED=$seed "$TMP/test_kdtree" "$s" > "$TMP/kd/$seed.$s" 2>/dev/null &
    [ "$(jobs -r | wc -l)" -ge 2 ] && wait -n
  done
done
wait
for f in "$TMP"/kd/*; do sed "s/^\(PASS\|FAIL\) /\1 seed ${f##*/}: /" "$f"; done > "$TMP/kd_all.txt"
count < "$TMP/kd_all.txt"
spd=${SPD:-../shared/spd}
if [ -d "$spd" ]; then
  for f in "$spd"/*.nff; do
    n=$(basename "$f" .nff)
    ./ray -t 1 -s 160x160 -o "$TMP/$n.1.ppm" "$f" && ./ray -t 2 -s 160x160 -o "$TMP/$n.2.ppm" "$f" \
      && ./ray -t 3 -s 160x160 -o "$TMP/$n.3.ppm" "$f" || { echo "FAIL $n renders"; continue; }
    cmp -s "$TMP/$n.1.ppm" "$TMP/$n.2.ppm" && cmp -s "$TMP/$n.1.ppm" "$TMP/$n.3.ppm" \
      && echo "PASS $n: same bytes with 1, 2 and 3 threads" || echo "FAIL $n: output depends on the thread count"
  done > "$TMP/spd.all"
  count < "$TMP/spd.all"
else
  echo "note: $spd not found; the SPD thread checks were skipped"
fi
echo "$pass passed, $fail failed"
[ "$fail" = 0 ]
