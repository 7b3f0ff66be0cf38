#!/usr/bin/env bash
# Sweep throughput: the same sweep with --jobs 1 and --jobs 2 (or JOBS).
#
#   scripts/bench_sweep.sh [path/to/granflow]      (default: builds the release binary)
#
# Two sweeps of the collapse scenario (scenarios/collapse.toml):
#   uniform:  8 runs of about equal cost (slope 22°, erodible beds 0.5 to 4 mm, fixed
#             end time 1 s, 3000 cells): pure throughput;
#   paper:    scenarios/sweeps/erodible_bed.toml (12 runs of unequal length, each to
#             rest) at 3000 cells.
# Each repetition times --jobs 1 then --jobs JOBS back to back (interleaved, so both see
# the same machine), REPEAT times. Prints the fastest and the median wall time of each,
# runs per second and the speed-up. Other processes on the machine lower and scatter
# the numbers: the fastest repetition is the least disturbed one. Needs python3.
# CASES="uniform paper" (default) selects the sweeps.
set -euo pipefail
shopt -s inherit_errexit
cd "$(dirname "$0")/.."
REPEAT=${REPEAT:-5}
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
set = ["domain.cells=3000", "time.t_end=1.0", "time.stop_at_rest=false", "output.every=0.25"]
[axes]
initial.erodible_bed = [0.5e-3, 1e-3, 1.5e-3, 2e-3, 2.5e-3, 3e-3, 3.5e-3, 4e-3]
TOML

# Wall time (s) of: granflow sweep FILE --jobs J --force -q ARGS…
timed() {
    local jobs=$1 file=$2
    shift 2
    local t0 t1
    t0=$(date +%s.%N)
    "$BIN" sweep "$file" --output "$work/out-$jobs" --jobs "$jobs" --force -q "$@" >/dev/null
    t1=$(date +%s.%N)
    python3 -c "print($t1 - $t0)"
}

echo "machine: $(nproc) CPUs, $(lscpu | sed -n 's/^Model name: *//p'), $(uname -sr)"
echo "load average before: $(cut -d' ' -f1-3 /proc/loadavg)"
report() {
    local name=$1 runs=$2
    shift 2
    local one=() many=()
    for _ in $(seq "$REPEAT"); do
        one+=("$(timed 1 "$@")")
        many+=("$(timed "$JOBS" "$@")")
    done
    python3 - "$name" "$runs" "$JOBS" "${one[*]}" "${many[*]}" <<'PY'
import statistics, sys
name, runs, jobs = sys.argv[1], int(sys.argv[2]), sys.argv[3]
one = [float(x) for x in sys.argv[4].split()]
many = [float(x) for x in sys.argv[5].split()]
for label, pick in (("fastest", min), ("median", statistics.median)):
    a, b = pick(one), pick(many)
    print(f"{name:8s} {runs:3d} runs {label:8s} --jobs 1: {a:6.2f} s ({runs/a:5.2f} runs/s)"
          f"  --jobs {jobs}: {b:6.2f} s ({runs/b:5.2f} runs/s)  speed-up {a/b:4.2f}x")
print(f"{'':8s} all --jobs 1: {' '.join(f'{t:.2f}' for t in one)}")
print(f"{'':8s} all --jobs {jobs}: {' '.join(f'{t:.2f}' for t in many)}")
PY
}
for case in ${CASES:-uniform paper}; do
    case $case in
    uniform) report uniform 8 "$work/uniform.toml" ;;
    paper) report paper 12 scenarios/sweeps/erodible_bed.toml --set domain.cells=3000 ;;
    *) echo "unknown case $case" >&2 && exit 2 ;;
    esac
done
echo "load average after: $(cut -d' ' -f1-3 /proc/loadavg)"
