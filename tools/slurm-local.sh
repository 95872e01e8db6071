#!/usr/bin/env bash
# tools/slurm-local.sh start|stop|status|env
#
# A real Slurm cluster of one node, this machine, for CI and tests: the
# Slurm recipe (tools/render.sbatch, tools/merge.sbatch) is then run by the
# same sbatch a university cluster has, not by a simulation of it.
#
#   start   munged, slurmctld and slurmd, each as root in the background,
#           then waits until the node is idle; does nothing if already up
#   stop    cancels what is queued, ends the three daemons (by the pids they
#           wrote), and forgets the jobs; does nothing if already down
#   status  exit 0 if the cluster answers and its node is idle or busy
#   env     prints `export SLURM_CONF=...`: eval it before sbatch, squeue
#
# It installs nothing (CI installs slurm-wlm and munge: FARM-README-snippet.md
# has the line) and touches nothing outside its directory, RAY_SLURM_DIR
# (default /tmp/ray-slurm): its own munge key and socket, its own
# slurm.conf on its own ports, so a Slurm or munge the machine already runs
# is neither used nor disturbed, and nothing in /etc is written.
#
# Why this slurm.conf: no systemd and no delegated cgroup here (a container
# or CI's VM), so processes are tracked by /proc (proctrack/linuxproc) and
# tasks are not confined (task/none); no accounting database (slurmdbd), so
# sacct does not work and jobs are followed with squeue and scontrol.  The
# daemons run as root (SlurmUser=root), so no directory needs a slurm owner.
set -u

dir=${RAY_SLURM_DIR:-/tmp/ray-slurm}
conf=$dir/slurm.conf
# Not Slurm's default ports (6817, 6818), so a system Slurm can run beside.
ctld_port=${RAY_SLURM_CTLD_PORT:-16817}
d_port=${RAY_SLURM_D_PORT:-16818}
export SLURM_CONF=$conf

die() { echo "slurm-local: $*" >&2; exit 1; }
say() { echo "slurm-local: $*" >&2; }

# The pid in FILE if that process is alive and is the program named, else
# nothing: a pid file left by a daemon that died may name another process.
alive() {
  local file=$1 name=$2 pid
  [ -r "$file" ] || return 1
  pid=$(cat "$file" 2>/dev/null) || return 1
  [[ $pid =~ ^[0-9]+$ ]] || return 1
  [ "$(cat "/proc/$pid/comm" 2>/dev/null)" = "$name" ] || return 1
  echo "$pid"
}

# The node's state as sinfo sees it ("idle", "mixed", "down*", ...), or
# nothing when the controller does not answer.
node_state() { sinfo -h -N -o '%T' 2>/dev/null | head -n 1; }

up() {
  alive "$dir/munged.pid" munged >/dev/null && alive "$dir/slurmctld.pid" slurmctld >/dev/null \
    && alive "$dir/slurmd.pid" slurmd >/dev/null || return 1
  case $(node_state) in idle|mixed|allocated|completing) return 0;; *) return 1;; esac
}

