#!/usr/bin/env python3
"""Runout change with erodible-bed thickness: a sweep against the lab and the paper.

    python scripts/compare_erodible_lab.py SWEEP_DIR

SWEEP_DIR is the output of `granflow sweep scenarios/sweeps/erodible_bed.toml`. For
each slope, prints the runout change between the thinnest and the thickest bed of the
sweep, next to the change measured in the laboratory and computed by the models of
Fernández-Nieto et al. 2016 (§4.2.4 gives these numbers only at 19° and 22°; its figures, not its text,
hold the other slopes), then the settled time of every bed thickness (the time from
which the kinetic energy stays at or below 1e-6 of its peak; the paper's Fig. 13 plots
the time at which the front stops against h_i). Also prints the wall time of the
sweep's runs, so accuracy can be weighed against cost.
"""

import csv
import pathlib
import sys

# Fernández-Nieto et al. 2016, §4.2.4: (h_i from, h_i to) in m -> runout change in % for
# lab, μ(I)-monolayer, μ(I)-MSM (20 layers), μ(I)-C-MSM
PAPER = {
    19.0: ((1.5e-3, 5.3e-3), {"lab": 15.1, "monolayer": -1.1, "MSM": 2.5, "C-MSM": 6.8}),
    22.0: ((1.82e-3, 4.6e-3), {"lab": 26.9, "monolayer": 2.2, "MSM": 4.4, "C-MSM": 8.6}),
}


def main():
    if len(sys.argv) != 2:
        print(__doc__, file=sys.stderr)
        return 2
    rows = list(csv.DictReader(open(pathlib.Path(sys.argv[1]) / "summary.csv")))
    by_slope = {}
    for r in rows:
        if not r["status"].startswith(("completed", "stopped_at_rest")):
            continue
        by_slope.setdefault(float(r["domain.slope_deg"]), []).append(r)
    print(f"{'slope':>6} {'h_i (mm)':>14} {'runout (m)':>16} {'change':>8}  paper (lab / mono / MSM / C-MSM)")
    for slope, rs in sorted(by_slope.items()):
        rs.sort(key=lambda r: float(r["initial.erodible_bed"]))
        lo, hi = rs[0], rs[-1]
        r0, r1 = float(lo["runout"]), float(hi["runout"])
        change = 100 * (r1 - r0) / r0
        paper = ""
        if slope in PAPER:
            (a, b), p = PAPER[slope]
            paper = f"{p['lab']:+.1f} / {p['monolayer']:+.1f} / {p['MSM']:+.1f} / {p['C-MSM']:+.1f} % ({a*1e3:g} → {b*1e3:g} mm)"
        h0, h1 = 1e3 * float(lo["initial.erodible_bed"]), 1e3 * float(hi["initial.erodible_bed"])
        print(f"{slope:>6g} {h0:>6.2f} → {h1:<5.2f} {r0:>7.3f} → {r1:<6.3f} {change:>+7.1f}%  {paper}")
    print(f"\n{'slope':>6}  settled time (s) for h_i = … (mm)")
    for slope, rs in sorted(by_slope.items()):
        cells = "  ".join(
            f"{1e3 * float(r['initial.erodible_bed']):.2f}: {float(r['settled_time']):.3f}"
            for r in rs)
        print(f"{slope:>6g}  {cells}")
    wall = sum(float(r["wall_time_s"]) for r in rows)
    print(f"\n{len(rows)} runs, {wall:.2f} s of run wall time in all")
    return 0


if __name__ == "__main__":
    sys.exit(main())
