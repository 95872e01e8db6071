#!/usr/bin/env bash
# make bench: the Whitted renderer's time against its error, and the kd-tree
# against brute force, against itself at growing N, against Embree and
# against POV-Ray.
#
# Sections (BENCH_PARTS picks some; all by default), each a table in
# bench/out/bench.txt with its targets beside the numbers:
#   render  time against error: for each scene a reference is rendered with
#           the double build at many samples per pixel, then every build
#           (double, float) at every sample count is timed and compared with
#           it by tools/ppmdiff; plotted to bench.svg
#   spd     ./ray --accel kd against --accel none on the SPD scenes, one
#           thread, same small image for both: time per ray and its ratio
#   build   kd-tree build time against N (10k to 1M triangles), the fitted
#           exponent, and the tree's bytes per triangle; the same for the
#           BVH (SAH and median) and the grid (bench/raybench.c)
#   rays    traversal Mrays/s on meshes, one thread, primary and random rays,
#           against Embree's rtcIntersect1 on the very same rays, hits
#           compared ray by ray (bench/raybench.c, ../shared/embree)
#   accel   every structure on the same rays, one thread: for each SPD scene
#           and the 100k-triangle sphere, build time, memory, primary- and
#           random-ray Mrays/s (CPU time, best / median / worst of 5 rounds,
#           the structures taking turns) for kd, bvh-sah, bvh-median, grid
#           and none, and the recursive forms kd-rec and bvh-rec; Embree on
#           the sphere's very rays, alternating with ours (bench/raybench.c
#           accel)
#   anim    which structures suit animation: 300 balls falling through SPD
#           gears, and every sphere of SPD balls twisted, 60 frames, one
#           thread; per frame the build (or refit) and the trace of 256x256
#           primary rays, for rebuilding the kd-tree, rebuilding the BVH,
#           refitting the BVH, rebuilding the grid (bench/raybench.c anim)
#   pov     SPD balls at 512x512, one thread: ./ray against --accel none and
#           against POV-Ray 3.7; and POV-Ray's other SPD scenes
#   pt      the path tracer: each estimator's CPU time against its RMSE on the
#           Cornell box and smallpt's scene, against smallpt, and its rays
#           per second against Whitted's (bench/pt.sh; plotted to pt.svg)
# Embree and POV-Ray are instruments, not dependencies: when one is missing
# its rows say "not installed, skipped".  BENCH_INSTALL=1 first tries
# `apt-get install -y libembree-dev povray` for the missing ones.
#
# Writes, under bench/out/ (rebuilt freely, never committed):
#   bench.txt   every table        bench.tsv   time against error, one row per render
#   bench.svg   seconds against RMSE, log-log, one line per scene and build
#   *.ppm       every render and the references, for a look at the error
#   *.log       the raw output each table was read from
#
# Knobs (environment; defaults keep `make bench` near 4 minutes on 2 cores):
#   BENCH_PARTS="render spd build rays accel anim pov pt"
#   BENCH_SPP="1 4 16"       sample counts to time
#   BENCH_REF_SPP=64         reference sample count (should exceed the above)
#   BENCH_FLAKE_LEVEL=4      sphereflake recursion (4: 7381 spheres)
#   BENCH_FLAKE_SIZE=WxH     sphereflake image size; by default the largest
#                            of 512x512, 256x256, 128x128 whose renders are
#                            expected to fit in BENCH_FLAKE_BUDGET seconds,
#                            judged from one 128x128 render
#   BENCH_FLAKE_BUDGET=150
#   BENCH_MINRAY_SIZE=512x512
#   BENCH_THREADS=N          ./ray -t N in the render section (default:
#                            ./ray's own, every core); the others use one
#   BENCH_SPD_DIR=scenes/spd              the SPD scenes (make spd writes them;
#                                         POV-Ray's pov/ files: ../shared/spd)
#   BENCH_SPD="balls_s4 gears_s4 mount_s6 rings_s7 teapot_s6 tetra_s6 tree_s11"
#   BENCH_NONE_BUDGET=2      seconds one brute-force render may take: sets
#                            each SPD scene's image size, from a 16x16 probe
#   BENCH_BUILD_MAX=1000000  largest mesh of the build section
#   BENCH_EMBREE_DIR=../shared/embree     the harness and its tools
#   BENCH_MESHES="sphere100k teapot_s12"  sphereNk / sphereNm: a tessellated
#                            sphere of N thousand / million triangles;
#                            other names: that SPD scene's polygons, seen
#                            from its own camera
#   BENCH_RAYS_RES=1024      primary rays: a square image of this side
#   BENCH_RAYS_N=1000000     random rays
#   BENCH_ACCEL_SPD="balls_s4 ..."  the SPD scenes of the accel section
#                            (default: BENCH_SPD), from BENCH_SPD_DIR, else
#                            from scenes/spd (make spd)
#   BENCH_ACCEL_RES=512      their primary rays: a square image of this side,
#                            from the scene's own camera
#   BENCH_ACCEL_N=300000     their random rays
#   BENCH_INSTALL=1          try apt-get for a missing Embree or POV-Ray
#   BENCH_BALLS_NONE_FULL=1  brute force renders balls at 512x512 for the
#                            speed-up target (about 35 s); 0: its time per
#                            ray at a smaller size stands for it
# CC and CFLAGS choose the compiler, as for make.
set -u -o pipefail
export LC_ALL=C   # a '.' decimal point from `time` and awk, whatever the locale
cd "$(dirname "$0")/.." || exit 2

CC=${CC:-cc}
CFLAGS=${CFLAGS:--O2}
SPPS=${BENCH_SPP:-1 4 16}
REF_SPP=${BENCH_REF_SPP:-64}
FLAKE_LEVEL=${BENCH_FLAKE_LEVEL:-4}
FLAKE_SIZE=${BENCH_FLAKE_SIZE:-}
FLAKE_BUDGET=${BENCH_FLAKE_BUDGET:-150}
MINRAY_SIZE=${BENCH_MINRAY_SIZE:-512x512}
THREADS=${BENCH_THREADS:-}
PARTS=${BENCH_PARTS:-render spd build rays accel anim pov pt}
SPD_DIR=${BENCH_SPD_DIR:-scenes/spd}
POV_DIR=${BENCH_POV_DIR:-../shared/spd/pov}
SPD_SCENES=${BENCH_SPD:-balls_s4 gears_s4 mount_s6 rings_s7 teapot_s6 tetra_s6 tree_s11}
NONE_BUDGET=${BENCH_NONE_BUDGET:-2}
BUILD_MAX=${BENCH_BUILD_MAX:-1000000}
EMBREE_DIR=${BENCH_EMBREE_DIR:-../shared/embree}
MESHES=${BENCH_MESHES:-sphere100k teapot_s12}
RAYS_RES=${BENCH_RAYS_RES:-1024}
RAYS_N=${BENCH_RAYS_N:-1000000}
OUT=bench/out

die() { echo "bench/run.sh: $*" >&2; exit 1; }
say() { echo "bench: $*" >&2; }

for n in $SPPS $REF_SPP; do
  case $n in ''|*[!0-9]*|0) die "sample counts must be whole numbers from 1, not '$n'";; esac
done
for n in $SPPS; do
  [ "$n" -lt "$REF_SPP" ] || die "BENCH_REF_SPP ($REF_SPP) must exceed every count in BENCH_SPP ($SPPS)"
