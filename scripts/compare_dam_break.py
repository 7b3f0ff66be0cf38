#!/usr/bin/env python3
"""Frictionless dam breaks against their exact solutions, error against run time.

    python scripts/compare_dam_break.py [--granflow PATH] [--cells 100 200 400 800 1600]
                                        [--out DIR] [--plot]

Runs scenarios/dam_break_dry.toml (Ritter) and scenarios/dam_break_wet.toml (Stoker)
at each resolution with `granflow run`, then reports, per case and resolution, the L1
error of h at the final time, the observed order between successive grids, and the
run's wall time (from /summary/wall_time_s). With --plot, writes
DIR/dam_break_convergence.png (error against Δx and against wall time).
Exit status 1 if any error fails to decrease under refinement.
"""

import argparse
import math
import pathlib
import subprocess
import sys

import numpy as np

from granflow_io import Run

G = 9.81
ROOT = pathlib.Path(__file__).resolve().parent.parent


def exact_h(x, t, h_l, h_r):
    """Exact depth of the dam break h_l | h_r (h_r = 0: Ritter; else Stoker)."""
    c_l = math.sqrt(G * h_l)
    if h_r == 0.0:
        h_m, u_m, shock = 0.0, 2 * c_l, 2 * c_l
    else:
        def mismatch(h):
            return 2 * (c_l - math.sqrt(G * h)) - (h - h_r) * math.sqrt(
                G * (h + h_r) / (2 * h * h_r))
        lo, hi = h_r, h_l
        for _ in range(200):
            mid = 0.5 * (lo + hi)
            lo, hi = (mid, hi) if mismatch(mid) > 0 else (lo, mid)
        h_m = 0.5 * (lo + hi)
        u_m = 2 * (c_l - math.sqrt(G * h_m))
        shock = u_m * h_m / (h_m - h_r)
    xi = x / t
    c_m = math.sqrt(G * h_m)
    fan = (2 * c_l - xi) ** 2 / (9 * G)
    return np.where(xi <= -c_l, h_l,
           np.where(xi <= u_m - c_m, fan,
           np.where(xi < shock, h_m, h_r)))


def run(granflow, scenario, cells, out):
    h5 = out / f"{scenario.stem}_{cells}.h5"
    subprocess.run([granflow, "run", str(scenario), "-q", "-o", str(h5),
                    "--set", f"domain.cells={cells}"], check=True)
    return Run(h5)


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--granflow", default=str(ROOT / "target/release/granflow"))
    p.add_argument("--cells", type=int, nargs="+", default=[100, 200, 400, 800, 1600])
    p.add_argument("--out", default="out/dam_break")
    p.add_argument("--plot", action="store_true")
    args = p.parse_args()
    out = pathlib.Path(args.out)
    out.mkdir(parents=True, exist_ok=True)

    cases = [("Ritter (dry bed)", "dam_break_dry.toml", 1.0, 0.0),
             ("Stoker (wet bed)", "dam_break_wet.toml", 1.0, 0.1)]
    results = {}
    ok = True
    for name, file, h_l, h_r in cases:
        rows = []
        for cells in args.cells:
            r = run(args.granflow, ROOT / "scenarios" / file, cells, out)
            t = r.t[-1]
            err = np.sum(np.abs(r.h[-1] - exact_h(r.x, t, h_l, h_r))) * r.dx
            rows.append((cells, r.dx, err, r.wall_time))
        results[name] = rows
        print(f"\n{name}: L1 error of h at t = {t:g} s")
        print(f"{'cells':>7} {'dx (m)':>10} {'L1(h)':>11} {'order':>6} {'wall (s)':>9}")
        for k, (cells, dx, err, wall) in enumerate(rows):
            order = "" if k == 0 else f"{math.log(rows[k-1][2] / err) / math.log(rows[k-1][1] / dx):6.2f}"
            print(f"{cells:>7} {dx:>10.5f} {err:>11.4e} {order:>6} {wall:>9.4f}")
            if k and err >= rows[k - 1][2]:
                ok = False

    if args.plot:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        fig, (a1, a2) = plt.subplots(1, 2, figsize=(10, 4))
        for name, rows in results.items():
            dx = [r[1] for r in rows]
            err = [r[2] for r in rows]
            wall = [r[3] for r in rows]
            a1.loglog(dx, err, "o-", label=name)
            a2.loglog(wall, err, "o-", label=name)
        ref = np.array([r[1] for r in next(iter(results.values()))])
        a1.loglog(ref, ref * 2, "k--", label="order 1")
        a1.set_xlabel("Δx (m)"); a1.set_ylabel("L1 error of h (m²)"); a1.legend()
        a2.set_xlabel("wall time (s)"); a2.set_ylabel("L1 error of h (m²)"); a2.legend()
        import plot_common
        for a in (a1, a2):
            plot_common.readable_log_axis(a.xaxis)
            plot_common.readable_log_axis(a.yaxis)
            a.grid(True, which="major", alpha=0.3)
        fig.tight_layout()
        png = out / "dam_break_convergence.png"
        try:
            plot_common.save(fig, png, 150)
        except plot_common.EmptyPlot as e:
            return plot_common.fail_empty(e)
        print(f"\nplot: {png}")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
