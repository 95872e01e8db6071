#!/usr/bin/env bash
# bench/skips.sh: every skip and sampler at equal error (make bench, part
# "skips"; also runs alone: bash bench/skips.sh).
#
# One row per skip (or sampler) and scene: the setting with it, at one
# sample count, against the setting without it at a ladder of sample
# counts.  Each run's error is its lit RMSE (bench/pfmerr.c: linear
# values, the pixels where the reference stays below 1, so that the
# lamps' edges, noisy for every setting alike, do not drown the rest)
# against one reference of the scene: the default at many samples, another
# seed (the path tracer's; Whitted's samples are a fixed pattern).  The
# time at equal error is "with"'s CPU time against the time at which
# "without" reaches "with"'s RMSE, by log-log interpolation between the
# two runs of its ladder that bracket it (bench/table.c time-at; "<T"
# when its cheapest run is already below).  Every run is on one thread;
# its CPU time (user + system) is the median of BENCH_ROUNDS rounds in
# which all the row's runs take turns, printed with the least and the
# greatest.  The runs go to bench/out/skips.tsv and the log-log plot of
# time against error, one line a setting, to bench/out/skips.svg.
#
# A row: LABEL|SCENE|SIZE|WITH|WITHOUT|LADDER, WITH and WITHOUT ./ray's
# options (WITHOUT gets -n N for each N of LADDER).  Knobs:
# BENCH_SKIPS (the rows, one a line), BENCH_SKIPS_REF_SPP (path tracer,
# 2048), BENCH_SKIPS_WHITTED_REF_SPP (256), BENCH_ROUNDS (3).
set -u -o pipefail
export LC_ALL=C
cd "$(dirname "$0")/.." || exit 2

