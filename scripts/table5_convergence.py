#!/usr/bin/env python3
"""Convergence of the multilayer non-hydrostatic model (Escalante et al. 2023, §5.2, Table 5).

    python scripts/table5_convergence.py [--granflow PATH] [--jobs N] [--out DIR]
                                         [--reference NX N] [--family NX,N ...]
                                         [--quick] [--min-order-h X] [--min-order-v X]
                                         [--set KEY=VALUE ...] [--force]

Runs, through one `granflow sweep` (scenarios/nh_multilayer_convergence.toml: a
smooth mass on a 20° plane, [-0.5, 1.5] m, free outflow, CFL 0.7, Table 1 material,
t = 0.15 s), the family (Nx, N) = (100, 2), (200, 4), (400, 8), (800, 16), (1600, 32)
(cells and layers refined together) and a reference, by default the paper's
(6400, 128) (3614 s and 1 GiB here, on a shared 2-vCPU machine; --reference 3200 64:
2 min). It reads the snapshot at t = 0.15 s of every run, averages the reference onto
each run's cells and layers (the projection of Escalante et al. 2023, eq. 35, as `project` in
tests/nh_multilayer.rs), and prints the L1 errors of eq. (35),

    ||h - h_ref||_1 = dx sum_i |h_i - h_ref_i|,
    ||v - v_ref||_1 = dx sum_i h_i/N sum_a |v_a,i - v_ref_a,i|,   v = u(z), w(z),

and the observed orders log(e_prev/e)/log(Nx/Nx_prev), beside the paper's Table 5
values in brackets, with each run's wall time and steps, then the differences between
consecutive runs (each against the next finer one of the list, the last against the
reference), which need no reference. It writes DIR/table5.csv.

--quick is the cheap check run in CI: reference (800, 16), family (100, 2), (200, 4).
--min-order-h / --min-order-v: exit 1 if the last order of h (resp. of u(z) and w(z))
is below the value (an assertion on the run; no default).
--set KEY=VALUE is passed to every run (e.g. `--set time.cfl=0.04375`: the paper's
CFL is 0.7; the errors are then not those of the paper's runs).

The runs go to DIR (default out/table5_convergence, or out/table5_quick with --quick)
and a later invocation reuses every run already done with the same scenario (the
sweep's resume), so a larger family or another reference only runs what is new.
Exit status: 0, 1 if a run failed or an order is below its --min-order, 2 on bad
arguments.
"""

import argparse
import csv
import json
import math
import os
import pathlib
import shutil
import subprocess
import sys
import time

import numpy as np

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
from granflow_io import Run  # noqa: E402

ROOT = pathlib.Path(__file__).resolve().parent.parent
SCENARIO = ROOT / "scenarios" / "nh_multilayer_convergence.toml"
T_FINAL = 0.15

FAMILY = [(100, 2), (200, 4), (400, 8), (800, 16), (1600, 32)]
REFERENCE = (6400, 128)
QUICK_FAMILY = [(100, 2), (200, 4)]
QUICK_REFERENCE = (800, 16)

# Escalante et al. 2023, Table 5 (reference (6400, 128)): (Nx, N) -> errors and orders of h, u(z),
# w(z). The paper's w(z) errors repeat its h errors digit for digit while its w(z)
# orders differ from those of h: they are printed as they are.
PAPER = {
    (100, 2): (1.59e-2, None, 4.14e-2, None, 1.59e-2, None),
    (200, 4): (1.22e-2, 0.39, 2.62e-2, 0.66, 1.22e-2, 0.68),
    (400, 8): (6.40e-3, 0.93, 1.16e-2, 1.18, 6.40e-3, 1.29),
    (800, 16): (3.06e-3, 1.06, 5.58e-3, 1.05, 3.06e-3, 1.22),
    (1600, 32): (1.35e-3, 1.18, 2.65e-3, 1.07, 1.35e-3, 1.18),
}

