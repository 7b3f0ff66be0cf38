#!/usr/bin/env python3
"""Plot a sweep: runout, time of rest or settling, final maximum thickness, and when
the runs have them the maximum wave height and the mass that left the domain, against
the swept keys.

    python scripts/plot_sweep.py DIR [--out FILE] [--x KEY] [--format png|pdf|svg] [--dpi N]

DIR is the output directory of `granflow sweep` (it reads DIR/summary.csv and
DIR/sweep-plan.toml, see docs/sweeps.md). The swept keys are the columns between `run`
and `runout`. With one swept key, each quantity is plotted against it; with several,
against --x (default: the first swept key), one line per combination of the other
keys. Keys zipped with --x (a `[[zip]]` group) vary with it: their runs are not a
series, so they are drawn as markers, not joined. Every run that ended (completed,
stopped_at_rest, settled, outflowed, no_mass) is plotted; failed or missing runs are
left out and listed. The time panel shows the stop time (at rest, filled markers),
else the settled time (open markers), else t_end for a run still moving (crosses).
Writes DIR/sweep.png (or .pdf, .svg) unless --out is given; exits with 1 and a message
when there is nothing to plot. Needs numpy and matplotlib.
"""

import argparse
import csv
import itertools
import math
import pathlib
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

import plot_common  # noqa: E402

try:
    import tomllib
except ImportError:  # Python < 3.11: zipped keys are not recognised
    tomllib = None

ENDED = ("completed", "stopped_at_rest", "settled", "outflowed", "no_mass")


def number(v):
    try:
        return float(v)
    except (TypeError, ValueError):
        return v


def value(r, key):
    """The float in column `key` of row `r`, NaN when empty or absent."""
    try:
        return float(r.get(key) or "nan")
    except ValueError:
        return math.nan


def flatten(table, prefix=""):
    """{dotted key: value} of a TOML table parsed into nested dicts."""
    out = {}
    for k, v in table.items():
        key = f"{prefix}{k}"
        if isinstance(v, dict):
            out.update(flatten(v, key + "."))
        else:
            out[key] = v
    return out


def zip_groups(directory):
    """The key sets of the sweep's [[zip]] groups (from DIR/sweep-plan.toml)."""
    plan = pathlib.Path(directory) / "sweep-plan.toml"
    if tomllib is None or not plan.is_file():
        return []
    try:
        sweep = tomllib.loads(tomllib.loads(plan.read_text())["sweep_toml"])
    except (tomllib.TOMLDecodeError, KeyError):
        return []
    groups = sweep.get("zip", [])
    if isinstance(groups, dict):
        groups = [groups]
    return [set(flatten(g)) for g in groups]


def rest_time(r):
    """(time, kind): the stop time, else the settled time, else t_end of a run still
    moving."""
    for key, kind in (("stop_time", "at rest"), ("settled_time", "settled")):
        t = value(r, key)
        if math.isfinite(t):
            return t, kind
    return value(r, "t_end"), "still moving at t_end"


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("dir")
    p.add_argument("--out")
    p.add_argument("--x", help="swept key on the horizontal axis")
    plot_common.add_output_options(p)
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
    ok = [r for r in rows if r["status"] in ENDED]
    for r in rows:
        if r not in ok:
            print(f"left out: {r['run']} ({r['status'] or 'no result'})")
    if not ok:
        statuses = sorted({r["status"] or "no result" for r in rows})
        print(f"error: nothing to plot: no run of '{args.dir}' has ended "
              f"(statuses: {', '.join(statuses)})", file=sys.stderr)
        return 1

    zipped = set()
    for g in zip_groups(args.dir):
        if xkey in g:
            zipped |= g - {xkey}
    others = [k for k in keys if k != xkey and k not in zipped]
    joined = not zipped
    groups = {}
    for r in ok:
        groups.setdefault(tuple(r[k] for k in others), []).append(r)

    quantities = [("runout", "runout (m)"), ("rest", "time of rest or settling (s)"),
                  ("h_max_final", "final max thickness (m)")]
    if any(math.isfinite(value(r, "max_wave_amplitude")) for r in ok):
        quantities.append(("max_wave_amplitude", "max wave height |η − η₀| (m)"))
    if any(value(r, "outflowed_fraction") > 1e-9 for r in ok):
        quantities.append(("outflowed_fraction", "mass that left the domain (%)"))

    fig, axs = plt.subplots(1, len(quantities), figsize=(4.6 * len(quantities), 4.2),
                            squeeze=False)
    axs = axs[0]
    markers = itertools.cycle("os^Dv<>p*")
    cmap = plt.get_cmap("viridis")
    style = "-" if joined else "none"
    for n, (label, rs) in enumerate(sorted(groups.items())):
        rs.sort(key=lambda r: (number(r[xkey]), r["index"]))
        colour = cmap(n / max(1, len(groups) - 1)) if len(groups) > 1 else "k"
        marker = next(markers)
        name = ", ".join(f"{k} = {v}" for k, v in zip(others, label)) or None
        xs = [number(r[xkey]) for r in rs]
        for a, (q, ylabel) in zip(axs, quantities):
            if q == "rest":
                ts = [rest_time(r) for r in rs]
                a.plot(xs, [t for t, _ in ts], ls=style, color=colour, lw=1, label=name)
                for kind, face, m in (("at rest", colour, marker), ("settled", "none", marker),
                                      ("still moving at t_end", colour, "x")):
                    pts = [(x, t) for x, (t, k) in zip(xs, ts) if k == kind]
                    if pts:
                        a.plot(*zip(*pts), ls="none", marker=m, color=colour,
                               markerfacecolor=face, label=kind if n == 0 else None)
            else:
                scale = 100.0 if q == "outflowed_fraction" else 1.0
                ys = [scale * value(r, q) for r in rs]
                a.plot(xs, ys, ls=style, marker=marker, color=colour, label=name)
            a.set_xlabel(xkey)
            a.set_ylabel(ylabel)
    if len(groups) > 1:
        axs[0].legend(fontsize=7)
    axs[1].legend(fontsize=7)
    for a in axs:
        a.grid(alpha=0.3)
    note = f"; {', '.join(sorted(zipped))} zipped with {xkey}: not joined" if zipped else ""
    fig.suptitle(f"{pathlib.Path(args.dir).resolve().name}: {len(ok)} of {len(rows)} runs{note}",
                 fontsize=10)
    fig.tight_layout()
    out = args.out or str(pathlib.Path(args.dir) / f"sweep.{args.format}")
    try:
        plot_common.save(fig, out, args.dpi)
    except plot_common.EmptyPlot as e:
        return plot_common.fail_empty(e)
    print(f"plot: {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