done
for n in $NONE_BUDGET $BUILD_MAX $RAYS_RES $RAYS_N; do
  case $n in ''|*[!0-9]*|0) die "BENCH_NONE_BUDGET, BENCH_BUILD_MAX, BENCH_RAYS_RES and BENCH_RAYS_N must be whole numbers from 1, not '$n'";; esac
done
for p in $PARTS; do
  case $p in render|spd|build|rays|accel|anim|pov|pt) ;; *) die "BENCH_PARTS: unknown section '$p' (render spd build rays accel anim pov pt)";; esac
done
part() { [[ " $PARTS " == *" $1 "* ]]; }
mkdir -p "$OUT" || die "cannot create $OUT"
status=0   # 1 once a section of ours (not an instrument) failed

# ---------------------------------------------------------------- builds
# Both renderer builds come from one command line that differs only in
# -DREAL, so that the float/double comparison measures nothing else; they
# are built here rather than taken from make so that this holds even when
# ./ray is stale.  OpenMP is detected as the Makefile does.
OMP=$(echo 'int main(void){return 0;}' | $CC -fopenmp -x c - -o /dev/null 2>/dev/null && echo -fopenmp)
RAYSRC=(ray.c)
# Each acceleration module is linked once ray.c uses it, not merely because
# it exists: a half-written one must not break the bench of a renderer that
# ignores it.
for m in kdtree bvh grid; do
  if grep -q "^#include \"$m.h\"" ray.c && [ -f $m.c ]; then RAYSRC+=($m.c); fi
done

build() {  # build OUTPUT CC-ARGS...
  local out=$1; shift
  # $CFLAGS is split into words on purpose, as make does.
  # shellcheck disable=SC2086
  if ! $CC $CFLAGS "$@" -o "$out" -lm 2>"$OUT/build.log"; then
    cat "$OUT/build.log" >&2
    die "cannot build $out with: $CC $CFLAGS $* -lm"
  fi
}
say "building into $OUT/ with $CC $CFLAGS $OMP"
# $OMP is one word or none.
# shellcheck disable=SC2086
build "$OUT/ray_double" $OMP "${RAYSRC[@]}"
# shellcheck disable=SC2086
build "$OUT/ray_float" $OMP -DREAL=float "${RAYSRC[@]}"
build "$OUT/ppmdiff" tools/ppmdiff.c
build "$OUT/sphereflake" bench/sphereflake.c
build "$OUT/svgplot" bench/svgplot.c
# raybench includes ray.c whole and calls its internals, which change as
# ray.c does: when it no longer builds, its sections say so and the bench
# goes on (and fails at the end) rather than losing the other tables.
# No OpenMP: everything it times runs on one thread.
RAYBENCH=$OUT/raybench
# $CFLAGS is split into words on purpose, as make does.
# shellcheck disable=SC2086
if ! $CC $CFLAGS -o "$RAYBENCH" bench/raybench.c "${RAYSRC[@]:1}" -lm 2>"$OUT/raybench-build.log"; then
  cat "$OUT/raybench-build.log" >&2
  say "bench/raybench.c does not build: the build and rays sections will be skipped"
  RAYBENCH=
  status=1
fi

"$OUT/sphereflake" "$FLAKE_LEVEL" >"$OUT/sphereflake.sph" || die "sphereflake $FLAKE_LEVEL failed"

# ------------------------------------------------------------- rendering
TARGS=()
[ -n "$THREADS" ] && TARGS=(-t "$THREADS")
TIMEFORMAT=%3R

# render BIN SCENE SIZE SPP OUTPUT [ARGS...]: renders once; its wall-clock
# seconds go to $took, its messages to $OUT/ray.err.  The whole process is
# timed, scene loading included, since that is where any acceleration
# structure gets built.
render() {
  if ! { time "$1" ${TARGS[@]+"${TARGS[@]}"} "${@:6}" -s "$3" -n "$4" -o "$5" "$2" 2>"$OUT/ray.err"; } 2>"$OUT/time.txt"; then
    cat "$OUT/ray.err" >&2
    die "failed: $1 ${TARGS[*]:-} ${*:6} -s $3 -n $4 -o $5 $2"
  fi
  took=$(tail -n 1 "$OUT/time.txt")
}

# timed BIN SCENE SIZE SPP OUTPUT: like render, but short renders are
# repeated and the fastest kept (of 5 under half a second, of 3 under two),
# since one short run measures start-up and other processes as much as the
# renderer; the fastest run is the one least disturbed.
timed() {
  local best n
  render "$@"; best=$took
  n=$(awk "BEGIN { print ($best < 0.5) ? 4 : ($best < 2) ? 2 : 0 }")
  while [ "$n" -gt 0 ]; do
    render "$@"
    best=$(awk "BEGIN { print ($took < $best) ? $took : $best }")
    n=$((n - 1))
  done
  took=$best
}

# reference NAME SCENE SIZE: the double build at $REF_SPP, kept between runs
# while the binary, the scene and the settings are unchanged.
reference() {
  local name=$1 scene=$2 size=$3 key
  key="$(cksum <"$OUT/ray_double") $(cksum <"$scene") $size $REF_SPP ${TARGS[*]:-}"
  ref=$OUT/$name-ref.ppm
  if [ -f "$ref" ] && [ "$(cat "$OUT/$name-ref.key" 2>/dev/null)" = "$key" ]; then
    say "$name: reference at $REF_SPP spp unchanged since the last run, reused"
    return
  fi
  rm -f "$OUT/$name-ref.key"
  say "$name: reference, double build at $REF_SPP spp ..."
  render "$OUT/ray_double" "$scene" "$size" "$REF_SPP" "$ref"
  say "$name: reference took $took s"
  printf '%s\n' "$key" >"$OUT/$name-ref.key"
}

# error IMAGE REFERENCE: sets $rmse and $psnr from ppmdiff's summary line.
error() {
  local line rc
  line=$("$OUT/ppmdiff" "$1" "$2" 2>"$OUT/ppmdiff.err"); rc=$?
  [ "$rc" -le 1 ] || { cat "$OUT/ppmdiff.err" >&2; die "ppmdiff failed on $1"; }
  rmse=$(printf '%s\n' "$line" | sed -n 's/.*RMSE \([^,]*\),.*/\1/p')
  psnr=$(printf '%s\n' "$line" | sed -n 's/.*PSNR \([^ ]*\) dB.*/\1/p')
  if [ -z "$rmse" ] || [ -z "$psnr" ]; then die "cannot read ppmdiff's output: $line"; fi
}

spheres() { awk '$1 ~ /^[-+.0-9]/ { n++ } END { print n + 0 }' "$1"; }

# shellcheck disable=SC2086
base_spp=$(printf '%s\n' $SPPS | sort -n | head -n 1)
nsum=0; for n in $SPPS; do nsum=$((nsum + n)); done
: >"$OUT/bench.tsv"
: >"$OUT/bench.txt"
t_start=$SECONDS

# bench NAME SCENE SIZE
bench() {
  local name=$1 scene=$2 size=$3 nsph spp b base
  nsph=$(spheres "$scene")
  # The cheapest render first, to warn early when the rest will take long.
  timed "$OUT/ray_double" "$scene" "$size" "$base_spp" "$OUT/$name-double-$base_spp.ppm"
  base=$took
  say "$name ($size, $nsph spheres): double $base_spp spp: $took s"
  awk "BEGIN { e = $base / $base_spp * (2 * $nsum + $REF_SPP);
               if (e > 120) printf \"bench: %s: expect about %.0f s more; BENCH_* in bench/run.sh trade size for time\\n\", \"$name\", e }" >&2
  reference "$name" "$scene" "$size"
  for spp in $SPPS; do
    for b in double float; do
      if [ "$b" = double ] && [ "$spp" = "$base_spp" ]; then
        took=$base
      else
        timed "$OUT/ray_$b" "$scene" "$size" "$spp" "$OUT/$name-$b-$spp.ppm"
        say "$name: $b $spp spp: $took s"
      fi
      error "$OUT/$name-$b-$spp.ppm" "$ref"
      printf '%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\n' "$name" "$size" "$nsph" "$b" \
        "$spp" "$took" "$(awk "BEGIN { printf \"%.2f\", $took / $base }")" \
        "$rmse" "$psnr" >>"$OUT/bench.tsv"
    done
  done
}

