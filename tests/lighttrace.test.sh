# Light tracing (--estimator light): paths from the lights, joined to the
# camera and splatted.  Its image is the path tracer's in expectation: on
# scenes where every path it needs has a diffuse vertex the camera sees
# (no glass or mirror between the camera and a diffuse surface), in 16
# blocks of the image, the mean of each block's per-pixel differences
# from MIS's image is 0 within 4.5 standard errors (pixels are
# independent, so the spread of the differences gives the error), and
# over the whole image within 4.  Scenes: the Cornell box (triangle lamp,
# every bounce), a large one-sided lamp close over a floor (lamp.sph,
# direct light), a glowing sphere over a ball on a floor (soft.sph), and
# point lights over diffuse balls, a two-sided triangle lamp over a floor,
# lamps seen only directly, through a glass ball and in a mirror ball
# (nothing diffuse: the camera's half alone); and a moving lamp at the shutter's one
# instant against the lamp put there.  The same bytes on 1 and 3 threads;
# split renders and --adaptive refused.
. tests/lib.sh
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
for r in "cornell.sph -n 256" "lamp.sph -n 64 -d 2" "soft.sph --pt -n 128 -d 3" "points.sph -n 64 -d 3" \
         "twosided.sph -n 64 -d 3" "seen.sph -n 64 -d 6"; do
  set -- $r
  f=$1; shift
  scene=scenes/$f; [ -f "$TMP/$f" ] && scene=$TMP/$f
  ./ray "$scene" "$@" -s 32x32 --seed 3 -o "$TMP/mis.pfm" 2>/dev/null
  ./ray "$scene" "$@" -s 32x32 --seed 4 --estimator light -o "$TMP/light.pfm" 2>/dev/null
  read -r worst whole <<<"$(blocks "$TMP/mis.pfm" "$TMP/light.pfm" 32 32)"
  awk -v b="$worst" -v z="$whole" 'BEGIN { exit !(b != "" && b < 4.5 && z < 4 && z > -4) }' \
    && ok "$f $*: light tracing's image is MIS's in expectation (worst of 16 blocks $worst standard errors, the whole image $whole)" \
    || bad "$f $*: light tracing differs from MIS: worst block '$worst' standard errors, the whole image '$whole'"
done

# a lamp that moves, seen at the shutter's one instant, is the lamp put there
for at in moving placed; do
  { echo "integrator path"; echo "camera 0 -8 3   0 0 1   0 0 1   50"
    echo "tri -9 -9 0  9 -9 0  9 9 0     .8 .8 .8  .8 0 0 0 1"; echo "tri -9 -9 0  9 9 0  -9 9 0     .8 .8 .8  .8 0 0 0 1"
    echo "0 0 1   .85 .35 .25   1   .8 0 0 0 1"
    if [ $at = moving ]; then echo "shutter 1 1"; echo "move 3 0 0"; echo "-1.5 1 2.5   1 .9 .7   .4   0 0 0 6 1"
    else echo "1.5 1 2.5   1 .9 .7   .4   0 0 0 6 1"; fi; } >"$TMP/$at.sph"
done
./ray "$TMP/placed.sph" -s 32x32 -n 64 -d 3 --seed 3 -o "$TMP/mis.pfm" 2>/dev/null
./ray "$TMP/moving.sph" -s 32x32 -n 64 -d 3 --seed 4 --estimator light -o "$TMP/light.pfm" 2>/dev/null
read -r worst whole <<<"$(blocks "$TMP/mis.pfm" "$TMP/light.pfm" 32 32)"
awk -v b="$worst" -v z="$whole" 'BEGIN { exit !(b != "" && b < 4.5 && z < 4 && z > -4) }' \
  && ok "a moving lamp at shutter 1 1, light traced, is MIS's lamp put there (worst of 16 blocks $worst standard errors, the whole image $whole)" \
  || bad "a moving lamp at shutter 1 1, light traced, differs from the lamp put there: worst block '$worst', whole image '$whole'"

./ray scenes/cornell.sph -s 40x30 -n 8 -t 1 --estimator light -o "$TMP/t1.pfm" 2>/dev/null
./ray scenes/cornell.sph -s 40x30 -n 8 -t 3 --estimator light -o "$TMP/t3.pfm" 2>/dev/null
[ -s "$TMP/t1.pfm" ] && cmp -s "$TMP/t1.pfm" "$TMP/t3.pfm" \
  && ok "--estimator light: the same bytes on 1 and 3 threads" || bad "--estimator light: 1 and 3 threads differ"

for opt in "--adaptive 2" "--crop 0,0,8,8" "--samples 0:4" "-o $TMP/x.part"; do
  # shellcheck disable=SC2086
  ./ray scenes/cornell.sph -s 16x16 -n 8 --estimator light -o "$TMP/r.pfm" $opt 2>"$TMP/err"; rc=$?
  [ $rc = 2 ] && grep -q "whole images only" "$TMP/err" \
    && ok "--estimator light with $opt refused, exit 2: $(sed "s|$TMP/||" "$TMP/err")" \
    || bad "--estimator light with $opt: exit $rc, $(cat "$TMP/err")"
done
