#!/usr/bin/env bash
# bench/pt.sh: the path tracer's time against error (make bench, part "pt";
# also runs alone: bash bench/pt.sh).
#
# For the Cornell box, smallpt's scene and the caustic: a reference
# rendered at many samples (MIS, another seed, every core; kept in
# bench/out between runs while ./ray and the scene are unchanged), then
# each estimator (bsdf, nee, mis; and light tracing, BDPT, photon mapping
# and progressive photon mapping on the Cornell box and the caustic, see
# estimators_of) at 1, 4, 16, 64 and 256 samples per
# pixel on one thread, each run's CPU time (user + system, of the whole
# process) against its RMSE on linear values (bench/pfmerr.c).  The
# estimators take turns (bsdf nee mis bsdf nee mis ...) in BENCH_PT_ROUNDS rounds at each sample count;
# the time is the median of the rounds, printed with the least and the
# greatest (the image, of a fixed seed, is the same each time).  The fitted
# slope of log RMSE against log time is printed per estimator: -0.5 for an
# unbiased estimator whose error is noise.  Plotted, log-log, to
# bench/out/pt.svg.  Every comparison below takes turns too, and its ratio
# is the median of the rounds' ratios, with their range.
#
# Targets, each printed with its figures:
#   - Cornell box: MIS reaches the RMSE of BSDF sampling at 256 spp in at
#     most 1/10 of its time (MIS's time at that RMSE by log-log
#     interpolation between its two bracketing runs);
#   - smallpt's scene: our BSDF-only estimator costs no more CPU per sample
#     than smallpt (Beason 2008) built with g++ -O3, one thread, 1024x768 at
#     4 samples a pixel both; smallpt is not part of this project: set
#     BENCH_SMALLPT=path/to/smallpt.cpp (the 99-line original) to run it;
#   - smallpt's scene, 256x192: at smallpt's CPU time for 64 spp, the noise
#     of our default (MIS) at most half of smallpt's; the noise of each is
#     the RMSE between the images of two seeds, over sqrt 2, of the linear
#     values clamped to 0..1 as smallpt clamps them (bench/pfmerr.c's
#     clamped_rmse; smallpt's P3 read back through its 1/2.2 power).  Ours
#     runs at BENCH_SMALLPT_SPP (32) and its noise is taken to smallpt's
#     time as noise^2 x time is constant for an unbiased estimator.  smallpt
#     is built from BENCH_SMALLPT with its size and seed set by sed (the
#     lines it changes are named below; another source is not run);
#   - rays per second of the path tracer (MIS) within 10% of the Whitted
#     renderer's on the same scene (smallpt's), one thread;
#   - the caustic: BDPT or progressive photon mapping reaches the RMSE of
#     MIS at 1024 spp in at most 1/10 of its time (MIS and BDPT also run at
#     1024 spp there, taking turns; each method's figure is printed),
#     over the whole image and over the floor seen directly (floor_rmse of
#     bench/pfmerr.c: where the caustic lands, not the glass ball, whose
#     images of the lamp only the camera's paths find, for every estimator).
#     The caustic's reference is BDPT's, at BENCH_PT_REF_SPP: MIS's own
#     error there falls as spp^-0.2 (issue 21), so a reference of MIS's
#     would hold its noise.
#
# Knobs: BENCH_PT_REF_SPP (4096), BENCH_PT_SPP ("1 4 16 64 256"), BENCH_PT_TOP (1024: the
#        caustic's MIS and BDPT run there too),
#        BENCH_PT_SCENES ("cornell:128x128 smallpt:128x96 caustic:160x120"), BENCH_SMALLPT,
#        BENCH_SMALLPT_SPP, BENCH_PT_ROUNDS (BENCH_ROUNDS, else 3).
set -u -o pipefail
export LC_ALL=C
cd "$(dirname "$0")/.." || exit 2

REF_SPP=${BENCH_PT_REF_SPP:-4096}
SPPS=${BENCH_PT_SPP:-1 4 16 64 256}
TOP=${BENCH_PT_TOP:-1024}
SCENES=${BENCH_PT_SCENES:-cornell:128x128 smallpt:128x96 caustic:160x120}
SMALLPT=${BENCH_SMALLPT:-}
ROUNDS=${BENCH_PT_ROUNDS:-${BENCH_ROUNDS:-3}}

# The arithmetic and the tables are bench/table.c's, as in bench/run.sh;
# bench/lib.sh names its subcommands, builds the tools and times a run.
LOG=pt
. bench/lib.sh
build_time_tools || die "cannot build ray, pfmerr, svgplot or table"
RAY=$OUT/ray_pt