ROUNDS=${BENCH_ROUNDS:-3}
REF_SPP=${BENCH_SKIPS_REF_SPP:-2048}
WREF_SPP=${BENCH_SKIPS_WHITTED_REF_SPP:-256}
ROWS=${BENCH_SKIPS:-"every Whitted skip (--no-skip)|scenes/whitted.sph|320x240|-n 4|--no-skip|4 8
every Whitted skip (--no-skip)|scenes/spd/mount_s6.nff|256x256|-n 1|--no-skip|1 2
Whitted adaptive AA|scenes/whitted.sph|320x240|-n 64 --adaptive 2||4 8 16 32 64
light tree (--light-choice)|scenes/lights100.sph|320x240|-n 16|--light-choice power|16 32 64 128 256
Sobol' samples (--sampler)|scenes/cornell.sph|128x128|-n 64 --sampler sobol|--sampler independent|64 128 256
Russian roulette|scenes/cornell.sph|128x128|-d 16 -n 64|-d 16 --no-roulette|32 64 128 256
path tracer adaptive|scenes/cornell.sph|128x128|-n 256 --adaptive 4||64 128 256
the lamp in its cap, the loop (--no-skip)|scenes/smallpt.sph|128x96|-n 64|--no-skip|64 128 256 512"}
LOG=skips
. bench/lib.sh
build_time_tools || die "cannot build ray, pfmerr, svgplot or table"
RAY=$OUT/ray_pt

# reference SCENE SIZE: the scene's default at many samples (kept while
# ./ray and the scene are unchanged); its file into $ref.
reference() {
  local scene=$1 size=$2 key n=$REF_SPP
  "$RAY" --stats=kv -s 8x8 -o "$OUT/skips-probe.pfm" "$scene" 2>"$OUT/skips.kv" || die "$scene does not render"
  [ "$(kv "$OUT/skips.kv" renderer 2>/dev/null)" = path ] || n=$WREF_SPP
  ref=$OUT/skips-ref-$(basename "$scene" | tr . _)-$size.pfm
  key="$(cksum <"$RAY") $(cksum <"$scene") $size $n"
  if [ -f "$ref" ] && [ "$(cat "$ref.key" 2>/dev/null)" = "$key" ]; then return; fi
  say "skips: $scene: reference, $n samples a pixel on every core ..."
  "$RAY" --seed 99 -s "$size" -n "$n" -o "$ref" "$scene" 2>"$OUT/skips.err" || { cat "$OUT/skips.err" >&2; die "the reference failed"; }
  printf '%s\n' "$key" >"$ref.key"
}

# row TSV KEY KIND SPP IMAGE "TIMES": one run's line of skips.tsv, in
# bench/lib.sh's record() layout but with the lit RMSE in the RMSE column
# (time-at reads that one); med and lit stay set.
row() {
  local rmse disp lo hi
  read -r rmse lit disp <<<"$("$OUT/pfmerr" "$5" "$ref" | sed 's/rmse=\([^ ]*\) lit_rmse=\([^ ]*\) display_rmse=\([^ ]*\).*/\1 \2 \3/')"
  # shellcheck disable=SC2086
  read -r lo med hi <<<"$(spread $6)"
  printf '%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\n' "$2" "$size" "$3" "$4" "$med" "$lit" "$rmse" "$disp" "$lo" "$hi" \
    "$(printf '%s' "${6% }" | tr ' ' ,)" >>"$1"
}

: >"$OUT/skips.tsv"
{
  echo "Every skip and sampler at equal error, one thread; cpu s: CPU seconds (user + system), the median of $ROUNDS"
  echo "rounds in which the row's runs take turns; RMSE: linear, the pixels below 1 in the reference (the default"
  echo "at $REF_SPP samples, Whitted's at $WREF_SPP); without: its time at with's RMSE, by log-log interpolation"
  echo "between the bracketing runs of its ladder of sample counts"
  echo
  printf '%-31s %-20s %-8s %-28s %9s %8s %10s %8s %7s\n' skip scene size with RMSE "cpu s" "without:" "cpu s" ratio
} | tee "$OUT/skips.txt"
k=0
while IFS='|' read -r label scene size with without ladder; do
  [ -n "$label" ] || continue
  k=$((k + 1))
  if [ ! -f "$scene" ]; then
    printf '%-31s %-20s (skipped: %s not found; make spd writes the SPD scenes)\n' "$label" "$(basename "$scene")" "$scene" | tee -a "$OUT/skips.txt"
    continue
  fi
  reference "$scene" "$size"
  declare -A times=()
  for ((round = 1; round <= ROUNDS; round++)); do
    # shellcheck disable=SC2086 # a setting is several words
    cpu "$RAY" -t 1 -s "$size" $with -o "$OUT/skips-$k-with.pfm" "$scene" || die "failed: $scene $with"
    times[with]+="$cpu "
    for n in $ladder; do
      # shellcheck disable=SC2086
      cpu "$RAY" -t 1 -s "$size" $without -n "$n" -o "$OUT/skips-$k-$n.pfm" "$scene" || die "failed: $scene $without -n $n"
      times[$n]+="$cpu "
    done
  done
  row "$OUT/skips.tsv" "$k" with "$(sed -n 's/.*-n \([0-9]*\).*/\1/p' <<<"$with")" "$OUT/skips-$k-with.pfm" "${times[with]}"
  t_with=$med e_with=$lit
  for n in $ladder; do row "$OUT/skips.tsv" "$k" without "$n" "$OUT/skips-$k-$n.pfm" "${times[$n]}"; done
  t_wo=$(table time-at "$OUT/skips.tsv" "$k" without "$e_with" 0)
  if [ -z "$t_wo" ]; then r="(not reached)"
  elif [ "${t_wo#<}" != "$t_wo" ]; then r="<$(ratio %.2f "$t_with" "${t_wo#<}")"
  else r=$(ratio %.2f "$t_with" "$t_wo"); fi
  printf '%-31s %-20s %-8s %-28s %9.5f %8.3f %10s %8s %7s\n' "$label" "$(basename "$scene")" "$size" "$with" "$e_with" "$t_with" \
    "$without" "${t_wo:--}" "$r" | tee -a "$OUT/skips.txt"
  unset times
done <<<"$ROWS"
echo "(ratio: with's time over without's at the same RMSE; under 1, the skip pays)" | tee -a "$OUT/skips.txt"

# the plot: each row's with and without, time against error
[ -s "$OUT/skips.tsv" ] || exit 0                # every row skipped: nothing to plot
sed 's/^\([0-9]*\)\t/row\1\t/' "$OUT/skips.tsv" >"$OUT/skips-plot.tsv"
table pt-plot "$OUT/skips-plot.tsv" |
  "$OUT/svgplot" --title "make bench: every skip at equal error (row/with, row/without; labels: samples per pixel)" \
    --xlabel "CPU seconds, one thread (median of the rounds)" --ylabel "lit RMSE (linear) against the reference" \
    >"$OUT/skips.svg" || die "svgplot failed"