OK_STATUS = ("completed",)


def pair(text):
    try:
        nx, n = (int(v) for v in text.replace("x", ",").split(","))
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected NX,N (e.g. 400,8), got {text!r}")
    if nx < 1 or n < 1:
        raise argparse.ArgumentTypeError(f"cells and layers must be positive: {text!r}")
    return nx, n


def sweep_file(path, runs, sets):
    cells = ", ".join(str(nx) for nx, _ in runs)
    layers = ", ".join(str(n) for _, n in runs)
    quoted = ", ".join(json.dumps(s) for s in sets)
    path.write_text(
        "# written by scripts/table5_convergence.py\n"
        f'scenario = "{SCENARIO.as_posix()}"\n'
        f"set = [{quoted}]\n\n"
        "[[zip]]\n"
        f"domain.cells = [{cells}]\n"
        f"model.layers = [{layers}]\n"
    )


def final_state(run):
    """(h, u, w) at t = 0.15 s: h (nx,), u and w (N, nx)."""
    k = len(run.t) - 1
    if abs(run.t[k] - T_FINAL) > 1e-9:
        raise RuntimeError(f"{run.path}: last snapshot at t = {run.t[k]}, not {T_FINAL}")
    if run.w is None:
        raise RuntimeError(f"{run.path}: no w dataset (not a non-hydrostatic run?)")
    return run.h[k], run.u[k], run.w[k]


