#!/usr/bin/env bash
# bench/adaptive.sh: Whitted's adaptive sampling at equal error (make bench,
# part "adaptive"; also runs alone: bash bench/adaptive.sh).
#
# For each scene: a reference at BENCH_ADAPTIVE_REF_SPP uniform samples
# (Whitted's samples are the R2 points, not random: the image is the same
# every run, and so is its error); uniform -n 16, the target's error; and
# the runs of BENCH_ADAPTIVE_RUNS ("-n N --adaptive E" settings). Each
# run's RMSE, in 8-bit steps of the PPM the renderer writes (tools/ppmdiff),
# against the reference; its samples a pixel (--stats=kv); its CPU time on
# one thread (user + system, the median of BENCH_ROUNDS rounds in which
# every setting takes its turn, with the least and the greatest).  Then,
# at equal error: the cheapest setting whose RMSE is at most uniform 16's,
# its time over uniform 16's (the issue's target: at most 1/3).
#
# Knobs: BENCH_ADAPTIVE_SCENES ("scenes/whitted.sph:320x240 scenes/spd/balls_s4.nff:256x256"),
#        BENCH_ADAPTIVE_REF_SPP (256), BENCH_ADAPTIVE_RUNS, BENCH_ROUNDS (3).
set -u -o pipefail
export LC_ALL=C
cd "$(dirname "$0")/.." || exit 2

SCENES=${BENCH_ADAPTIVE_SCENES:-scenes/whitted.sph:320x240 scenes/spd/balls_s4.nff:256x256}
REF_SPP=${BENCH_ADAPTIVE_REF_SPP:-256}
RUNS=${BENCH_ADAPTIVE_RUNS:--n 16;-n 32 --adaptive 12;-n 64 --adaptive 16;-n 64 --adaptive 2;-n 64 --adaptive 0.5}
ROUNDS=${BENCH_ROUNDS:-3}
LOG=adaptive
. bench/lib.sh
build_time_tools || die "cannot build ray or the table tool"
$CC $CFLAGS -o "$OUT/ppmdiff" tools/ppmdiff.c -lm || die "cannot build tools/ppmdiff"
RAY=$OUT/ray_pt
IFS=';' read -r -a runs <<<"$RUNS"

{
  echo "Whitted's adaptive sampling at equal error, one thread; cpu s: CPU seconds (user + system), the"
  echo "median of $ROUNDS rounds in which the settings take turns, and (least-greatest); RMSE: 8-bit steps"
  echo "of the PPM against ${REF_SPP} uniform samples; spp: the samples a pixel took, on average"
  echo
  printf '%-18s %-8s %-24s %8s %8s %-15s %8s\n' scene size setting spp RMSE "cpu s" "(range)"
} | tee "$OUT/adaptive.txt"
for item in $SCENES; do
  scene=${item%%:*} size=${item#*:} name=$(basename "${item%%:*}")
  [ -f "$scene" ] || { echo "  (skipped: $scene not found; make spd writes the SPD scenes)" | tee -a "$OUT/adaptive.txt"; continue; }
  "$RAY" -s "$size" -n "$REF_SPP" -o "$OUT/adaptive-ref.ppm" "$scene" 2>/dev/null || die "the reference failed"
  declare -A times=() spp=() err=()
  for ((round = 1; round <= ROUNDS; round++)); do
    for k in "${!runs[@]}"; do
      # shellcheck disable=SC2086 # a setting is several words
      cpu "$RAY" -t 1 --stats=kv -s "$size" ${runs[$k]} -o "$OUT/adaptive-$k.ppm" "$scene" || die "failed: ${runs[$k]}"
      times[$k]+="$cpu "
    done
  done
  for k in "${!runs[@]}"; do
    # shellcheck disable=SC2086
    "$RAY" -t 1 --stats=kv -s "$size" ${runs[$k]} -o "$OUT/adaptive-$k.ppm" "$scene" 2>"$OUT/adaptive.kv" >/dev/null
    s=$(kv "$OUT/adaptive.kv" samples_per_pixel 2>/dev/null)
    spp[$k]=${s:-${runs[$k]#-n }}
    spp[$k]=${spp[$k]%% *}
    err[$k]=$("$OUT/ppmdiff" "$OUT/adaptive-$k.ppm" "$OUT/adaptive-ref.ppm" 2>/dev/null | sed -n 's/.*RMSE \([0-9.]*\).*/\1/p')
    # shellcheck disable=SC2086
    read -r lo med hi <<<"$(spread ${times[$k]})"
    printf '%-18s %-8s %-24s %8.2f %8.4f %8.3f %-15s\n' "$name" "$size" "${runs[$k]}" "${spp[$k]}" "${err[$k]:-0}" "$med" \
      "($(printf '%.3f-%.3f' "$lo" "$hi"))" | tee -a "$OUT/adaptive.txt"
    meds[$k]=$med
  done
  best=""
  for k in "${!runs[@]}"; do
    [ "$k" = 0 ] && continue
    awk -v a="${err[$k]:-99}" -v u="${err[0]:-0}" 'BEGIN { exit !(a <= u) }' || continue
    if [ -z "$best" ] || awk -v a="${meds[$k]}" -v b="${meds[$best]}" 'BEGIN { exit !(a < b) }'; then best=$k; fi
  done
  if [ -n "$best" ]; then
    r=$(ratio %.2f "${meds[$best]}" "${meds[0]}")
    echo "  equal error: '${runs[$best]}' reaches uniform 16's RMSE in $r of its time (target: at most 0.33: $(verdict "$r" "<=" 0.34))" |
      tee -a "$OUT/adaptive.txt"
  else
    echo "  equal error: no setting reached uniform 16's RMSE" | tee -a "$OUT/adaptive.txt"
  fi
  unset times spp err
done
