#!/usr/bin/env python3
"""Error against run time for the granular model family (Escalante et al. 2023, §5.5.3, Table 9),
and for the scheme's two orders (--orders).

    python scripts/error_vs_runtime.py [--granflow PATH] [--jobs N] [--out DIR]
                                       [--slopes 0,22] [--set KEY=VALUE ...]
    python scripts/error_vs_runtime.py --orders [--granflow PATH] [--out DIR]
                                       [--cases ritter,stoker,mangeney,collapse,thacker2d,collapse2d]
                                       [--limiters minmod,van_leer,mc]
    python scripts/error_vs_runtime.py --basilisk-radial BINARY [--granflow PATH] [--out DIR]
                                       [--passes 3]

--orders: numerics.order = 1 and 2 (order 2 with each limiter of --limiters) on
  ritter    the dry dam break (scenarios/dam_break_dry.toml): L1(h) against the exact
            Ritter solution at t = 0.3 s, and the lag of the h = 1 mm front behind the
            exact 1 mm contour (relative to its distance from the dam), 256 … 4096 cells;
  stoker    the wet dam break (scenarios/dam_break_wet.toml): L1(h) against Stoker's
            solution, 256 … 4096 cells;
  mangeney  a Coulomb dam break on a 35° plane, δ = 30°, h₀ = 0.1 m on [−2.5, 2] m
            (Mangeney et al. 2000: in the frame sliding with ½ a t²,
            a = g(sin θ − cos θ tan δ), the solution is Ritter's with g cos θ):
            L1(h) over x ≥ −1.5 m (the wall's own rarefaction has not reached it)
            at t = 0.5 s, 256 … 4096 cells;
  collapse  the μ(I) collapse on 22° (scenarios/collapse.toml, ends when settled):
            |runout − runout of order 2 on 5120 cells|, 160 … 1280 cells;
  thacker2d Thacker's (1981) radial paraboloid on a raster (Cartesian, frictionless,
            bowl b = −h₀(1 − r²/a²), a = 1 m, h₀ = 0.1 m, shoreline at r₀ = 0.8 m at
            t = 0) at t = T/8: L1(h) relative to the mass, over the disk r < 0.4 m
            (which the shoreline's waves have not reached) and over the raster,
            50² … 400² cells on [−1.6, 1.6]²;
  collapse2d the radial collapse (scenarios/radial_collapse.toml, Coulomb 27°, its
            deposit at t = 1 s): L1(h) relative to the mass against order 2 (MC) on
            320² cells, its cell means averaged onto the coarser grid, 40² … 160² cells.
It prints one table per case (cells, order, limiter, error, observed order between
successive grids, wall time from /summary/wall_time_s, CPU time: user + system of the
run's process) and writes DIR/orders.csv. One run at a time (rasters on
`--threads`, default 1).

--basilisk-radial: the radial collapse side by side with Basilisk's saint-venant.h
  (BINARY built from benches/basilisk/saint_venant_radial.c with Basilisk's qcc):
  granflow's orders 1 and 2 (MC) and Basilisk's orders 1 and 2 on 40², 80², 160² cells,
  each deposit at t = 1 s against the same reference (granflow's order 2 on 320²,
  averaged onto the coarser grid; L1(h) relative to the mass), and the distance between
  the two codes' 320² order-2 deposits (how much the reference favours granflow).
  granflow writes snapshots at 0 and 1 s only (output.every = 1), Basilisk its final h
  as text. CPU: user + system of each process, median of --passes passes interleaved
  between the codes. Writes DIR/basilisk_radial.csv.

Runs, through one `granflow sweep` per slope, the collapse of Escalante et al. 2023, §5.1/§5.5
(scenarios/nh_multilayer_collapse.toml: domain [-0.2, 3] m, 640 cells, Table 1
material, CFL 0.1) with the models of Table 9 — H-1, H-10, H-20 l. and NH-1, NH-2,
NH-5, NH-8, NH-10 l. — and the reference NH-20 l., for
  θ = 0°:  h_i = 1 mm,    t_ini = 0.24 s, t_fin = 1.5 s,
  θ = 22°: h_i = 1.82 mm, t_ini = 0.32 s, t_fin = 3 s.
It prints the relative l2 error of h against NH-20 l. at t_ini and t_fin and the
wall time of each run beside the paper's values, writes DIR/error_vs_runtime.csv
and DIR/error_vs_runtime.png (error against wall time, log-log, one labelled point
per model, both slopes), and exits with 1 if a reference run failed (2 on bad
arguments). `--set` is passed to every run (e.g. `--set domain.cells=160` for a
quick check; the errors are then not those of the paper's grid).
"""

