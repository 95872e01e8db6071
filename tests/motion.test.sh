# Motion blur: moving objects against every structure (tests/test_motion.c,
# which includes ray.c whole), and what the images promise: a streak as
# long as the motion, the sphere's light conserved along it, velocity 0
# the static image byte for byte, shadows and light samples at each ray's
# instant, and the same bytes on 1 and 2 threads.  Monte Carlo checks
# compare floats (PFM), never bytes, within stated standard errors.
. tests/lib.sh

$CC $CFLAGS -std=c99 -o "$TMP/test_motion" tests/test_motion.c $RAY_PARTS -lm \
  || { bad "tests/test_motion.c compiles"; exit 1; }
"$TMP/test_motion"

# --- the streak.  A white glowing sphere of radius 0.5 at 100 from the eye,
# on black, through a narrow lens: one pixel is 0.05 across at the sphere
# (fov = 2 atan(0.05 * 121 / 200)), so the sphere is 20 pixels across.
# Moving 2 during the shutter it moves D = 40 pixels; the shutter runs from
# -0.5 to 0.5, so its centre passes the image's centre at the middle.
# Through the BVH: a sphere its box did not follow would lose light.
streak() {   # streak FILE VELOCITY
  cat >"$1" <<EOF
size 121 31
ambient 0 0 0
background 0 0 0
camera 0 -100 0   0 0 0   0 0 1   3.46533791808405
shutter -0.5 0.5
move $2 0 0
0 0 0   1 1 1   .5   0 0 0 1 1
EOF
}
streak "$TMP/still.sph" 0
streak "$TMP/moving.sph" 2
for r in whitted pt; do
  ./ray --$r -n 64 --accel bvh -o "$TMP/still_$r.pfm" "$TMP/still.sph" 2>/dev/null
  ./ray --$r -n 64 --accel bvh -o "$TMP/moving_$r.pfm" "$TMP/moving.sph" 2>/dev/null
done

cat >"$TMP/images.py" <<'EOF'
import struct, sys, math
def pfm(name):
    d = open(name, 'rb').read()
    parts = d.split(b'\n', 3)
    w, h = map(int, parts[1].split())
    v = struct.unpack('<%df' % (3 * w * h), parts[3][:12 * w * h])
    return w, h, [[v[3 * (j * w + i)] for i in range(w)] for j in range(h)]
