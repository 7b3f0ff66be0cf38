#!/usr/bin/env bash
# The hockey-stick figures of docs/performance.md ("Cost that follows the flow") as
# re-run for the current numbers: one thread twice (active tiles), the full sweep
# once, two threads twice. From the repository's root after
# `cargo build --release --example flow_cost`.
set -euo pipefail
fc=target/release/examples/flow_cost
h=scenarios/hockey_channel.toml
echo "# load $(cat /proc/loadavg) $(date -u +%FT%TZ) commit $(git rev-parse --short HEAD)"
$fc $h --threads 1
$fc $h --threads 2
$fc $h --threads 1
$fc $h --threads 2
$fc $h --threads 1 --full
echo "# load $(cat /proc/loadavg) $(date -u +%FT%TZ)"
