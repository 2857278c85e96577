#!/usr/bin/env bash
# A real single-node Slurm (Debian's slurmctld, slurmd, munge; scripts/setup --slurm) on this
# machine: `clothbake batch --emit slurm` for three small fabrics, sbatch, wait, and the assets
# must be byte-identical to local bakes of the same files. Exit 77 (skipped) when Slurm is not
# installed or its daemons cannot start here. Usage: slurm_single_node.sh CLOTHBAKE
set -euo pipefail
exe="$1"
for tool in slurmctld slurmd munged sbatch squeue; do
  command -v "$tool" >/dev/null 2>&1 || [[ -x /usr/sbin/$tool ]] || { echo "no $tool: skipped"; exit 77; }
done
work=$(mktemp -d /tmp/clothbake-slurm-XXXXXX)
pids=()
cleanup() {
  for f in "$work"/slurmctld.pid "$work"/slurmd.pid; do
    [[ -f "$f" ]] && pids+=("$(cat "$f")")
  done
  for p in "${pids[@]}"; do kill "$p" 2>/dev/null || true; done
  for p in "${pids[@]}"; do  # the daemons write their state on the way out
    for _ in $(seq 50); do kill -0 "$p" 2>/dev/null || break; sleep 0.1; done
  done
  rm -rf "$work"
}
trap cleanup EXIT
mkdir -p "$work"/{state,spool,log,lib,munge}
host=$(hostname -s)
port=$(( 20000 + $$ % 20000 ))
mem=$(( $(awk '/MemTotal/{print $2}' /proc/meminfo) / 1024 - 512 ))
# munge: reuse a running munged, else start one with its own key and socket.
if ! munge -n 2>/dev/null | unmunge >/dev/null 2>&1; then
  dd if=/dev/urandom of="$work/munge/munge.key" bs=1024 count=1 status=none
  chmod 400 "$work/munge/munge.key"
  /usr/sbin/munged --force --key-file="$work/munge/munge.key" --socket="$work/munge/socket" \
    --pid-file="$work/munge/pid" --log-file="$work/munge/log" --seed-file="$work/munge/seed" ||
    { echo "munged cannot start: skipped"; exit 77; }
  pids+=("$(cat "$work/munge/pid")")
  socket="AuthInfo=socket=$work/munge/socket"
else
  socket=""
fi
cat > "$work/slurm.conf" <<CONF
ClusterName=clothbake-test
SlurmctldHost=$host
SlurmUser=$(id -un)
SlurmctldPort=$port
SlurmdPort=$((port + 1))
AuthType=auth/munge
$socket
StateSaveLocation=$work/state
SlurmdSpoolDir=$work/spool
SlurmctldPidFile=$work/slurmctld.pid
SlurmdPidFile=$work/slurmd.pid
SlurmctldLogFile=$work/log/slurmctld.log
SlurmdLogFile=$work/log/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core_Memory
ReturnToService=2
JobAcctGatherType=jobacct_gather/none
NodeName=$host CPUs=$(nproc) RealMemory=$mem State=UNKNOWN
PartitionName=test Nodes=$host Default=YES MaxTime=INFINITE State=UP
CONF
export SLURM_CONF="$work/slurm.conf"
/usr/sbin/slurmctld -f "$SLURM_CONF" || { echo "slurmctld cannot start: skipped"; exit 77; }
/usr/sbin/slurmd -f "$SLURM_CONF" || { echo "slurmd cannot start: skipped"; exit 77; }
for _ in $(seq 60); do sinfo -h -o %T 2>/dev/null | grep -q idle && break; sleep 1; done
sinfo -h -o %T | grep -q idle || { echo "the node never became idle"; cat "$work"/log/*.log; exit 1; }

for w in plain twill2/1 satin5; do
  printf '[weave]\nname = "%s"\n[bake]\nresolution = 16\nparallax_dirs = 4\nvisibility_dirs = 4\nradiance_dirs = 6\nclusters = 2\n' \
    "$w" > "$work/lib/${w//\//}.toml"
done
"$exe" batch "$work/lib" -o "$work/out" --emit slurm --json > "$work/emit.json"
job=$(sbatch --parsable "$work/out/clothbake-batch.sbatch")
for _ in $(seq 300); do [[ -z "$(squeue -h -j "$job" 2>/dev/null)" ]] && break; sleep 1; done
[[ -z "$(squeue -h -j "$job")" ]] || { echo "job $job did not finish"; exit 1; }
status=0
# One array task per fabric: each writes its own log (#SBATCH --output=...slurm-%A_%a.log).
for task in 0 1 2; do
  [[ -f "$work/out/.clothbake-batch/slurm-${job}_${task}.log" ]] ||
    { echo "array task $task of job $job left no log: not run as a job array"; ls -la "$work/out/.clothbake-batch"; status=1; }
done
for name in plain twill21 satin5; do
  "$exe" bake "$work/lib/$name.toml" -o "$work/local-$name.cbk" --quiet
  if cmp -s "$work/out/$name.cbk" "$work/local-$name.cbk"; then
    echo "$name: Slurm asset identical to the local bake"
  else
    echo "$name: Slurm asset differs or is missing"; cat "$work"/out/.clothbake-batch/slurm-*.log || true
    status=1
  fi
done
exit $status
