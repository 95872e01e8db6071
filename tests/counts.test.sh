# What --stats counts: the same for any number of threads, and within bounds
# on fixed scenes.  Images alone let two kinds of bug through:
#  - threads that share one set of counters render the same bytes, but
#    --stats with 2 threads reports twice the rays;
#  - a kd-tree or a BVH built badly (its SAH with the counts of the two
#    sides swapped) renders the same bytes, slower: the kd-tree 70 times,
#    the BVH with up to 5.5 times the tree steps a ray.
# Counts are deterministic (each pixel's random numbers are its own, and the
# shadow cache starts each row empty), so they are compared exactly, and the
# tree's work is bounded without timing anything.
. tests/lib.sh

# counts ARGS...: the lines of --stats that count work, without the times
# (the scene, image and time lines, and the tree's build time, are left out).
# One structure named: auto chooses by a timed probe, and its choice (not
# the picture) may differ from run to run.
counts() {
  ./ray --accel kd "$@" --stats -o "$TMP/c.ppm" 2>&1 >/dev/null | grep -E '^(rays|hits|per ray|samples|skips) '
}

# The SPD scenes as make spd writes them, generated here by tools/spd.
for d in balls:4 gears:4 mount:6 rings:7 teapot:6 tetra:6 tree:11; do
  tools/spd "${d%:*}" "${d#*:}" >"$TMP/${d%:*}.nff" || bad "tools/spd ${d%:*} ${d#*:}"
done

# The same counts with 1, 2 and 3 threads, Whitted's and the path tracer's.
if ./ray -t 2 -s 8x8 --stats -o "$TMP/c.ppm" scenes/minray.sph 2>&1 | grep -q "2 threads"; then
  while read -r name args; do
    # shellcheck disable=SC2086 # args holds several words
    one=$(counts -t 1 $args)
    same=1
    for t in 2 3; do
      # shellcheck disable=SC2086
      [ "$(counts -t $t $args)" = "$one" ] || { same=0; diff <(echo "$one") <(counts -t $t $args) | sed 's/^/    /'; }
    done
    if [ "$same" = 1 ] && [ -n "$one" ]; then
      ok "--stats counts the same with 1, 2 and 3 threads: $name ($(echo "$one" | head -1))"
    else
      bad "--stats counts differ between 1, 2 and 3 threads: $name"
    fi
  done <<LIST
whitted-mesh   -s 64x48 -n 2 scenes/mesh.sph
whitted-balls  -s 48x48 $TMP/balls.nff
pt-cornell     --pt -s 32x24 -n 2 scenes/cornell.sph
pt-smallpt     --pt -s 32x24 -n 2 scenes/smallpt.sph
LIST
else
  skip "--stats counts on 1 and 2 threads: ray was built without OpenMP (one thread only)"
fi

