#!/usr/bin/env bash
# bench/dist.sh: the distribution effects' time against error (make bench,
# part "dist"; also runs alone: bash bench/dist.sh).
#
# For each effect's scene (dof: the lens; soft: an area light; glossy:
# glossy plates; motion: motion blur) and each renderer (Whitted's, and the path tracer with
# MIS): a reference by that renderer at BENCH_DIST_REF_SPP samples (seed 99,
# every core; kept in bench/out while ./ray and the scene are unchanged),
# then runs at each of BENCH_DIST_SPP samples per pixel on one thread, the
# two renderers taking turns in BENCH_DIST_ROUNDS rounds; each run's CPU
# time (user + system, the median of the rounds, with the least and the
# greatest) against its RMSE on linear values (bench/pfmerr.c) against its
# own renderer's reference.  The fitted slope of log RMSE against log time
# is printed per scene and renderer: -0.5 where the error is noise alone.
# Plotted, log-log, to bench/out/dist.svg.
#
# Knobs: BENCH_DIST_REF_SPP (1024), BENCH_DIST_SPP ("1 4 16 64"),
#        BENCH_DIST_SCENES ("dof:160x80 soft:160x120 glossy:160x80 motion:160x120"),
#        BENCH_DIST_ROUNDS (BENCH_ROUNDS, else 3).
set -u -o pipefail
export LC_ALL=C
cd "$(dirname "$0")/.." || exit 2

REF_SPP=${BENCH_DIST_REF_SPP:-1024}
SPPS=${BENCH_DIST_SPP:-1 4 16 64}
SCENES=${BENCH_DIST_SCENES:-dof:160x80 soft:160x120 glossy:160x80 motion:160x120}
ROUNDS=${BENCH_DIST_ROUNDS:-${BENCH_ROUNDS:-3}}
LOG=dist
. bench/lib.sh
build_time_tools || die "cannot build ray, pfmerr, svgplot or table"
RAY=$OUT/ray_pt

# The renderers by name, as the table calls them, and their options.
flags() { [ "$1" = whitted ] && echo --whitted || echo --pt --estimator mis; }

# reference NAME SIZE RENDERER: that renderer at $REF_SPP spp, seed 99 (the
# runs use seed 0: a reference sharing their numbers would share their noise).
reference() {
  local name=$1 size=$2 who=$3 key
  key="$(cksum <"$RAY") $(cksum <"scenes/$name.sph") $size $REF_SPP"
  ref=$OUT/dist-$name-$who-ref.pfm
  if [ -f "$ref" ] && [ "$(cat "$ref.key" 2>/dev/null)" = "$key" ]; then
    say "dist: $name $who: reference unchanged since the last run, reused"
    return
  fi
  say "dist: $name $who: reference at $REF_SPP spp on every core ..."
  # shellcheck disable=SC2046 # flags gives several words
  "$RAY" $(flags "$who") --seed 99 -s "$size" -n "$REF_SPP" -o "$ref" "scenes/$name.sph" 2>"$OUT/dist.err" ||
    { cat "$OUT/dist.err" >&2; die "the reference failed"; }
  printf '%s\n' "$key" >"$ref.key"
}

: >"$OUT/dist.tsv"
{
  echo "Distribution effects: time against error, one thread; cpu s: CPU seconds (user + system) of the whole"
  echo "run, the median of $ROUNDS rounds in which the renderers take turns, and (least-greatest);"
  echo "RMSE: linear values against the same renderer's ${REF_SPP}-spp reference (another seed), every pixel"
  echo "and channel; display: 8-bit sRGB levels"
  echo
  printf '%-8s %-8s %-8s %5s %8s %-15s %10s %8s\n' scene size renderer spp "cpu s" "(range)" RMSE display
} | tee "$OUT/dist.txt"
for item in $SCENES; do
  name=${item%%:*} size=${item#*:}
  [ -f "scenes/$name.sph" ] || die "scenes/$name.sph not found"
  for who in whitted mis; do reference "$name" "$size" "$who"; done
  for spp in $SPPS; do
    declare -A times=()
    for ((round = 1; round <= ROUNDS; round++)); do
      for who in whitted mis; do
        # shellcheck disable=SC2046
        cpu "$RAY" $(flags "$who") -t 1 -s "$size" -n "$spp" -o "$OUT/dist-$name-$who-$spp.pfm" "scenes/$name.sph" ||
          die "failed: $name $who $spp"
        times[$who]+="$cpu "
      done
    done
    for who in whitted mis; do
      record "$OUT/dist.tsv" "$name" "$size" "$who" "$spp" "$OUT/dist-$name-$who-$spp.pfm" \
        "$OUT/dist-$name-$who-ref.pfm" "${times[$who]}"
      printf '%-8s %-8s %-8s %5s %8.3f %-15s %10.5f %8.2f\n' "$name" "$size" "$who" "$spp" "$med" \
        "($(printf '%.3f-%.3f' "$lo" "$hi"))" "$rmse" "$disp" | tee -a "$OUT/dist.txt"
    done
    unset times
  done
done

fit_and_plot dist "make bench: distribution effects, time against error (labels: samples per pixel)" \
  "RMSE (linear) against the renderer's $REF_SPP-spp reference" || die "svgplot failed"
