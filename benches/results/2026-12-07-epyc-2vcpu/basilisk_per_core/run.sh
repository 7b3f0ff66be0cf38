#!/usr/bin/env bash
# The per-core side-by-side of docs/performance.md ("Per core against Basilisk's
# saint-venant.h"): granflow's hyperbolic stage on the cone at rest
# (examples/hydrostatic_2d_cost.rs, Cartesian frame, one thread) and Basilisk's
# Saint-Venant solver on the same set-up (benches/basilisk/saint_venant_cone.c built
# with Basilisk's qcc -O2, orders 2 and 1), interleaved pass by pass; user CPU
# seconds of each process (/usr/bin/time), the load average before each pass.
# Usage, from the repository's root after
# `cargo build --release --example hydrostatic_2d_cost`:
#   benches/results/2026-12-07-epyc-2vcpu/basilisk_per_core/run.sh PATH/TO/cone PASSES
set -euo pipefail
cone=$1
passes=${2:-5}
gf=target/release/examples/hydrostatic_2d_cost
user() { /usr/bin/time -f "%U" "$@" 2>&1 >/dev/null | tail -1; }
echo "# commit $(git rev-parse --short HEAD) $(date -u +%FT%TZ)"
for rep in $(seq "$passes"); do
  for case in "256 100" "256 0" "1024 10" "1024 0"; do
    set -- $case
    load=$(cut -d' ' -f1 /proc/loadavg)
    g=$(user $gf "$1" "$2" cartesian 1 hyperbolic)
    b2=$(user "$cone" "$1" "$2" 2)
    b1=$(user "$cone" "$1" "$2" 1)
    echo "rep $rep n $1 steps $2 granflow $g basilisk2 $b2 basilisk1 $b1 load $load"
  done
done
