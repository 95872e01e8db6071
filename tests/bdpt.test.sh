# Bidirectional path tracing (--estimator bdpt).  Its MIS weights
# (tests/test_bdpt.c): on sampled paths, the pdfs the walks and joins give
# are the path's own, and each path's strategies' weights add up to 1.
# Its image is the path tracer's in expectation on every scene, glass and
# mirrors included (the floor seen through a ball, which light tracing
# leaves black, and the caustic): in 16 blocks of the image, the mean of
# each block's per-pixel differences from MIS's image is 0 within 4.5
# standard errors (pixels are independent, so the spread of the
# differences gives the error), and over the whole image within 4.  The
# scenes: tests/estimators.sh's, the Cornell box, a room of GGX, Phong and
# diffuse surfaces under a glowing sphere and a two-sided triangle
# (room.sph), seen.sph over a floor, a floor and balls seen in a mirror
# (and the mirror's caustic on the floor), the 100 lamps of lights100.sph, a one-sided lamp close over a floor,
# a glowing sphere over a ball, the caustic, and a sky over a floor (the
# sky found by the camera's paths alone).  The furnace's mean is exact
# within 4 standard errors.  The images of every strategy (--strategy S,T)
# add up to the whole image, and each has light in it.  The same bytes on
# 1 and 3 threads; split renders, --adaptive and a lens refused.
. tests/lib.sh
. tests/estimators.sh
cat >"$TMP/mirror.sph" <<'SCENE'
integrator path
background 0 0 0
camera 0 -6 2   0 4 2   0 0 1   50
tri -3 3 0  3 3 0  3 3 5     1 1 1  0 .9 0 0 1
tri -3 3 0  3 3 5  -3 3 5     1 1 1  0 .9 0 0 1
tri -9 -12 0  9 -12 0  9 9 0     .8 .8 .8  .8 0 0 0 1
tri -9 -12 0  9 9 0  -9 9 0     .8 .8 .8  .8 0 0 0 1
0 -9 1   .85 .35 .25   1   .8 0 0 0 1
-2 -8 .5   .4 .5 .9   .5   .8 0 0 0 1
0 -5 9   1 .9 .7   .6   0 0 0 30 1
SCENE
cat >"$TMP/room.sph" <<'SCENE'
integrator path
background 0 0 0
camera 0 -7 2.5   0 0 1.5   0 0 1   60
tri -4 -8 0  4 -8 0  4 4 0     .8 .8 .8  .8 0 0 0 1
tri -4 -8 0  4 4 0  -4 4 0     .8 .8 .8  .8 0 0 0 1
tri -4 -8 5  4 4 5  4 -8 5     .7 .7 .8  .8 0 0 0 1
tri -4 -8 5  -4 4 5  4 4 5     .7 .7 .8  .8 0 0 0 1
tri -4 4 0  4 4 0  4 4 5     .8 .6 .5  .8 0 0 0 1
tri -4 4 0  4 4 5  -4 4 5     .8 .6 .5  .8 0 0 0 1
tri -4 -8 0  -4 4 0  -4 4 5     .5 .8 .5  .8 0 0 0 1
tri -4 -8 0  -4 4 5  -4 -8 5     .5 .8 .5  .8 0 0 0 1
tri 4 -8 0  4 4 5  4 4 0     .5 .5 .8  .8 0 0 0 1
tri 4 -8 0  4 -8 5  4 4 5     .5 .5 .8  .8 0 0 0 1
1.5 1 3.5   1 .9 .7   .4   0 0 0 6 1
tri -3 3 0.5  -1 3 0.5  -2 3 3     1 .9 .7  0 0 0 3 1
rough .3
0 0 1          .85 .35 .25   1      .5 .5 0 0 1
rough .1
-2 -1 .6        .3 .8 .4      .6     0 .9 0 0 1
rough 0
glossy 30
2 -1 .6        .3 .8 .4      .6     .4 .5 0 0 1
SCENE
# shellcheck disable=SC2086 # CFLAGS and RAY_PARTS hold several words
$CC $CFLAGS -std=c99 -o "$TMP/test_bdpt" tests/test_bdpt.c $RAY_PARTS -lm || { bad "tests/test_bdpt.c compiles"; exit 1; }
"$TMP/test_bdpt" scenes/glossy.sph "$TMP/room.sph"

