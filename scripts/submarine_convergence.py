#!/usr/bin/env python3
"""Mesh convergence of the final deposit of Fernández-Nieto et al. 2008, §5.1 and §5.2 (Fig. 4 and 6).

Runs a submarine scenario at Δx = 1/20, 1/40, 1/80, 1/160, 1/320 (10 m channel:
200 ... 3200 cells), reads the final interface b + H₂cos²θ and the grain thickness,
and prints the L1 distance of each grid's deposit to the finest grid's (the finest
averaged onto the coarser cells), with the observed order.

    python3 scripts/submarine_convergence.py scenarios/submarine_landslide.toml --out out/conv
    python3 scripts/submarine_convergence.py scenarios/lake_landslide.toml --out out/conv \\
        --set rheology.mu_deg=25

Needs h5py and numpy, and a release build (cargo build --release).
"""

import argparse
import math
import pathlib
import subprocess
import sys

import h5py
import numpy as np

ROOT = pathlib.Path(__file__).resolve().parent.parent


def run(granflow, scenario, cells, out, sets):
    path = out / f"{scenario.stem}_{cells}.h5"
    cmd = [str(granflow), "run", str(scenario), "--output", str(path),
           "--set", f"domain.cells={cells}"]
    for s in sets:
        cmd += ["--set", s]
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL)
    with h5py.File(path, "r") as f:
        x = f["grid/x"][:]
        h = f["snapshots/h"][-1]
        interface = f["snapshots/interface"][-1]
        t = f["snapshots/t"][-1]
    return x, h, interface, t


def coarsen(fine, factor):
    return fine.reshape(-1, factor).mean(axis=1)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("scenario", type=pathlib.Path)
    ap.add_argument("--out", type=pathlib.Path, default=pathlib.Path("out/convergence"))
    ap.add_argument("--set", action="append", default=[], help="extra KEY=VALUE overrides")
    ap.add_argument("--cells", type=int, nargs="+", default=[200, 400, 800, 1600, 3200])
    ap.add_argument("--granflow", type=pathlib.Path, default=ROOT / "target/release/granflow")
    args = ap.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    cells = sorted(args.cells)
    if any(cells[-1] % n for n in cells):
        sys.exit("every grid must divide the finest one")
    runs = {n: run(args.granflow, args.scenario, n, args.out, args.set) for n in cells}
    xf, hf, zf, t = runs[cells[-1]]
    length = (xf[1] - xf[0]) * len(xf)
    print(f"{args.scenario.name} {' '.join(args.set)}: deposit at t = {t:g} s, "
          f"reference {cells[-1]} cells")
    print(f"{'cells':>6} {'dx':>9} {'L1(h2)':>11} {'L1(interface)':>14} {'order':>6}")
    previous = None
    for n in cells[:-1]:
        _, h, z, _ = runs[n]
        dx = length / n
        factor = cells[-1] // n
        e_h = float(np.abs(h - coarsen(hf, factor)).sum() * dx)
        e_z = float(np.abs(z - coarsen(zf, factor)).sum() * dx)
        order = "" if previous is None else f"{math.log2(previous / e_z):6.2f}"
        print(f"{n:>6} {dx:>9.5f} {e_h:>11.3e} {e_z:>14.3e} {order:>6}")
        previous = e_z


if __name__ == "__main__":
    main()
