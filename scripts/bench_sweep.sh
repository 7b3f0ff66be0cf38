#!/usr/bin/env bash
# Sweep throughput: the same sweep with --jobs 1 and --jobs 2 (or JOBS), best of REPEAT.
#
#   scripts/bench_sweep.sh [path/to/granflow]      (default: builds target/release)
#
# Two sweeps of the collapse scenario (scenarios/collapse.toml):
#   uniform:  8 runs of equal cost (slope 22°, 8 erodible-bed thicknesses, fixed end
#             time 1 s, 4000 cells), the pure throughput case;
#   paper:    scenarios/sweeps/erodible_bed.toml (12 runs of unequal length, each to
#             rest) at 3000 cells.
# Prints wall times, runs per second and the speed-up, plus the machine and its load
# (other processes on the machine distort the numbers; run it on an idle machine).
set -euo pipefail
shopt -s inherit_errexit
cd "$(dirname "$0")/.."
REPEAT=${REPEAT:-3}
JOBS=${JOBS:-2}
if [[ $# -ge 1 ]]; then
    BIN=$(realpath "$1")
else
    cargo build --release --quiet
    BIN=$(realpath "${CARGO_TARGET_DIR:-target}/release/granflow")
fi
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

cat >"$work/uniform.toml" <<TOML
scenario = "$PWD/scenarios/collapse.toml"
set = ["domain.cells=4000", "time.t_end=1.0", "time.stop_at_rest=false", "output.every=0.25"]
[axes]
initial.erodible_bed = [0, 0.5e-3, 1e-3, 1.5e-3, 2e-3, 2.5e-3, 3e-3, 3.5e-3]
TOML

# Best wall time (s) of REPEAT runs of: granflow sweep FILE --jobs J --force -q ARGS…
best() {
    local jobs=$1 file=$2; shift 2
    local best=
    for _ in $(seq "$REPEAT"); do
        local t0 t1
        t0=$(date +%s.%N)
        "$BIN" sweep "$file" --output "$work/out" --jobs "$jobs" --force -q "$@" >/dev/null
        t1=$(date +%s.%N)
        best=$(python3 -c "t=$t1-$t0; b='$best'; print(min(t, float(b)) if b else t)")
    done
    echo "$best"
}

echo "machine: $(nproc) CPUs, $(lscpu | sed -n 's/^Model name: *//p'), load average before: $(cut -d' ' -f1-3 /proc/loadavg)"
report() {
    local name=$1 runs=$2; shift 2
    local t1 tn
    t1=$(best 1 "$@")
    tn=$(best "$JOBS" "$@")
    python3 - "$name" "$runs" "$t1" "$tn" "$JOBS" <<'PY'
import sys
name, runs, t1, tn, jobs = sys.argv[1], int(sys.argv[2]), float(sys.argv[3]), float(sys.argv[4]), sys.argv[5]
print(f"{name:8s} {runs:3d} runs  --jobs 1: {t1:7.2f} s ({runs/t1:6.2f} runs/s)  "
      f"--jobs {jobs}: {tn:7.2f} s ({runs/tn:6.2f} runs/s)  speed-up {t1/tn:4.2f}x")
PY
}
report uniform 8 "$work/uniform.toml"
report paper 12 scenarios/sweeps/erodible_bed.toml --set domain.cells=3000
echo "load average after: $(cut -d' ' -f1-3 /proc/loadavg)"
