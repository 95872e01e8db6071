#!/usr/bin/env bash
# The render-farm recipes of the README run for real, on this machine as
# the farm: a scene split into 4 parts (--tile i/4), the parts rendered by
# GNU parallel (through a host file, as over ssh) and by a real Slurm job
# array with a dependent merge job (tools/render.sbatch, tools/merge.sbatch
# on the one-node cluster of tools/slurm-local.sh); each merge must be the
# bytes of one whole run.  Where Slurm cannot start here, render.sbatch and
# merge.sbatch are run by bash with the task ids Slurm would give.
#
# RAY=path tests another program with ray's command line (default ./ray).
. tests/lib.sh
export RAY=${RAY:-./ray}
# GNU parallel keeps its state in $HOME/.parallel unless told otherwise.
export PARALLEL_HOME=$TMP/parallel-home
N=4
scenes=(cornell whitted)
declare -A file=([cornell]=scenes/cornell.sph [whitted]=scenes/whitted.sph)
declare -A opts=([cornell]="--pt -s 64x48 -n 8" [whitted]="-s 64x48 -n 4")

help=$("$RAY" --help 2>&1)
if ! grep -q -- '--tile' <<<"$help" || ! grep -q -- '--merge' <<<"$help"; then
  skip "the farm recipes (GNU parallel, Slurm): $RAY has no --tile and --merge"
  exit 0
fi

# One whole run of each scene: what every merge must equal.
for s in "${scenes[@]}"; do
  # shellcheck disable=SC2086  # the options are split on purpose
  "$RAY" "${file[$s]}" ${opts[$s]} -o "$TMP/whole-$s.ppm" 2>"$TMP/whole-$s.err" \
    || { bad "the whole run of ${file[$s]} ${opts[$s]}: $(tail -n 1 "$TMP/whole-$s.err")"; exit 0; }
done

# (a) GNU parallel.  A host file of one line, ":", is this machine without
# ssh; a lab's lists its machines, and the command is the same.
if ! command -v parallel >/dev/null; then
  skip "GNU parallel renders 4 parts and merges them: parallel is not installed (apt-get install parallel)"
elif ! parallel --version 2>/dev/null | grep -q 'GNU parallel'; then
  skip "GNU parallel renders 4 parts and merges them: this parallel is not GNU's (moreutils'?)"
else
  echo : >"$TMP/hosts"
  for s in "${scenes[@]}"; do
    p=$TMP/par-$s
    mkdir -p "$p"
    start=$SECONDS
    # shellcheck disable=SC2086
    parallel -j1 --sshloginfile "$TMP/hosts" --workdir "$PWD" --halt now,fail=1 \
      "$RAY" "${file[$s]}" ${opts[$s]} --tile {}/$N -o "$p/part{}.part" ::: $(seq 0 $((N - 1))) \
      </dev/null >"$TMP/par-$s.log" 2>&1 \
      && "$RAY" --merge "$TMP/par-$s.ppm" "$p"/part{0..3}.part 2>>"$TMP/par-$s.log"
    rc=$?
    if [ "$rc" = 0 ] && cmp -s "$TMP/par-$s.ppm" "$TMP/whole-$s.ppm"; then
      ok "GNU parallel: ${file[$s]} ${opts[$s]} in $N parts (--tile i/$N, parallel --sshloginfile), merged: the whole run's bytes ($((SECONDS - start)) s)"
    elif [ "$rc" = 0 ]; then
      bad "GNU parallel: ${file[$s]} ${opts[$s]} in $N parts merged differs from the whole run: $(cmp "$TMP/par-$s.ppm" "$TMP/whole-$s.ppm" 2>&1)"
    else
      bad "GNU parallel: ${file[$s]} ${opts[$s]} in $N parts: exit $rc: $(tail -n 2 "$TMP/par-$s.log" | tr '\n' ' ')"
    fi
  done
  # What makes a failed farm loud rather than a wrong image: a hole refused.
  if ! [ -f "$TMP/par-whitted/part3.part" ]; then
    :   # the parts were not all rendered: that failed above
  elif "$RAY" --merge "$TMP/hole.ppm" "$TMP"/par-whitted/part{0,1,3}.part 2>"$TMP/hole.err"; then
    bad "ray --merge with part 2 of $N missing exited 0"
  else
    ok "ray --merge with part 2 of $N missing refuses, exit non-zero: $(head -n 1 "$TMP/hole.err")"
  fi
fi

# The scripts' body with the task ids Slurm would give, run by bash:
# where a real Slurm cannot run, the scripts are still tested.
simulated() {
  local why=$1 s p i rc
  for s in "${scenes[@]}"; do
    p=$TMP/sim-$s rc=0
    for i in $(seq 0 $((N - 1))); do
      SLURM_ARRAY_TASK_ID=$i SLURM_ARRAY_TASK_COUNT=$N SLURM_ARRAY_TASK_MIN=0 SLURM_ARRAY_TASK_MAX=$((N - 1)) \
        SCENE=${file[$s]} RAY_OPTS=${opts[$s]} PARTS=$p bash tools/render.sbatch 2>>"$TMP/sim-$s.log" || rc=$?
    done
    [ "$rc" = 0 ] && SCENE=${file[$s]} PARTS=$p OUT=$TMP/sim-$s.ppm bash tools/merge.sbatch 2>>"$TMP/sim-$s.log" || rc=$?
    if [ "$rc" = 0 ] && cmp -s "$TMP/sim-$s.ppm" "$TMP/whole-$s.ppm"; then
      ok "tools/render.sbatch x$N and merge.sbatch run by bash with simulated task ids ($why): ${file[$s]} ${opts[$s]}, the whole run's bytes"
    else
      bad "tools/render.sbatch x$N and merge.sbatch with simulated task ids: ${file[$s]} ${opts[$s]}: exit $rc: $(tail -n 2 "$TMP/sim-$s.log" | tr '\n' ' ')"
    fi
  done
}

