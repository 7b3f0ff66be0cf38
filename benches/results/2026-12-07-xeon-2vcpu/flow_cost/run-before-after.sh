#!/usr/bin/env bash
# Before/after on the hockey-stick run of docs/performance.md ("Cost that follows the
# flow"): builds `examples/flow_cost.rs` at two commits (default: AFTER = h36f, the
# raster step in fewer parallel passes, and BEFORE = the commit of main it branched
# from; give BEFORE = main and AFTER = the merged commit once it is merged), each in a
# detached worktree with its own target directory (kept between calls, so a second call
# builds nothing), then runs them with run-idle.sh: PASSES (default 5) interleaved passes of one and two threads,
# AFTER as "this" and BEFORE as "base", and the medians of each. Run it from the
# repository's root on an idle machine (run-idle.sh prints the load average before and
# after; build first, then wait for the load to fall, with BUILD_ONLY=1).
#
#   benches/results/2026-12-07-xeon-2vcpu/flow_cost/run-before-after.sh [BEFORE] [AFTER]
#   BUILD_ONLY=1 benches/results/2026-12-07-xeon-2vcpu/flow_cost/run-before-after.sh
set -euo pipefail
after=${2:-h36f}
before=${1:-$(git merge-base main "$after")}
root=$(git rev-parse --show-toplevel)
work=${WORK:-/tmp/flow-cost-before-after}
mkdir -p "$work"
build() {
    local rev=$1 sha dir
    sha=$(git rev-parse --short "$rev")
    dir=$work/$sha
    if [ ! -x "$dir/target/release/examples/flow_cost" ]; then
        [ -d "$dir/src" ] || git worktree add --detach "$dir/src" "$sha" >&2
        (cd "$dir/src" && CARGO_TARGET_DIR=$dir/target cargo build --release --example flow_cost >&2)
    fi
    echo "$dir/target/release/examples/flow_cost"
}
bin_before=$(build "$before")
bin_after=$(build "$after")
echo "# before: $before = $(git rev-parse --short "$before"), after: $after = $(git rev-parse --short "$after")"
[ -n "${BUILD_ONLY:-}" ] && exit 0
cd "$root"
"$root/benches/results/2026-12-07-epyc-2vcpu/flow_cost/run-idle.sh" "$bin_after" "$bin_before"