# estimators_of NAME SPP: the estimators that take turns on a scene: light
# tracing (--estimator light) too where the camera sees no diffuse
# surface through glass or a mirror, which it cannot render (smallpt's
# balls), or where it is the point (the caustic's floor; its ball, black
# to light tracing, is then its error), and BDPT and photon mapping
# (its 200,000 photons) and progressive photon mapping (its passes: the
# samples) with it; at $TOP spp (the caustic's alone), MIS and BDPT.
estimators_of() {
  if [ "$2" = "$TOP" ]; then echo mis bdpt; return; fi
  case $1 in cornell|caustic) echo bsdf nee mis light bdpt photon ppm ;; *) echo bsdf nee mis ;; esac
}

# spps_of NAME: the sample counts a scene runs at.
spps_of() {
  case $1 in caustic) echo "$SPPS $TOP" ;; *) echo "$SPPS" ;; esac
}

# reference_of NAME: the estimator of a scene's reference.
reference_of() {
  case $1 in caustic) echo bdpt ;; *) echo mis ;; esac
}

# reference NAME SIZE: MIS (or reference_of's) at $REF_SPP spp, seed 99
# (the runs use seed 0: a reference sharing their random numbers would
# share their noise).
reference() {
  local name=$1 size=$2 key est
  est=$(reference_of "$1")
  key="$(cksum <"$RAY") $(cksum <"scenes/$name.sph") $size $REF_SPP $est"
  ref=$OUT/pt-$name-ref.pfm
  if [ -f "$ref" ] && [ "$(cat "$OUT/pt-$name-ref.key" 2>/dev/null)" = "$key" ]; then
    say "pt: $name: reference unchanged since the last run, reused"
    return
  fi
  say "pt: $name: reference, $est at $REF_SPP spp on every core ..."
  "$RAY" --pt --estimator "$est" --seed 99 -s "$size" -n "$REF_SPP" -o "$ref" "scenes/$name.sph" 2>"$OUT/pt.err" ||
    { cat "$OUT/pt.err" >&2; die "the reference failed"; }
  printf '%s\n' "$key" >"$OUT/pt-$name-ref.key"
}

