#!/usr/bin/env bash
# Speed-up of `granflow sweep --jobs 2` over `--jobs 1` on scenarios/sweeps/slopes.toml
# (five runs whose wall times grow with the slope, the longest last in sweep order),
# for one or two binaries (e.g. before and after a change of the run order):
#
#   scripts/bench_sweep_order.sh NEW_GRANFLOW [OLD_GRANFLOW]
#
# Each repetition runs, for each binary, --jobs 1 then --jobs 2 back to back, timed by
# /usr/bin/time (elapsed wall seconds), REPEAT times (default 7). Prints every time, the
# fastest of each and the ratio jobs1 / jobs2 of the fastest: the least disturbed
# repetition on a machine that other processes share. Extra sweep options in SWEEP_ARGS
# (e.g. SWEEP_ARGS="--set domain.cells=2560" for runs four times finer and longer).
set -euo pipefail
cd "$(dirname "$0")/.."
REPEAT=${REPEAT:-7}
bins=("$(realpath "$1")")
[[ $# -ge 2 ]] && bins+=("$(realpath "$2")")
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
echo "machine: $(nproc) CPUs, load average before: $(cut -d' ' -f1-3 /proc/loadavg)"
declare -A times
for ((r = 1; r <= REPEAT; r++)); do
    for b in "${!bins[@]}"; do
        for j in 1 2; do
            /usr/bin/time -f "%e" -o "$work/t" "${bins[$b]}" sweep scenarios/sweeps/slopes.toml \
                --output "$work/out-$b-$j" --jobs "$j" --force --quiet ${SWEEP_ARGS:-} >/dev/null
            times[$b,$j]+="$(cat "$work/t") "
        done
    done
done
for b in "${!bins[@]}"; do
    python3 - "${bins[$b]}" "${times[$b,1]}" "${times[$b,2]}" <<'PY'
import sys
name, one, two = sys.argv[1], [float(v) for v in sys.argv[2].split()], [float(v) for v in sys.argv[3].split()]
print(f"{name}\n  --jobs 1: {' '.join(f'{v:.2f}' for v in one)} s (fastest {min(one):.2f})"
      f"\n  --jobs 2: {' '.join(f'{v:.2f}' for v in two)} s (fastest {min(two):.2f})"
      f"\n  speed-up of the fastest: {min(one) / min(two):.2f}x")
PY
done
echo "load average after: $(cut -d' ' -f1-3 /proc/loadavg)"
