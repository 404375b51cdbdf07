#!/usr/bin/env bash
# The Slurm job array of deploy/slurm/submit_bricks.sh on a one-node cluster this test starts
# (munged, slurmctld and slurmd from Debian, in a temporary folder, on free ports): the plan,
# the bricks as array tasks and the merge after them give the mesh and report of one process.
# Skips (77) with the reason where Slurm or munge is not installed or will not start.
# Usage: slurm_bricks_test.sh SHEETMESH_PIPELINE REPO_DIR
set -euo pipefail
cli=$(realpath "$1")
repo=$(realpath "$2")
for p in munged slurmctld slurmd sbatch squeue sinfo scontrol; do
  if ! command -v "$p" >/dev/null; then
    echo "SKIP: $p is not installed (Debian: munge, slurmctld, slurmd, slurm-client)"
    exit 77
  fi
done
dir=$(mktemp -d /tmp/sheetmesh_slurm.XXXXXX)
export SLURM_CONF=$dir/slurm.conf
stop() {
  scontrol shutdown >/dev/null 2>&1 || true
  [ -f "$dir/slurmd.pid" ] && kill "$(cat "$dir/slurmd.pid")" 2>/dev/null || true
  [ -f "$dir/slurmctld.pid" ] && kill "$(cat "$dir/slurmctld.pid")" 2>/dev/null || true
  [ -f "$dir/munged.pid" ] && kill "$(cat "$dir/munged.pid")" 2>/dev/null || true
  sleep 1
  rm -rf "$dir"
}
trap stop EXIT
skip() {
  echo "SKIP: $1"
  for f in munged slurmctld slurmd; do [ -f "$dir/$f.log" ] && tail -5 "$dir/$f.log"; done
  exit 77
}

# munge: its own key and socket.
head -c 1024 /dev/urandom > "$dir/munge.key"
chmod 400 "$dir/munge.key"
munged -f --key-file="$dir/munge.key" --socket="$dir/munge.socket" --pid-file="$dir/munged.pid" \
  --log-file="$dir/munged.log" --seed-file="$dir/munged.seed" || skip "munged did not start"

read -r ctld_port slurmd_port < <(/usr/bin/python3 -c '
import socket
s = [socket.socket() for _ in range(2)]
for x in s: x.bind(("127.0.0.1", 0))
print(*[x.getsockname()[1] for x in s])')
host=$(hostname)
mem=$(awk '/MemTotal/ {print int($2 / 1024 / 2)}' /proc/meminfo)
mkdir -p "$dir/state" "$dir/spool"
user=$(id -un)
cat > "$SLURM_CONF" <<CONF
ClusterName=sheetmeshtest
SlurmctldHost=$host
AuthType=auth/munge
AuthInfo=socket=$dir/munge.socket
CredType=cred/munge
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SwitchType=switch/none
MpiDefault=none
SlurmUser=$user
SlurmdUser=root
SlurmctldPort=$ctld_port
SlurmdPort=$slurmd_port
SlurmctldPidFile=$dir/slurmctld.pid
SlurmdPidFile=$dir/slurmd.pid
SlurmdSpoolDir=$dir/spool
StateSaveLocation=$dir/state
SchedulerType=sched/backfill
SelectType=select/cons_tres
SelectTypeParameters=CR_Core_Memory
ReturnToService=2
JobCompType=jobcomp/none
AccountingStorageType=accounting_storage/none
JobAcctGatherType=jobacct_gather/none
SlurmctldLogFile=$dir/slurmctld.log
SlurmdLogFile=$dir/slurmd.log
NodeName=$host CPUs=$(nproc) RealMemory=$mem State=UNKNOWN
PartitionName=test Nodes=ALL Default=YES MaxTime=INFINITE State=UP
CONF
slurmctld -i || skip "slurmctld did not start"
slurmd || skip "slurmd did not start (it runs as root)"
for _ in $(seq 30); do
  sinfo -h -o %t 2>/dev/null | grep -q idle && break
  sleep 1
done
sinfo -h -o %t | grep -q idle || skip "the node did not come up: $(sinfo 2>&1 | tail -1)"

# The volume, and the one-process run to compare with.
"$cli" phantom --preset=sample -o "$dir/sample_128x112x96_u8.raw" >/dev/null
flags=(--r=5 --output_previews=false --unit=um --spacing=5,5,6)
"$cli" run "$dir/sample_128x112x96_u8.raw" -o "$dir/one" "${flags[@]}" >/dev/null 2>&1

SHEETMESH_PIPELINE=$cli BRICK_SIZE=48x40x64 BRICK_MEM=300M MERGE_MEM=2G \
  "$repo/deploy/slurm/submit_bricks.sh" "$dir/sample_128x112x96_u8.raw" "$dir/merged" \
  "${flags[@]}" | tee "$dir/submitted"
merge=$(sed -n 's/.*merge \([0-9]*\).*/\1/p' "$dir/submitted")
for _ in $(seq 300); do
  squeue -h -j "$merge" 2>/dev/null | grep -q . || break
  sleep 1
done
if [ ! -f "$dir/merged/report.json" ]; then
  echo "FAIL: the merge wrote no report"
  cat "$dir/merged.merge.log" "$dir"/merged.plan/logs/*.log 2>/dev/null | tail -20
  exit 1
fi
bricks=$(ls "$dir/merged.plan/bricks" | grep -c '\.bin$')
[ "$bricks" -eq 18 ] || { echo "FAIL: $bricks brick files, not 18"; exit 1; }
cmp "$dir/one/surface.ply" "$dir/merged/surface.ply" || {
  echo "FAIL: the array's surface differs from one process's"
  exit 1
}
/usr/bin/python3 - "$dir/one/report.json" "$dir/merged/report.json" <<'PY'
import json, sys
def clean(v):
    if isinstance(v, dict):
        return {k: clean(x) for k, x in v.items()
                if k not in ("timings", "seconds", "path", "dir") and not k.endswith("_seconds")}
    if isinstance(v, list):
        return [clean(x) for x in v]
    return v
a, b = (clean(json.load(open(p))) for p in sys.argv[1:])
bad = [k for k in set(a) | set(b) if a.get(k) != b.get(k)]
if bad:
    sys.exit("FAIL: the reports differ in %s" % bad)
PY
echo "PASS: 18 bricks as a Slurm array, merged: the same surface and report as one process"