# the furnace: inside a glowing sphere of albedo a = .5 and Le = 1.5,
# L = Le (1 - a^(N+1)) / (1 - a) after N bounces, Le / (1 - a) unbounded
for r in "4 2.8125" "0 3"; do
  set -- $r
  d=""; [ "$1" != 0 ] && d="-d $1"
  # shellcheck disable=SC2086
  ./ray "$TMP/furnace.sph" -s 32x32 -n 64 $d --estimator bdpt -o "$TMP/f.pfm" 2>/dev/null
  z=$(mean_z "$TMP/f.pfm" "$2")
  read -r mean z <<<"$z"
  awk -v z="$z" 'BEGIN { exit !(z != "" && z < 4 && z > -4) }' \
    && ok "the furnace${d:+ at $d}: BDPT's mean $mean is $2 within $z standard errors" \
    || bad "the furnace${d:+ at $d}: BDPT's mean '$mean' is not $2: '$z' standard errors"
done
{ cat "$TMP/seen.sph"   # and a floor, seen through the ball
  echo "tri -9 -9 0  9 -9 0  9 9 0     .8 .8 .8  .8 0 0 0 1"; echo "tri -9 -9 0  9 9 0  -9 9 0     .8 .8 .8  .8 0 0 0 1"
} >"$TMP/through.sph"
cat >"$TMP/sky.sph" <<'SCENE'
integrator path
background .6 .7 .9
camera 0 -8 3   0 0 1   0 0 1   50
light -3 -2 5   2 2 2
tri -9 -9 0  9 -9 0  9 9 0     .8 .8 .8  .8 0 0 0 1
tri -9 -9 0  9 9 0  -9 9 0     .8 .8 .8  .8 0 0 0 1
0 0 1          .85 .35 .25   1      .8 0 0 0 1
SCENE
# scene, MIS's samples, BDPT's samples, options for both
for r in "cornell.sph 256 64" "room.sph 256 64" "lamp.sph 64 16 -d 2" "soft.sph 128 32 --pt -d 3" "points.sph 64 16 -d 3" \
         "twosided.sph 64 16 -d 3" "seen.sph 256 64 -d 6" "through.sph 256 64 -d 6" "caustic.sph 1024 128" "mirror.sph 1024 256" "lights100.sph 64 16" "sky.sph 256 64 -d 3" \
         "moving.sph 64 16 -d 3"; do
  set -- $r
  f=$1 nm=$2 nb=$3; shift 3
  scene=scenes/$f; [ -f "$TMP/$f" ] && scene=$TMP/$f
  ref=$scene; [ "$f" = moving.sph ] && ref=$TMP/placed.sph
  ./ray "$ref" "$@" -n "$nm" -s 32x32 --seed 3 -o "$TMP/mis.pfm" 2>/dev/null
  ./ray "$scene" "$@" -n "$nb" -s 32x32 --seed 4 --estimator bdpt -o "$TMP/bdpt.pfm" 2>/dev/null
  read -r worst whole <<<"$(blocks "$TMP/mis.pfm" "$TMP/bdpt.pfm" 32 32)"
  awk -v b="$worst" -v z="$whole" 'BEGIN { exit !(b != "" && b < 4.5 && z < 4 && z > -4) }' \
    && ok "$f${*:+ $*}: BDPT's image is MIS's in expectation (worst of 16 blocks $worst standard errors, the whole image $whole)" \
    || bad "$f${*:+ $*}: BDPT differs from MIS: worst block '$worst' standard errors, the whole image '$whole'"
done