# Each structure's work on fixed scenes, each figure at most its bound, set
# about 10% above what the structure did when its table was written: the
# kd-tree's SAH cost and its intersection tests and tree steps a ray (make
# test, November 2026); the BVH's the same, its SAH cost that of its
# four-way tree, and the grid's references an object and tests and steps
# (cells) a ray (December 2026).  Images cannot see a structure built
# badly; these can.  The kd-tree's SAH with the counts of the two sides
# swapped makes them 10 to 4000 times larger (gears: SAH cost 33 -> 17770,
# 5 -> 22680 tests a ray); the BVH's makes its SAH cost 1.1 to 9 times
# larger on 12 of the 15 scenes (balls: 2.93 -> 26.1, and its steps a ray
# 6.9 -> 38.4), though it finds the same hits.  A better structure may
# lower the bounds; raise one only for a reason, said in the commit.
# (smallpt.sph's tests and steps a ray rose, the same structures, when its
# lamp came to be sampled in the cap the ceiling leaves seen: shadow rays
# that stopped at the ceiling near their start now cross the room.)
# work ACCEL NAME FIRST < TABLE: one line a scene of TABLE, `scene | args |
# bounds: FIRST, tests, steps | today's`, FIRST the figure --stats gives
# before "references per object" or after "SAH cost".
work() {
  local accel=$1 what=$2 first=$3 scene args bounds got c t s lim tests steps
  while IFS='|' read -r scene args bounds _; do
    case $scene in ''|'#'*) continue ;; esac
    scene=$(echo $scene)          # the table's blanks off
    read -r lim tests steps <<<"$bounds"
    case $scene in spd/*) file=$TMP/${scene#spd/}.nff ;; *) file=scenes/$scene ;; esac
    # shellcheck disable=SC2086 # args holds several words
    got=$(./ray --accel "$accel" -t 1 $args --stats -o "$TMP/c.ppm" "$file" 2>&1 >/dev/null |
          awk '/SAH cost/ { for (i = 1; i < NF; i++) if ($i == "cost") c = $(i + 1) + 0 }
               /references per object/ { for (i = 2; i < NF; i++) if ($i == "references") c = $(i - 1) + 0 }
               /^per ray/ { t = $3; s = $6 } END { if (c != "" && t != "") print c, t, s }')
    if [ -z "$got" ]; then bad "$what work on $scene: no $first or per-ray line in --stats"; continue; fi
    read -r c t s <<<"$got"
    if awk -v c="$c" -v t="$t" -v s="$s" -v C="$lim" -v T="$tests" -v S="$steps" \
         'BEGIN { exit !(c <= C && t <= T && s <= S) }'; then
      ok "$what work on $scene: $first $c <= $lim, per ray $t tests <= $tests, $s steps <= $steps"
    else
      bad "$what work on $scene: $first $c (at most $lim), per ray $t tests (at most $tests), $s steps (at most $steps)"
    fi
  done
}

work kd kd-tree "SAH cost" <<'BOUNDS'
# scene      | ./ray arguments | bounds: SAH cost, tests and steps a ray | today's
spd/balls    | -s 48x48        | 5.6   5.5   24.3 | 5.09  4.94  22.03
spd/gears    | -s 48x48        | 36.8  5.8   24.3 | 33.44 5.20  22.02
spd/mount    | -s 48x48        | 39.7  5.6   18.2 | 36.03 5.03  16.50
spd/rings    | -s 48x48        | 47.3  16.2  32.2 | 42.98 14.71 29.19
spd/teapot   | -s 48x48        | 26.3  5.4   22.1 | 23.87 4.90  20.04
spd/tetra    | -s 48x48        | 24.7  1.9   13.9 | 22.40 1.72  12.59
spd/tree     | -s 48x48        | 3.9   3.8   15.0 | 3.52  3.37  13.59
whitted.sph  | -s 48x48        | 2.4   2.8   6.0  | 2.10  2.46  5.37
minray.sph   | -s 48x48        | 3.0   3.4   4.0  | 2.66  3.07  3.58
mesh.sph     | -s 48x48        | 7.0   4.1   6.9  | 6.31  3.68  6.27
demo.nff     | -s 48x48        | 5.1   4.4   3.7  | 4.58  3.92  3.28
cornell.sph  | -s 24x24 -n 1   | 14.7  10.2  9.8  | 13.36 9.26  8.89
smallpt.sph  | -s 24x24 -n 1   | 6.0   9.5   1.1  | 5.40  8.66  0.99
caustic.sph  | -s 24x24 -n 1   | 4.0   5.8   1.1  | 3.60  5.23  0.98
bleed.sph    | -s 24x24 -n 1   | 3.8   2.8   5.8  | 3.45  2.51  5.22
BOUNDS

work bvh BVH "SAH cost" <<'BOUNDS'
# scene      | ./ray arguments | bounds: SAH cost (four-way), tests and steps a ray | today's
spd/balls    | -s 48x48        | 3.3   2.1   7.7   | 2.93  1.86  6.93
spd/gears    | -s 48x48        | 20.0  4.4   10.8  | 18.10 3.99  9.76
spd/mount    | -s 48x48        | 13.3  2.4   6.9   | 12.07 2.18  6.27
spd/rings    | -s 48x48        | 21.4  6.3   16.0  | 19.37 5.66  14.52
spd/teapot   | -s 48x48        | 11.0  2.7   8.4   | 9.91  2.45  7.63
spd/tetra    | -s 48x48        | 9.9   1.9   4.2   | 9.00  1.71  3.73
spd/tree     | -s 48x48        | 3.2   1.7   3.8   | 2.89  1.48  3.38
whitted.sph  | -s 48x48        | 2.2   0.9   2.5   | 2.00  0.81  2.23
minray.sph   | -s 48x48        | 2.4   1.6   2.6   | 2.18  1.43  2.34
mesh.sph     | -s 48x48        | 3.4   2.2   3.4   | 3.06  1.98  3.09
demo.nff     | -s 48x48        | 3.4   1.5   2.8   | 3.02  1.30  2.46
cornell.sph  | -s 24x24 -n 1   | 9.4   3.9   6.6   | 8.52  3.46  5.98
smallpt.sph  | -s 24x24 -n 1   | 3.7   8.2   10.6  | 3.29  7.39  9.57
caustic.sph  | -s 24x24 -n 1   | 2.9   2.2   2.8   | 2.61  1.96  2.48
bleed.sph    | -s 24x24 -n 1   | 3.2   1.6   2.6   | 2.90  1.45  2.36
BOUNDS

work grid grid "references an object" <<'BOUNDS'
# scene      | ./ray arguments | bounds: references an object, tests and steps a ray | today's
spd/balls    | -s 48x48        | 2.0   188.6 8.3   | 1.75  171.38 7.49
spd/gears    | -s 48x48        | 3.6   18.4  13.0  | 3.24  16.72 11.74
spd/mount    | -s 48x48        | 3.1   9.9   11.7  | 2.81  8.92  10.57
spd/rings    | -s 48x48        | 5.0   33.6  15.9  | 4.50  30.46 14.41
spd/teapot   | -s 48x48        | 3.8   15.9  13.3  | 3.37  14.44 12.06
spd/tetra    | -s 48x48        | 3.8   11.4  10.1  | 3.39  10.33 9.11
spd/tree     | -s 48x48        | 2.1   513.4 11.2  | 1.85  466.69 10.15
whitted.sph  | -s 48x48        | 3.1   2.4   1.4   | 2.80  2.18  1.22
minray.sph   | -s 48x48        | 4.4   5.0   1.4   | 4.00  4.48  1.19
mesh.sph     | -s 48x48        | 3.9   13.7  4.7   | 3.52  12.45 4.23
demo.nff     | -s 48x48        | 5.0   3.5   1.9   | 4.50  3.18  1.64
cornell.sph  | -s 24x24 -n 1   | 7.6   10.4  3.9   | 6.82  9.39  3.46
smallpt.sph  | -s 24x24 -n 1   | 13.6  9.5   1.1   | 12.33 8.66  0.99
caustic.sph  | -s 24x24 -n 1   | 4.6   5.4   2.1   | 4.17  4.90  1.90
bleed.sph    | -s 24x24 -n 1   | 10.7  9.8   1.7   | 9.67  8.90  1.51
BOUNDS

# --no-skip: the plain algorithm's work.  Every shading point sends a shadow
# ray to every point light (none is skipped for facing away, no cache
# answers first), so on scenes lit by point lights alone the shadow rays
# are exactly the lights times the shading points (the hits of primary,
# reflected and refracted rays); the rays of weight under 1/512 are traced
# too (whitted.sph has some), and the image stays within a step of the
# default one; --stats says so.  Where no ray was too faint, the default's
# shadow rays and those it counts as skipped for lights behind add up to
# --no-skip's.
for f in scenes/whitted.sph "$TMP/balls.nff"; do
  ./ray --accel kd --no-skip -s 64x48 --stats=kv -o "$TMP/ns.ppm" "$f" 2>"$TMP/ns.kv" >/dev/null
  ./ray --accel kd -s 64x48 --stats=kv -o "$TMP/sk.ppm" "$f" 2>"$TMP/sk.kv" >/dev/null
  read -r lights shadow hits skip refl <<<"$(for k in point_lights rays_shadow hits no_skip rays_reflected; do sed -n "s/^$k //p" "$TMP/ns.kv"; done | tr '\n' ' ')"
  refl0=$(sed -n 's/^rays_reflected //p' "$TMP/sk.kv")
  shadow0=$(sed -n 's/^rays_shadow //p' "$TMP/sk.kv") behind=$(sed -n 's/^skipped_behind //p' "$TMP/sk.kv")
  [ -n "$lights" ] && [ "$shadow" = $((lights * hits)) ] && [ "$skip" = 1 ] && [ "$refl" -ge "$refl0" ] \
    && { [ "$f" != scenes/whitted.sph ] || [ "$refl" -gt "$refl0" ]; } \
    && { [ "$refl" != "$refl0" ] || [ "$shadow" = $((shadow0 + behind)) ]; } \
    && tools/ppmdiff -t 1 "$TMP/ns.ppm" "$TMP/sk.ppm" >/dev/null 2>&1 \
    && ok "--no-skip on $(basename "$f"): $shadow shadow rays = $lights lights x $hits shading points; $refl reflected rays against $refl0 (the default's $shadow0 shadow rays and $behind skipped behind); within a step of the default image" \
    || bad "--no-skip on $(basename "$f"): shadow '$shadow', lights '$lights', hits '$hits', no_skip '$skip'"
done
