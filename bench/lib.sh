# bench/lib.sh - sourced by bench/run.sh and the scripts of its parts: their names for
# bench/table.c's subcommands (its top lists them all), built as $OUT/table.
# kv LOG KEY: KEY's value in a log of ./ray --stats=kv ("key value" lines),
# e.g. cpu_s, the render's CPU seconds (every thread; the scene's reading
# and the structure's build are not in it), or rays, every ray of any kind.
# spread V...: "least median greatest" of the values (the median of an even
# count: the mean of the two in the middle); median V...; range FORMAT V...:
# "least-greatest", each in FORMAT (printf's); ratios "A1 A2 ..." "B1 B2
# ...": A1/B1 A2/B2 ..., the pairs' ratios; ratio FORMAT A B: one;
# verdict A OP B: "met" or "NOT MET".
# die MESSAGE: the script's name and MESSAGE on stderr, exit 1; say: a
# progress line.  And $OUT made, for the script that sources this.
# The scripts' shared defaults (run.sh sets its own first): the compiler
# and its flags as make passes them, and where everything is written.
CC=${CC:-cc}
CFLAGS=${CFLAGS:--O2}
OUT=bench/out

die() { echo "$0: $*" >&2; exit 1; }
say() { echo "bench: $*" >&2; }
mkdir -p "$OUT" || die "cannot create $OUT"

table() { "$OUT/table" "$@"; }
kv() { table kv "$@"; }
spread() { table spread "$@"; }
median() { table median "$@"; }
range() { table range "$@"; }
ratios() { table ratios "$@"; }
ratio() { table ratio "$@"; }
verdict() { table verdict "$@"; }

# build_time_tools: ./ray (with OpenMP where the compiler has it) as
# $OUT/ray_pt, and bench/pfmerr.c, svgplot.c and table.c, for bench/pt.sh
# and bench/dist.sh.
build_time_tools() {
  local omp
  omp=$(echo 'int main(void){return 0;}' | $CC -fopenmp -x c - -o /dev/null 2>/dev/null && echo -fopenmp)
  # shellcheck disable=SC2086
  $CC $CFLAGS $omp -o "$OUT/ray_pt" ray.c scene.c image.c cli.c kdtree.c bvh.c grid.c photons.c -lm &&
    $CC $CFLAGS -o "$OUT/pfmerr" bench/pfmerr.c -lm && $CC $CFLAGS -o "$OUT/svgplot" bench/svgplot.c -lm &&
    $CC $CFLAGS -o "$OUT/table" bench/table.c -lm
}

# cpu CMD...: runs CMD; its CPU seconds (user + system) go to $cpu (in
# whole milliseconds, as `time` prints them: the shell's own arithmetic),
# its stderr to $OUT/$LOG.err (LOG: the caller's name).
cpu() {
  local TIMEFORMAT='%3U %3S' u s ms
  { time "$@" >/dev/null 2>"$OUT/$LOG.err"; } 2>"$OUT/$LOG.time" || { cat "$OUT/$LOG.err" >&2; return 1; }
  read -r u s < <(tail -n 1 "$OUT/$LOG.time")
  ms=$((10#${u/./} + 10#${s/./}))
  cpu=$(printf '%d.%03d' $((ms / 1000)) $((ms % 1000)))
}

# record TSV NAME SIZE KIND SPP IMAGE REFERENCE "TIMES": one render's row of
# a time-against-error table (bench/pt.sh's and bench/dist.sh's): its RMSEs
# against the reference (bench/pfmerr.c) and the spread of its rounds'
# times, appended to TSV; rmse, lit, disp, lo, med, hi and rounds (the
# rounds' times in order, by commas) stay set for the caller's table.
record() {
  local tsv=$1 name=$2 size=$3 kind=$4 spp=$5 img=$6 ref=$7 times=$8
  read -r rmse lit disp <<<"$("$OUT/pfmerr" "$img" "$ref" |
    sed 's/rmse=\([^ ]*\) lit_rmse=\([^ ]*\) display_rmse=\([^ ]*\).*/\1 \2 \3/')"
  # shellcheck disable=SC2086
  read -r lo med hi <<<"$(spread $times)"
  rounds=$(printf '%s' "${times% }" | tr ' ' ,)
  printf '%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\n' "$name" "$size" "$kind" "$spp" "$med" "$rmse" "$lit" \
    "$disp" "$lo" "$hi" "$rounds" >>"$tsv"
}

# fit_and_plot NAME TITLE YLABEL: the slope of log RMSE against log CPU
# time, least squares, per scene and kind of $OUT/NAME.tsv (runs under
# 0.05 s left out: their time is mostly start-up; noise alone gives
# -0.5), appended to $OUT/NAME.txt; and the log-log plot, one line per
# scene and kind, to $OUT/NAME.svg.
fit_and_plot() {
  local name=$1 title=$2 ylabel=$3 slopes
  slopes=$(table pt-slopes "$OUT/$name.tsv")
  { echo; echo "slope of log RMSE against log time (unbiased noise: -0.5):"; printf '%s\n' "$slopes" | sed 's/^/  /'; echo; } |
    tee -a "$OUT/$name.txt"
  table pt-plot "$OUT/$name.tsv" |
    "$OUT/svgplot" --title "$title" --xlabel "CPU seconds, one thread (median of the rounds)" \
      --ylabel "$ylabel" >"$OUT/$name.svg"
}