def project(v, nx, n):
    """Average a reference field (N_f, nx_f) onto n layers and nx cells (eq. 35)."""
    n_f, nx_f = v.shape
    return v.reshape(n, n_f // n, nx, nx_f // nx).mean(axis=(1, 3))


def errors(run, ref):
    h, u, w = final_state(run)
    h_r, u_r, w_r = ref
    n, nx = u.shape
    dx = run.dx
    e_h = dx * np.abs(h - project(h_r[None, :], nx, 1)[0]).sum()

    def layered(v, v_r):
        return dx * (h / n * np.abs(v - project(v_r, nx, n)).sum(axis=0)).sum()

    return e_h, layered(u, u_r), layered(w, w_r)


def orders_along(seq, errs):
    """Observed orders between consecutive entries of seq: log(e_prev/e)/log(Nx/Nx_prev)."""
    out, prev = {}, None
    for p in seq:
        e = errs[p]
        if prev is None:
            out[p] = [None] * 3
        else:
            ratio = math.log(p[0] / prev[0])
            out[p] = [math.log(a / b) / ratio if a > 0 and b > 0 else math.nan for a, b in zip(errs[prev], e)]
        prev = p
    return out


def fmt_err(v, p):
    ours = f"{v:.3e}" if np.isfinite(v) else "   -     "
    return f"{ours} [{p:.2e}]" if p is not None else f"{ours} [   -    ]"


def fmt_order(v, p):
    ours = f"{v:5.2f}" if v is not None and np.isfinite(v) else "    -"
    return f"{ours} [{p:4.2f}]" if p is not None else f"{ours} [  - ]"


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--granflow", default=shutil.which("granflow") or str(ROOT / "target/release/granflow"))
    ap.add_argument("--jobs", type=int, default=1, help="runs at once (default 1: timings on one core)")
    ap.add_argument("--out", default=None, help="output directory (default out/table5_convergence, "
                                                 "out/table5_quick with --quick)")
    ap.add_argument("--reference", nargs=2, type=int, metavar=("NX", "N"), default=None,
                    help=f"reference cells and layers (default {REFERENCE[0]} {REFERENCE[1]})")
    ap.add_argument("--family", nargs="+", type=pair, metavar="NX,N", default=None,
                    help="the runs compared with the reference (default "
                         + " ".join(f"{a},{b}" for a, b in FAMILY) + ")")
    ap.add_argument("--quick", action="store_true",
                    help=f"reference {QUICK_REFERENCE}, family {QUICK_FAMILY} (a few seconds)")
    ap.add_argument("--min-order-h", type=float, default=None, metavar="X",
                    help="exit 1 if the last order of h is below X")
    ap.add_argument("--min-order-v", type=float, default=None, metavar="X",
                    help="exit 1 if the last order of u(z) or w(z) is below X")
    ap.add_argument("--set", action="append", default=[], dest="sets", metavar="KEY=VALUE",
                    help="scenario override passed to every run (repeatable)")
    ap.add_argument("--force", action="store_true", help="run again the runs already done")
    args = ap.parse_args()

    reference = tuple(args.reference) if args.reference else (QUICK_REFERENCE if args.quick else REFERENCE)
    family = args.family or (QUICK_FAMILY if args.quick else FAMILY)
    out = pathlib.Path(args.out or ("out/table5_quick" if args.quick else "out/table5_convergence"))
    nx_f, n_f = reference
    skipped = [p for p in family if p == reference]
    family = [p for p in family if p != reference]
    for p in skipped:
        print(f"note: {p} is the reference; left out of the family")
    bad = [(nx, n) for nx, n in family if nx_f % nx or n_f % n]
    if bad or not family:
        print(f"error: the reference {reference} must be a refinement of every run of the family "
              f"(cells and layers dividing {nx_f} and {n_f}): {bad or 'empty family'}", file=sys.stderr)
        return 2
    if len(set(family)) != len(family):
        print(f"error: a run is listed twice in the family: {family}", file=sys.stderr)
        return 2
    if not pathlib.Path(args.granflow).exists():
        print(f"error: granflow binary not found: {args.granflow} (cargo build --release)", file=sys.stderr)
        return 2
    out.mkdir(parents=True, exist_ok=True)

    runs = family + [reference]
    sw = out / "sweep.toml"
    sweep_file(sw, runs, args.sets)
    load0 = os.getloadavg()
    t0 = time.time()
    cmd = [args.granflow, "sweep", str(sw), "--jobs", str(args.jobs), "--output", str(out), "--quiet"]
    if args.force:
        cmd.append("--force")
    print(f"running {len(runs)} runs (reference {reference}) into {out}; load average {load0[0]:.2f}",
          flush=True)
    code = subprocess.run(cmd, check=False).returncode
    elapsed = time.time() - t0
    summary = {}
    summary_path = out / "summary.csv"
    if summary_path.exists():
        for r in csv.DictReader(open(summary_path)):
            summary[(int(r["domain.cells"]), int(r["model.layers"]))] = r
    failed = [p for p in runs if p not in summary or summary[p]["status"] not in OK_STATUS]
    for p in failed:
        status = summary[p]["status"] if p in summary else "no result"
        print(f"error: run {p} did not complete: {status}", file=sys.stderr)
    if code != 0 and not failed:
        print(f"error: granflow sweep exited with {code}", file=sys.stderr)
        return 1
    if reference in failed:
        return 1

    ref = final_state(Run(out / f"{summary[reference]['run']}.h5"))
    print(f"\nEscalante et al. 2023, Table 5 at t = {T_FINAL} s against ({nx_f}, {n_f}) "
          f"(paper's values in brackets, its reference (6400, 128))"
          + (f"; every run with {' '.join(args.sets)}" if args.sets else ""))
    print(f"{'(Nx, N)':>11}  {'error h':>20} {'order h':>12}  {'error u(z)':>20} {'order u':>12}  "
          f"{'error w(z)':>20} {'order w':>12}  {'wall s':>8} {'steps':>6}")
    runs_ok = {p: Run(out / f"{summary[p]['run']}.h5") for p in runs if p not in failed}
    errs = {p: errors(runs_ok[p], ref) if p in runs_ok else (math.nan,) * 3 for p in family}
    orders = orders_along(family, errs)
    rows = []
    for p in family:
        r, e, o = summary.get(p), errs[p], orders[p]
        ok = p in runs_ok
        paper = PAPER.get(p, (None,) * 6)
        wall = float(r["wall_time_s"]) if ok else math.nan
        steps = r["steps"] if ok else "-"
        print(f"{str(p):>11}  " + "  ".join(f"{fmt_err(e[v], paper[2 * v]):>20} {fmt_order(o[v], paper[2 * v + 1]):>12}"
                                            for v in range(3))
              + f"  {wall:8.2f} {steps:>6}" + ("" if ok else f"  {r['status'] if r else 'no result'}"))
        rows.append({
            "cells": p[0], "layers": p[1], "ref_cells": nx_f, "ref_layers": n_f,
            "err_h": e[0], "order_h": o[0], "err_u": e[1], "order_u": o[1],
            "err_w": e[2], "order_w": o[2],
            "paper_err_h": paper[0], "paper_order_h": paper[1], "paper_err_u": paper[2],
            "paper_order_u": paper[3], "paper_err_w": paper[4], "paper_order_w": paper[5],
            "wall_time_s": wall, "steps": steps, "status": r["status"] if r else "no result",
        })

    r = summary[reference]
    print(f"{'reference':>11}  {str(reference):>20} {'':>12}  {'':>20} {'':>12}  {'':>20} {'':>12}  "
          f"{float(r['wall_time_s']):8.2f} {r['steps']:>6}")

    # Reference-free: each run against the next finer run of the list (the last against
    # the reference). If e_k ~ C dx^p, these differences fall at the same order p.
    chain = family + [reference]
    diffs = {}
    for a, b in zip(chain, chain[1:]):
        refines = b[0] % a[0] == 0 and b[1] % a[1] == 0
        diffs[a] = (errors(runs_ok[a], final_state(runs_ok[b]))
                    if refines and a in runs_ok and b in runs_ok else (math.nan,) * 3)
    d_orders = orders_along(family, diffs)
    for a, b, prev in zip(chain[1:], chain[2:], chain):
        if b[0] * prev[0] != a[0] * a[0]:  # orders only between equal refinement ratios
            d_orders[a] = [None] * 3
    print("\ndifferences between consecutive runs (no reference; same norms):")
    print(f"{'(Nx, N)':>11} {'against':>11}  {'h':>9} {'order':>5}  {'u(z)':>9} {'order':>5}  {'w(z)':>9} {'order':>5}")
    for (a, b), row in zip(zip(chain, chain[1:]), rows):
        d, o = diffs[a], d_orders[a]
        print(f"{str(a):>11} {str(b):>11}  " + "  ".join(
            f"{d[v]:9.3e} {o[v]:5.2f}" if o[v] is not None else f"{d[v]:9.3e} {'-':>5}" for v in range(3)))
        row.update({"next_cells": b[0], "next_layers": b[1], "diff_h": d[0], "diff_order_h": d_orders[a][0],
                    "diff_u": d[1], "diff_order_u": d_orders[a][1], "diff_w": d[2], "diff_order_w": d_orders[a][2]})
    load1 = os.getloadavg()
    print(f"sweep wall time {elapsed:.1f} s (runs already done are reused); load average "
          f"{load0[0]:.2f} at the start, {load1[0]:.2f} at the end")
    with open(out / "table5.csv", "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    print(f"wrote {out / 'table5.csv'}")

    status = 1 if failed else 0
    last = rows[-1]
    for name, key, bound in (("h", "order_h", args.min_order_h), ("u(z)", "order_u", args.min_order_v),
                             ("w(z)", "order_w", args.min_order_v)):
        if bound is None:
            continue
        o = last[key]
        if o is None or not np.isfinite(o) or o < bound:
            print(f"error: last order of {name} is {o}, below {bound}", file=sys.stderr)
            status = 1
    return status


if __name__ == "__main__":
    sys.exit(main())