# The last lines of the daemons' logs, for an error that says why.
logs() {
  local f
  for f in "$dir"/log/*.log; do
    [ -s "$f" ] || continue
    echo "--- $f" >&2
    # slurmd's complaints about PMIx (an MPI library not installed) are noise here.
    grep -v -e 'pmix' -e 'MPI: Cannot create context' "$f" | tail -n 8 >&2
  done
}

# Ends the daemons named (NAME.pid in $dir), waiting for them (up to 10 s)
# so that a start right after finds the ports free.  Each takes about 2 s
# to exit after SIGTERM, so all are signalled first and then waited for.
end() {
  local name pid pids=()
  for name in "$@"; do
    if pid=$(alive "$dir/$name.pid" "$name"); then kill "$pid" 2>/dev/null; pids+=("$pid:$name"); fi
    rm -f "$dir/$name.pid"
  done
  for _ in $(seq 100); do
    local left=0
    for pid in "${pids[@]}"; do [ -d "/proc/${pid%%:*}" ] && left=1; done
    [ "$left" = 0 ] && return 0
    sleep 0.1
  done
  for pid in "${pids[@]}"; do
    if [ -d "/proc/${pid%%:*}" ]; then say "${pid#*:} (${pid%%:*}) still running after 10 s: killing it"; kill -9 "${pid%%:*}" 2>/dev/null; fi
  done
}

write_conf() {
  local host=$1 cpus=$2
  cat >"$conf" <<EOF
# Written by tools/slurm-local.sh: one node, this machine ($host), for tests.
ClusterName=raylocal
# The address is given so that nothing depends on what $host resolves to.
SlurmctldHost=$host(127.0.0.1)
SlurmctldPort=$ctld_port
SlurmdPort=$d_port
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$dir/munge/socket
StateSaveLocation=$dir/spool/ctld
SlurmdSpoolDir=$dir/spool/d
SlurmctldPidFile=$dir/slurmctld.pid
SlurmdPidFile=$dir/slurmd.pid
SlurmctldLogFile=$dir/log/slurmctld.log
SlurmdLogFile=$dir/log/slurmd.log
# No systemd, no cgroup delegation: processes found through /proc, tasks not confined.
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
# No accounting database.
AccountingStorageType=accounting_storage/none
JobAcctGatherType=jobacct_gather/none
JobCompType=jobcomp/none
MpiDefault=none
# A job whose dependency failed (the merge after a failed tile) is cancelled
# rather than left pending for ever; and jobs are started as soon as CPUs
# are free, not in passes 3 s apart (batch_sched_delay's default), since a
# test's jobs take a second each.
DependencyParameters=kill_invalid_depend
SchedulerParameters=batch_sched_delay=0,sched_min_interval=100000
# The node comes back by itself after a restart of the daemons.
ReturnToService=2
NodeName=$host NodeAddr=127.0.0.1 CPUs=$cpus State=UNKNOWN
PartitionName=local Nodes=$host Default=YES MaxTime=INFINITE State=UP
EOF
}

start() {
  local p host cpus
  if up; then say "already running ($conf)"; return 0; fi
  [ "$(id -u)" = 0 ] || die "must run as root: slurmd starts each job as its user"
  for p in munged munge unmunge slurmctld slurmd sinfo sbatch squeue scontrol; do
    command -v "$p" >/dev/null || die "$p not found: install slurm-wlm and munge (apt-get install slurm-wlm munge)"
  done
  # Half up (a daemon died, or a stop was interrupted): start from nothing.
  stop_daemons
  host=$(hostname -s 2>/dev/null) || die "hostname -s failed"
  [ -n "$host" ] || die "hostname -s printed nothing"
  cpus=$(nproc)
  # munged insists: its key readable by its user alone, the socket's
  # directory searchable by all (every job's user must reach it).
  mkdir -p "$dir/key" "$dir/munge" "$dir/log" || die "cannot create $dir"
  chmod 755 "$dir" "$dir/munge" && chmod 700 "$dir/key" || die "cannot set permissions under $dir"
  if [ ! -s "$dir/key/munge.key" ]; then
    head -c 1024 /dev/urandom >"$dir/key/munge.key" && chmod 400 "$dir/key/munge.key" || die "cannot write the munge key"
  fi
  # Jobs of an earlier cluster are not wanted back.
  rm -rf "$dir/spool" && mkdir -p "$dir/spool/ctld" "$dir/spool/d" || die "cannot create $dir/spool"
  write_conf "$host" "$cpus" || die "cannot write $conf"

  munged --key-file="$dir/key/munge.key" --socket="$dir/munge/socket" --pid-file="$dir/munged.pid" \
    --log-file="$dir/log/munged.log" --seed-file="$dir/key/munged.seed" 2>>"$dir/log/munged.log" \
    || { logs; die "munged did not start"; }
  munge -S "$dir/munge/socket" -n 2>/dev/null | unmunge -S "$dir/munge/socket" >/dev/null 2>&1 \
    || { logs; stop_daemons; die "munged started but a credential does not decode"; }

  slurmctld -f "$conf" 2>>"$dir/log/slurmctld.log" || { logs; stop_daemons; die "slurmctld did not start"; }
  slurmd -f "$conf" -N "$host" 2>>"$dir/log/slurmd.log" || { logs; stop_daemons; die "slurmd did not start"; }

  # The node registers within a second or two; 30 s before giving up.
  for _ in $(seq 150); do
    case $(node_state) in idle) say "up: node $host, $cpus CPUs, partition local; SLURM_CONF=$conf"; return 0;; esac
    sleep 0.2
  done
  say "the node did not become idle in 30 s (sinfo: '$(node_state)')"
  logs
  stop_daemons
  exit 1
}

stop_daemons() { end slurmd slurmctld munged; }

stop() {
  # Running jobs would go on without the daemons: cancel them first.
  if alive "$dir/slurmctld.pid" slurmctld >/dev/null; then
    scancel --full -u "$(id -un)" 2>/dev/null
    for _ in $(seq 50); do [ -z "$(squeue -h 2>/dev/null)" ] && break; sleep 0.2; done
  fi
  stop_daemons
  rm -rf "$dir/spool"
  say "stopped"
}

cmd_env() { printf 'export SLURM_CONF=%q\n' "$conf"; }

case ${1:-} in
  start) start;;
  stop) stop;;
  status) if up; then say "up ($conf)"; else say "down"; exit 1; fi;;
  env) cmd_env;;
  *) echo "usage: $0 start|stop|status|env" >&2; exit 2;;
esac