# every strategy of paths up to 3 rays, one image each, adds up to the whole
# (all but (1, 1): the eye seeing a light is s = 0's alone)
for scene in scenes/cornell.sph "$TMP/room.sph"; do
  ./ray "$scene" -s 16x16 -n 16 -d 3 --estimator bdpt -o "$TMP/all.pfm" 2>/dev/null
  list=""
  for st in 0,2 0,3 1,2 2,1 0,4 1,3 2,2 3,1; do
    ./ray "$scene" -s 16x16 -n 16 -d 3 --estimator bdpt --strategy $st -o "$TMP/s$st.pfm" 2>/dev/null
    list="$list $TMP/s$st.pfm"
  done
  # shellcheck disable=SC2086
  out=$(python3 -c "$PFM_PY
whole = pfm(sys.argv[1]); parts = [pfm(f) for f in sys.argv[2:]]
total = [sum(p[k] for p in parts) for k in range(len(whole))]
err = max(abs(t - w) / (abs(w) + 1e-3) for t, w in zip(total, whole))
lit = sum(1 for p in parts if sum(p) > 0)
print('%.2g %d' % (err, lit))" "$TMP/all.pfm" $list)
  read -r err lit <<<"$out"
  awk -v e="$err" -v l="$lit" 'BEGIN { exit !(e != "" && e < 1e-4 && l == 8) }' \
    && ok "$(basename "$scene"): the 8 strategies' images of paths up to 3 rays add up to the whole (largest difference $err of a pixel), each lit" \
    || bad "$(basename "$scene"): the strategies' images do not add up to the whole: largest difference '$err', $lit of 8 lit"
done

./ray scenes/cornell.sph -s 40x30 -n 8 -t 1 --estimator bdpt -o "$TMP/t1.pfm" 2>/dev/null
./ray scenes/cornell.sph -s 40x30 -n 8 -t 3 --estimator bdpt -o "$TMP/t3.pfm" 2>/dev/null
[ -s "$TMP/t1.pfm" ] && cmp -s "$TMP/t1.pfm" "$TMP/t3.pfm" \
  && ok "--estimator bdpt: the same bytes on 1 and 3 threads" || bad "--estimator bdpt: 1 and 3 threads differ"

for opt in "--adaptive 2" "--crop 0,0,8,8" "--samples 0:4" "-o $TMP/x.part" "scenes/dof.sph"; do
  scene=scenes/cornell.sph
  case $opt in *.sph) scene=$opt; opt="";; esac
  # shellcheck disable=SC2086
  ./ray "$scene" -s 16x16 -n 8 --pt --estimator bdpt -o "$TMP/r.pfm" $opt 2>"$TMP/err"; rc=$?
  [ $rc = 2 ] && grep -q "whole images only" "$TMP/err" && [ ! -e "$TMP/r.pfm" ] \
    && ok "--estimator bdpt with ${opt:-$scene} refused, exit 2: $(sed "s|$TMP/||" "$TMP/err")" \
    || bad "--estimator bdpt with ${opt:-$scene}: exit $rc, $(cat "$TMP/err")"
done
for opt in "--strategy 1,1" "--estimator bdpt --strategy 1,0" "--estimator bdpt --strategy 0,1" "--estimator bdpt --strategy x"; do
  # shellcheck disable=SC2086
  ./ray scenes/cornell.sph -s 16x16 -n 1 -o "$TMP/r.pfm" $opt 2>"$TMP/err"; rc=$?
  [ $rc = 2 ] && grep -q "strategy" "$TMP/err" && [ ! -e "$TMP/r.pfm" ] \
    && ok "$opt refused, exit 2: $(head -1 "$TMP/err")" || bad "$opt: exit $rc, $(cat "$TMP/err")"
done
./ray "$TMP/sky.sph" -s 8x8 -n 1 --estimator bdpt -o "$TMP/r.pfm" 2>"$TMP/err"
grep -q "only the camera's paths find the sky" "$TMP/err" && ok "a sky under bdpt: warned that only the camera's paths find it" \
  || bad "a sky under bdpt: no warning ($(cat "$TMP/err"))"