: >"$OUT/pt.tsv"
t_b='' e_b='' rounds_b='' cornell_size=''
: >"$OUT/pt-targets.txt"
{
  echo "Path tracing: time against error, one thread (./ray -t 1 --pt); cpu s: CPU seconds (user + system) of the whole"
  echo "run, the median of $ROUNDS rounds in which the three estimators take turns, and (least-greatest)"
  echo "RMSE: linear radiance against a ${REF_SPP}-spp reference (another seed; MIS's, the caustic's BDPT's), every pixel and channel;"
  echo "lit RMSE: the same without the pixels where the reference reaches 1 (the lamp, and its edges, whose"
  echo "noise of covering the pixel is every estimator's); display: 8-bit sRGB levels"
  echo
  printf '%-8s %-8s %-5s %5s %8s %-15s %10s %10s %8s\n' scene size est spp "cpu s" "(range)" RMSE "lit RMSE" display
} | tee "$OUT/pt.txt"
for item in $SCENES; do
  name=${item%%:*} size=${item#*:}
  [ -f "scenes/$name.sph" ] || die "scenes/$name.sph not found"
  reference "$name" "$size"
  for spp in $(spps_of "$name"); do
    declare -A times=()
    for ((round = 1; round <= ROUNDS; round++)); do
      for est in $(estimators_of "$name" "$spp"); do
        cpu "$RAY" --pt -t 1 --estimator "$est" -s "$size" -n "$spp" -o "$OUT/pt-$name-$est-$spp.pfm" "scenes/$name.sph" ||
          die "failed: $name $est $spp"
        times[$est]+="$cpu "
      done
    done
    for est in $(estimators_of "$name" "$spp"); do
      record "$OUT/pt.tsv" "$name" "$size" "$est" "$spp" "$OUT/pt-$name-$est-$spp.pfm" "$ref" "${times[$est]}"
      # target 1's figures (below): the Cornell box's first BSDF run at 256 spp
      if [ "$name/$est/$spp" = cornell/bsdf/256 ] && [ -z "$e_b" ]; then
        t_b=$med e_b=$rmse rounds_b=$rounds cornell_size=$size
      fi
      printf '%-8s %-8s %-5s %5s %8.3f %-15s %10.5f %10.5f %8.2f\n' "$name" "$size" "$est" "$spp" "$med" \
        "($(printf '%.3f-%.3f' "$lo" "$hi"))" "$rmse" "$lit" "$disp" | tee -a "$OUT/pt.txt"
    done
    unset times
  done
done

fit_and_plot pt "make bench: path tracing, time against error (labels: samples per pixel)" \
  "RMSE (linear) against the $REF_SPP-spp reference" || die "svgplot failed"

# The caustic's floor: each caustic run's RMSE over the floor seen directly
# (bench/pfmerr.c's floor_rmse, by the scene's --view normal), as a table
# of its own in pt.tsv's columns, for target 4.
: >"$OUT/pt-floor.tsv"
if grep -q "^caustic	" "$OUT/pt.tsv"; then
  csize=$(awk -F'\t' '$1 == "caustic" { print $2; exit }' "$OUT/pt.tsv")
  "$RAY" --view normal -s "$csize" -o "$OUT/pt-caustic-normal.pfm" scenes/caustic.sph 2>"$OUT/pt.err" ||
    die "the caustic's normals failed"
  { echo; echo "the caustic's floor (the pixels whose first hit faces up): RMSE against the same reference"; } | tee -a "$OUT/pt.txt"
  while IFS=$'\t' read -r n sz est spp med rest; do
    [ "$n" = caustic ] || continue
    f=$("$OUT/pfmerr" "$OUT/pt-caustic-$est-$spp.pfm" "$OUT/pt-caustic-ref.pfm" "$OUT/pt-caustic-normal.pfm" |
      sed 's/.*floor_rmse=\([^ ]*\).*/\1/')
    printf '%s\t%s\t%s\t%s\t%s\t%s\t%s\n' "$n" "$sz" "$est" "$spp" "$med" "$f" "$(cut -f2- <<<"$rest")" >>"$OUT/pt-floor.tsv"
    printf '  %-5s %5s %8.3f s  floor RMSE %.5f\n' "$est" "$spp" "$med" "$f" | tee -a "$OUT/pt.txt"
  done <"$OUT/pt.tsv"
fi

# Target 4 (issue 21): on the caustic, BDPT's (and progressive photon
# mapping's) time at the RMSE of MIS at $TOP spp, round by round (log-log
# interpolation between the method's two bracketing runs of that round),
# against MIS's time; over the whole image (TSV pt.tsv) and over the floor
# (pt-floor.tsv).
beats_mis() {
  local est=$1 tsv=$2 what=$3 e_m t_m r_m xs='' k tm tb x v name
  name=$(case $est in bdpt) echo BDPT ;; *) echo "progressive photon mapping" ;; esac)
  read -r e_m t_m r_m <<<"$(awk -F'\t' -v top="$TOP" '$1 == "caustic" && $3 == "mis" && $4 == top { print $6, $5, $11 }' "$tsv")"
  [ -n "$e_m" ] || return 0
  tb=$(table time-at "$tsv" caustic "$est" "$e_m" 0)
  if [ -z "$tb" ]; then
    echo "caustic, $what: $name never reached MIS's RMSE at $TOP spp ($e_m): NOT MET" >>"$OUT/pt-targets.txt"
    return 0
  fi
  IFS=, read -r -a tms <<<"$r_m"
  for ((k = 1; k <= ${#tms[@]}; k++)); do
    tm=$(table time-at "$tsv" caustic "$est" "$e_m" "$k")
    xs+="$(ratio %.4g "${tms[k - 1]}" "${tm#<}") "
  done
  # shellcheck disable=SC2086
  x=$(printf %.1f "$(median $xs)")
  v=$(verdict "$x" ">=" 10)
  # shellcheck disable=SC2086
  echo "caustic $csize, one thread, $what: MIS at $TOP spp: RMSE $e_m in $t_m s CPU; $name reaches it in $tb s (medians of $ROUNDS rounds taking turns): ${x}x less time ($(range %.1f $xs), the rounds' ratios) (target >= 10x): $v" >>"$OUT/pt-targets.txt"
}
if [ -s "$OUT/pt-floor.tsv" ]; then
  for est in bdpt ppm; do
    beats_mis $est "$OUT/pt.tsv" "the whole image"
    beats_mis $est "$OUT/pt-floor.tsv" "the floor"
  done
fi

# Target 1: MIS against BSDF sampling at 256 spp on the Cornell box, round
# by round: each round's BSDF time against the time at which that round's
# MIS runs reach the same RMSE (the RMSEs are the same each round).
if [ -n "$e_b" ]; then
  # mis_at ROUND: MIS's time at RMSE $e_b in that round (1, 2, ...; 0: the
  # medians), by log-log interpolation between its two bracketing runs;
  # "<T" when its cheapest run is already below; empty when never reached.
  mis_at() { table time-at "$OUT/pt.tsv" cornell mis "$e_b" "$1"; }
  t_m=$(mis_at 0)
  if [ -z "$t_m" ]; then
    echo "Cornell box: MIS never reached BSDF sampling's RMSE at 256 spp ($e_b): NOT MET" >>"$OUT/pt-targets.txt"
  else
    xs=''
    IFS=, read -r -a tb <<<"$rounds_b"
    for ((k = 1; k <= ${#tb[@]}; k++)); do
      tm=$(mis_at "$k")
      xs+="$(ratio %.4g "${tb[k - 1]}" "${tm#<}") "
    done
    # shellcheck disable=SC2086
    x=$(printf %.1f "$(median $xs)")
    v=$(verdict "$x" ">=" 10)
    # shellcheck disable=SC2086
    echo "Cornell box $cornell_size, one thread: BSDF sampling at 256 spp: RMSE $e_b in $t_b s CPU; MIS reaches it in ${t_m} s (medians of $ROUNDS rounds taking turns): ${x}x less time ($(range %.1f $xs), the rounds' ratios) (target >= 10x): $v" >>"$OUT/pt-targets.txt"
  fi
fi

# Target 2: CPU time per sample against smallpt, 1024x768 at 4 spp each,
# taking turns in $ROUNDS rounds.
if [ -n "$SMALLPT" ] && [ -f "$SMALLPT" ] && command -v g++ >/dev/null && g++ -O3 -w -o "$OUT/smallpt" "$SMALLPT" 2>"$OUT/smallpt-build.log"; then
  ours='' sp=''
  for ((round = 1; round <= ROUNDS; round++)); do
    cpu "$RAY" --pt -t 1 --estimator bsdf -s 1024x768 -n 4 -o "$OUT/pt-ours-smallpt.pfm" scenes/smallpt.sph || die "ray failed"
    ours+="$cpu "
    cpu bash -c "cd $OUT && OMP_NUM_THREADS=1 exec ./smallpt 4" || die "smallpt failed"
    sp+="$cpu "
  done
  samples=$((1024 * 768 * 4))
  # shellcheck disable=SC2086
  us_o=$(table us-per "$(median $ours)" "$samples" %.3f)
  # shellcheck disable=SC2086
  us_s=$(table us-per "$(median $sp)" "$samples" %.3f)
  q=$(ratios "$ours" "$sp")
  # shellcheck disable=SC2086
  qm=$(printf %.2f "$(median $q)")
  v=$(verdict "$qm" "<=" 1)
  # shellcheck disable=SC2086
  echo "smallpt's scene 1024x768 at 4 spp, one thread, medians of $ROUNDS rounds taking turns: ours (BSDF sampling) $us_o us of CPU a sample, smallpt (g++ -O3) $us_s us: ratio $qm ($(range %.2f $q), the rounds' ratios) (target <= 1): $v" >>"$OUT/pt-targets.txt"
else
  cpu "$RAY" --pt -t 1 --estimator bsdf -s 1024x768 -n 4 -o "$OUT/pt-ours-smallpt.pfm" scenes/smallpt.sph || die "ray failed"
  us_o=$(table us-per "$cpu" $((1024 * 768 * 4)) %.3f)
  echo "smallpt's scene 1024x768 at 4 spp, one thread: ours (BSDF sampling) $us_o us of CPU a sample; smallpt not run (set BENCH_SMALLPT=path/to/smallpt.cpp)" >>"$OUT/pt-targets.txt"
fi

# Target 4: noise at equal CPU time against smallpt at 64 spp, 256x192:
# smallpt's size and seed made settable (its `int w=1024, h=768` and the
# seed {0,0,y*y*y} of each row), two seeds each, the CPU times of the
# first seed's runs taking turns in $ROUNDS rounds.
SP_SPP=${BENCH_SMALLPT_SPP:-32}
if [ -x "$OUT/smallpt" ] && grep -q 'int w=1024, h=768' "$SMALLPT" && grep -q 'Xi\[3\]={0,0,y\*y\*y}' "$SMALLPT" &&
   sed 's/int w=1024, h=768/int w=256, h=192/; s/Xi\[3\]={0,0,y\*y\*y}/Xi[3]={SEED,0,(unsigned short)(y*y*y)}/' "$SMALLPT" >"$OUT/smallpt-seeded.cpp" &&
   g++ -O3 -w -DSEED=1 -o "$OUT/smallpt1" "$OUT/smallpt-seeded.cpp" && g++ -O3 -w -DSEED=2 -o "$OUT/smallpt2" "$OUT/smallpt-seeded.cpp"; then
  ours='' sp=''
  for ((round = 1; round <= ROUNDS; round++)); do
    cpu "$RAY" -t 1 -s 256x192 -n "$SP_SPP" --seed 1 -o "$OUT/pt-noise1.pfm" scenes/smallpt.sph || die "ray failed"
    ours+="$cpu "
    cpu bash -c "cd $OUT && OMP_NUM_THREADS=1 exec ./smallpt1 64" || die "smallpt failed"
    sp+="$cpu "
    mv "$OUT/image.ppm" "$OUT/smallpt1.ppm"
  done
  "$RAY" -t 1 -s 256x192 -n "$SP_SPP" --seed 2 -o "$OUT/pt-noise2.pfm" scenes/smallpt.sph 2>/dev/null || die "ray failed"
  (cd "$OUT" && OMP_NUM_THREADS=1 ./smallpt2 64 2>/dev/null && mv image.ppm smallpt2.ppm) || die "smallpt failed"
  n_o=$("$OUT/pfmerr" "$OUT/pt-noise1.pfm" "$OUT/pt-noise2.pfm" | sed 's/.*clamped_rmse=\([^ ]*\).*/\1/')
  n_s=$("$OUT/pfmerr" "$OUT/smallpt1.ppm" "$OUT/smallpt2.ppm" | sed 's/.*clamped_rmse=\([^ ]*\).*/\1/')
  # shellcheck disable=SC2086
  t_o=$(median $ours) t_s=$(median $sp)
  eq=$(awk -v n="$n_o" -v a="$t_o" -v b="$t_s" 'BEGIN { printf "%.4f", n / sqrt(2) * sqrt(a / b) }')
  r=$(awk -v e="$eq" -v n="$n_s" 'BEGIN { printf "%.2f", e / (n / sqrt(2)) }')
  q=$(ratios "$ours" "$sp")
  v=$(verdict "$r" "<=" 0.5)
  # shellcheck disable=SC2086
  echo "smallpt's scene 256x192, one thread: smallpt at 64 spp $t_s s CPU ($(range %.2f $sp)), noise $(awk -v n="$n_s" 'BEGIN { printf "%.4f", n / sqrt(2) }'); ours (MIS) at $SP_SPP spp $t_o s ($(range %.2f $ours); time ratios $(range %.2f $q)), noise $(awk -v n="$n_o" 'BEGIN { printf "%.4f", n / sqrt(2) }'), at smallpt's time $eq: ratio $r (target <= 0.5): $v" >>"$OUT/pt-targets.txt"
else
  echo "smallpt's scene: the noise at equal time against smallpt not measured (set BENCH_SMALLPT to smallpt's 99-line source, which g++ builds)" >>"$OUT/pt-targets.txt"
fi

# Target 3: rays per second, path tracing (MIS) against Whitted, smallpt's
# scene, 256x192 at 16 spp, one thread: Whitted, MIS and BSDF sampling
# taking turns in 5 rounds ($ROUNDS if more: these runs are short, about a
# second, and short runs spread widely on a busy machine).
mr1() {  # mr1 ARGS...: Mrays per CPU second of one run, to $mr
  cpu "$RAY" -t 1 --stats=kv -s 256x192 -n 16 -o "$OUT/pt-rays.ppm" "$@" scenes/smallpt.sph || die "ray failed"
  mr=$(table mrays "$(kv "$OUT/pt.err" rays)" "$cpu")
}
mr_w='' mr_p='' mr_b='' mr_rounds=$((ROUNDS > 5 ? ROUNDS : 5))
for ((round = 1; round <= mr_rounds; round++)); do
  mr1 --whitted; mr_w+="$mr "
  mr1 --pt --estimator mis; mr_p+="$mr "
  mr1 --pt --estimator bsdf; mr_b+="$mr "
done
q=$(ratios "$mr_p" "$mr_w")
# shellcheck disable=SC2086
r=$(printf %.2f "$(median $q)")
v=$(verdict "$r" ">=" 0.9)
# shellcheck disable=SC2086
echo "smallpt's scene 256x192, one thread, medians of $mr_rounds rounds taking turns: path tracing (MIS) $(printf %.2f "$(median $mr_p)") Mrays/s ($(range %.2f $mr_p)) (BSDF sampling $(printf %.2f "$(median $mr_b)")), Whitted $(printf %.2f "$(median $mr_w)") Mrays/s ($(range %.2f $mr_w)): ratio $r ($(range %.2f $q), the rounds' ratios) (target >= 0.9): $v" >>"$OUT/pt-targets.txt"

{ echo "Path tracing targets"; sed 's/^/  /' "$OUT/pt-targets.txt"; echo; } | tee -a "$OUT/pt.txt"