if part render; then
  bench minray scenes/minray.sph "$MINRAY_SIZE"

  # The sphereflake's cost depends on the renderer's acceleration far more than
  # the minray scene's does (brute force against a kd-tree is 100x here), so its
  # size follows the renderer rather than staying fixed.  One 128x128 probe
  # splits the cost into start-up (scene, tree: paid per run) and rendering
  # (scales with pixels and samples), the latter from --stats' "time" line;
  # without that line all of it counts as rendering, which overestimates.
  nruns=$(( $(wc -w <<<"$SPPS") * 2 + 1 ))
  if [ -z "$FLAKE_SIZE" ]; then
    render "$OUT/ray_double" "$OUT/sphereflake.sph" 128x128 1 "$OUT/sphereflake-probe.ppm" --stats
    rt=$(sed -n 's/^time *\([0-9.]*\) s.*/\1/p' "$OUT/ray.err" | head -n 1)
    rt=${rt:-$took}
    FLAKE_SIZE=128x128
    for w in 512 256; do
      est=$(awk "BEGIN { f = $took - $rt; if (f < 0) f = 0;
                         printf \"%.0f\", $nruns * f + $rt * ($w / 128)^2 * (2 * $nsum + $REF_SPP) }")
      if [ "$est" -le "$FLAKE_BUDGET" ]; then FLAKE_SIZE=${w}x$w; break; fi
      say "sphereflake: ${w}x$w would take about $est s, over BENCH_FLAKE_BUDGET=$FLAKE_BUDGET"
    done
    say "sphereflake: ${FLAKE_SIZE} (128x128 at 1 spp took $took s)"
  fi
  bench sphereflake "$OUT/sphereflake.sph" "$FLAKE_SIZE"

  # report
  threads=${THREADS:-"all cores ($(getconf _NPROCESSORS_ONLN 2>/dev/null || echo '?'))"}
  {
    echo "make bench: time against error of ./ray, built with $CC $CFLAGS $OMP; threads: $threads"
    echo "reference: double build at $REF_SPP spp, per scene; RMSE and PSNR against it, in 8-bit units"
    echo "seconds: wall clock of one ./ray run, the fastest of 5 under 0.5 s, of 3 under 2 s; ratio: to double at $base_spp spp"
    echo "spheres: in the scene file, ground and lights included"
    echo
    printf '%-12s %-9s %7s  %-6s %4s %8s %7s %8s %7s\n' scene size spheres build spp seconds ratio RMSE PSNR
    awk -F'\t' '{ printf "%-12s %-9s %7s  %-6s %4s %8.3f %7s %8s %7s\n", $1, $2, $3, $4, $5, $6, $7, $8, $9 }' "$OUT/bench.tsv"
  } | tee -a "$OUT/bench.txt"

  awk -F'\t' '{ print $1 "/" $4, $6, $8, $5 }' "$OUT/bench.tsv" |
    "$OUT/svgplot" --title "make bench: Whitted ray tracer, time against error (labels: samples per pixel)" \
      --xlabel "seconds per image (wall clock)" \
      --ylabel "RMSE against the $REF_SPP-spp double reference" >"$OUT/bench.svg" ||
    die "svgplot failed"
  echo | tee -a "$OUT/bench.txt"
fi

# ================================================ the kd-tree's sections
# Everything below runs on one thread: a speed-up is a property of the
# algorithm, and one thread keeps it from depending on the machine's cores
# and on whatever else runs on them.

targets=()   # one line per target, printed together at the end
verdict() { awk "BEGIN { exit !($1) }" && echo met || echo "NOT MET"; }
num() { [[ ${1:-} =~ ^[0-9]+([.][0-9]*)?([eE][-+]?[0-9]+)?$ ]]; }

# install_pkg PACKAGE: only with BENCH_INSTALL=1, and never fatal: the
# instruments are optional, and a machine without apt or root just skips.
install_pkg() {
  local sudo=
  [ "${BENCH_INSTALL:-}" = 1 ] || return 1
  command -v apt-get >/dev/null || return 1
  [ "$(id -u)" = 0 ] || sudo="sudo -n"
  say "BENCH_INSTALL=1: apt-get install -y $1"
  { $sudo apt-get update -qq && DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq "$1"; } \
    >"$OUT/apt-$1.log" 2>&1
}

# Readers of ./ray --stats, saved to a log.
stat_rays() { sed -n 's/^rays *\([0-9]*\):.*/\1/p' "$1" | head -n 1; }
stat_seconds() { sed -n 's/^time *\([0-9.]*\) s.*/\1/p' "$1" | head -n 1; }
stat_tests() { sed -n 's/^per ray *\([0-9.]*\) intersection tests.*/\1/p' "$1" | head -n 1; }
stat_built() { sed -n 's/.*built in \([0-9.]*\) s.*/\1/p' "$1" | head -n 1; }
# Every object of the scene line ("7381 spheres, 0 cones, 2 triangles, 3
# lights; ..."), lights aside, whatever kinds ray.c comes to count.
stat_objects() {
  sed -n 's/^scene *//p' "$1" | head -n 1 |
    awk -F', ' '{ n = 0; for (i = 1; i <= NF; i++) if ($i !~ /light/) n += $i; print n }'
}
# The tree's bytes from its shape, as kdtree.h lays it out: 8-byte nodes,
# then a 4-byte primitive number per reference (objects per leaf times the
# non-empty leaves).  --stats prints the size in MB to one decimal, too
# coarse for the small scenes.
stat_tree_bytes() {
  awk '/^kd-tree/ { for (i = 2; i < NF; i++) {
         if ($(i + 1) == "nodes,") n = $i
         if ($(i + 1) == "leaves") l = $i
         if ($i ~ /^\(/) e = substr($i, 2)
         if ($(i + 1) == "objects" && $(i + 2) == "per") p = $i } }
       END { if (n != "") printf "%.0f", 8 * n + 4 * p * (l - e) }' "$1"
}

# ray1 SCENE SIZE ACCEL OUTPUT LOG [ARGS...]: one single-threaded ./ray run
# with --stats into LOG, its wall clock in $took; fails when ./ray does.
ray1() {
  local scene=$1 size=$2 accel=$3 out=$4 log=$5
  shift 5
  { time "$OUT/ray_double" -t 1 --stats --accel "$accel" -s "$size" -o "$out" "$@" "$scene" 2>"$log"; } \
    2>"$OUT/time.txt" || return 1
  took=$(tail -n 1 "$OUT/time.txt")
  if ! num "$(stat_seconds "$log")" || ! num "$(stat_rays "$log")"; then
    say "cannot read the time and rays of ./ray --stats in $log"
    return 1
  fi
}

