#!/usr/bin/env python3
"""Compare a run's gauges (and slide shapes) with your own flume or field data.

    python scripts/compare_gauges.py RUN.h5 LAB_DIR [--threshold A] [--plot PNG]
           [--no-plot]

RUN.h5 is a granflow output file of a run with `output.gauges` (docs/output-format.md,
/gauges). LAB_DIR holds CSV files (header line first; lines starting with `#` are
comments; metres and seconds; formats in docs/validation.md, "Bring your own flume
data"):
  gauge_<x>.csv     columns `t,eta`: the free-surface elevation measured at x (e.g.
                    gauge_6.5.csv for a gauge at x = 6.5 m). The run must have a gauge
                    at that x (to 1e-9 m): add it to output.gauges.
  slide_t<T>.csv    columns `x,y`: the elevation of the top of the slide at time T
                    (e.g. slide_t2.5.csv). Compared with the run's snapshot at T (the
                    submarine model's `interface`, b + h for the granular model); the
                    run must have a snapshot at T (to 1e-6 s): choose output.every.
At least one file is needed.

Per gauge, over the lab times inside the run's time range (the run's series is
interpolated linearly in time onto them):
  rms        (mean (η_run − η_lab)²)^½
  peak       max |η − η0| of each series, η0 its first value; peak_err = run − lab
  arrival    first time |η − η0| exceeds --threshold (default 1e-3 m), linearly
             interpolated between the two samples around the crossing (nan if never);
             arrival_diff = run − lab (a lab series recorded s seconds later gives −s)
Per slide shape: the RMS and largest |y_run − y_lab| over the lab points (the run's
surface interpolated linearly in x). With matplotlib, a PNG of run against lab
(default: <RUN stem>_vs_lab.png next to RUN.h5). Exit code 2 on bad input.
Needs h5py and numpy (matplotlib for the plot).
"""

import argparse
import math
import pathlib
import re
import sys

import h5py
import numpy as np


class InputError(Exception):
    pass


GAUGE_FILE = re.compile(r"^gauge_(.+)\.csv$")
SLIDE_FILE = re.compile(r"^slide_t(.+)\.csv$")


def read_table(path, columns):
    """Two numeric columns under the header `columns` ('t,eta' or 'x,y'), as arrays
    sorted by the first column."""
    lines = [l for l in pathlib.Path(path).read_text().splitlines()
             if l.strip() and not l.lstrip().startswith("#")]
    if not lines:
        raise InputError(f"{path}: no data")
    header = ",".join(c.strip().lower() for c in lines[0].split(","))
    if header != columns:
        raise InputError(f"{path}: the header must be '{columns}', found '{lines[0]}'")
    rows = []
    for n, l in enumerate(lines[1:], start=2):
        parts = l.split(",")
        try:
            a, b = (float(p) for p in parts)
        except ValueError:
            raise InputError(f"{path}: data line {n}: expected two numbers, found '{l}'")
        if not (math.isfinite(a) and math.isfinite(b)):
            raise InputError(f"{path}: data line {n}: not a finite number: '{l}'")
        rows.append((a, b))
    if len(rows) < 2:
        raise InputError(f"{path}: at least two data rows are needed")
    rows.sort()
    a = np.array([r[0] for r in rows])
    if np.any(np.diff(a) == 0):
        raise InputError(f"{path}: two rows have the same {columns.split(',')[0]}")
    return a, np.array([r[1] for r in rows])


def number_in_name(path, pattern, what):
    m = pattern.match(path.name)
    try:
        v = float(m.group(1))
    except ValueError:
        v = math.nan
    if not math.isfinite(v):
        raise InputError(f"{path}: the file name must give the {what} as a number")
    return v


