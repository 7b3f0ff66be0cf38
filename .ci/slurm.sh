#!/usr/bin/env bash
# Sharded sweeps on a real Slurm: a throw-away single-node cluster on this machine.
#
#   bash .ci/slurm.sh path/to/granflow
#
# 1. Installs Debian's slurm-wlm and munge when they are missing (needs root).
# 2. Starts, from a temporary directory and as daemons of this script only: munged (as
#    the munge user, own key and socket), slurmctld and slurmd (node and controller at
#    127.0.0.1, proctrack/linuxproc, task/none, no accounting).
# 3. Submits scenarios/sweeps/slopes.toml (coarse grid) as a 2-task job array, each task
#    running `granflow sweep --shard $SLURM_ARRAY_TASK_ID/2`, and waits for it.
# 4. Merges the shards (`granflow sweep merge`) and checks that the merged summary equals
#    a local, unsharded run of the same sweep: every column but wall_time_s identical.
# 5. Stops the daemons it started (by PID, on any exit) and removes the directory.
#
# Environment: SLURM_CI_PORT (first slurmctld port tried, default 16817; slurmd uses the
# next one; ports in use are skipped),
# SLURM_CI_KEEP=1 keeps the temporary directory (logs) for inspection.
set -euo pipefail
shopt -s inherit_errexit

