#!/usr/bin/env bash
# Runs the fuzz targets that `make fuzz` built, each for FUZZ_SECONDS (60),
# one after another:  bash fuzz/run.sh sph nff obj
#
# Each target reads its seeds (build/fuzz/seeds-FORMAT, made by make from
# scenes/ and fuzz/seeds/) and keeps what it learns in build/fuzz/corpus-FORMAT,
# so that a later run goes on from there.  The readers' messages (stderr) are
# hidden (-close_fd_mask=2); libFuzzer's own lines go to build/fuzz/FORMAT.log.
# An input that crashes, trips a sanitizer, aborts (the tree and the loop
# disagree, or the path tracer makes a NaN: see fuzz_scene.c) or takes more
# than 10 s is written to build/fuzz/FORMAT-crash-* (or -timeout-, -oom-,
# -slow-unit-) and fails the run; rerun the target on that file to see why:
#     build/fuzz/fuzz_sph build/fuzz/sph-crash-...
#
# FUZZ_SEED=N fixes libFuzzer's random numbers (-seed=N): CI does, so that on
# the same code it makes the same inputs, and a finding there can be had again.
cd "$(dirname "$0")/.." || exit 2
secs=${FUZZ_SECONDS:-60}
seed=${FUZZ_SEED:+-seed=$FUZZ_SEED}
status=0
for f in "$@"; do
  target=build/fuzz/fuzz_$f corpus=build/fuzz/corpus-$f log=build/fuzz/$f.log
  if [ ! -x "$target" ]; then echo "fuzz: $target is not built (make fuzz builds it)"; status=2; continue; fi
  mkdir -p "$corpus"
  echo "fuzz_$f: ${secs} s from $(ls build/fuzz/seeds-$f | wc -l) seeds and $(ls "$corpus" | wc -l) inputs of earlier runs, dictionary fuzz/$f.dict"
  # shellcheck disable=SC2086 # $seed is empty or one word
  "$target" -max_total_time="$secs" $seed -timeout=10 -max_len=8192 -close_fd_mask=2 \
    -dict="fuzz/$f.dict" -artifact_prefix="build/fuzz/$f-" -print_final_stats=1 \
    "$corpus" "build/fuzz/seeds-$f" >"$log" 2>&1
  rc=$?
  runs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -n 1)
  cov=$(grep -oE 'cov: [0-9]+' "$log" | tail -n 1)
  echo "fuzz_$f: ${runs:-?} executions, ${cov:-cov: ?} edges, $(ls "$corpus" | wc -l) inputs in $corpus"
  if [ "$rc" != 0 ]; then
    status=1
    echo "fuzz_$f: FOUND SOMETHING (exit $rc); from $log:"
    grep -E 'ERROR|SUMMARY|Test unit written|deadly signal|timeout' "$log" | head -n 20 | sed 's/^/    /'
    # the input once more, with stderr: the reader's message, what differs, the sanitizer's report
    unit=$(sed -n 's/.*Test unit written to //p' "$log" | tail -n 1)
    if [ -f "$unit" ]; then
      echo "fuzz_$f: $target $unit says:"
      "$target" "$unit" 2>&1 | grep -vE '^(INFO|Running|Executed|\*\*\*)' | head -n 30 | sed 's/^/    /'
    fi
  fi
done
exit $status