def read_lab(lab_dir):
    """({x: (t, eta)}, {T: (x, y)}) from the files of lab_dir."""
    lab_dir = pathlib.Path(lab_dir)
    if not lab_dir.is_dir():
        raise InputError(f"{lab_dir}: not a directory")
    gauges, slides = {}, {}
    for p in sorted(lab_dir.iterdir()):
        if GAUGE_FILE.match(p.name):
            gauges[number_in_name(p, GAUGE_FILE, "gauge position x")] = read_table(p, "t,eta")
        elif SLIDE_FILE.match(p.name):
            slides[number_in_name(p, SLIDE_FILE, "time")] = read_table(p, "x,y")
    if not gauges and not slides:
        raise InputError(f"{lab_dir}: no gauge_<x>.csv or slide_t<T>.csv file")
    return gauges, slides


class RunGauges:
    """The gauges, grid and slide surfaces of a granflow output file."""

    def __init__(self, path):
        with h5py.File(path, "r") as f:
            if "gauges" not in f:
                raise InputError(f"{path}: the run has no gauges (set output.gauges)")
            g = f["gauges"]
            self.gx = g["x"][:]
            self.t = g["t"][:]
            self.eta = g["eta"][:]
            self.x = f["grid/x"][:]
            b = f["grid/b"][:]
            snaps = f["snapshots"]
            self.snap_t = snaps["t"][:]
            self.top = snaps["interface"][:] if "interface" in snaps else b + snaps["h"][:]
        self.path = pathlib.Path(path)

    def gauge(self, x):
        k = np.flatnonzero(np.abs(self.gx - x) <= 1e-9 * max(1.0, abs(x)))
        if k.size == 0:
            have = ", ".join(f"{v:g}" for v in self.gx)
            raise InputError(f"the run has no gauge at x = {x:g} (it has {have}): "
                             f"add it to output.gauges")
        return self.t, self.eta[:, k[0]]

    def surface(self, t):
        k = int(np.argmin(np.abs(self.snap_t - t)))
        if abs(self.snap_t[k] - t) > 1e-6 * max(1.0, abs(t)):
            raise InputError(f"the run has no snapshot at t = {t:g} (nearest "
                             f"{self.snap_t[k]:g}): choose output.every to hit it")
        return self.x, self.top[k]


def arrival(t, eta, threshold):
    """First time |η − η0| > threshold, linearly interpolated; nan if never."""
    d = np.abs(eta - eta[0])
    above = np.flatnonzero(d > threshold)
    if above.size == 0:
        return math.nan
    k = above[0]
    if k == 0:
        return float(t[0])
    w = (threshold - d[k - 1]) / (d[k] - d[k - 1])
    return float(t[k - 1] + w * (t[k] - t[k - 1]))


def compare_gauge(run, x, lab, threshold):
    t_run, eta_run = run.gauge(x)
    t_lab, eta_lab = lab
    inside = (t_lab >= t_run[0]) & (t_lab <= t_run[-1])
    if inside.sum() < 2:
        raise InputError(f"gauge at x = {x:g}: fewer than two lab times inside the "
                         f"run's [{t_run[0]:g}, {t_run[-1]:g}] s")
    tl, el = t_lab[inside], eta_lab[inside]
    on_lab = np.interp(tl, t_run, eta_run)
    peak_run = float(np.max(np.abs(eta_run - eta_run[0])))
    peak_lab = float(np.max(np.abs(eta_lab - eta_lab[0])))
    a_run, a_lab = arrival(t_run, eta_run, threshold), arrival(t_lab, eta_lab, threshold)
    return {
        "x": x, "n": int(inside.sum()),
        "rms": float(np.sqrt(np.mean((on_lab - el) ** 2))),
        "peak_run": peak_run, "peak_lab": peak_lab, "peak_err": peak_run - peak_lab,
        "arrival_run": a_run, "arrival_lab": a_lab, "arrival_diff": a_run - a_lab,
        "series": (t_run, eta_run, t_lab, eta_lab),
    }


def compare_slide(run, t, lab):
    x_run, y_run = run.surface(t)
    x_lab, y_lab = lab
    inside = (x_lab >= x_run[0]) & (x_lab <= x_run[-1])
    if inside.sum() < 2:
        raise InputError(f"slide at t = {t:g}: fewer than two lab points inside the run's domain")
    d = np.interp(x_lab[inside], x_run, y_run) - y_lab[inside]
    return {"t": t, "n": int(inside.sum()), "rms": float(np.sqrt(np.mean(d ** 2))),
            "max_err": float(np.max(np.abs(d))), "series": (x_run, y_run, x_lab, y_lab)}


