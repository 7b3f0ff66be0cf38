#!/usr/bin/env python3
"""Compare a run's deposit (or thickness profile at a time) with your own lab data.

    python scripts/compare_deposit.py RUN.h5 LAB.csv [--frame along-slope|horizontal]
           [--x-shift DX] [--time T] [--threshold H] [--plot PNG]
    python scripts/compare_deposit.py --sweep DIR --map MAP.csv [--plot-dir PLOTS]

LAB.csv has a header line and two columns, `x,h` (thickness) or `x,z` (free-surface
elevation, turned into a thickness h = z − b with the run's bed); lines starting with
`#` are comments. Units: metres. The frame of the lab data (--frame):
  along-slope  x along the inclined plane, h normal to it: the frame of a run in local
               coordinates (default for those runs);
  horizontal   x horizontal, h (or z) vertical: the frame of a Cartesian run (default
               for those). Given for a local run on a plane of slope θ, the profile is
               mapped to the plane with X = x / cos θ and h_n = h_v cos θ, which is
               exact for a plane bed and a deposit much thinner than it is long
               (`x,z` data cannot be mapped this way: give thicknesses).
--x-shift DX is added to the lab x (after the mapping) to put the lab origin on the
run's (e.g. the gate position). The run's snapshot nearest to --time is used (default:
the last one, the deposit). The run's h is interpolated linearly onto the lab points.

Reports, over the lab points' x range (trapezoidal rule):
  L1 = ∫|h_run − h_lab| dx,  L2 = (∫(h_run − h_lab)² dx)^½, each also relative to
  ∫h_lab dx and (∫h_lab² dx)^½; the front position (largest x with h > --threshold,
  default the run's front threshold) of both and their difference; the maximum
  thickness of both and their difference. With --plot, lab against run.

--sweep DIR --map MAP.csv does the same for runs of a sweep: MAP.csv has columns
`run,lab` and optionally `frame,x_shift,time` (one row per run; `run` is the run name
of DIR/summary.csv, `lab` a CSV path relative to MAP.csv). Prints one row per run and
writes DIR/deposit_comparison.csv. Formats and an example: docs/validation.md.
Needs h5py and numpy (matplotlib for plots).
"""

import argparse
import csv
import math
import pathlib
import sys

import numpy as np

from granflow_io import Run


class InputError(Exception):
    pass


def read_lab(path):
    """(kind, x, values): kind 'h' or 'z', rows sorted by x."""
    lines = [l for l in pathlib.Path(path).read_text().splitlines()
             if l.strip() and not l.lstrip().startswith("#")]
    if not lines:
        raise InputError(f"{path}: no data")
    header = [c.strip().lower() for c in lines[0].split(",")]
    if len(header) != 2 or header[0] != "x" or header[1] not in ("h", "z"):
        raise InputError(f"{path}: the header must be 'x,h' or 'x,z', found '{lines[0]}'")
    rows = []
    for n, l in enumerate(lines[1:], start=2):
        try:
            x, v = (float(c) for c in l.split(","))
        except ValueError:
            raise InputError(f"{path}: data line {n}: expected two numbers, found '{l}'")
        if not (math.isfinite(x) and math.isfinite(v)):
            raise InputError(f"{path}: data line {n}: not a finite number: '{l}'")
        rows.append((x, v))
    if len(rows) < 2:
        raise InputError(f"{path}: at least two data rows are needed")
    rows.sort()
    x, v = np.array(rows).T
    if np.any(np.diff(x) == 0):
        raise InputError(f"{path}: two rows have the same x")
    return header[1], x, v


def to_run_frame(run, kind, x, v, frame, x_shift):
    """Lab points as (x, h) in the run's frame."""
    local = run.attrs.get("coordinates") == "local"
    frame = frame or ("along-slope" if local else "horizontal")
    if frame not in ("along-slope", "horizontal"):
        raise InputError(f"unknown frame '{frame}' (along-slope or horizontal)")
    if local and frame == "horizontal":
        if kind == "z":
            raise InputError("x,z data in the horizontal frame cannot be mapped to a local "
                             "run: give thicknesses (x,h) or along-slope data")
        c = math.cos(math.radians(float(run.attrs.get("slope_deg", 0.0))))
        x, v = x / c, v * c
    elif not local and frame == "along-slope":
        raise InputError("along-slope data for a Cartesian run: give horizontal data")
    x = x + x_shift
    h = v - np.interp(x, run.x, run.b) if kind == "z" else v
    return x, np.maximum(h, 0.0)


def front(x, h, threshold):
    wet = np.nonzero(h > threshold)[0]
    return float(x[wet[-1]]) if len(wet) else float("nan")


def integrate(x, f):
    return float(np.sum(0.5 * (f[1:] + f[:-1]) * np.diff(x)))


def compare(run, lab_path, frame=None, x_shift=0.0, time=None, threshold=None):
    kind, x_raw, v = read_lab(lab_path)
    x, h_lab = to_run_frame(run, kind, x_raw, v, frame, x_shift)
    k = len(run.t) - 1 if time is None else run.snapshot(time)
    h_run_grid = run.h[k]
    h_run = np.interp(x, run.x, h_run_grid)
    if threshold is None:
        threshold = run.front_threshold
    d = h_run - h_lab
    l1, l2 = integrate(x, np.abs(d)), math.sqrt(integrate(x, d * d))
    m1, m2 = integrate(x, h_lab), math.sqrt(integrate(x, h_lab * h_lab))
    f_lab, f_run = front(x, h_lab, threshold), front(run.x, h_run_grid, threshold)
    return {
        "t": float(run.t[k]),
        "L1": l1, "L1_rel": l1 / m1 if m1 > 0 else float("nan"),
        "L2": l2, "L2_rel": l2 / m2 if m2 > 0 else float("nan"),
        "front_lab": f_lab, "front_run": f_run, "front_error": f_run - f_lab,
        "h_max_lab": float(h_lab.max()), "h_max_run": float(h_run_grid.max()),
        "h_max_error": float(h_run_grid.max() - h_lab.max()),
        "threshold": threshold,
        "_x": x, "_h_lab": h_lab, "_k": k,
    }


