#!/usr/bin/env bash
# The scale-out path of `vio sweep` on a real Slurm: starts a single-node
# cluster on this machine (munged + slurmctld + slurmd from Debian's
# slurm-wlm and munge, a generated slurm.conf, free ports, everything in a
# temporary folder), simulates a short flight, submits the job array that
# `vio sweep --emit_jobs` writes with sbatch, waits for it, collects the
# table with --collect_only, and checks that results.csv equals a local
# sweep's in every column that does not measure time or memory.
#
# usage: tools/slurm_check.sh [--vio=PATH] [--keep]
#   --vio   the vio binary (default: build/bin/vio)
#   --keep  keep the temporary folder (logs, slurm.conf, both sweeps)
# Exit: 0 passed, 1 failed, 77 skipped (not root, Slurm or munge not
# installed: `tools/install_deps.sh slurm`, or the daemons do not start).
# Install what it needs first with INSTALL=1 (tools/install_deps.sh slurm).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
vio="$root/build/bin/vio"
keep=0
for arg in "$@"; do
  case "$arg" in
    --vio=*) vio="${arg#--vio=}" ;;
    --keep) keep=1 ;;
    *) echo "slurm_check: unknown argument '$arg' (usage: slurm_check.sh [--vio=PATH] [--keep])" >&2; exit 2 ;;
  esac
done

skip() { echo "slurm_check: SKIPPED: $*" >&2; exit 77; }
fail() { echo "slurm_check: FAILED: $*" >&2; exit 1; }
say() { echo "slurm_check: $*"; }

[ -x "$vio" ] || fail "no vio binary at $vio (build it: tools/build.sh vio, or give --vio=PATH)"
[ "$(id -u)" -eq 0 ] || skip "needs root to start slurmd and munged"
[ "${INSTALL:-0}" = 1 ] && "$root/tools/install_deps.sh" slurm
for tool in munged slurmctld slurmd sbatch sinfo scontrol; do
  command -v "$tool" >/dev/null || skip "'$tool' not found: install Slurm with tools/install_deps.sh slurm"
done

tmp="$(mktemp -d /tmp/vio_slurm_check.XXXXXX)"
chmod 755 "$tmp"
pids=()
cleanup() {
  for pid in "${pids[@]}"; do kill "$pid" 2>/dev/null || true; done
  for pid in "${pids[@]}"; do wait "$pid" 2>/dev/null || true; done
  if [ "$keep" -eq 1 ]; then say "kept $tmp"; else rm -rf "$tmp"; fi
}
trap cleanup EXIT

free_port() {
  /usr/bin/python3 -c 'import socket; s = socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])'
}

# munge: its own key, socket and logs in $tmp.
mkdir -p "$tmp/munge"
chmod 700 "$tmp/munge"
dd if=/dev/urandom of="$tmp/munge/munge.key" bs=1024 count=1 status=none
chmod 400 "$tmp/munge/munge.key"
munged --foreground --force --key-file="$tmp/munge/munge.key" --socket="$tmp/munge/munge.socket" \
  --pid-file="$tmp/munge/munged.pid" --log-file="$tmp/munge/munged.log" --seed-file="$tmp/munge/munge.seed" \
  > "$tmp/munge/stdout.log" 2>&1 &
pids+=($!)

host="$(hostname -s)"
cpus="$(nproc)"
mkdir -p "$tmp/state" "$tmp/spool" "$tmp/log"
cat > "$tmp/slurm.conf" <<EOF
ClusterName=viocheck
SlurmctldHost=$host(127.0.0.1)
SlurmctldPort=$(free_port)
SlurmdPort=$(free_port)
SrunPortRange=$(free_port)-$(free_port)
AuthType=auth/munge
AuthInfo=socket=$tmp/munge/munge.socket
CredType=cred/munge
SlurmUser=root
SlurmdUser=root
StateSaveLocation=$tmp/state
SlurmdSpoolDir=$tmp/spool
SlurmctldPidFile=$tmp/slurmctld.pid
SlurmdPidFile=$tmp/slurmd.pid
SlurmctldLogFile=$tmp/log/slurmctld.log
SlurmdLogFile=$tmp/log/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
SchedulerType=sched/builtin
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
MpiDefault=none
SwitchType=switch/none
ReturnToService=2
NodeName=$host NodeAddr=127.0.0.1 CPUs=$cpus RealMemory=1024 State=UNKNOWN
PartitionName=check Nodes=$host Default=YES MaxTime=INFINITE State=UP
EOF
export SLURM_CONF="$tmp/slurm.conf"

