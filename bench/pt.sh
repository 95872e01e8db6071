#!/usr/bin/env bash
# bench/pt.sh: the path tracer's time against error (make bench, part "pt";
# also runs alone: bash bench/pt.sh).
#
# For the Cornell box and smallpt's scene: a reference rendered at many
# samples (MIS, another seed, every core; kept in bench/out between runs
# while ./ray and the scene are unchanged), then each estimator (bsdf, nee,
# mis) at 1, 4, 16, 64 and 256 samples per pixel on one thread, each run's
# CPU time (user + system, of the whole process) against its RMSE on
# linear values (bench/pfmerr.c).  The fitted slope of log RMSE against
# log time is printed per estimator: -0.5 for an unbiased estimator whose
# error is noise.  Plotted, log-log, to bench/out/pt.svg.
#
# Targets, each printed with its figures:
#   - Cornell box: MIS reaches the RMSE of BSDF sampling at 256 spp in at
#     most 1/10 of its time (MIS's time at that RMSE by log-log
#     interpolation between its two bracketing runs);
#   - smallpt's scene: our BSDF-only estimator costs no more CPU per sample
#     than smallpt (Beason 2008) built with g++ -O3, one thread, 1024x768 at
#     4 samples a pixel both; smallpt is not part of this project: set
#     BENCH_SMALLPT=path/to/smallpt.cpp (the 99-line original) to run it;
#   - rays per second of the path tracer (MIS) within 10% of the Whitted
#     renderer's on the same scene (smallpt's), one thread.
#
# Knobs: BENCH_PT_REF_SPP (4096), BENCH_PT_SPP ("1 4 16 64 256"),
#        BENCH_PT_SCENES ("cornell:128x128 smallpt:128x96"), BENCH_SMALLPT.
set -u -o pipefail
export LC_ALL=C
cd "$(dirname "$0")/.." || exit 2

CC=${CC:-cc}
CFLAGS=${CFLAGS:--O2}
OUT=bench/out
REF_SPP=${BENCH_PT_REF_SPP:-4096}
SPPS=${BENCH_PT_SPP:-1 4 16 64 256}
SCENES=${BENCH_PT_SCENES:-cornell:128x128 smallpt:128x96}
SMALLPT=${BENCH_SMALLPT:-}
mkdir -p "$OUT"
die() { echo "bench/pt.sh: $*" >&2; exit 1; }
say() { echo "bench: $*" >&2; }

OMP=$(echo 'int main(void){return 0;}' | $CC -fopenmp -x c - -o /dev/null 2>/dev/null && echo -fopenmp)
# shellcheck disable=SC2086
$CC $CFLAGS $OMP -o "$OUT/ray_pt" ray.c kdtree.c bvh.c grid.c -lm || die "cannot build ray"
# shellcheck disable=SC2086
$CC $CFLAGS -o "$OUT/pfmerr" bench/pfmerr.c -lm || die "cannot build pfmerr"
# shellcheck disable=SC2086
$CC $CFLAGS -o "$OUT/svgplot" bench/svgplot.c -lm || die "cannot build svgplot"
RAY=$OUT/ray_pt

# cpu CMD...: runs CMD; its CPU seconds (user + system) go to $cpu.
cpu() {
  local TIMEFORMAT='%3U %3S' t
  { time "$@" >/dev/null 2>"$OUT/pt.err"; } 2>"$OUT/pt.time" || { cat "$OUT/pt.err" >&2; return 1; }
  t=$(tail -n 1 "$OUT/pt.time")
  cpu=$(awk -v t="$t" 'BEGIN { split(t, a, " "); printf "%.3f", a[1] + a[2] }')
}

# reference NAME SIZE: MIS at $REF_SPP spp, seed 99 (the runs use seed 0:
# a reference sharing their random numbers would share their noise).
reference() {
  local name=$1 size=$2 key
  key="$(cksum <"$RAY") $(cksum <"scenes/$name.sph") $size $REF_SPP"
  ref=$OUT/pt-$name-ref.pfm
  if [ -f "$ref" ] && [ "$(cat "$OUT/pt-$name-ref.key" 2>/dev/null)" = "$key" ]; then
    say "pt: $name: reference unchanged since the last run, reused"
    return
  fi
  say "pt: $name: reference, MIS at $REF_SPP spp on every core ..."
  "$RAY" --pt --seed 99 -s "$size" -n "$REF_SPP" -o "$ref" "scenes/$name.sph" 2>"$OUT/pt.err" ||
    { cat "$OUT/pt.err" >&2; die "the reference failed"; }
  printf '%s\n' "$key" >"$OUT/pt-$name-ref.key"
}