# ray_best: ray1, three runs when the first takes under 2 s of wall clock;
# the least wall clock in $took and the least render time in $rsecs.
ray_best() {
  local runs w r
  ray1 "$@" || return 1
  w=$took
  r=$(stat_seconds "$5")
  runs=$(awk "BEGIN { print ($took < 2) ? 2 : 0 }")
  while [ "$runs" -gt 0 ]; do
    ray1 "$@" || return 1
    w=$(awk "BEGIN { print ($took < $w) ? $took : $w }")
    r=$(awk "BEGIN { s = $(stat_seconds "$5"); print (s < $r) ? s : $r }")
    runs=$((runs - 1))
  done
  took=$w
  rsecs=$r
}

# rfield LOG SET KEY: KEY's value on raybench's "result" lines (of set SET,
# when not empty); the last one wins.
rfield() {
  awk -v set="$2" -v key="$3" '
    $1 == "result" && (set == "" || $2 == "set=" set) {
      for (i = 2; i <= NF; i++) if (index($i, key "=") == 1) v = substr($i, length(key) + 2) }
    END { print v }' "$1"
}

# rfield_max LOG SET KEY: the largest of KEY's values over LOG's rounds.
rfield_max() {
  awk -v set="$2" -v key="$3" '
    $1 == "result" && (set == "" || $2 == "set=" set) {
      for (i = 2; i <= NF; i++) if (index($i, key "=") == 1) { x = substr($i, length(key) + 2) + 0; if (x > v) v = x } }
    END { print v }' "$1"
}

# best_of OLD NEW max|min: the better of two figures, either may be empty.
best_of() {
  if [ -z "$1" ]; then echo "$2"; elif [ -z "$2" ]; then echo "$1"
  else awk -v a="$1" -v b="$2" -v m="$3" 'BEGIN { print (m == "max") == (b + 0 > a + 0) ? b : a }'; fi
}

# ------------------------------------------------------- kd against none
balls_none_us=   # kept for the POV-Ray section
if part spd; then
  t_part=$SECONDS
  {
    echo "kd-tree against brute force on the SPD scenes: ./ray -t 1 --accel kd and --accel none, the same image for"
    echo "both (its side chosen so that brute force takes about ${NONE_BUDGET} s), depth 5.  us/ray: render time from --stats"
    echo "(scene and tree excluded) per ray of any kind; speed-up: none's us/ray over kd's.  kd: fastest of 3 runs; when one"
    echo "sample per pixel renders in under 0.05 s (--stats counts milliseconds), kd is timed at 'spp' samples per pixel of"
    echo "the same image.  images: kd's and none's 1-spp pictures compared byte for byte.  bytes/obj: the tree per object."
    echo
    printf '%-10s %7s %5s %8s %9s %8s %4s %9s %6s %8s %9s  %s\n' scene objects image rays "none us" "kd us" spp \
      speed-up tests "build s" bytes/obj images
  } | tee -a "$OUT/bench.txt"
  for name in $SPD_SCENES; do
    scene=$SPD_DIR/$name.nff
    if [ ! -f "$scene" ]; then
      printf '%-10s not found (%s): skipped\n' "$name" "$scene" | tee -a "$OUT/bench.txt"
      continue
    fi
    # A 16x16 probe of brute force sets the size: its cost is in proportion
    # to pixels times objects, and objects range from 4k to 270k.
    say "spd: $name: brute force at 16x16 to choose the size"
    if ! ray1 "$scene" 16x16 none "$OUT/spd-$name-none.ppm" "$OUT/spd-$name-none.log"; then
      printf '%-10s ./ray --accel none failed, see %s\n' "$name" "$OUT/spd-$name-none.log" | tee -a "$OUT/bench.txt"
      status=1
      continue
    fi
    t16=$(stat_seconds "$OUT/spd-$name-none.log")
    side=16
    for w in 96 64 48 32 24; do
      if awk "BEGIN { exit !($t16 * ($w / 16)^2 <= $NONE_BUDGET) }"; then side=$w; break; fi
    done
    size=${side}x$side
    if [ "$side" != 16 ]; then
      say "spd: $name: brute force at $size"
      ray1 "$scene" "$size" none "$OUT/spd-$name-none.ppm" "$OUT/spd-$name-none.log" || { status=1; continue; }
    fi
    say "spd: $name: kd-tree at $size"
    if ! ray_best "$scene" "$size" kd "$OUT/spd-$name-kd.ppm" "$OUT/spd-$name-kd.log"; then
      printf '%-10s ./ray --accel kd failed, see %s\n' "$name" "$OUT/spd-$name-kd.log" | tee -a "$OUT/bench.txt"
      status=1
      continue
    fi
    none_log=$OUT/spd-$name-none.log kd_log=$OUT/spd-$name-kd.log
    none_rays=$(stat_rays "$none_log") kd_rays=$(stat_rays "$kd_log")
    images=identical
    cmp -s "$OUT/spd-$name-none.ppm" "$OUT/spd-$name-kd.ppm" || { images=DIFFER; status=1; }
    [ "$none_rays" = "$kd_rays" ] || images="$images; rays differ ($none_rays none, $kd_rays kd)"
    kd_s=$rsecs spp=1
    if awk "BEGIN { exit !($kd_s < 0.05) }"; then
      spp=$(awk "BEGIN { k = int(0.1 / ($kd_s > 0.001 ? $kd_s : 0.001)) + 1; print (k > 64) ? 64 : k }")
      ray_best "$scene" "$size" kd "$OUT/spd-$name-kd-n.ppm" "$OUT/spd-$name-kd-n.log" -n "$spp" || { status=1; continue; }
      kd_s=$rsecs
      kd_rays=$(stat_rays "$OUT/spd-$name-kd-n.log")
    fi
    objects=$(stat_objects "$kd_log")
    row=$(awk -v n="$name" -v o="$objects" -v sz="$size" -v nr="$none_rays" -v ns="$(stat_seconds "$none_log")" \
      -v kr="$kd_rays" -v ks="$kd_s" -v spp="$spp" -v t="$(stat_tests "$kd_log")" -v b="$(stat_built "$kd_log")" \
      -v by="$(stat_tree_bytes "$kd_log")" -v im="$images" 'BEGIN {
        nu = ns / nr * 1e6; ku = ks / kr * 1e6
        printf "%-10s %7d %5s %8d %9.2f %8.4f %4d %8.0fx %6.2f %8.3f %9.1f  %s", n, o, sz, nr, nu, ku, spp, nu / ku, t, b, by / o, im }')
    echo "$row" | tee -a "$OUT/bench.txt"
    [ "$name" = balls_s4 ] && balls_none_us=$(awk -v s="$(stat_seconds "$none_log")" -v r="$none_rays" -v sz="$size" \
      'BEGIN { printf "%.4f %s", s / r * 1e6, sz }')
  done
  echo "(tests: hit tests per kd query; brute force tests every object.  $((SECONDS - t_part)) s)" | tee -a "$OUT/bench.txt"
  echo | tee -a "$OUT/bench.txt"
fi

# ------------------------------------------------------------ build time
if part build; then
  t_part=$SECONDS
  if [ -z "$RAYBENCH" ]; then
    echo "build time against N: bench/raybench.c did not build, skipped" | tee -a "$OUT/bench.txt"
  else
    say "build: kd-trees of 10k to $BUILD_MAX triangles"
    if "$RAYBENCH" build "$BUILD_MAX" >"$OUT/build.log" 2>&1; then
      grep -v '^result ' "$OUT/build.log" | tee -a "$OUT/bench.txt"
      p=$(rfield "$OUT/build.log" "" exponent)
      if num "$p"; then
        targets+=("build time ~ N^$p, 10k to $BUILD_MAX triangles (target: exponent <= 1.15): $(verdict "$p <= 1.15")")
      fi
      targets+=("tree size: $(rfield "$OUT/build.log" "" bytes_per_tri) bytes/triangle at $(rfield "$OUT/build.log" "" triangles) triangles (cube-sphere; no target)")
    else
      cat "$OUT/build.log" >&2
      echo "build time against N: raybench failed, see $OUT/build.log" | tee -a "$OUT/bench.txt"
      status=1
    fi
  fi
  echo "($((SECONDS - t_part)) s)" | tee -a "$OUT/bench.txt"
  echo | tee -a "$OUT/bench.txt"
