#!/usr/bin/env python3
"""Plot one granflow run: thickness snapshots, front position and diagnostics.

    python scripts/plot_run.py RUN.h5 [--out RUN.png] [--every K]

Left: bed and free surface (b + h) at every K-th snapshot (normal to the reference
plane in local coordinates). Right: front position against time. Runs of the dilatant
model (seed 002) get a third panel with the volume fraction φ of the same snapshots
(cells thinner than 1 mm left out). Prints the summary attributes.
"""

import argparse
import pathlib

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from granflow_io import Run  # noqa: E402


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("run")
    p.add_argument("--out")
    p.add_argument("--every", type=int, default=0, help="plot every K-th snapshot")
    args = p.parse_args()
    r = Run(args.run)
    every = args.every or max(1, len(r.t) // 8)
    panels = 3 if r.phi is not None else 2
    fig, axes = plt.subplots(1, panels, figsize=(6 * panels, 4))
    a1, a2 = axes[0], axes[1]
    a1.plot(r.x, r.b, "k-", lw=1, label="bed b")
    for k in sorted(set(range(0, len(r.t), every)) | {len(r.t) - 1}):
        a1.plot(r.x, r.b + r.h[k], lw=1, label=f"t = {r.t[k]:.2f} s")
        if r.phi is not None:
            phi = np.where(r.h[k] > 1e-3, r.phi[k], np.nan)
            axes[2].plot(r.x, phi, lw=1, label=f"t = {r.t[k]:.2f} s")
    if r.phi is not None:
        axes[2].set_xlabel("x (m)")
        axes[2].set_ylabel("volume fraction φ (h > 1 mm)")
        axes[2].legend(fontsize=7)
    a1.set_xlabel("x (m)")
    a1.set_ylabel("b + h (m)")
    a1.legend(fontsize=7)
    a2.plot(r.front_t, r.front_x, "b-")
    a2.set_xlabel("t (s)")
    a2.set_ylabel("front position (m)", color="b")
    fig.suptitle(f"{pathlib.Path(args.run).name}: {r.attrs.get('model')}, "
                 f"{r.attrs.get('pressure')}, {r.attrs.get('layers')} layer(s), "
                 f"θ = {r.attrs.get('slope_deg')}°")
    fig.tight_layout()
    out = args.out or str(pathlib.Path(args.run).with_suffix(".png"))
    fig.savefig(out, dpi=110)
    for k, v in sorted(r.summary.items()):
        print(f"{k:>22}: {v}")
    print(f"plot: {out}")


if __name__ == "__main__":
    main()