def row_profile(img):           # the middle row, through the sphere's centre
    w, h, px = img
    return px[h // 2]
def support(p):                 # pixels from the first lit to the last
    lit = [i for i, x in enumerate(p) if x > 0]
    return lit[-1] - lit[0] + 1
def spread(p):                  # the variance of the row's light along x
    m = sum(i * x for i, x in enumerate(p)) / sum(p)
    return sum((i - m) ** 2 * x for i, x in enumerate(p)) / sum(p)
def energy(img, spp):           # the image's sum, and its standard error
    w, h, px = img              # (each sample 0 or 1: p(1-p)/spp a pixel)
    s = sum(sum(r) for r in px)
    var = sum(x * (1 - x) / spp for r in px for x in r if 0 < x < 1)
    return s, math.sqrt(var)
def same(a, b):                 # no more than 0.5% of the pixels differ
    (w, h, a), (_, _, b) = a, b
    px = [(x, y) for ra, rb in zip(a, b) for x, y in zip(ra, rb)]
    differ = sum(1 for x, y in px if abs(x - y) > 1e-4 * (1 + y))
    print('%d of %d pixels differ' % (differ, w * h))
    assert differ <= 0.005 * w * h and sum(y for x, y in px) > 0
what, r = sys.argv[1], sys.argv[2]
still, moving = pfm(sys.argv[3]), pfm(sys.argv[4])
D, spp = 40, 64
if what == 'same':
    same(still, moving)
elif what == 'length':
    ls, lm = support(row_profile(still)), support(row_profile(moving))
    # a box of width D convolved adds D^2/12 to the variance of the row
    dm = math.sqrt(12 * (spread(row_profile(moving)) - spread(row_profile(still))))
    print('%s: static %d px, moving %d px: longer by %d (predicted %d); by the spread, D = %.2f'
          % (r, ls, lm, lm - ls, D, dm))
    # the streak's ends are lit for under 1% of the shutter: a pixel there
    # may catch no sample, so the lit length may fall short by one a side
    assert D - 2 <= lm - ls <= D and abs(dm - D) <= 0.5
else:
    (es, ss), (em, sm) = energy(still, spp), energy(moving, spp)
    z = (em - es) / math.hypot(ss, sm)
    print('%s: static %.2f +- %.2f, moving %.2f +- %.2f, ratio %.4f, %.2f standard errors apart'
          ' (pi r^2 = %.2f)' % (r, es, ss, em, sm, em / es, z, math.pi * 100))
    assert abs(z) <= 4
EOF
for r in whitted pt; do
  if out=$(python3 "$TMP/images.py" length $r "$TMP/still_$r.pfm" "$TMP/moving_$r.pfm" 2>&1); then
    ok "motion $r: a sphere moving 40 pixels leaves a streak 40 pixels longer ($out)"
  else bad "motion $r: a sphere moving 40 pixels leaves a streak 40 pixels longer ($out)"; fi
  if out=$(python3 "$TMP/images.py" energy $r "$TMP/still_$r.pfm" "$TMP/moving_$r.pfm" 2>&1); then
    ok "motion $r: the streak holds the still sphere's light, within 4 standard errors ($out)"
  else bad "motion $r: the streak holds the still sphere's light, within 4 standard errors ($out)"; fi
done

# --- velocity 0: scenes/motion.sph with every `move` made 0 0 0, against
# the same file without its motion lines, and scenes/mesh.sph under a
# `move 0 0 0` (a mesh, cones, a one-sided floor) against itself: the same
# bytes, and the same counts through the kd-tree, whose exact clipping a
# moving object would give up.
grep -v -E '^(move|shutter) ' scenes/motion.sph >"$TMP/static.sph"
sed -E 's/^move .*/move 0 0 0/' scenes/motion.sph >"$TMP/zero.sph"
cp scenes/mesh.sph scenes/ball.obj "$TMP/"
{ printf 'shutter 0 1\nmove 0 0 0\n'; cat scenes/mesh.sph; } >"$TMP/mesh0.sph"
counts() { grep -E '^(rays|queries|nearest_queries|hits|tests|steps|samples_discarded)' "$1"; }
for pair in static:zero mesh:mesh0; do
  a=${pair%:*} b=${pair#*:}
  for r in whitted pt; do
    ./ray --$r -s 80x60 -n 4 --accel kd --stats=kv -o "$TMP/$a.$r.ppm" "$TMP/$a.sph" 2>"$TMP/$a.$r.kv"
    ./ray --$r -s 80x60 -n 4 --accel kd --stats=kv -o "$TMP/$b.$r.ppm" "$TMP/$b.sph" 2>"$TMP/$b.$r.kv"
    check "motion $r: velocity 0 renders the static image byte for byte ($b.sph)" \
      cmp "$TMP/$a.$r.ppm" "$TMP/$b.$r.ppm"
    if [ -n "$(counts "$TMP/$b.$r.kv")" ] && [ "$(counts "$TMP/$a.$r.kv")" = "$(counts "$TMP/$b.$r.kv")" ]; then
      ok "motion $r: velocity 0 keeps --stats' counts ($b.sph)"
    else bad "motion $r: velocity 0 keeps --stats' counts ($b.sph)"; fi
  done
done
# and the moving scene is not the static one
./ray -s 80x60 -n 4 -o "$TMP/moving.ppm" scenes/motion.sph 2>/dev/null
if cmp -s "$TMP/moving.ppm" "$TMP/static.whitted.ppm"; then bad "motion: scenes/motion.sph moves"
else ok "motion: scenes/motion.sph moves"; fi

# --- every ray at the shutter's instant.  With `shutter 1 1` every sample
# is taken at time 1, so the moving scene must look like the static scene
# with each object put where it is at time 1: shadows (shadow rays keep
# their camera ray's time), reflections, a moving lamp sampled where it is
# (a glowing sphere and triangle: the path tracer's light sampling and MIS,
# Whitted's glowing sphere).
# Floats compared: the ray moved the other way rounds differently, so a
# pixel on an edge may differ; no more than 0.5% of them may.
cat >"$TMP/room.sph" <<'EOF'
size 60 45
ambient .05 .05 .05
background .1 .1 .15
camera 0 -9 3.2   0 0 1   0 0 1   45
light -6 -8 12   .6 .6 .6
tri -9 -9 0   9 -9 0   9 9 0     .8 .8 .8  .8 .2 0 0 1
tri -9 -9 0   9 9 0   -9 9 0     .8 .8 .8  .8 .2 0 0 1
EOF
{ cat "$TMP/room.sph"; cat <<'EOF'; } >"$TMP/at1.sph"
shutter 1 1
move 1.5 -.5 .3
-2 0 .8        .9 .3 .2   .8   .7 .3 0 0 1
move -1 .5 0
1.5 1 2.6      1 .9 .7    .4   0 0 0 4 1
move .5 0 .2
cone 1 -1 0 .4  1 -1 1.2 0     .3 .8 .3  .8 .1 0 0 1
move 0 1 .5
tri -1 -3 .2  0 -3 .2  -.5 -3 1.2     .3 .3 .9  .8 .2 0 0 1
move .5 .5 -.5
tri -2 -1 4.5  1 -1 4.5  0 1 5     1 1 1  0 0 0 3 1
EOF
{ cat "$TMP/room.sph"; cat <<'EOF'; } >"$TMP/placed.sph"
-.5 -.5 1.1    .9 .3 .2   .8   .7 .3 0 0 1
.5 1.5 2.6     1 .9 .7    .4   0 0 0 4 1
cone 1.5 -1 .2 .4  1.5 -1 1.4 0     .3 .8 .3  .8 .1 0 0 1
tri -1 -2 .7  0 -2 .7  -.5 -2 1.7     .3 .3 .9  .8 .2 0 0 1
tri -1.5 -.5 4  1.5 -.5 4  .5 1.5 4.5     1 1 1  0 0 0 3 1
EOF
for r in whitted pt; do
  ./ray --$r -n 16 -o "$TMP/at1_$r.pfm" "$TMP/at1.sph" 2>/dev/null
  ./ray --$r -n 16 -o "$TMP/placed_$r.pfm" "$TMP/placed.sph" 2>/dev/null
  if out=$(python3 "$TMP/images.py" same $r "$TMP/at1_$r.pfm" "$TMP/placed_$r.pfm" 2>&1); then
    ok "motion $r: at shutter 1 1 the scene is the scene moved to time 1, shadows and lamps too ($out)"
  else bad "motion $r: at shutter 1 1 the scene is the scene moved to time 1, shadows and lamps too ($out)"; fi
done

# --- the same bytes on 1 and 2 threads, both renderers
for r in whitted pt; do
  ./ray --$r -t 1 -s 64x48 -n 8 -o "$TMP/t1_$r.ppm" scenes/motion.sph 2>/dev/null
  ./ray --$r -t 2 -s 64x48 -n 8 -o "$TMP/t2_$r.ppm" scenes/motion.sph 2>/dev/null
  check "motion $r: the same bytes on 1 and 2 threads" cmp "$TMP/t1_$r.ppm" "$TMP/t2_$r.ppm"
done

# --- the scene lines: what the reader refuses
printf 'shutter 1 0\n' >"$TMP/bad1.sph"
printf 'move 1 2\n' >"$TMP/bad2.sph"
printf 'shutter 0 2e6\n' >"$TMP/bad3.sph"
for f in bad1 bad2 bad3; do
  if ./ray -s 4x4 -o "$TMP/x.ppm" "$TMP/$f.sph" 2>"$TMP/$f.err"; then
    bad "motion: '$(cat "$TMP/$f.sph")' is refused with its line (it was read)"
  else
    grep -q "$f.sph:1: " "$TMP/$f.err" && ok "motion: '$(cat "$TMP/$f.sph")' is refused with its line" \
      || bad "motion: '$(cat "$TMP/$f.sph")' is refused with its line ($(cat "$TMP/$f.err"))"
  fi
done