import argparse
import csv
import pathlib
import shutil
import subprocess
import sys

import numpy as np

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
from granflow_io import Run  # noqa: E402

ROOT = pathlib.Path(__file__).resolve().parent.parent
SCENARIO = ROOT / "scenarios" / "nh_multilayer_collapse.toml"

# (pressure, layers, label); the reference is NH-20 l.
MODELS = [
    ("nonhydrostatic", 20, "NH-20 l."),
    ("nonhydrostatic", 10, "NH-10 l."),
    ("nonhydrostatic", 8, "NH-8 l."),
    ("nonhydrostatic", 5, "NH-5 l."),
    ("nonhydrostatic", 2, "NH-2 l."),
    ("nonhydrostatic", 1, "NH-1 l."),
    ("hydrostatic", 20, "H-20 l."),
    ("hydrostatic", 10, "H-10 l."),
    ("hydrostatic", 1, "H-1 l."),
]

# slope: (h_i, t_ini, t_fin, output interval, {label: (err t_ini %, err t_fin %, t_comp s)})
CASES = {
    0: (1e-3, 0.24, 1.5, 0.06, {
        "NH-20 l.": (None, None, 1096.7), "NH-10 l.": (0.30, 0.33, 368.2),
        "NH-8 l.": (0.45, 0.47, 197.7), "NH-5 l.": (0.79, 0.88, 60.1),
        "NH-2 l.": (1.68, 1.93, 14.2), "NH-1 l.": (3.05, 2.30, 6.4),
        "H-20 l.": (10.01, 8.32, 56.1), "H-10 l.": (10.41, 8.58, 28.8),
        "H-1 l.": (11.65, 11.25, 4.7)}),
    22: (1.82e-3, 0.32, 3.0, 0.04, {
        "NH-20 l.": (None, None, 1517.4), "NH-10 l.": (0.92, 1.92, 544.6),
        "NH-8 l.": (1.31, 2.87, 290.6), "NH-5 l.": (2.19, 5.58, 89.2),
        "NH-2 l.": (4.70, 14.18, 21.0), "NH-1 l.": (6.47, 22.80, 9.7),
        "H-20 l.": (7.36, 11.21, 79.4), "H-10 l.": (8.23, 12.90, 41.0),
        "H-1 l.": (11.78, 31.93, 7.1)}),
}


def sweep_file(path, slope, extra_sets):
    h_i, _, t_fin, every, _ = CASES[slope]
    sets = [
        "time.cfl=0.1",
        f"domain.slope_deg={slope}",
        f"initial.erodible_bed={h_i}",
        f"time.t_end={t_fin}",
        f"output.every={every}",
        "time.stop_at_rest=false",
    ] + list(extra_sets)
    pressures = ", ".join(f'"{p}"' for p, _, _ in MODELS)
    layers = ", ".join(str(n) for _, n, _ in MODELS)
    path.write_text(
        f'scenario = "{SCENARIO}"\n'
        f"set = [{', '.join(repr(s).replace(chr(39), chr(34)) for s in sets)}]\n\n"
        "[[zip]]\n"
        f"model.pressure = [{pressures}]\n"
        f"model.layers = [{layers}]\n"
    )


def h_at(run, t):
    k = int(np.argmin(np.abs(run.t - t)))
    if abs(run.t[k] - t) > 1e-9:
        raise RuntimeError(f"{run.path}: no snapshot at t = {t} (nearest {run.t[k]})")
    return run.h[k]


def l2_percent(h, ref):
    return 100.0 * np.linalg.norm(h - ref) / np.linalg.norm(ref)


G = 9.81