# (b) Slurm: the cluster is started here unless it is already up, and then
# stopped again on the way out.
slurm_skip() {
  skip "Slurm: tools/render.sbatch as an array of $N and merge.sbatch after it: $1"
  simulated "no real Slurm here"
  exit 0
}
command -v sbatch >/dev/null || slurm_skip "sbatch is not installed (apt-get install slurm-wlm munge)"
if ! tools/slurm-local.sh status >/dev/null 2>&1; then
  tools/slurm-local.sh start >"$TMP/slurm-start.log" 2>&1 \
    || slurm_skip "tools/slurm-local.sh start failed: $(grep 'slurm-local:' "$TMP/slurm-start.log" | tail -n 1)"
  trap 'tools/slurm-local.sh stop >/dev/null 2>&1; rm -rf "$TMP"' EXIT
fi
eval "$(tools/slurm-local.sh env)"

start=$SECONDS
ids=()
for s in "${scenes[@]}"; do
  jid=$(SCENE=${file[$s]} RAY_OPTS=${opts[$s]} PARTS=$TMP/slurm-$s \
        sbatch --parsable --array=0-$((N - 1)) -o "$TMP/slurm-$s-%a.out" tools/render.sbatch 2>"$TMP/sbatch.err") \
    || { bad "sbatch --array=0-$((N - 1)) tools/render.sbatch: $(tail -n 1 "$TMP/sbatch.err")"; continue; }
  mid=$(SCENE=${file[$s]} PARTS=$TMP/slurm-$s OUT=$TMP/slurm-$s.ppm \
        sbatch --parsable --dependency=afterok:"$jid" -o "$TMP/slurm-$s-merge.out" tools/merge.sbatch 2>"$TMP/sbatch.err") \
    || { bad "sbatch --dependency=afterok:$jid tools/merge.sbatch: $(tail -n 1 "$TMP/sbatch.err")"; scancel "$jid"; continue; }
  ids+=("$s:$jid:$mid")
done
[ "${#ids[@]}" = 0 ] && exit 0

# No accounting here, so no sacct: the jobs are waited for until squeue no
# longer lists them, and scontrol (which remembers an ended job for
# MinJobAge, 300 s) tells how each ended.
all=$(for x in "${ids[@]}"; do IFS=: read -r _ j m <<<"$x"; printf '%s,%s,' "$j" "$m"; done)
all=${all%,}
deadline=$((SECONDS + 300))
# A merge whose tasks failed is cancelled by the cluster
# (kill_invalid_depend); on another cluster it may wait for ever, with the
# reason DependencyNeverSatisfied, which ends the wait too.
queued() { squeue -h -j "$all" -o '%r' 2>/dev/null | grep -v -x DependencyNeverSatisfied; }
while [ -n "$(queued)" ] && [ "$SECONDS" -lt "$deadline" ]; do sleep 0.5; done
if [ -n "$(queued)" ]; then
  bad "Slurm: jobs $all still queued after 300 s: $(squeue -h -j "$all" -o '%i %T %r' | tr '\n' ';')"
  scancel "${all//,/ }" 2>/dev/null
  exit 0
fi
took=$((SECONDS - start))
scancel "${all//,/ }" 2>/dev/null   # the merges left pending, if any
for x in "${ids[@]}"; do
  IFS=: read -r s jid mid <<<"$x"
  state=$(scontrol show job "$mid" 2>/dev/null | sed -n 's/.*JobState=\([A-Z_]*\).*/\1/p' | head -n 1)
  tiles=$(scontrol show job "$jid" 2>/dev/null | sed -n 's/.*JobState=\([A-Z_]*\).*/\1/p' | sort | uniq -c | tr -s ' \n' '  ')
  if [ "$state" = COMPLETED ] && cmp -s "$TMP/slurm-$s.ppm" "$TMP/whole-$s.ppm"; then
    ok "Slurm: ${file[$s]} ${opts[$s]}: sbatch --array=0-$((N - 1)) tools/render.sbatch, then merge.sbatch (afterok): the whole run's bytes (all jobs ${took} s)"
  elif [ "$state" = COMPLETED ]; then
    bad "Slurm: ${file[$s]} ${opts[$s]}: the merged image differs from the whole run: $(cmp "$TMP/slurm-$s.ppm" "$TMP/whole-$s.ppm" 2>&1)"
  else
    bad "Slurm: ${file[$s]} ${opts[$s]}: merge job $mid ${state:-unknown}, tasks:${tiles:- unknown}; $(cat "$TMP/slurm-$s"-*.out 2>/dev/null | grep -v '^render.sbatch: task\|^merge.sbatch: ' | tail -n 2 | tr '\n' ' ')"
  fi
done
