#!/usr/bin/env bash
# test_sweep_slurm.sh — `taslab sweep --slurm` on a real single-node Slurm cluster of its own (ctest; DESIGN section 9).
# Starts munged (a generated key) and slurmctld + slurmd (Debian's packages, installed by scripts/setup) with their
# configuration, state and sockets in a temporary folder, submits a tiny sweep with --slurm (a job array, one task
# per run, and a dependent report job), waits for it, and checks that every frame equals that of a local --jobs 1
# sweep byte for byte and that the report exists. The daemons are stopped at the end whatever happens.
# Needs root (the daemons run as root here) and Debian's Slurm and munge: under CI (CI set) their absence fails the
# test; outside CI it skips with a message (exit 77; tests/require.sh).
# Usage: test_sweep_slurm.sh TASLAB_BINARY WORK_DIR
set -euo pipefail
taslab="$1" work="$2"
source "$(dirname "$0")/require.sh"
require "test_sweep_slurm: the Slurm test starts slurmctld, slurmd and munged and needs root" test "$(id -u)" -eq 0
for b in slurmctld slurmd munged sbatch squeue sinfo; do
  require "test_sweep_slurm: $b is not installed (run scripts/setup)" test -n "$(command -v "$b")"
done
rm -rf "$work" && mkdir -p "$work"/{state,spool,munge}
chmod 700 "$work/munge"
source "$(dirname "$0")/lsan_env.sh"
pids=()
cleanup() {
  for p in "${pids[@]}"; do kill "$p" 2>/dev/null || true; done
  for p in "${pids[@]}"; do wait "$p" 2>/dev/null || true; done
}
trap cleanup EXIT

# munge with a key of its own
dd if=/dev/urandom of="$work/munge/munge.key" bs=1024 count=1 status=none
chmod 400 "$work/munge/munge.key"
munged --foreground --force --key-file="$work/munge/munge.key" --socket="$work/munge/munge.socket" \
  --pid-file="$work/munge/munged.pid" --log-file="$work/munge/munged.log" --seed-file="$work/munge/munged.seed" \
  >"$work/munged.out" 2>&1 &
pids+=($!)
for _ in $(seq 50); do [ -S "$work/munge/munge.socket" ] && break; sleep 0.1; done

host=$(hostname -s)
port=$(( 20000 + RANDOM % 20000 ))
cat >"$work/slurm.conf" <<CONF
ClusterName=taslabtest
SlurmctldHost=$host(127.0.0.1)
SlurmctldPort=$port
SlurmdPort=$((port + 1))
AuthType=auth/munge
AuthInfo=socket=$work/munge/munge.socket
CredType=cred/munge
SlurmUser=root
SlurmdUser=root
StateSaveLocation=$work/state
SlurmdSpoolDir=$work/spool
SlurmctldPidFile=$work/slurmctld.pid
SlurmdPidFile=$work/slurmd.pid
SlurmctldLogFile=$work/slurmctld.log
SlurmdLogFile=$work/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
SchedulerType=sched/backfill
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
MpiDefault=none
ReturnToService=2
NodeName=$host NodeAddr=127.0.0.1 CPUs=$(nproc) RealMemory=1000 State=UNKNOWN
PartitionName=debug Nodes=$host Default=YES MaxTime=INFINITE State=UP
CONF
export SLURM_CONF="$work/slurm.conf"
slurmctld -D -i -f "$SLURM_CONF" >"$work/slurmctld.out" 2>&1 &
pids+=($!)
slurmd -D -f "$SLURM_CONF" -N "$host" >"$work/slurmd.out" 2>&1 &
pids+=($!)
state=""
for _ in $(seq 150); do
  state=$(sinfo -h -o %t 2>/dev/null || true)
  [ "$state" = idle ] && break
  sleep 0.2
done
[ "$state" = idle ] || { echo "the cluster did not come up (node state '$state'):"; tail -5 "$work"/slurm*.log; exit 1; }
echo "cluster up: node $host idle"

args=(--scenes turntable --cameras orbit --variants ref,tfr@8,rrc/4 --frames 0:3 --size 48x32 --device lavapipe --validation)
"$taslab" sweep "${args[@]}" --out "$work/cluster" --slurm --slurm-opts "--time=10 --job-name=taslab-test" >"$work/submit.out"
echo "submitted: $(tr '\n' ' ' <"$work/submit.out")"
for _ in $(seq 600); do
  [ -z "$(squeue -h 2>/dev/null)" ] && [ -f "$work/cluster/report/index.html" ] && break
  sleep 0.5
done
[ -f "$work/cluster/report/index.html" ] || { echo "no report after the jobs:"; squeue; tail -n 20 "$work"/cluster/slurm/logs/* || true; exit 1; }
ls "$work"/cluster/slurm/logs/run-*_*.out >/dev/null || { echo "no array task ran"; exit 1; }
echo "cluster sweep done: $(ls "$work"/cluster/slurm/logs | wc -l) job logs"

"$taslab" sweep "${args[@]}" --out "$work/local" --jobs 1 --quiet >/dev/null
n=0
for f in "$work"/local/runs/turntable/orbit/*/frames/*; do
  g="$work/cluster/${f#"$work/local/"}"
  cmp -s "$f" "$g" || { echo "differs: $f vs $g"; exit 1; }
  n=$((n + 1))
done
[ "$n" -eq 18 ] || { echo "expected 18 frame files (3 runs x 3 frames x EXR+PNG), compared $n"; exit 1; }
for f in summary.csv table1.md report/index.html clips/turntable/orbit/tfr-T8.webm metrics/turntable/orbit/rrc-N4/summary.json; do
  [ -f "$work/cluster/$f" ] || { echo "missing on the cluster side: $f"; exit 1; }
done
echo "frames equal byte for byte ($n files), report present"
echo "1 passed, 0 failed"