def dam_break_h(x, t, h_l, h_r, g=G):
    """Exact depth of the flat frictionless dam break h_l | h_r (h_r = 0: Ritter)."""
    c_l = np.sqrt(g * h_l)
    if h_r == 0.0:
        h_m, u_m, shock = 0.0, 2 * c_l, 2 * c_l
    else:
        def mismatch(h):
            return 2 * (c_l - np.sqrt(g * h)) - (h - h_r) * np.sqrt(g * (h + h_r) / (2 * h * h_r))
        lo, hi = h_r, h_l
        for _ in range(200):
            mid = 0.5 * (lo + hi)
            lo, hi = (mid, hi) if mismatch(mid) > 0 else (lo, mid)
        h_m = 0.5 * (lo + hi)
        u_m = 2 * (c_l - np.sqrt(g * h_m))
        shock = u_m * h_m / (h_m - h_r)
    xi = x / t
    c_m = np.sqrt(g * h_m)
    fan = (2 * c_l - xi) ** 2 / (9 * g)
    return np.where(xi <= -c_l, h_l, np.where(xi <= u_m - c_m, fan, np.where(xi < shock, h_m, h_r)))


MANGENEY = dict(theta=35.0, delta=30.0, h0=0.1, t=0.5)
MANGENEY_TOML = f"""# Coulomb dam break on a slope (Mangeney et al. 2000), written by error_vs_runtime.py
[domain]
x_min = -2.5
x_max = 2.0
cells = 400
slope_deg = {MANGENEY['theta']}

[rheology]
law = "coulomb"
mu_deg = {MANGENEY['delta']}

[initial]
h = "if(x < 0, {MANGENEY['h0']}, 0)"

[boundary]
right = "outflow"

[time]
t_end = {MANGENEY['t']}
cfl = 0.5

[output]
every = {MANGENEY['t']}
"""


def mangeney_h(x, t):
    th, de = np.radians(MANGENEY["theta"]), np.radians(MANGENEY["delta"])
    g_n = G * np.cos(th)
    a = G * (np.sin(th) - np.cos(th) * np.tan(de))
    return dam_break_h(x - 0.5 * a * t * t, t, MANGENEY["h0"], 0.0, g=g_n)


def run_case(granflow, scenario, cells, sets, h5):
    cmd = [granflow, "run", str(scenario), "-q", "-o", str(h5), "--set", f"domain.cells={cells}"]
    for s in sets:
        cmd += ["--set", s]
    subprocess.run(cmd, check=True)
    return Run(h5)


# Thacker's (1981) radial paraboloid (module documentation).
THACKER = dict(a=1.0, h0=0.1, r0=0.8)


def thacker_h(x, y, t):
    a, h0, r0 = THACKER["a"], THACKER["h0"], THACKER["r0"]
    big_a = (a * a - r0 * r0) / (a * a + r0 * r0)
    omega = np.sqrt(8 * G * h0) / a
    c = 1 - big_a * np.cos(omega * t)
    r2 = (x * x + y * y) / (a * a)
    eta = h0 * (np.sqrt(1 - big_a ** 2) / c - 1 - r2 * ((1 - big_a ** 2) / c ** 2 - 1))
    return np.maximum(eta + h0 * (1 - r2), 0.0)


def thacker_toml():
    a, h0, r0 = THACKER["a"], THACKER["h0"], THACKER["r0"]
    big_a = (a * a - r0 * r0) / (a * a + r0 * r0)
    period = float(2 * np.pi / (np.sqrt(8 * G * h0) / a))
    k0 = float(np.sqrt(1 - big_a ** 2) / (1 - big_a) - 1)
    k2 = float((1 - big_a ** 2) / (1 - big_a) ** 2 - 1)
    return f"""[domain]
x_min = -1.6
x_max = 1.6
y_min = -1.6
y_max = 1.6
cells = [100, 100]
coordinates = "cartesian"

[bed]
b = "-{h0}*(1 - (x^2 + y^2)/{a * a})"

[rheology]
law = "coulomb"
mu = 0.0

[model]
kind = "granular"

[initial]
h = "max({h0}*({k0!r} - (x^2 + y^2)/{a * a}*{k2!r}) + {h0}*(1 - (x^2 + y^2)/{a * a}), 0)"

[boundary]
west = "wall"
east = "wall"
south = "wall"
north = "wall"

[time]
t_end = {period / 8!r}
cfl = 0.4

[output]
every = {period / 8!r}
"""