fi

# ---------------------------------------------------- traversal vs Embree
# make_mesh NAME: sets $mesh_obj, and $mesh_view to the SPD scene whose
# camera the primary rays take (empty: embree_rays' default view).  Meshes
# are made once and kept in $OUT: they depend on nothing of ours.
make_mesh() {
  local name=$1 n tmp
  mesh_view='' mesh_obj=$OUT/mesh-$1.obj
  [ -s "$mesh_obj" ] && { [[ $name == sphere* ]] || mesh_view=$SPD_DIR/$name.nff; return 0; }
  command -v python3 >/dev/null || { mesh_why="python3 not installed"; return 1; }
  tmp=$mesh_obj.tmp
  case $name in
    sphere[0-9]*k | sphere[0-9]*m)
      n=${name#sphere}; n=${n%[km]}
      [[ $n =~ ^[0-9]+$ ]] || { mesh_why="not a sphereNk or sphereNm"; return 1; }
      case $name in *k) n=$((n * 1000)) ;; *) n=$((n * 1000000)) ;; esac
      [ -f "$EMBREE_DIR/tools/gen_sphere.py" ] || { mesh_why="$EMBREE_DIR/tools/gen_sphere.py not found"; return 1; }
      python3 "$EMBREE_DIR/tools/gen_sphere.py" "$n" "$tmp" 2>>"$OUT/mesh.log" || { mesh_why="gen_sphere.py failed"; return 1; } ;;
    *)
      mesh_view=$SPD_DIR/$name.nff
      # an SPD database at another size than make spd's: tools/spd makes it
      if [ ! -f "$mesh_view" ] && [ -x tools/spd ] && [[ $name =~ ^([a-z]+)_s([0-9]+)$ ]]; then
        tools/spd "${BASH_REMATCH[1]}" "${BASH_REMATCH[2]}" >"$mesh_view.tmp" 2>>"$OUT/mesh.log" \
          && mv "$mesh_view.tmp" "$mesh_view"
      fi
      [ -f "$mesh_view" ] || { mesh_why="$mesh_view not found"; return 1; }
      [ -f "$EMBREE_DIR/tools/nff2obj.py" ] || { mesh_why="$EMBREE_DIR/tools/nff2obj.py not found"; return 1; }
      python3 "$EMBREE_DIR/tools/nff2obj.py" "$mesh_view" "$tmp" 2>>"$OUT/mesh.log" || { mesh_why="nff2obj.py failed"; return 1; } ;;
  esac
  mv "$tmp" "$mesh_obj"
}

# find_embree: Embree's harness, built here as its README says (the project
# never links it), in $embree; empty, with the reason in $embree_why, when
# it cannot be had.
find_embree() {
  embree=
  if [ ! -f "$EMBREE_DIR/embree_rays.c" ]; then
    embree_why="harness not found ($EMBREE_DIR/embree_rays.c), skipped"
  else
    ecc=$(command -v gcc || echo "$CC")
    eb() { "$ecc" -O2 -march=native -fopenmp -o "$OUT/embree_rays" "$EMBREE_DIR/embree_rays.c" -lembree3 -lm >"$OUT/embree-build.log" 2>&1; }
    if [ "$OUT/embree_rays" -nt "$EMBREE_DIR/embree_rays.c" ] || eb || { install_pkg libembree-dev && eb; }; then
      embree=$OUT/embree_rays
    else
      embree_why="not installed, skipped (libembree-dev; BENCH_INSTALL=1 tries apt-get)"
    fi
  fi
}