: >"$OUT/pt.tsv"
: >"$OUT/pt-targets.txt"
{
  echo "Path tracing: time against error, one thread (./ray -t 1 --pt), CPU seconds of the whole run"
  echo "RMSE: linear radiance against a ${REF_SPP}-spp MIS reference (another seed), every pixel and channel;"
  echo "lit RMSE: the same without the pixels where the reference reaches 1 (the lamp, and its edges, whose"
  echo "noise of covering the pixel is every estimator's); display: 8-bit sRGB levels"
  echo
  printf '%-8s %-8s %-5s %5s %8s %10s %10s %8s\n' scene size est spp "cpu s" RMSE "lit RMSE" display
} | tee "$OUT/pt.txt"
for item in $SCENES; do
  name=${item%%:*} size=${item#*:}
  [ -f "scenes/$name.sph" ] || die "scenes/$name.sph not found"
  reference "$name" "$size"
  for est in bsdf nee mis; do
    for spp in $SPPS; do
      img=$OUT/pt-$name-$est-$spp.pfm
      cpu "$RAY" --pt -t 1 --estimator "$est" -s "$size" -n "$spp" -o "$img" "scenes/$name.sph" ||
        die "failed: $name $est $spp"
      read -r rmse lit disp <<<"$("$OUT/pfmerr" "$img" "$ref" |
        sed 's/rmse=\([^ ]*\) lit_rmse=\([^ ]*\) display_rmse=\([^ ]*\).*/\1 \2 \3/')"
      printf '%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\n' "$name" "$size" "$est" "$spp" "$cpu" "$rmse" "$lit" "$disp" >>"$OUT/pt.tsv"
      printf '%-8s %-8s %-5s %5s %8.3f %10.5f %10.5f %8.2f\n' "$name" "$size" "$est" "$spp" "$cpu" "$rmse" "$lit" "$disp" |
        tee -a "$OUT/pt.txt"
    done
  done
done

# The slope of log RMSE against log CPU time, least squares, per scene and
# estimator (runs under 0.05 s left out: their time is mostly start-up).
slopes=$(awk -F'\t' '$5 >= 0.05 { k = $1 "/" $3; x = log($5); y = log($6);
    n[k]++; sx[k] += x; sy[k] += y; sxx[k] += x * x; sxy[k] += x * y }
  END { for (k in n) if (n[k] > 1) printf "%s %.2f\n", k, (n[k] * sxy[k] - sx[k] * sy[k]) / (n[k] * sxx[k] - sx[k] * sx[k]) }' "$OUT/pt.tsv" | sort)
{ echo; echo "slope of log RMSE against log time (unbiased noise: -0.5):"; printf '%s\n' "$slopes" | sed 's/^/  /'; echo; } |
  tee -a "$OUT/pt.txt"

# The plot: one line per scene and estimator, its slope in its name.
awk -F'\t' -v slopes="$slopes" 'BEGIN { n = split(slopes, l, "\n"); for (i = 1; i <= n; i++) { split(l[i], p, " "); s[p[1]] = p[2] } }
  { k = $1 "/" $3; print k ",slope=" s[k], $5, $6, $4 }' "$OUT/pt.tsv" |
  "$OUT/svgplot" --title "make bench: path tracing, time against error (labels: samples per pixel)" \
    --xlabel "CPU seconds, one thread" --ylabel "RMSE (linear) against the $REF_SPP-spp reference" >"$OUT/pt.svg" ||
  die "svgplot failed"

