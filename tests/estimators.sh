# Shared by tests/lighttrace.test.sh and tests/bdpt.test.sh (sourced after
# tests/lib.sh): the scenes both check an estimator on against MIS, and the
# checkers.  Point lights over diffuse balls; a two-sided triangle lamp over
# a floor; a lamp moving during a shutter open at one instant, and the lamp
# put where it is then; lamps seen directly, through a glass ball and in
# a mirror ball, and nothing diffuse (seen.sph); the furnace, inside a glowing sphere of albedo .5
# and Le 1.5, where after N bounces L = Le (1 - a^(N+1)) / (1 - a).
cat >"$TMP/points.sph" <<'SCENE'
integrator path
background 0 0 0
camera 0 -8 3   0 0 1   0 0 1   50
light -3 -2 5   2 2 2
light 2.5 1 3   1.5 .8 .5
tri -9 -9 0  9 -9 0  9 9 0     .8 .8 .8  .8 0 0 0 1
tri -9 -9 0  9 9 0  -9 9 0     .8 .8 .8  .8 0 0 0 1
0 0 1          .85 .35 .25   1      .8 0 0 0 1
2 -1 .6        .3 .8 .4      .6     .7 0 0 0 1
SCENE
cat >"$TMP/twosided.sph" <<'SCENE'
integrator path
background 0 0 0
camera 0 -8 3   0 0 1   0 0 1   50
tri -9 -9 0  9 -9 0  9 9 0     .8 .8 .8  .8 0 0 0 1
tri -9 -9 0  9 9 0  -9 9 0     .8 .8 .8  .8 0 0 0 1
tri -2 1 1  2 1 1  0 1 4     1 .9 .7  0 0 0 3 1
SCENE
cat >"$TMP/seen.sph" <<'SCENE'
integrator path
background 0 0 0
camera 0 -8 2   0 0 1.5   0 0 1   40
0 3 2       1 .9 .7      1.2    0 0 0 4 1
-1.2 0 1.2  1 1 1        .9     0 0 1 0 1.5
1.4 0 1.6   1 1 1        .8     0 .4 0 0 1
tri -4 6 0  4 6 0  0 6 5     .5 .7 1  0 0 0 2 1
0 -16 3     1 1 1        5      0 0 0 1 1
SCENE
for at in moving placed; do
  { echo "integrator path"; echo "camera 0 -8 3   0 0 1   0 0 1   50"
    echo "tri -9 -9 0  9 -9 0  9 9 0     .8 .8 .8  .8 0 0 0 1"; echo "tri -9 -9 0  9 9 0  -9 9 0     .8 .8 .8  .8 0 0 0 1"
    echo "0 0 1   .85 .35 .25   1   .8 0 0 0 1"
    if [ $at = moving ]; then echo "shutter 1 1"; echo "move 3 0 0"; echo "-1.5 1 2.5   1 .9 .7   .4   0 0 0 6 1"
    else echo "1.5 1 2.5   1 .9 .7   .4   0 0 0 6 1"; fi; } >"$TMP/$at.sph"
done
echo "integrator path
camera 0 .5 .3   1 0 0   0 0 1   90
0 0 0   1 1 1   2   .5 0 0 1.5 1" >"$TMP/furnace.sph"

blocks() {   # the worst block's z and the whole image's, of image $2 minus image $1 (w x h)
  python3 -c "$PFM_PY
a, b = pfm(sys.argv[1]), pfm(sys.argv[2])
w, h = int(sys.argv[3]), int(sys.argv[4])
def z(ks):
    d = [sum(b[3 * k:3 * k + 3]) - sum(a[3 * k:3 * k + 3]) for k in ks]
    n = len(d); m = sum(d) / n; v = sum((x - m) ** 2 for x in d) / (n - 1)
    return m / (v / n) ** 0.5 if v > 0 else (0 if m == 0 else 99)
worst = max(abs(z([(y * h // 4 + j) * w + x * w // 4 + i for j in range(h // 4) for i in range(w // 4)]))
            for y in range(4) for x in range(4))
print('%.2f %.2f' % (worst, z(range(w * h))))" "$1" "$2" "$3" "$4"
}
mean_z() {   # image $1's mean (of r, g, b) and its distance from $2 in standard errors
  python3 -c "$PFM_PY
a = pfm(sys.argv[1]); d = [sum(a[3 * k:3 * k + 3]) / 3 for k in range(len(a) // 3)]
n = len(d); m = sum(d) / n; v = sum((x - m) ** 2 for x in d) / (n - 1)
print('%.4f %.2f' % (m, (m - float(sys.argv[2])) / (v / n) ** 0.5 if v > 0 else 99))" "$1" "$2"
}

threads_agree() {   # label, then ray's arguments: the same bytes on 1 and 3 threads (the first kept in $TMP/t1.pfm)
  local label=$1
  shift
  ./ray "$@" -t 1 -o "$TMP/t1.pfm" 2>/dev/null
  ./ray "$@" -t 3 -o "$TMP/t3.pfm" 2>/dev/null
  [ -s "$TMP/t1.pfm" ] && cmp -s "$TMP/t1.pfm" "$TMP/t3.pfm" \
    && ok "$label: the same bytes on 1 and 3 threads" || bad "$label: 1 and 3 threads differ"
}
