#!/usr/bin/env bash
# The hockey-stick run of docs/performance.md ("Cost that follows the flow") on one and
# two threads, PASSES (default 3) interleaved passes (1 thread, 2 threads, 1, 2, ...),
# then the median of each: the run loop's wall and CPU time as `flow_cost` prints them,
# and the speed-up (median one-thread wall / median two-thread wall). With a second
# argument, a `flow_cost` binary built at another commit runs interleaved with this
# one (the same passes), for a before/after on the same machine state. From the
# repository's root after `cargo build --release --example flow_cost`; on an idle
# machine (the load average is printed before and after).
#
#   benches/results/2026-12-07-epyc-2vcpu/flow_cost/run-idle.sh [FLOW_COST] [BASELINE_FLOW_COST]
set -euo pipefail
fc=${1:-target/release/examples/flow_cost}
base=${2:-}
passes=${PASSES:-3}
h=scenarios/hockey_channel.toml
log=$(mktemp)
echo "# load $(cut -d' ' -f1-3 /proc/loadavg) $(date -u +%FT%TZ) commit $(git rev-parse --short HEAD)"
for p in $(seq "$passes"); do
    for t in 1 2; do
        for which in this ${base:+base}; do
            bin=$fc
            [ "$which" = base ] && bin=$base
            out=$("$bin" "$h" --threads "$t")
            run=$(grep -o 'run [0-9.]* s wall, [0-9.]* s CPU' <<<"$out")
            hash=$(grep -o 'hash 0x[0-9a-f]*' <<<"$out")
            echo "pass $p $which threads $t: $run, $hash"
            echo "$which $t $(awk '{print $2, $5}' <<<"$run")" >>"$log"
        done
    done
done
echo "# load $(cut -d' ' -f1-3 /proc/loadavg) $(date -u +%FT%TZ)"
median() { sort -g | awk '{v[NR] = $1} END {print (NR % 2) ? v[(NR + 1) / 2] : (v[NR / 2] + v[NR / 2 + 1]) / 2}'; }
for which in this ${base:+base}; do
    w1=$(awk -v w="$which" '$1 == w && $2 == 1 {print $3}' "$log" | median)
    c1=$(awk -v w="$which" '$1 == w && $2 == 1 {print $4}' "$log" | median)
    w2=$(awk -v w="$which" '$1 == w && $2 == 2 {print $3}' "$log" | median)
    c2=$(awk -v w="$which" '$1 == w && $2 == 2 {print $4}' "$log" | median)
    echo "$which: median of $passes: 1 thread $w1 s wall, $c1 s CPU; 2 threads $w2 s wall, $c2 s CPU; speed-up $(awk -v a="$w1" -v b="$w2" 'BEGIN {printf "%.2f", a / b}')"
done
rm -f "$log"