# Target 1: MIS against BSDF sampling at 256 spp on the Cornell box.
row() { awk -F'\t' -v n="$1" -v e="$2" -v s="$3" '$1 == n && $3 == e && $4 == s { print $5, $6 }' "$OUT/pt.tsv"; }
if read -r t_b e_b <<<"$(row cornell bsdf 256)" && [ -n "${e_b:-}" ]; then
  t_m=$(awk -F'\t' -v e="$e_b" '$1 == "cornell" && $3 == "mis" { t[++n] = $5; r[n] = $6 }
    END { for (i = 1; i < n; i++) if (r[i] >= e && r[i + 1] <= e) {
            s = log(r[i + 1] / r[i]) / log(t[i + 1] / t[i]); printf "%.4f", t[i] * exp(log(e / r[i]) / s); exit }
          if (n && r[1] <= e) printf "<%s", t[1]; else print "" }' "$OUT/pt.tsv")
  if [ -z "$t_m" ]; then
    echo "Cornell box: MIS never reached BSDF sampling's RMSE at 256 spp ($e_b): NOT MET" >>"$OUT/pt-targets.txt"
  else
    tm=${t_m#<}
    x=$(awk "BEGIN { printf \"%.1f\", $t_b / $tm }")
    v=$(awk "BEGIN { exit !($t_b / $tm >= 10) }" && echo met || echo "NOT MET")
    echo "Cornell box 128x128, one thread: BSDF sampling at 256 spp: RMSE $e_b in $t_b s CPU; MIS reaches it in ${t_m} s: ${x}x less time (target >= 10x): $v" >>"$OUT/pt-targets.txt"
  fi
fi

# Target 2: CPU time per sample against smallpt, 1024x768 at 4 spp each,
# alternated, the best of three of each.
best_ours= best_sp=
if [ -n "$SMALLPT" ] && [ -f "$SMALLPT" ] && command -v g++ >/dev/null && g++ -O3 -w -o "$OUT/smallpt" "$SMALLPT" 2>"$OUT/smallpt-build.log"; then
  for _ in 1 2 3; do
    cpu "$RAY" --pt -t 1 --estimator bsdf -s 1024x768 -n 4 -o "$OUT/pt-ours-smallpt.pfm" scenes/smallpt.sph || die "ray failed"
    best_ours=$(awk -v a="$cpu" -v b="${best_ours:-1e9}" 'BEGIN { print (a < b) ? a : b }')
    cpu bash -c "cd $OUT && OMP_NUM_THREADS=1 exec ./smallpt 4" || die "smallpt failed"
    best_sp=$(awk -v a="$cpu" -v b="${best_sp:-1e9}" 'BEGIN { print (a < b) ? a : b }')
  done
  samples=$((1024 * 768 * 4))
  us_o=$(awk "BEGIN { printf \"%.3f\", $best_ours / $samples * 1e6 }")
  us_s=$(awk "BEGIN { printf \"%.3f\", $best_sp / $samples * 1e6 }")
  v=$(awk "BEGIN { exit !($us_o <= $us_s) }" && echo met || echo "NOT MET")
  echo "smallpt's scene 1024x768 at 4 spp, one thread: ours (BSDF sampling) $us_o us of CPU a sample, smallpt (g++ -O3) $us_s us: ratio $(awk "BEGIN { printf \"%.2f\", $us_o / $us_s }") (target <= 1): $v" >>"$OUT/pt-targets.txt"
else
  cpu "$RAY" --pt -t 1 --estimator bsdf -s 1024x768 -n 4 -o "$OUT/pt-ours-smallpt.pfm" scenes/smallpt.sph || die "ray failed"
  us_o=$(awk "BEGIN { printf \"%.3f\", $cpu / (1024 * 768 * 4) * 1e6 }")
  echo "smallpt's scene 1024x768 at 4 spp, one thread: ours (BSDF sampling) $us_o us of CPU a sample; smallpt not run (set BENCH_SMALLPT=path/to/smallpt.cpp)" >>"$OUT/pt-targets.txt"
fi

# Target 3: rays per second, path tracing (MIS) against Whitted, smallpt's
# scene, 256x192 at 16 spp, one thread, the best of three of each.
mrays() {  # mrays ARGS...: sets $mr, Mrays per CPU second
  local best=
  for _ in 1 2 3; do
    cpu "$RAY" -t 1 --stats -s 256x192 -n 16 -o "$OUT/pt-rays.ppm" "$@" scenes/smallpt.sph || die "ray failed"
    rays=$(sed -n 's/^rays *\([0-9]*\):.*/\1/p' "$OUT/pt.err" | head -n 1)
    best=$(awk -v a="$cpu" -v b="${best:-1e9}" 'BEGIN { print (a < b) ? a : b }')
  done
  mr=$(awk "BEGIN { printf \"%.2f\", $rays / $best / 1e6 }")
}
mrays --whitted; mr_w=$mr
mrays --pt --estimator mis; mr_p=$mr
mrays --pt --estimator bsdf; mr_b=$mr
r=$(awk "BEGIN { printf \"%.2f\", $mr_p / $mr_w }")
v=$(awk "BEGIN { exit !($mr_p >= 0.9 * $mr_w) }" && echo met || echo "NOT MET")
echo "smallpt's scene 256x192, one thread: path tracing (MIS) $mr_p Mrays/s (BSDF sampling $mr_b), Whitted $mr_w Mrays/s: ratio $r (target >= 0.9): $v" >>"$OUT/pt-targets.txt"

{ echo "Path tracing targets"; sed 's/^/  /' "$OUT/pt-targets.txt"; echo; } | tee -a "$OUT/pt.txt"