for _ in $(seq 50); do [ -S "$tmp/munge/munge.socket" ] && break; sleep 0.2; done
[ -S "$tmp/munge/munge.socket" ] || skip "munged did not start: $(tail -n 3 "$tmp/munge/munged.log" "$tmp/munge/stdout.log" 2>/dev/null)"
slurmctld -D -i -f "$SLURM_CONF" > "$tmp/log/slurmctld.stdout" 2>&1 &
pids+=($!)
slurmd -D -f "$SLURM_CONF" -N "$host" > "$tmp/log/slurmd.stdout" 2>&1 &
pids+=($!)
say "single-node Slurm starting in $tmp (node $host, $cpus CPUs)"
state=""
for _ in $(seq 60); do
  state="$(sinfo -h -n "$host" -o %T 2>/dev/null || true)"
  [ "$state" = idle ] && break
  sleep 0.5
done
if [ "$state" != idle ]; then
  skip "the node did not become idle within 30 s (state '${state:-none}'); $(tail -n 2 "$tmp/log/slurmctld.log" "$tmp/log/slurmd.log" 2>/dev/null | tr '\n' ' ')"
fi
say "node $host idle"

runs=swf:5,msckf:5,swf:10
"$vio" simulate --output_dir="$tmp/data" --duration_s=12 --seed=3 > "$tmp/simulate.log" 2>&1 ||
  fail "vio simulate: $(tail -n 5 "$tmp/simulate.log")"
sweep() { "$vio" sweep --datasets="$tmp/data" --runs="$runs" "$@"; }

sweep --output_dir="$tmp/slurm" --emit_jobs > "$tmp/emit.log"
lines="$(wc -l < "$tmp/slurm/jobs.txt")"
say "submitting $lines array tasks: sbatch --array=1-$lines --wait"
timeout 600 sbatch --parsable --wait --array="1-$lines" --output="$tmp/log/task_%a.out" --chdir="$tmp" \
  --wrap="sed -n \"\${SLURM_ARRAY_TASK_ID}p\" $tmp/slurm/jobs.txt | bash" > "$tmp/sbatch.log" 2>&1 ||
  fail "the job array failed: $(cat "$tmp/sbatch.log"; tail -n 5 "$tmp"/log/task_*.out)"
job="$(head -n 1 "$tmp/sbatch.log")"
ran="$(grep -c "_job_complete: JobId=${job}_[0-9]*([0-9]*) WEXITSTATUS 0" "$tmp/log/slurmctld.log" || true)"
[ "$ran" -eq "$lines" ] || fail "slurmctld completed $ran of the $lines array tasks with exit 0 (log: $tmp/log)"
say "job $job: slurmctld ran the $lines array tasks, each with exit 0"
sweep --output_dir="$tmp/slurm" --collect_only > "$tmp/collect.log" ||
  fail "collecting the Slurm sweep: $(tail -n 5 "$tmp/collect.log")"
sweep --output_dir="$tmp/local" --jobs=2 > "$tmp/local.log" || fail "the local sweep: $(tail -n 5 "$tmp/local.log")"

# Every column but those measuring time and memory and the run folder.
deterministic() {
  /usr/bin/python3 - "$1" <<'EOF'
import csv, sys
skip = {"ms_per_frame", "real_time_factor", "peak_memory_mb", "run_dir"}
for row in csv.DictReader(open(sys.argv[1])):
    print(",".join(f"{k}={v}" for k, v in row.items() if k not in skip))
EOF
}
if ! diff <(deterministic "$tmp/local/results.csv") <(deterministic "$tmp/slurm/results.csv") > "$tmp/diff.log"; then
  fail "results.csv of the Slurm sweep differs from the local sweep's: $(cat "$tmp/diff.log")"
fi
say "PASSED: the Slurm sweep's results.csv equals the local sweep's ($lines runs; timing columns aside)"
deterministic "$tmp/slurm/results.csv" | cut -c1-160 | sed 's/^/  /'