def compare(run_path, lab_dir, threshold=1e-3):
    """(gauge results, slide results) of a run against the data of lab_dir."""
    if not (math.isfinite(threshold) and threshold > 0):
        raise InputError(f"--threshold must be a positive number, got {threshold}")
    gauges, slides = read_lab(lab_dir)
    run = RunGauges(run_path)
    g = [compare_gauge(run, x, gauges[x], threshold) for x in sorted(gauges)]
    s = [compare_slide(run, t, slides[t]) for t in sorted(slides)]
    return g, s


def report(g, s, threshold):
    if g:
        print(f"gauges (arrival: |eta - eta0| > {threshold:g} m; diff = run - lab)")
        print(f"{'x [m]':>9} {'n':>5} {'rms [m]':>10} {'peak run':>10} {'peak lab':>10} "
              f"{'peak err':>10} {'arr run':>9} {'arr lab':>9} {'arr diff':>9}")
        for r in g:
            print(f"{r['x']:9.4g} {r['n']:5d} {r['rms']:10.3e} {r['peak_run']:10.4g} "
                  f"{r['peak_lab']:10.4g} {r['peak_err']:10.3e} {r['arrival_run']:9.4g} "
                  f"{r['arrival_lab']:9.4g} {r['arrival_diff']:9.3g}")
    if s:
        print("slide shapes (top of the slide; run - lab)")
        print(f"{'t [s]':>9} {'n':>5} {'rms [m]':>10} {'max [m]':>10}")
        for r in s:
            print(f"{r['t']:9.4g} {r['n']:5d} {r['rms']:10.3e} {r['max_err']:10.3e}")


def plot(g, s, out):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    panels = len(g) + len(s)
    fig, axes = plt.subplots(panels, 1, figsize=(7, 2.4 * panels), squeeze=False)
    for ax, r in zip(axes[:, 0], g):
        t_run, eta_run, t_lab, eta_lab = r["series"]
        ax.plot(t_lab, eta_lab, "k.", ms=3, label="lab")
        ax.plot(t_run, eta_run, "C0-", lw=1.2, label="run")
        ax.set_title(f"gauge x = {r['x']:g} m: rms {r['rms']:.2e} m, "
                     f"arrival diff {r['arrival_diff']:.3g} s", fontsize=9)
        ax.set_xlabel("t [s]")
        ax.set_ylabel("eta [m]")
        ax.legend(fontsize=8)
    for ax, r in zip(axes[len(g):, 0], s):
        x_run, y_run, x_lab, y_lab = r["series"]
        ax.plot(x_lab, y_lab, "k.", ms=3, label="lab")
        ax.plot(x_run, y_run, "C1-", lw=1.2, label="run")
        ax.set_title(f"slide at t = {r['t']:g} s: rms {r['rms']:.2e} m", fontsize=9)
        ax.set_xlabel("x [m]")
        ax.set_ylabel("top of slide [m]")
        ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(out, dpi=110)
    plt.close(fig)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("run", help="granflow HDF5 file of a run with gauges")
    ap.add_argument("lab_dir", help="directory of gauge_<x>.csv and slide_t<T>.csv")
    ap.add_argument("--threshold", type=float, default=1e-3,
                    help="arrival threshold on |eta - eta0| (m, default 1e-3)")
    ap.add_argument("--plot", help="PNG to write (default <RUN stem>_vs_lab.png)")
    ap.add_argument("--no-plot", action="store_true", help="print only")
    args = ap.parse_args()
    try:
        g, s = compare(args.run, args.lab_dir, args.threshold)
    except (InputError, OSError, KeyError) as e:
        print(f"compare_gauges: {e}", file=sys.stderr)
        return 2
    report(g, s, args.threshold)
    if not args.no_plot:
        run = pathlib.Path(args.run)
        out = args.plot or str(run.with_name(run.stem + "_vs_lab.png"))
        plot(g, s, out)
        print(f"plot: {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