def report(name, r):
    print(f"{name}: t = {r['t']:.4g} s")
    print(f"  L1 thickness error  {r['L1']:.4e} m²  ({100 * r['L1_rel']:.2f} % of ∫h_lab)")
    print(f"  L2 thickness error  {r['L2']:.4e} m^1.5 ({100 * r['L2_rel']:.2f} % of ‖h_lab‖)")
    print(f"  front (h > {r['threshold']:g} m)   lab {r['front_lab']:.4f} m, run "
          f"{r['front_run']:.4f} m, error {r['front_error']:+.4f} m")
    print(f"  max thickness       lab {r['h_max_lab']:.4f} m, run {r['h_max_run']:.4f} m, "
          f"error {r['h_max_error']:+.4f} m")


def plot(run, r, lab_name, out):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    k = r["_k"]
    fig, a = plt.subplots(figsize=(9, 4))
    a.plot(run.x, run.h[k], "-", color="tab:blue", lw=1.5,
           label=f"run {pathlib.Path(run.path).name}, t = {r['t']:.3g} s")
    a.plot(r["_x"], r["_h_lab"], "o", color="k", ms=3, label=f"lab {lab_name}")
    for f, c in ((r["front_run"], "tab:blue"), (r["front_lab"], "k")):
        if math.isfinite(f):
            a.axvline(f, color=c, ls=":", lw=1)
    lo = min(r["_x"].min(), r["front_run"] if math.isfinite(r["front_run"]) else np.inf)
    hi = max(r["_x"].max(), r["front_run"] if math.isfinite(r["front_run"]) else -np.inf)
    pad = 0.1 * (hi - lo)
    a.set_xlim(lo - pad, hi + pad)
    a.set_xlabel("x (m, run frame)")
    a.set_ylabel("thickness h (m)")
    a.set_title(f"L1 {100 * r['L1_rel']:.1f} %, front error {r['front_error']:+.3f} m, "
                f"max-thickness error {r['h_max_error']:+.4f} m", fontsize=10)
    a.legend(fontsize=8)
    fig.tight_layout()
    pathlib.Path(out).parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=110)
    plt.close(fig)
    print(f"  plot: {out}")


def sweep(args):
    out_dir = pathlib.Path(args.sweep)
    names = {r["run"] for r in csv.DictReader(open(out_dir / "summary.csv", newline=""))}
    map_path = pathlib.Path(args.map)
    rows = list(csv.DictReader(open(map_path, newline="")))
    if not rows or "run" not in rows[0] or "lab" not in rows[0]:
        raise InputError(f"{map_path}: needs the columns run,lab")
    fields = ["run", "lab", "t", "L1", "L1_rel", "L2", "L2_rel", "front_lab", "front_run",
              "front_error", "h_max_lab", "h_max_run", "h_max_error"]
    table = []
    for m in rows:
        if m["run"] not in names:
            raise InputError(f"{map_path}: run '{m['run']}' is not in {out_dir}/summary.csv")
        run = Run(out_dir / f"{m['run']}.h5")
        lab = map_path.parent / m["lab"]
        r = compare(run, lab, m.get("frame") or None, float(m.get("x_shift") or 0.0),
                    float(m["time"]) if m.get("time") else None, args.threshold)
        report(m["run"], r)
        if args.plot_dir:
            plot(run, r, m["lab"], pathlib.Path(args.plot_dir) / f"{m['run']}.png")
        table.append({"run": m["run"], "lab": m["lab"], **{k: r[k] for k in fields[2:]}})
    out = out_dir / "deposit_comparison.csv"
    with open(out, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=fields)
        w.writeheader()
        w.writerows(table)
    print(f"\n{len(table)} runs compared; table in {out}")


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("run", nargs="?")
    p.add_argument("lab", nargs="?")
    p.add_argument("--frame", choices=["along-slope", "horizontal"])
    p.add_argument("--x-shift", type=float, default=0.0)
    p.add_argument("--time", type=float)
    p.add_argument("--threshold", type=float)
    p.add_argument("--plot")
    p.add_argument("--sweep", metavar="DIR")
    p.add_argument("--map", metavar="MAP.csv")
    p.add_argument("--plot-dir")
    args = p.parse_args()
    try:
        if args.sweep:
            if not args.map or args.run:
                p.error("--sweep DIR needs --map MAP.csv and no RUN/LAB arguments")
            sweep(args)
            return 0
        if not (args.run and args.lab):
            p.error("give RUN.h5 and LAB.csv, or --sweep DIR --map MAP.csv")
        run = Run(args.run)
        r = compare(run, args.lab, args.frame, args.x_shift, args.time, args.threshold)
        report(f"{args.run} vs {args.lab}", r)
        if args.plot:
            plot(run, r, pathlib.Path(args.lab).name, args.plot)
        return 0
    except (InputError, OSError) as e:
        print(f"error: {e}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
