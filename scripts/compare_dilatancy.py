#!/usr/bin/env python3
"""Dense, loose and incompressible collapses of Bouchut et al. 2021, §4.3 on one slope.

    python scripts/compare_dilatancy.py [--slope 22] [--out out/dilatancy] [--cells 640]

Runs scenarios/dilatancy_dense.toml (φ0 = 0.62), scenarios/dilatancy_loose.toml
(φ0 = 0.55) and the dense file with dilatancy.k = 0 (incompressible) on the slope,
then prints and plots, against time, the front position (h > 1 mm) and the maximum
thickness of the three runs, and the relative volume change ∫h/∫h(0) of the dilatant
ones (Bouchut et al. 2021, Fig. 9 and 14). Needs the release binary (cargo build --release),
h5py, numpy and matplotlib.
"""

import argparse
import os
import pathlib
import subprocess

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from granflow_io import Run  # noqa: E402

ROOT = pathlib.Path(__file__).resolve().parent.parent
BIN = pathlib.Path(os.environ.get("CARGO_TARGET_DIR", ROOT / "target")) / "release" / "granflow"
CASES = [
    ("dense", "dilatancy_dense.toml", []),
    ("loose", "dilatancy_loose.toml", []),
    ("K = 0", "dilatancy_dense.toml", ["dilatancy.k=0"]),
]


def run(name, scenario, sets, slope, cells, t_end, out):
    out.mkdir(parents=True, exist_ok=True)
    file = out / f"{name.replace(' ', '').replace('=', '')}_{slope:g}.h5"
    args = [str(BIN), "run", str(ROOT / "scenarios" / scenario), "--quiet"]
    for s in sets + [f"domain.slope_deg={slope}", f"domain.cells={cells}",
                     f"time.t_end={t_end}", f"output.file={file}", "output.every=0.06"]:
        args += ["--set", s]
    subprocess.run(args, check=True)
    return Run(file)


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--slope", type=float, default=22.0)
    p.add_argument("--cells", type=int, default=640)
    p.add_argument("--t-end", type=float, default=1.8)
    p.add_argument("--out", default="out/dilatancy")
    args = p.parse_args()
    out = pathlib.Path(args.out)
    runs = {name: run(name, sc, sets, args.slope, args.cells, args.t_end, out)
            for name, sc, sets in CASES}
    fig, (a1, a2, a3) = plt.subplots(1, 3, figsize=(16, 4))
    print(f"θ = {args.slope:g}°: t, then front (m) / max h (m) of " + ", ".join(runs))
    # A run that came to rest has fewer snapshots: its last one is the deposit.
    longest = max(runs.values(), key=lambda r: len(r.t))
    for k in range(0, len(longest.t), max(1, len(longest.t) // 10)):
        row = []
        for r in runs.values():
            h = r.h[min(k, len(r.t) - 1)]
            front = r.x[h > 1e-3].max() if (h > 1e-3).any() else np.nan
            row.append(f"{front:.3f} / {h.max():.4f}")
        print(f"  t = {longest.t[k]:5.2f} s: " + ", ".join(row))
    for name, r in runs.items():
        a1.plot(r.front_t, r.front_x, label=name)
        a2.plot(r.t, r.h.max(axis=1), label=name)
        if name != "K = 0":
            vol = r.h.sum(axis=1)
            a3.plot(r.t, vol / vol[0] - 1.0, label=name)
    a1.set_ylabel("front position (m)")
    a2.set_ylabel("maximum thickness (m)")
    a3.set_ylabel("relative volume change ∫h/∫h(0) − 1")
    for a in (a1, a2, a3):
        a.set_xlabel("t (s)")
        a.legend(fontsize=8)
    fig.suptitle(f"Bouchut et al. 2021, §4.3 collapse, θ = {args.slope:g}°, {args.cells} cells")
    fig.tight_layout()
    png = out / f"dilatancy_{args.slope:g}.png"
    fig.savefig(png, dpi=110)
    print(f"plot: {png}")


if __name__ == "__main__":
    main()