if [[ $# -ne 1 ]]; then
    echo "usage: $0 path/to/granflow" >&2
    exit 2
fi
BIN=$(realpath "$1")
REPO=$(cd "$(dirname "$0")/.." && pwd)
SWEEP=$REPO/scenarios/sweeps/slopes.toml
SETS=(--set domain.cells=200)
SHARDS=2
PORT=${SLURM_CI_PORT:-16817} # first port tried; moved up while taken (another cluster)
START=$(date +%s)

log() { echo "[slurm-ci $(($(date +%s) - START))s] $*"; }
die() {
    echo "[slurm-ci] FAILED: $*" >&2
    exit 1
}

[[ -x $BIN ]] || die "$BIN is not an executable"
[[ $(id -u) -eq 0 ]] || die "needs root (installs packages, runs the Slurm daemons)"

# --- 1. packages -------------------------------------------------------------------
if ! command -v slurmctld >/dev/null || ! command -v slurmd >/dev/null ||
    ! command -v sbatch >/dev/null || ! command -v munged >/dev/null; then
    log "installing slurm-wlm and munge"
    # Keep package scripts from starting the system's own services while installing.
    made_policy=
    if [[ ! -e /usr/sbin/policy-rc.d ]]; then
        printf '#!/bin/sh\nexit 101\n' >/usr/sbin/policy-rc.d
        chmod 755 /usr/sbin/policy-rc.d
        made_policy=1
    fi
    export DEBIAN_FRONTEND=noninteractive
    installed=0
    apt-get update -qq && apt-get install -y -qq slurm-wlm munge >/dev/null && installed=1
    [[ -n $made_policy ]] && rm -f /usr/sbin/policy-rc.d
    [[ $installed -eq 1 ]] || die "apt-get install slurm-wlm munge failed"
fi
id munge >/dev/null 2>&1 || die "no munge user (the munge package creates it)"

# --- 2. daemons ----------------------------------------------------------------------
T=$(mktemp -d /tmp/granflow-slurm-ci.XXXXXX)
chmod 755 "$T" # munged (as munge) must reach its own directory below
PIDS=()        # daemons started here, stopped on exit

cleanup() {
    local code=$?
    for pid in "${PIDS[@]}"; do
        kill "$pid" 2>/dev/null || true
    done
    for pid in "${PIDS[@]}"; do
        for _ in $(seq 50); do
            kill -0 "$pid" 2>/dev/null || break
            sleep 0.1
        done
        kill -9 "$pid" 2>/dev/null || true
    done
    if [[ $code -ne 0 ]]; then
        for f in "$T"/*.log "$T"/job-*.out; do
            [[ -f $f ]] || continue
            echo "----- $f (last lines)" >&2
            tail -n 20 "$f" >&2
        done
    fi
    if [[ ${SLURM_CI_KEEP:-0} == 1 ]]; then
        echo "[slurm-ci] kept $T" >&2
    else
        rm -rf "$T"
    fi
    echo "[slurm-ci] $([[ $code -eq 0 ]] && echo PASSED || echo FAILED) in $(($(date +%s) - START)) s" >&2
    exit "$code"
}
trap cleanup EXIT
trap 'exit 130' INT TERM

# Waits for a PID file written by a daemon; echoes the PID.
pid_from() {
    local file=$1
    for _ in $(seq 100); do
        if [[ -s $file ]] && kill -0 "$(cat "$file")" 2>/dev/null; then
            cat "$file"
            return 0
        fi
        sleep 0.1
    done
    return 1
}

log "munged (own key in $T/munge, socket in $T/munge-run)"
mkdir -p "$T/munge" "$T/munge-run"
dd if=/dev/urandom of="$T/munge/munge.key" bs=1024 count=1 status=none
chown -R munge:munge "$T/munge" "$T/munge-run"
chmod 700 "$T/munge"
chmod 755 "$T/munge-run" # clients need to reach the socket
chmod 400 "$T/munge/munge.key"
MUNGE_SOCKET=$T/munge-run/munge.socket
runuser -u munge -- munged \
    --socket="$MUNGE_SOCKET" --key-file="$T/munge/munge.key" \
    --pid-file="$T/munge/munged.pid" --log-file="$T/munge/munged.log" \
    --seed-file="$T/munge/munged.seed" ||
    die "munged did not start: $(tail -n 5 "$T/munge/munged.log" 2>/dev/null)"
PIDS+=("$(pid_from "$T/munge/munged.pid")") || die "munged wrote no PID"
munge --socket="$MUNGE_SOCKET" -n | unmunge --socket="$MUNGE_SOCKET" >/dev/null ||
    die "munge round trip failed"

# Two free ports (slurmctld, slurmd), so that several copies of this script can run.
port_taken() { (exec 3<>"/dev/tcp/127.0.0.1/$1") 2>/dev/null; }
for _ in $(seq 50); do
    port_taken "$PORT" || port_taken $((PORT + 1)) || break
    PORT=$((PORT + 2))
done
HOST=$(hostname -s)
CPUS=$(nproc)
mkdir -p "$T/state" "$T/spool"
export SLURM_CONF=$T/slurm.conf
cat >"$SLURM_CONF" <<EOF
ClusterName=granflowci
SlurmctldHost=$HOST(127.0.0.1)
SlurmctldPort=$PORT
SlurmdPort=$((PORT + 1))
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$MUNGE_SOCKET
StateSaveLocation=$T/state
SlurmdSpoolDir=$T/spool
SlurmctldPidFile=$T/slurmctld.pid
SlurmdPidFile=$T/slurmd.pid
SlurmctldLogFile=$T/slurmctld.log
SlurmdLogFile=$T/slurmd.log
SlurmctldDebug=info
SlurmdDebug=info
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
SchedulerType=sched/backfill
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
ReturnToService=2
MpiDefault=none
SlurmdTimeout=30
InactiveLimit=0
MinJobAge=30
NodeName=$HOST NodeAddr=127.0.0.1 CPUs=$CPUS RealMemory=512 State=UNKNOWN
PartitionName=ci Nodes=$HOST Default=YES MaxTime=INFINITE State=UP
EOF

log "slurmctld and slurmd ($HOST at 127.0.0.1, ports $PORT/$((PORT + 1)), $CPUS CPUs)"
slurmctld -i -f "$SLURM_CONF" || die "slurmctld did not start"
PIDS+=("$(pid_from "$T/slurmctld.pid")") || die "slurmctld wrote no PID"
slurmd -N "$HOST" -f "$SLURM_CONF" || die "slurmd did not start"
PIDS+=("$(pid_from "$T/slurmd.pid")") || die "slurmd wrote no PID"

state=
for _ in $(seq 120); do
    state=$(sinfo -h -N -n "$HOST" -o %T 2>/dev/null || true)
    [[ $state == idle ]] && break
    if [[ $state == down* || $state == drain* ]]; then
        scontrol update NodeName="$HOST" State=RESUME 2>/dev/null || true
    fi
    sleep 0.5
done
[[ $state == idle ]] || die "node $HOST is '$state', not idle"
log "node $HOST idle"

# --- 3. the sweep as a job array -----------------------------------------------------
OUT=$T/sharded
LOCAL=$T/local
cat >"$T/array.sh" <<EOF
#!/bin/bash
#SBATCH --job-name=granflow-sweep
#SBATCH --array=0-$((SHARDS - 1))
#SBATCH --ntasks=1
#SBATCH --cpus-per-task=1
#SBATCH --output=$T/job-%A_%a.out
set -euo pipefail
"$BIN" sweep "$SWEEP" ${SETS[*]} --output "$OUT" --jobs 1 \\
    --shard "\$SLURM_ARRAY_TASK_ID/$SHARDS"
EOF
log "sbatch --wait --array=0-$((SHARDS - 1))"
(cd "$T" && sbatch --wait --parsable "$T/array.sh") >"$T/sbatch.out" 2>&1 ||
    die "array job failed: $(cat "$T/sbatch.out")"
job=$(head -n 1 "$T/sbatch.out")
log "array job $job done"
for k in $(seq 0 $((SHARDS - 1))); do
    [[ -f $OUT/summary.shard-$k-of-$SHARDS.csv ]] || die "shard $k wrote no summary"
    grep -q "runs" "$T/job-${job}_$k.out" || die "no output from task $k"
done

# --- 4. merge and compare with a local run --------------------------------------------
"$BIN" sweep merge "$OUT" -q || die "granflow sweep merge failed"
"$BIN" sweep "$SWEEP" "${SETS[@]}" --output "$LOCAL" -q || die "local sweep failed"

# Drops the wall_time_s column (found by name in the header).
strip_wall() {
    awk -F, 'NR == 1 { for (i = 1; i <= NF; i++) if ($i == "wall_time_s") w = i }
             { out = ""; for (i = 1; i <= NF; i++) if (i != w) out = out (out == "" ? "" : ",") $i; print out }' "$1"
}
rows=$(($(wc -l <"$LOCAL/summary.csv") - 1))
[[ $rows -ge 2 ]] || die "local summary has $rows rows"
if ! diff <(strip_wall "$OUT/summary.csv") <(strip_wall "$LOCAL/summary.csv") >"$T/diff.txt"; then
    die "merged summary differs from the local run: $(cat "$T/diff.txt")"
fi
log "merged summary of $rows runs from $SHARDS Slurm tasks equals the local run"
cat "$OUT/summary.csv"
