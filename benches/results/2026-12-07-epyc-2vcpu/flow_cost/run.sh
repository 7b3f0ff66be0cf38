#!/usr/bin/env bash
# The benchmarks of docs/performance.md, "Cost that follows the flow", as run for the
# numbers there (from the repository's root, after
# `cargo build --release --example flow_cost --example hydrostatic_2d_cost`).
set -euo pipefail
fc=target/release/examples/flow_cost
cost=target/release/examples/hydrostatic_2d_cost
h=scenarios/hockey_channel.toml
echo "# load $(cat /proc/loadavg) $(date -u +%FT%TZ) commit $(git rev-parse --short HEAD)"
echo "## hockey stick, 5 m, one thread: active tiles, full sweep, active tiles"
$fc $h --threads 1
$fc $h --threads 1 --full
$fc $h --threads 1
echo "## hockey stick, 5 m, two threads (twice)"
$fc $h --threads 2
$fc $h --threads 2
echo "## DEM size (the same release; output at t = 0 and the end)"
$fc $h --threads 1 --set output.every=1000 --set domain.y_min=-4252.5 --set domain.y_max=-3747.5 --set 'domain.cells=[1001,101]'
$fc $h --threads 1 --set output.every=1000 --set domain.y_min=-6502.5 --set domain.y_max=-1497.5 --set 'domain.cells=[1001,1001]'
$fc $h --threads 1 --set output.every=1000 --set domain.x_min=-4002.5 --set domain.x_max=11807.5 --set domain.y_min=-11902.5 --set domain.y_max=3907.5 --set 'domain.cells=[3162,3162]'
echo "## fully wet step at 1024², one thread: 12 and 2 steps (CPU seconds of the process)"
for s in 12 2 12 2; do
  /usr/bin/time -f "$s steps: %U s user" $cost 1024 $s cartesian 1 both 2>&1 | tail -2
done
echo "# load $(cat /proc/loadavg) $(date -u +%FT%TZ)"