def raster_run(granflow, scenario, n, sets, h5, threads):
    """Runs `scenario` on n × n cells; returns (x, y, h at the end, t_end, wall s, CPU s)."""
    import h5py
    import resource
    cmd = [granflow, "run", str(scenario), "-q", "-o", str(h5), "--threads", str(threads),
           "--set", f"domain.cells=[{n},{n}]"]
    for s in sets:
        cmd += ["--set", s]
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    subprocess.run(cmd, check=True)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    with h5py.File(h5, "r") as f:
        x, y = f["grid/x"][:], f["grid/y"][:]
        h = f["snapshots/h"][-1]
        t = float(f["snapshots/t"][-1])
        wall = float(f["summary"].attrs["wall_time_s"])
    return x, y, h, t, wall, cpu


def coarsen2d(h, factor):
    ny, nx = h.shape
    return h.reshape(ny // factor, factor, nx // factor, factor).mean(axis=(1, 3))


def orders_2d(args, name, out, schemes, rows):
    """The raster cases of the order study (module documentation)."""
    if name == "thacker2d":
        scenario = out / "thacker2d.toml"
        scenario.write_text(thacker_toml())
        grids = [50, 100, 200, 400]
        labels = ["L1(h) r<0.4", "L1(h) all"]

        def errors(x, y, h, t, n):
            xx, yy = np.meshgrid(x, y)
            exact = thacker_h(xx, yy, t)
            inner = xx ** 2 + yy ** 2 < 0.16
            e = np.abs(h - exact)
            return [float(e[inner].sum() / exact[inner].sum()), float(e.sum() / exact.sum())]
    else:
        scenario = ROOT / "scenarios" / "radial_collapse.toml"
        grids, fine = [40, 80, 160], 320
        labels = ["L1(h) vs 320²"]
        ref_h5 = out / "collapse2d_reference.h5"
        _, _, ref, _, wall, cpu = raster_run(args.granflow, scenario, fine,
                                             ["numerics.order=2", "numerics.limiter=mc"], ref_h5, args.threads)
        print(f"\ncollapse2d: reference order 2 (mc) on {fine}² cells, wall {wall:.1f} s, CPU {cpu:.1f} s")

        def errors(x, y, h, t, n):
            r = coarsen2d(ref, fine // n)
            return [float(np.abs(h - r).sum() / r.sum())]
    print(f"\n{name}")
    for order, lim in schemes:
        prev = None
        for n in grids:
            sets = [f"numerics.order={order}"] + ([f"numerics.limiter={lim}"] if lim else [])
            h5 = out / f"{name}_o{order}_{lim or 'none'}_{n}.h5"
            x, y, h, t, wall, cpu = raster_run(args.granflow, scenario, n, sets, h5, args.threads)
            values = errors(x, y, h, t, n)
            orders = ([np.log(p / v) / np.log(2) if p > 0 and v > 0 else float("nan")
                       for p, v in zip(prev, values)] if prev else [float("nan")] * len(values))
            prev = values
            text = "  ".join(f"{label} {v:.4e} (order {o:5.2f})" for label, v, o in zip(labels, values, orders))
            print(f"  order {order} {lim or '':9} {n:4}² cells  {text}  wall {wall:.3f} s  CPU {cpu:.3f} s")
            for label, v, o in zip(labels, values, orders):
                rows.append(dict(case=name, order=order, limiter=lim or "", cells=n * n, measure=label,
                                 error=v, observed_order=o, wall_s=wall, cpu_s=cpu))


def basilisk_radial_h(binary, n, order, path):
    """Basilisk's deposit on n × n cells: (h as granflow's (ny, nx) array, CPU s)."""
    import resource
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    subprocess.run([binary, str(n), str(order), str(path)], check=True, stdout=subprocess.DEVNULL,
                   stderr=subprocess.DEVNULL)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    x, y, h = np.loadtxt(path, unpack=True)
    dx = 3.0 / n
    i = np.rint((x + 1.5) / dx - 0.5).astype(int)
    j = np.rint((y + 1.5) / dx - 0.5).astype(int)
    grid = np.full((n, n), np.nan)
    grid[j, i] = h
    if np.isnan(grid).any():
        raise RuntimeError(f"{binary}: {n}² cells expected, some missing")
    return grid, cpu


def basilisk_radial(args):
    """The radial collapse side by side with Basilisk (module documentation)."""
    out = pathlib.Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    scenario = ROOT / "scenarios" / "radial_collapse.toml"
    fine, grids = 320, [40, 80, 160]
    few = ["output.every=1"]
    x, y, ref, _, _, cpu = raster_run(args.granflow, scenario, fine, few + ["numerics.order=2", "numerics.limiter=mc"],
                                      out / "radial_granflow_ref.h5", 1)
    if not (np.allclose(x, -1.5 + 3.0 / fine * (np.arange(fine) + 0.5))
            and np.allclose(y, -1.5 + 3.0 / fine * (np.arange(fine) + 0.5))):
        raise RuntimeError("granflow's y axis is not increasing: the Basilisk grid cannot be matched")
    bas_ref, bas_cpu = basilisk_radial_h(args.basilisk_radial, fine, 2, out / "radial_basilisk_ref.txt")
    gap = float(np.abs(bas_ref - ref).sum() / ref.sum())
    print(f"reference: granflow order 2 (mc) on {fine}², CPU {cpu:.2f} s; Basilisk order 2 on {fine}², "
          f"CPU {bas_cpu:.2f} s; L1 distance between the two {gap:.4e}")
    runs = {}
    for p in range(args.passes):
        for n in grids:
            for code, order in (("granflow", 1), ("granflow", 2), ("basilisk", 1), ("basilisk", 2)):
                if code == "granflow":
                    sets = few + [f"numerics.order={order}"] + (["numerics.limiter=mc"] if order == 2 else [])
                    _, _, h, _, _, c = raster_run(args.granflow, scenario, n, sets,
                                                  out / f"radial_granflow_o{order}_{n}.h5", 1)
                else:
                    h, c = basilisk_radial_h(args.basilisk_radial, n, order, out / f"radial_basilisk_o{order}_{n}.txt")
                r = coarsen2d(ref, fine // n)
                err = float(np.abs(h - r).sum() / r.sum())
                runs.setdefault((code, order, n), []).append((err, c))
    rows = []
    print(f"\n{'code':9} {'order':>5} {'cells':>6} {'L1(h) rel.':>11} {'CPU s (median)':>15}  CPU s of each pass")
    for (code, order, n), v in sorted(runs.items()):
        cpus = [c for _, c in v]
        med = float(np.median(cpus))
        print(f"{code:9} {order:5} {n:5}² {v[0][0]:11.4e} {med:15.4f}  {' '.join(f'{c:.4f}' for c in cpus)}")
        rows.append(dict(code=code, order=order, cells=n * n, error=v[0][0], cpu_s=med))
    with open(out / "basilisk_radial.csv", "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    print(f"\nwrote {out / 'basilisk_radial.csv'}")
    return 0


def orders_study(args):
    out = pathlib.Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    scen = ROOT / "scenarios"
    (out / "mangeney.toml").write_text(MANGENEY_TOML)
    fine = [256, 512, 1024, 2048, 4096]

    def l1_h(exact, x_from=-np.inf):
        def error(r):
            keep = r.x >= x_from
            return float(np.sum(np.abs(r.h[-1] - exact(r.x, r.t[-1]))[keep]) * r.dx)
        return error

    ritter_front = 0.3 * (2 * np.sqrt(G) - 3 * np.sqrt(G * 1e-3))
    cases = {
        "ritter": (scen / "dam_break_dry.toml", fine, [
            ("L1(h) m²", l1_h(lambda x, t: dam_break_h(x, t, 1.0, 0.0))),
            ("front lag", lambda r: (ritter_front - float(r.front_x[-1])) / ritter_front)]),
        "stoker": (scen / "dam_break_wet.toml", fine, [
            ("L1(h) m²", l1_h(lambda x, t: dam_break_h(x, t, 1.0, 0.1)))]),
        "mangeney": (out / "mangeney.toml", fine, [("L1(h) m²", l1_h(mangeney_h, -1.5))]),
        "collapse": (scen / "collapse.toml", [160, 320, 640, 1280], [("runout error m", None)]),
    }
    limiters = args.limiters.split(",")
    schemes = [(1, None)] + [(2, lim) for lim in limiters]
    rows = []
    for name in args.cases.split(","):
        if name in ("thacker2d", "collapse2d"):
            orders_2d(args, name, out, schemes, rows)
            continue
        scenario, cells_list, measures = cases[name]
        reference = None
        if name == "collapse":
            h5 = out / "collapse_reference.h5"
            ref = run_case(args.granflow, scenario, 5120, ["numerics.order=2"], h5)
            reference = float(ref.summary["runout"])
            print(f"\ncollapse: reference runout {reference:.4f} m (order 2, {ref.attrs.get('limiter', 'default limiter')}, 5120 cells)")
        print(f"\n{name}")
        for order, lim in schemes:
            prev = None
            for cells in cells_list:
                sets = [f"numerics.order={order}"] + ([f"numerics.limiter={lim}"] if lim else [])
                h5 = out / f"{name}_o{order}_{lim or 'none'}_{cells}.h5"
                r = run_case(args.granflow, scenario, cells, sets, h5)
                values = []
                for label, f in measures:
                    values.append(abs(float(r.summary["runout"]) - reference) if f is None else f(r))
                wall = float(r.summary["wall_time_s"])
                orders = ([np.log(p / v) / np.log(2) if p > 0 and v > 0 else float("nan")
                           for p, v in zip(prev, values)] if prev else [float("nan")] * len(values))
                prev = values
                text = "  ".join(f"{label} {v:.4e} (order {o:5.2f})" for (label, _), v, o in zip(measures, values, orders))
                print(f"  order {order} {lim or '':9} {cells:5} cells  {text}  wall {wall:.4f} s")
                for (label, _), v, o in zip(measures, values, orders):
                    rows.append(dict(case=name, order=order, limiter=lim or "", cells=cells, measure=label,
                                     error=v, observed_order=o, wall_s=wall, cpu_s=float("nan")))
    with open(out / "orders.csv", "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    print(f"\nwrote {out / 'orders.csv'}")
    return 0


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--orders", action="store_true", help="the order study (module documentation)")
    ap.add_argument("--basilisk-radial", metavar="BINARY",
                    help="the radial collapse side by side with this Basilisk binary (module documentation)")
    ap.add_argument("--passes", type=int, default=3, help="interleaved passes (--basilisk-radial)")
    ap.add_argument("--cases", default="ritter,stoker,mangeney,collapse")
    ap.add_argument("--limiters", default="minmod,van_leer,mc")
    ap.add_argument("--granflow", default=shutil.which("granflow") or str(ROOT / "target/release/granflow"))
    ap.add_argument("--jobs", type=int, default=1, help="runs at once (default 1: timings on an idle core)")
    ap.add_argument("--threads", type=int, default=1, help="threads of a raster run (--orders)")
    ap.add_argument("--out", default="out/error_vs_runtime")
    ap.add_argument("--slopes", default="0,22")
    ap.add_argument("--set", action="append", default=[], dest="sets")
    args = ap.parse_args()
    if not pathlib.Path(args.granflow).exists():
        print(f"error: granflow binary not found: {args.granflow} (cargo build --release)", file=sys.stderr)
        return 2
    if args.basilisk_radial:
        if not pathlib.Path(args.basilisk_radial).exists():
            print(f"error: Basilisk binary not found: {args.basilisk_radial}", file=sys.stderr)
            return 2
        return basilisk_radial(args)
    if args.orders:
        known = ("ritter", "stoker", "mangeney", "collapse", "thacker2d", "collapse2d")
        bad = [c for c in args.cases.split(",") if c not in known]
        bad += [l for l in args.limiters.split(",") if l not in ("minmod", "van_leer", "mc")]
        if bad:
            print(f"error: unknown case or limiter: {', '.join(bad)}", file=sys.stderr)
            return 2
        return orders_study(args)
    try:
        slopes = [int(float(s)) for s in args.slopes.split(",")]
        if any(s not in CASES for s in slopes):
            raise ValueError
    except ValueError:
        print(f"error: --slopes takes values among {sorted(CASES)}", file=sys.stderr)
        return 2
    if not pathlib.Path(args.granflow).exists():
        print(f"error: granflow binary not found: {args.granflow} (cargo build --release)", file=sys.stderr)
        return 2
    out = pathlib.Path(args.out)
    out.mkdir(parents=True, exist_ok=True)

    rows, failed = [], False
    for slope in slopes:
        _, t_ini, t_fin, _, paper = CASES[slope]
        d = out / f"theta_{slope}"
        d.mkdir(exist_ok=True)
        sw = d / "sweep.toml"
        sweep_file(sw, slope, args.sets)
        cmd = [args.granflow, "sweep", str(sw), "--jobs", str(args.jobs), "--output", str(d), "--quiet"]
        subprocess.run(cmd, check=False)
        summary = {r["run"]: r for r in csv.DictReader(open(d / "summary.csv"))}
        by_label = {}
        for (pressure, layers, label), r in zip(MODELS, summary.values()):
            assert r["model.pressure"] == pressure and int(r["model.layers"]) == layers, r
            by_label[label] = r
        ref_row = by_label["NH-20 l."]
        if not ref_row["status"] in ("completed", "stopped_at_rest"):
            print(f"error: θ = {slope}°: the reference NH-20 l. run failed: {ref_row['status']}", file=sys.stderr)
            failed = True
            continue
        ref = Run(d / f"{ref_row['run']}.h5")
        ref_ini, ref_fin = h_at(ref, t_ini), h_at(ref, t_fin)
        print(f"\nθ = {slope}°  (t_ini = {t_ini} s, t_fin = {t_fin} s; paper's values in brackets)")
        print(f"{'model':10} {'err t_ini %':>18} {'err t_fin %':>18} {'wall s':>18}")
        for _, _, label in MODELS:
            r = by_label[label]
            p_ini, p_fin, p_t = paper[label]
            ok = r["status"] in ("completed", "stopped_at_rest")
            if ok and label != "NH-20 l.":
                run = Run(d / f"{r['run']}.h5")
                e_ini, e_fin = l2_percent(h_at(run, t_ini), ref_ini), l2_percent(h_at(run, t_fin), ref_fin)
            else:
                e_ini = e_fin = float("nan")
            wall = float(r["wall_time_s"]) if ok else float("nan")
            fmt = lambda v, p: f"{v:7.2f} [{p:6.2f}]" if p is not None else f"{'-':>7} [{'-':>6}]"
            print(f"{label:10} {fmt(e_ini, p_ini):>18} {fmt(e_fin, p_fin):>18} {wall:8.2f} [{p_t:7.1f}]"
                  + ("" if ok else f"  {r['status']}"))
            rows.append(dict(slope_deg=slope, model=label, err_t_ini_pct=e_ini, err_t_fin_pct=e_fin,
                             wall_s=wall, paper_err_t_ini_pct=p_ini, paper_err_t_fin_pct=p_fin,
                             paper_t_comp_s=p_t, status=r["status"]))

    with open(out / "error_vs_runtime.csv", "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0]) if rows else ["slope_deg"])
        w.writeheader()
        w.writerows(rows)
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        fig, ax = plt.subplots(figsize=(7, 5))
        for slope, marker in ((0, "o"), (22, "s")):
            pts = [r for r in rows if r["slope_deg"] == slope and np.isfinite(r["err_t_fin_pct"])]
            if not pts:
                continue
            ax.loglog([r["wall_s"] for r in pts], [r["err_t_fin_pct"] for r in pts], marker,
                      linestyle="none", label=f"θ = {slope}° (error at t_fin)")
            for r in pts:
                ax.annotate(r["model"], (r["wall_s"], r["err_t_fin_pct"]), fontsize=7,
                            xytext=(3, 3), textcoords="offset points")
        ax.set_xlabel("wall time (s)")
        ax.set_ylabel("relative l2 error of h against NH-20 l. (%)")
        ax.legend()
        import plot_common
        plot_common.readable_log_axis(ax.xaxis)
        plot_common.readable_log_axis(ax.yaxis)
        ax.grid(True, which="major", alpha=0.3)
        fig.tight_layout()
        try:
            plot_common.save(fig, out / "error_vs_runtime.png", 150)
        except plot_common.EmptyPlot as e:
            return plot_common.fail_empty(e)
    except ImportError:
        print("matplotlib not installed: no plot", file=sys.stderr)
    print(f"\nwrote {out / 'error_vs_runtime.csv'} and {out / 'error_vs_runtime.png'}")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
