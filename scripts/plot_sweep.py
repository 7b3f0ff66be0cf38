#!/usr/bin/env python3
"""Plot a sweep: runout, stop time and final maximum thickness against the swept keys.

    python scripts/plot_sweep.py DIR [--out PNG] [--x KEY]

DIR is the output directory of `granflow sweep` (it reads DIR/summary.csv, see
docs/sweeps.md). The swept keys are the columns between `run` and `runout`. With one
swept key, each quantity is plotted against it; with several, against --x (default:
the first swept key), one line per combination of the other keys. Runs that failed
are left out (and listed). Writes DIR/sweep.png unless --out is given.
Needs numpy and matplotlib.
"""

import argparse
import csv
import itertools
import pathlib
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

QUANTITIES = [("runout", "runout (m)"), ("stop_time", "stop time (s)"),
              ("h_max_final", "final max thickness (m)")]


def number(v):
    try:
        return float(v)
    except ValueError:
        return v


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("dir")
    p.add_argument("--out")
    p.add_argument("--x", help="swept key on the horizontal axis")
    args = p.parse_args()
    path = pathlib.Path(args.dir) / "summary.csv"
    if not path.is_file():
        print(f"error: no summary.csv in '{args.dir}' (is it a sweep's output directory?)",
              file=sys.stderr)
        return 2
    with open(path, newline="") as f:
        reader = csv.DictReader(f)
        cols = reader.fieldnames
        rows = list(reader)
    keys = cols[cols.index("run") + 1:cols.index("runout")]
    if not keys:
        print("error: summary.csv names no swept key", file=sys.stderr)
        return 2
    xkey = args.x or keys[0]
    if xkey not in keys:
        print(f"error: --x {xkey}: not a swept key ({', '.join(keys)})", file=sys.stderr)
        return 2
    ok = [r for r in rows if r["status"] in ("completed", "stopped_at_rest")]
    for r in rows:
        if r not in ok:
            print(f"left out: {r['run']} ({r['status']})")
    others = [k for k in keys if k != xkey]
    groups = {}
    for r in ok:
        groups.setdefault(tuple(r[k] for k in others), []).append(r)

    fig, axs = plt.subplots(1, 3, figsize=(15, 4.2))
    markers = itertools.cycle("os^Dv<>p*")
    cmap = plt.get_cmap("viridis")
    for n, (label, rs) in enumerate(sorted(groups.items())):
        rs.sort(key=lambda r: number(r[xkey]))
        colour = cmap(n / max(1, len(groups) - 1)) if len(groups) > 1 else "k"
        marker = next(markers)
        name = ", ".join(f"{k} = {v}" for k, v in zip(others, label)) or None
        for a, (q, ylabel) in zip(axs, QUANTITIES):
            xs = [number(r[xkey]) for r in rs]
            ys = [float(r[q]) for r in rs]
            a.plot(xs, ys, marker=marker, color=colour, label=name)
            a.set_xlabel(xkey)
            a.set_ylabel(ylabel)
    if len(groups) > 1:
        axs[0].legend(fontsize=7)
    fig.suptitle(f"{pathlib.Path(args.dir).resolve().name}: {len(ok)} of {len(rows)} runs")
    fig.tight_layout()
    out = args.out or str(pathlib.Path(args.dir) / "sweep.png")
    fig.savefig(out, dpi=110)
    print(f"plot: {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