if part rays; then
  t_part=$SECONDS
  find_embree
  {
    echo "Traversal, one thread: ray.c's nearest_hit() (tree walk, triangle test, hit point and normals) on ${RAYS_RES}x${RAYS_RES}"
    echo "primary and $RAYS_N random rays, best of 5 runs in each of 2 rounds; 'walk': kd_nearest() and then the triangle's u, v and"
    echo "unnormalised Ng, which is what rtcIntersect1 returns (triangle, t, u, v, Ng), no more and no less."
    if [ -n "$embree" ]; then
      echo "Embree: rtcIntersect1 on the very same rays (embree_rays -out; default-quality BVH), best of 5 in each of 2 rounds, alternating with ours."
      echo "ratio: walk over Embree, like for like (the target's figure); render: nearest_hit over Embree, which also computes the hit point,"
      echo "the unit shading normal and the material, work that Embree leaves to its caller."
      echo "disagree: rays whose hit differs from Embree's (triangle, or t by more than 1e-4 relative), by kind."
    else
      echo "Embree: $embree_why; the rays are made by raybench by embree_rays.c's conventions."
    fi
    echo
    printf '%-12s %9s %-8s %8s %8s %8s %6s %6s %6s %6s %7s  %s\n' mesh triangles rays "ours" "walk" "Embree" ratio \
      render steps tests repeat% "disagree"
  } | tee -a "$OUT/bench.txt"
  if [ -z "$RAYBENCH" ]; then
    echo "bench/raybench.c did not build: skipped" | tee -a "$OUT/bench.txt"
    MESHES=
  fi
  builds=()
  for mname in $MESHES; do
    mesh_why=
    if ! make_mesh "$mname"; then
      printf '%-12s cannot make the mesh (%s): skipped\n' "$mname" "$mesh_why" | tee -a "$OUT/bench.txt"
      continue
    fi
    log=$OUT/rays-$mname.log
    view=()
    [ -n "$mesh_view" ] && view=(-nffview "$mesh_view")
    emb_p='' emb_r='' emb_b=''
    # Two rounds, Embree then ours, each time: the machine's speed drifts by
    # several per cent over minutes, and alternating lets both meet the same
    # drift.  Each figure is the best of its rounds.
    rc=0
    : >"$log"
    for round in 1 2; do
      if [ -n "$embree" ]; then
        say "rays: $mname: Embree (round $round)"
        elog=$OUT/embree-$mname-$round.log
        if "$embree" "$mesh_obj" -mode both -res "$RAYS_RES" "$RAYS_RES" -nrays "$RAYS_N" -quality default \
          -threads 1 -buildthreads 1 -repeat 5 -out "$OUT/embree-$mname" ${view[@]+"${view[@]}"} >"$elog" 2>&1; then
          emb_b=$(best_of "$emb_b" "$(sed -n 's/.*BUILD quality=[^:]*: \([0-9.]*\) s.*/\1/p' "$elog" | head -n 1)" min)
          emb_p=$(best_of "$emb_p" "$(sed -n 's/.*TRACE primary .* best [0-9.]* s = \([0-9.]*\) Mrays\/s.*/\1/p' "$elog" | head -n 1)" max)
          emb_r=$(best_of "$emb_r" "$(sed -n 's/.*TRACE random .* best [0-9.]* s = \([0-9.]*\) Mrays\/s.*/\1/p' "$elog" | head -n 1)" max)
        else
          say "rays: $mname: embree_rays failed, see $elog"
        fi
      fi
      say "rays: $mname: ours (round $round)"
      if [ -n "$emb_p" ] && [ -n "$emb_r" ]; then
        sets=("embree-${mname}_primary" "embree-${mname}_random")
        "$RAYBENCH" rays "$mesh_obj" "$OUT/${sets[0]}.bin" "$OUT/${sets[1]}.bin" >>"$log" 2>&1 || rc=1
      else
        sets=(primary random)
        "$RAYBENCH" made "$mesh_obj" "$RAYS_RES" "$RAYS_RES" "$RAYS_N" ${mesh_view:+"$mesh_view"} >>"$log" 2>&1 || rc=1
      fi
    done
    if [ "$rc" != 0 ]; then
      cat "$log" >&2
      printf '%-12s raybench failed, see %s\n' "$mname" "$log" | tee -a "$OUT/bench.txt"
      status=1
      continue
    fi
    ntri=$(rfield "$log" "" objects)
    for k in 0 1; do
      set=${sets[$k]}
      kind=$([ "$k" = 0 ] && echo primary || echo random)
      emb=$([ "$k" = 0 ] && echo "$emb_p" || echo "$emb_r")
      ours=$(rfield_max "$log" "$set" mrays)
      walk=$(rfield_max "$log" "$set" bare_mrays)
      dis=$(awk -v set="$set" '$1 == "result" && $2 == "set=" set && /agree=/ {
              for (i = 3; i <= NF; i++) { split($i, kv, "="); v[kv[1]] = kv[2] }
              s = v["disagree"] " of " v["agree"] + v["disagree"] " hits"
              if (v["disagree"] > 0) {
                s = s " ("; sep = ""
                if (v["tie"]) { s = s sep v["tie"] " edge/vertex ties"; sep = ", " }
                if (v["tfloat"]) { s = s sep v["tfloat"] " float t"; sep = ", " }
                if (v["tdiff"]) { s = s sep v["tdiff"] " other t"; sep = ", " }
                if (v["ours_only"]) { s = s sep v["ours_only"] " ours only"; sep = ", " }
                if (v["embree_only"]) { s = s sep v["embree_only"] " Embree only"; sep = ", " }
                s = s ")" }
              last = s }
              END { print last }' "$log")
      printf '%-12s %9s %-8s %8.2f %8.2f %8s %6s %6s %6.1f %6.2f %7.1f  %s\n' "$mname" "$ntri" "$kind" "$ours" \
        "$walk" "$(if [ -n "$emb" ]; then printf '%.2f' "$emb"; else echo -; fi)" \
        "$(if [ -n "$emb" ]; then awk "BEGIN { printf \"%.2f\", $walk / $emb }"; else echo -; fi)" \
        "$(if [ -n "$emb" ]; then awk "BEGIN { printf \"%.2f\", $ours / $emb }"; else echo -; fi)" \
        "$(rfield "$log" "$set" steps_per_ray)" "$(rfield "$log" "$set" tests_per_ray)" \
        "$(rfield "$log" "$set" repeat_pct)" "${dis:-not compared}" | tee -a "$OUT/bench.txt"
      if [ "$mname" = sphere100k ] && [ "$kind" = primary ]; then
        if [ -n "$emb" ]; then
          r=$(awk "BEGIN { printf \"%.2f\", $walk / $emb }")
          rr=$(awk "BEGIN { printf \"%.2f\", $ours / $emb }")
          targets+=("primary rays, sphere100k, one thread: walk (triangle, t, u, v, Ng) $walk Mrays/s, Embree rtcIntersect1 $emb Mrays/s, ratio $r (target >= 0.5): $(verdict "$r >= 0.5"); with nearest_hit's hit point, normal and material $ours Mrays/s, ratio $rr")
        else
          targets+=("primary rays, sphere100k: walk $walk Mrays/s, nearest_hit $ours Mrays/s; Embree $embree_why")
        fi
      fi
    done
    eb_text="not measured"
    [ -n "$emb_b" ] && eb_text="$emb_b s (BVH, default quality, 1 thread)"
    builds+=("$(printf '%-12s build: ours %.3f s (SAH kd-tree, perfect splits), Embree %s; our tree: %.1f bytes/triangle, %.2f refs/triangle, depth %s' \
      "$mname" "$(rfield "$log" "" build_s)" "$eb_text" \
      "$(rfield "$log" "" bytes_per_obj)" "$(rfield "$log" "" refs_per_obj)" "$(rfield "$log" "" depth)")")
  done
  {
    echo "(steps, tests: tree steps and hit tests per ray; repeat%: tests of a primitive already tested by that ray, which the mailbox missed)"
    [ ${#builds[@]} -gt 0 ] && printf '%s\n' "${builds[@]}"
    echo "($((SECONDS - t_part)) s)"
    echo
  } | tee -a "$OUT/bench.txt"
fi

# ------------------------------------------- every structure, same rays
# accel_rows LOG SCENE: the table's rows from raybench accel's result lines.
accel_rows() {
  awk -v scene="$2" '
    $1 == "result" && $3 ~ /^accel=/ {
      for (i = 2; i <= NF; i++) { split($i, kv, "="); v[kv[1]] = kv[2] }
      a = v["accel"]
      if (!(a in build)) { build[a] = v["build_s"]; bytes[a] = v["bytes"]; names[++m] = a }
      if (v["build_s"] < build[a]) build[a] = v["build_s"]
      # of several runs (rounds against Embree), the one with the best median
      if (v["median"] + 0 < med[a, v["set"]]) next
      med[a, v["set"]] = v["median"] + 0
      fig[a, v["set"]] = sprintf("%6.2f %6.2f %6.2f", v["best"], v["median"], v["worst"])
      work[a, v["set"]] = sprintf("%5.1f %5.1f", v["steps"], v["tests"])
      if (v["differ"] > 0) bad[a] = bad[a] " " v["set"] ":" v["differ"] }
    END {
      for (k = 1; k <= m; k++) { a = names[k]
        printf "%-11s %-10s %8.4f %7.2f  %s  %s  %s  %s  %s\n", scene, a, build[a], bytes[a] / 1e6,
          fig[a, "primary"], fig[a, "random"], work[a, "primary"], work[a, "random"],
          (a in bad) ? "DIFFER" bad[a] : "same" } }' "$1"
}

if part accel; then
  t_part=$SECONDS
  find_embree
  ACCEL_SPD=${BENCH_ACCEL_SPD:-$SPD_SCENES}
  ACCEL_RES=${BENCH_ACCEL_RES:-512}
  ACCEL_N=${BENCH_ACCEL_N:-300000}
  {
    echo "Every structure on the same rays, one thread (bench/raybench.c accel): the loop asks one structure for the"
    echo "nearest hit and reads u, v, Ng for a triangle, as rtcIntersect1 returns.  Mrays/s by thread CPU time, best /"
    echo "median / worst of 5 rounds, the structures taking turns.  SPD scenes: ${ACCEL_RES}x${ACCEL_RES} primary rays"
    echo "from the scene's camera and $ACCEL_N random rays (origins in the scene box x1.5, uniform directions);"
    echo "sphere100k: Embree's own ${RAYS_RES}x${RAYS_RES} primary and $RAYS_N random rays.  none traces a prefix of"
    echo "the rays (about 2e7 tests).  build: CPU seconds, best of 3; -rec: the slide's recursive form of the same"
    echo "tree.  answers: every structure's (object, bitwise t) against the kd-tree's, ray by ray."
    echo
    printf '%-11s %-10s %8s %7s  %-20s  %-20s  %-11s  %-11s  %s\n' scene structure "build s" MB \
      "primary Mrays/s" "random Mrays/s" "prim st/te" "rand st/te" answers
  } | tee -a "$OUT/bench.txt"
  if [ -z "$RAYBENCH" ]; then
    echo "bench/raybench.c did not build: skipped" | tee -a "$OUT/bench.txt"
  else
    for name in $ACCEL_SPD; do
      scene=$SPD_DIR/$name.nff
      [ -f "$scene" ] || scene=scenes/spd/$name.nff
      if [ ! -f "$scene" ]; then
        printf '%-11s not found in %s or scenes/spd (make spd): skipped\n' "$name" "$SPD_DIR" | tee -a "$OUT/bench.txt"
        continue
      fi
      say "accel: $name"
      log=$OUT/accel-$name.log
      if "$RAYBENCH" accel "$scene" "$ACCEL_RES" "$ACCEL_RES" "$ACCEL_N" >"$log" 2>&1; then
        accel_rows "$log" "$name" | tee -a "$OUT/bench.txt"
      else
        printf '%-11s raybench failed, see %s\n' "$name" "$log" | tee -a "$OUT/bench.txt"
        status=1
      fi
    done
    mname=sphere100k
    if make_mesh "$mname"; then
      log=$OUT/accel-$mname.log
      : >"$log"
      emb_p='' emb_r='' emb_b='' rc=0
      for round in 1 2; do
        if [ -n "$embree" ]; then
          say "accel: $mname: Embree (round $round)"
          elog=$OUT/accel-embree-$round.log
          if "$embree" "$mesh_obj" -mode both -res "$RAYS_RES" "$RAYS_RES" -nrays "$RAYS_N" -quality default \
            -threads 1 -buildthreads 1 -repeat 5 -out "$OUT/accel-embree" >"$elog" 2>&1; then
            emb_b=$(best_of "$emb_b" "$(sed -n 's/.*BUILD quality=[^:]*: \([0-9.]*\) s.*/\1/p' "$elog" | head -n 1)" min)
            emb_p=$(best_of "$emb_p" "$(grep -A1 'TRACE primary' "$elog" | sed -n 's/.*thread CPU time: best [0-9.]* s = \([0-9.]*\) Mrays.*/\1/p' | head -n 1)" max)
            emb_r=$(best_of "$emb_r" "$(grep -A1 'TRACE random' "$elog" | sed -n 's/.*thread CPU time: best [0-9.]* s = \([0-9.]*\) Mrays.*/\1/p' | head -n 1)" max)
          fi
        fi
        say "accel: $mname: ours (round $round)"
        if [ -f "$OUT/accel-embree_primary.bin" ] && [ -f "$OUT/accel-embree_random.bin" ]; then
          "$RAYBENCH" accel "$mesh_obj" "$OUT/accel-embree_primary.bin" "$OUT/accel-embree_random.bin" >>"$log" 2>&1 || rc=1
        else
          "$RAYBENCH" accel "$mesh_obj" "$RAYS_RES" "$RAYS_RES" "$RAYS_N" >>"$log" 2>&1 || rc=1
        fi
      done
      if [ "$rc" != 0 ]; then
        printf '%-11s raybench failed, see %s\n' "$mname" "$log" | tee -a "$OUT/bench.txt"
        status=1
      else
        accel_rows "$log" "$mname" | tee -a "$OUT/bench.txt"
        if [ -n "$emb_p" ]; then
          printf '%-11s %-10s %8.4f %7s  %6.2f %-13s  %6.2f %-13s  (wall-clock build; CPU-time trace, best of 2 runs of 5)\n' \
            "$mname" Embree "$emb_b" - "$emb_p" "" "$emb_r" "" | tee -a "$OUT/bench.txt"
          best_p=$(awk '$1 == "result" && $2 == "set=primary" && $3 !~ /none|rec/ { split($5, b, "="); if (b[2] > m) m = b[2] } END { print m }' "$log")
          best_r=$(awk '$1 == "result" && $2 == "set=random" && $3 !~ /none|rec/ { split($5, b, "="); if (b[2] > m) m = b[2] } END { print m }' "$log")
          sah_b=$(awk '$1 == "result" && $3 == "accel=bvh-sah" { split($10, b, "="); print b[2]; exit }' "$log")
          rp=$(awk "BEGIN { printf \"%.2f\", $best_p / $emb_p }") rr=$(awk "BEGIN { printf \"%.2f\", $best_r / $emb_r }")
          rb=$(awk "BEGIN { printf \"%.2f\", $sah_b / $emb_b }")
          targets+=("sphere100k, one thread, CPU time: best of ours $best_p Mrays/s primary against Embree $emb_p: ${rp}x (target >= 0.8): $(verdict "$rp >= 0.8"); random $best_r against $emb_r: ${rr}x (target >= 0.5): $(verdict "$rr >= 0.5")")
          targets+=("sphere100k BVH SAH build $sah_b s (CPU) against Embree's $emb_b s (wall, one thread): ${rb}x (target <= 1.5): $(verdict "$rb <= 1.5")")
        else
          echo "(Embree: ${embree_why:-not run}; the rays were made here by its conventions)" | tee -a "$OUT/bench.txt"
        fi
      fi
    else
      printf '%-11s cannot make the mesh (%s): skipped\n' "$mname" "$mesh_why" | tee -a "$OUT/bench.txt"
    fi
  fi
  {
    echo "(st/te: steps (nodes, cells) and hit tests per ray.  $((SECONDS - t_part)) s)"
    echo
  } | tee -a "$OUT/bench.txt"
fi

# ------------------------------------------------------------- animation
if part anim; then
  t_part=$SECONDS
  echo "Which structures suit animation? (bench/raybench.c anim; CPU milliseconds per frame, one thread)" | tee -a "$OUT/bench.txt"
  if [ -z "$RAYBENCH" ]; then
    echo "bench/raybench.c did not build: skipped" | tee -a "$OUT/bench.txt"
  else
    for job in "gears_s4 60 300" "balls_s4 60 0"; do
      set -- $job
      scene=$SPD_DIR/$1.nff
      [ -f "$scene" ] || scene=scenes/spd/$1.nff
      if [ ! -f "$scene" ]; then
        echo "$1 not found: skipped" | tee -a "$OUT/bench.txt"
        continue
      fi
      say "anim: $1"
      if "$RAYBENCH" anim "$scene" "$2" "$3" >"$OUT/anim-$1.log" 2>&1; then
        grep -v '^result ' "$OUT/anim-$1.log" | tee -a "$OUT/bench.txt"
      else
        echo "$1: raybench anim failed, see $OUT/anim-$1.log" | tee -a "$OUT/bench.txt"
        status=1
      fi
    done
  fi
  echo "($((SECONDS - t_part)) s)" | tee -a "$OUT/bench.txt"
  echo | tee -a "$OUT/bench.txt"
fi

# ---------------------------------------------- balls and POV-Ray, 512x512
# pov1 POV OUTPUT LOG: one POV-Ray 3.7 run as ../shared/spd/README.md says
# (512x512, one worker thread, no anti-aliasing, 3.1 syntax); wall in $took.
pov1() {
  { time povray -D -A +FP +W512 +H512 +WT1 "+I$1" "+O$2" +MV3.1 >"$3" 2>&1; } 2>"$OUT/time.txt" || return 1
  took=$(tail -n 1 "$OUT/time.txt")
}
pov_trace() { sed -n 's/.*Trace Time:.*(\([0-9.]*\) seconds).*/\1/p' "$1" | head -n 1; }

if part pov; then
  t_part=$SECONDS
  povray_ok=
  if command -v povray >/dev/null || { install_pkg povray && command -v povray >/dev/null; }; then povray_ok=1; fi
  {
    echo "SPD scenes at 512x512, depth 5, one thread: ./ray -t 1 against POV-Ray 3.7 (povray +WT1 -A +MV3.1) on the same"
    echo "geometry, camera and lights (../shared/spd/pov).  wall: the whole run, scene to image, fastest of 3 under 2 s;"
    echo "render: ours from --stats, POV-Ray's 'Trace Time'.  x wall, x render: POV-Ray's time over ours (above 1: ours is"
    echo "faster).  rays: ours of every kind; POV-Ray's rays plus its shadow ray tests."
    echo
    printf '%-11s %-11s %8s %8s %8s %8s %7s %8s %9s %9s\n' pov nff "ours s" render "POV s" trace "x wall" "x render" \
      "our rays" "POV rays"
  } | tee -a "$OUT/bench.txt"
  for pair in balls:balls_s4 rings:rings_s7 tree:tree_s11 teapot_s12:teapot_s12; do
    pov=${pair%%:*} nff=${pair#*:}
    scene=$SPD_DIR/$nff.nff
    [ -f "$scene" ] || { printf '%-11s %s not found: skipped\n' "$pov" "$scene" | tee -a "$OUT/bench.txt"; continue; }
    say "pov: $nff: ours at 512x512"
    if ! ray_best "$scene" 512x512 kd "$OUT/pov-ours-$nff.ppm" "$OUT/pov-ours-$nff.log"; then
      printf '%-11s ./ray failed on %s\n' "$pov" "$scene" | tee -a "$OUT/bench.txt"
      status=1
      continue
    fi
    ours_w=$took ours_r=$rsecs ours_rays=$(stat_rays "$OUT/pov-ours-$nff.log")
    if [ "$nff" = balls_s4 ] && [ "${BENCH_BALLS_NONE_FULL:-1}" = 1 ]; then
      # The target is stated for 512x512, so brute force renders the same
      # 512x512 image, once (about 35 s on the 2-core machine); the speed-up
      # is the ratio of the two render times, and the images must be equal.
      say "pov: balls_s4: brute force at 512x512 (about half a minute)"
      if ray1 "$scene" 512x512 none "$OUT/pov-none-balls.ppm" "$OUT/pov-none-balls.log"; then
        none_r=$(stat_seconds "$OUT/pov-none-balls.log")
        same=identical
        cmp -s "$OUT/pov-none-balls.ppm" "$OUT/pov-ours-$nff.ppm" || { same=DIFFER; status=1; }
        sp=$(awk "BEGIN { printf \"%.0f\", $none_r / $ours_r }")
        targets+=("balls_s4 512x512, one thread: render kd $ours_r s, --accel none $none_r s (images $same), speed-up ${sp}x (target >= 100x): $(verdict "$sp >= 100")")
      fi
    elif [ "$nff" = balls_s4 ] && [ -n "$balls_none_us" ]; then
      # BENCH_BALLS_NONE_FULL=0: brute force's time per ray at the spd section's
      # size stands for the 512x512 render.
      read -r none_us none_size <<<"$balls_none_us"
      ku=$(awk "BEGIN { printf \"%.4f\", $ours_r / $ours_rays * 1e6 }")
      sp=$(awk "BEGIN { printf \"%.0f\", $none_us / $ku }")
      targets+=("balls_s4 512x512, one thread: kd ${ku} us/ray, --accel none $none_us us/ray (measured at $none_size: time per ray), speed-up ${sp}x (target >= 100x): $(verdict "$sp >= 100")")
    fi
    pov_w=- pov_t=- pov_rays=-
    if [ -z "$povray_ok" ]; then
      pov_w="POV-Ray not installed, skipped"
    elif [ ! -f "$POV_DIR/$pov.pov" ]; then
      pov_w="$POV_DIR/$pov.pov not found, skipped"
    else
      say "pov: $pov: POV-Ray"
      src=$(cd "$POV_DIR" && pwd)/$pov.pov
      if pov1 "$src" "$PWD/$OUT/pov-$pov.ppm" "$OUT/pov-$pov.log"; then
        pov_w=$took pov_t=$(pov_trace "$OUT/pov-$pov.log")
        if awk "BEGIN { exit !($took < 2) }"; then
          for _ in 1 2; do
            pov1 "$src" "$PWD/$OUT/pov-$pov.ppm" "$OUT/pov-$pov.log" || break
            pov_w=$(awk "BEGIN { print ($took < $pov_w) ? $took : $pov_w }")
            t=$(pov_trace "$OUT/pov-$pov.log")
            num "$t" && num "$pov_t" && pov_t=$(awk "BEGIN { print ($t < $pov_t) ? $t : $pov_t }")
          done
        fi
        pov_rays=$(awk '/^Rays:/ { r = $2 } /^Shadow Ray Tests:/ { s = $4 } END { if (r != "") print r + s }' "$OUT/pov-$pov.log")
      else
        pov_w="POV-Ray failed, see $OUT/pov-$pov.log"
      fi
    fi
    if num "$pov_w"; then
      rt=-
      if num "$pov_t"; then rt=$(awk "BEGIN { printf \"%.2f\", $pov_t / $ours_r }"); fi
      printf '%-11s %-11s %8.3f %8.3f %8.3f %8s %7.2f %8s %9s %9s\n' "$pov" "$nff" "$ours_w" "$ours_r" "$pov_w" "${pov_t:--}" \
        "$(awk "BEGIN { print $pov_w / $ours_w }")" "$rt" "$ours_rays" "${pov_rays:--}" | tee -a "$OUT/bench.txt"
      if [ "$nff" = balls_s4 ]; then
        targets+=("balls_s4 512x512, one thread: ours $ours_w s, POV-Ray 3.7 $pov_w s, wall clock (render $ours_r s against trace ${pov_t:-?} s) (target: faster than POV-Ray): $(verdict "$ours_w < $pov_w")")
      fi
    else
      printf '%-11s %-11s %8.3f %8.3f  %s\n' "$pov" "$nff" "$ours_w" "$ours_r" "$pov_w" | tee -a "$OUT/bench.txt"
      if [ "$nff" = balls_s4 ]; then targets+=("balls_s4 512x512, one thread: ours $ours_w s; POV-Ray: $pov_w"); fi
    fi
  done
  echo "($((SECONDS - t_part)) s)" | tee -a "$OUT/bench.txt"
  echo | tee -a "$OUT/bench.txt"
fi

# ------------------------------------------------------------ path tracing
if part pt; then
  t_part=$SECONDS
  if CC="$CC" CFLAGS="$CFLAGS" bash bench/pt.sh; then
    cat "$OUT/pt.txt" >>"$OUT/bench.txt"
    while IFS= read -r line; do targets+=("$line"); done <"$OUT/pt-targets.txt"
  else
    echo "the path-tracing section failed" | tee -a "$OUT/bench.txt"
    status=1
  fi
  echo "($((SECONDS - t_part)) s)" | tee -a "$OUT/bench.txt"
fi

# ---------------------------------------------------------------- targets
if [ ${#targets[@]} -gt 0 ]; then
  {
    echo "Targets"
    printf '  %s\n' "${targets[@]}"
    echo
  } | tee -a "$OUT/bench.txt"
fi
echo "tables in $OUT/bench.txt$(part render && echo ", plot in $OUT/bench.svg") ($((SECONDS - t_start)) s)"
[ "$status" = 0 ] || echo "bench/run.sh: a section failed (above)" >&2
exit "$status"
