#!/usr/bin/env python3
"""Writes the SYNTHETIC gauge and slide data of this directory (they are not lab data).

    python examples/lab_gauges/make_synthetic.py [GRANFLOW]

GRANFLOW is the granflow binary (default target/release/granflow). The data come from
a granflow run of scenarios/lake_landslide.toml (Fernández-Nieto et al. 2008, §5.2, δ₀ = 10°) on a finer
mesh than the scenario's (400 cells instead of 200) up to t = 10 s, so that comparing
the scenario as shipped with them shows small but non-zero errors:

    granflow run scenarios/lake_landslide.toml --set time.t_end=10
    python scripts/compare_gauges.py lake_landslide.h5 examples/lab_gauges

Files (formats: docs/validation.md, "Bring your own flume data"):
  gauge_<x>.csv   t,eta every 0.1 s at x = 4.5, 6 and 8 m (water surface, m)
  slide_t<T>.csv  x,y every 0.1 m at T = 2 and 5 s (top of the slide, m)
Values are rounded to 1e-6 m, like a careful measurement would be.
Needs h5py and numpy.
"""

import pathlib
import subprocess
import sys
import tempfile

import h5py
import numpy as np

HERE = pathlib.Path(__file__).resolve().parent
ROOT = HERE.parents[1]
NOTE = ("# SYNTHETIC data, not measurements: examples/lab_gauges/make_synthetic.py "
        "(granflow, lake_landslide.toml on 400 cells)\n")


def main():
    granflow = sys.argv[1] if len(sys.argv) > 1 else str(ROOT / "target/release/granflow")
    with tempfile.TemporaryDirectory() as tmp:
        h5 = pathlib.Path(tmp) / "fine.h5"
        subprocess.run([granflow, "run", str(ROOT / "scenarios/lake_landslide.toml"),
                        "--quiet", "--output", str(h5),
                        "--set", "domain.cells=400", "--set", "time.t_end=10",
                        "--set", "output.gauges=[4.5, 6, 8]",
                        "--set", "output.gauge_every=0.1"], check=True)
        with h5py.File(h5, "r") as f:
            gx, t, eta = f["gauges/x"][:], f["gauges/t"][:], f["gauges/eta"][:]
            x, ts, top = f["grid/x"][:], f["snapshots/t"][:], f["snapshots/interface"][:]
    for k, xg in enumerate(gx):
        rows = "".join(f"{a:.6f},{b:.6f}\n" for a, b in zip(t, eta[:, k]))
        (HERE / f"gauge_{xg:g}.csv").write_text(NOTE + "t,eta\n" + rows)
    for T in (2.0, 5.0):
        k = int(np.argmin(np.abs(ts - T)))
        rows = "".join(f"{a:.6f},{b:.6f}\n" for a, b in zip(x[1::4], top[k, 1::4]))
        (HERE / f"slide_t{T:g}.csv").write_text(NOTE + "x,y\n" + rows)


if __name__ == "__main__":
    main()
