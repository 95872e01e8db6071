#!/usr/bin/env bash
# bench/threads.sh: one thread against two (make bench, part "threads";
# also runs alone: bash bench/threads.sh).
#
# Each scene is rendered with -t 1 and -t 2 taking turns, BENCH_ROUNDS
# rounds (at least 5).  ./ray --stats=kv gives the render's wall-clock
# seconds (render_s) and its CPU seconds over every thread (cpu_s); from
# them, per round:
#
#   speed-up   render_s at one thread over render_s at two (the target: 1.9)
#   busy       cpu_s at two over twice its render_s: the share of the two
#              threads' time in which both computed.  Below 1: a thread
#              waited (rows handed out unevenly, the serial parts before
#              and after the render, a critical section)
#   per-ray    cpu_s at two over cpu_s at one: the CPU time the same rays
#              took on two threads, against one.  Above 1: each thread ran
#              slower for the other's company (shared caches and memory,
#              false sharing; on a virtual machine, other guests too)
#
# so that speed-up = 2 busy / per-ray, give or take the serial start-up: a
# speed-up short of 2 is put down to waiting or to running slower, which
# need different fixes (the code's, or an idler machine).  Medians of the
# rounds, with the least and the greatest.
#
# Knobs: BENCH_THREADS_SCENES ("scene:size:args;..."), BENCH_ROUNDS.
set -u -o pipefail
export LC_ALL=C
cd "$(dirname "$0")/.." || exit 2

SCENES=${BENCH_THREADS_SCENES:-scenes/spd/balls_s4.nff:512x512:-n 4;scenes/spd/teapot_s6.nff:512x512:-n 4;scenes/cornell.sph:256x256:--pt -n 16;scenes/smallpt.sph:256x192:--pt -n 16}
ROUNDS=${BENCH_ROUNDS:-5}
[ "$ROUNDS" -ge 5 ] 2>/dev/null || ROUNDS=5
. bench/lib.sh
build_time_tools || die "cannot build ray or the table tool"
RAY=$OUT/ray_pt
if ! echo 'int main(void){return 0;}' | $CC -fopenmp -x c - -o /dev/null 2>/dev/null; then
  { echo "One thread against two: $CC has no OpenMP here, so ray runs one thread: skipped"; echo; } | tee "$OUT/threads.txt"
  exit 0
fi
[ "$(getconf _NPROCESSORS_ONLN 2>/dev/null || echo 1)" -ge 2 ] || {
  { echo "One thread against two: this machine has one processor: skipped"; echo; } | tee "$OUT/threads.txt"
  exit 0
}
IFS=';' read -r -a scenes <<<"$SCENES"

{
  echo "One thread against two (./ray -t 1 and -t 2 taking turns, $ROUNDS rounds; medians and (least-greatest)):"
  echo "speed-up: wall clock of the render, one thread over two; busy: CPU seconds at two threads over twice their"
  echo "wall clock (1: neither thread waited); per-ray: CPU seconds at two threads over those at one (1: neither"
  echo "thread ran slower for the other's company).  speed-up = 2 busy / per-ray."
  echo
  printf '%-24s %-9s %-22s %-22s %-22s %s\n' scene size speed-up busy per-ray "target 1.9"
} | tee "$OUT/threads.txt"

# run1 T SCENE SIZE ARGS...: one render on T threads; its render_s and cpu_s to $w and $c.
run1() {
  local t=$1 scene=$2 size=$3
  shift 3
  # shellcheck disable=SC2068
  "$RAY" -t "$t" --stats=kv -s "$size" -o "$OUT/threads.ppm" $@ "$scene" 2>"$OUT/threads.err" >/dev/null ||
    die "ray failed on $scene: $(head -c 300 "$OUT/threads.err")"
  w=$(kv "$OUT/threads.err" render_s)
  c=$(kv "$OUT/threads.err" cpu_s)
}

for spec in "${scenes[@]}"; do
  IFS=: read -r scene size args <<<"$spec"
  [ -f "$scene" ] || { printf '%-24s not found (make spd writes the SPD scenes): skipped\n' "$scene" | tee -a "$OUT/threads.txt"; continue; }
  speed='' busy='' perray=''
  for ((round = 1; round <= ROUNDS; round++)); do
    say "threads: $scene, round $round"
    # shellcheck disable=SC2086
    run1 1 "$scene" "$size" $args; w1=$w c1=$c
    # shellcheck disable=SC2086
    run1 2 "$scene" "$size" $args; w2=$w c2=$c
    speed+="$(ratio %.3f "$w1" "$w2") "
    busy+="$(awk -v c="$c2" -v w="$w2" 'BEGIN { printf "%.3f", c / (2 * w) }') "
    perray+="$(ratio %.3f "$c2" "$c1") "
  done
  # shellcheck disable=SC2086
  s=$(printf %.2f "$(median $speed)") b=$(printf %.2f "$(median $busy)") p=$(printf %.2f "$(median $perray)")
  # shellcheck disable=SC2086
  printf '%-24s %-9s %-22s %-22s %-22s %s\n' "$(basename "$scene")" "$size" "$s ($(range %.2f $speed))" \
    "$b ($(range %.2f $busy))" "$p ($(range %.2f $perray))" "$(verdict "$s" ">=" 1.9)" | tee -a "$OUT/threads.txt"
done
echo | tee -a "$OUT/threads.txt"
