#!/usr/bin/env python3
"""Validate a granflow HDF5 file against the output contract (docs/output-format.md).

    python scripts/check_output.py FILE.h5 [--expect-layers N] [--unfinished]

A raster (2-D) run (root attribute grid = "raster") is checked against its own
layout: (ny, nx) grid arrays, (nt, ny, nx) snapshots (NaN exactly on the wall cells,
the NaN cells of /grid/b), the volume in /diagnostics/mass against sum(h) dx dy of
the snapshots, the /maps (h_max >= deposit, arrival_time NaN
exactly where h_max never exceeded the front threshold) and the XDMF file beside it
(it parses, and every dataset it names exists with the dimensions it states).

Prints one line starting with "OK" and exits 0 when the file conforms; otherwise
prints every problem found, one per line on stderr, and exits 1.
--unfinished accepts a file whose run has not reached finish() yet (no /summary
attributes), e.g. one read while the run is going or after it was killed.
"""

import argparse
import os
import sys
import xml.etree.ElementTree as ET

import h5py
import numpy as np

FORMAT_VERSION = 1

ROOT_ATTRS = {
    "format_version": "int",
    "granflow_version": "str",
    "model": "str",
    "pressure": "str",
    "layers": "int",
    "coordinates": "str",
    "slope_deg": "float",
    "scenario_toml": "str",
}
SUMMARY_ATTRS = {
    "runout": "float",
    "stop_time": "float",
    "settled_time": "float",
    "h_max_final": "float",
    "t_end": "float",
    "steps": "int",
    "wall_time_s": "float",
    "status": "str",
    "outflowed_fraction": "float",
    "front_at_end_time": "float",
    "max_speed_final": "float",
}

# The statuses a finished run can have (docs/output-format.md, /summary).
FINAL_STATUSES = ("completed", "stopped_at_rest", "settled", "outflowed", "no_mass",
                  "interrupted")
UNITS = {
    "grid/x": "m",
    "grid/b": "m",
    "grid/h_bed": "m",
    "snapshots/t": "s",
    "snapshots/h": "m",
    "snapshots/u": "m/s",
    "snapshots/w": "m/s",
    "snapshots/p_nh": "m^2/s^2",
    "snapshots/static_interface": "m",
    "snapshots/x": "m",
    "snapshots/layer": "1",
    "snapshots/level": "1",
    "snapshots/x_face": "m",
    "front/t": "s",
    "front/x": "m",
    "diagnostics/t": "s",
    "diagnostics/dt": "s",
    "diagnostics/mass": "m^2",
    "diagnostics/kinetic_energy": "m^4/s^2",
    "diagnostics/max_speed": "m/s",
}
OPTIONAL = ("snapshots/w", "snapshots/p_nh", "snapshots/static_interface", "snapshots/level",
            "snapshots/x_face")
REQUIRED = [name for name in UNITS if name not in OPTIONAL]
DIAGNOSTICS = ["t", "dt", "mass", "kinetic_energy", "max_speed"]


class Problems(Exception):
    pass


class Checker:
    def __init__(self, f, expect_layers, unfinished):
        self.f = f
        self.expect_layers = expect_layers
        self.unfinished = unfinished
        self.problems = []
        self.walls = None

    def fail(self, message):
        self.problems.append(message)

    def typed(self, where, name, value, kind):
        ok = {
            "int": isinstance(value, (int, np.integer)),
            "float": isinstance(value, (float, np.floating)),
            "str": isinstance(value, (str, bytes)),
        }[kind]
        if not ok:
            self.fail(f"{where} attribute {name!r} should be {kind}, is {type(value).__name__}")

    def attrs(self, where, obj, spec):
        for name, kind in spec.items():
            if name not in obj.attrs:
                self.fail(f"{where} attribute {name!r} is missing")
            else:
                self.typed(where, name, obj.attrs[name], kind)

    def datasets(self):
        """Required datasets exist, are float64 and carry the right units."""
        for name, unit in UNITS.items():
            if name not in self.f:
                if name in REQUIRED:
                    self.fail(f"dataset /{name} is missing")
                continue
            ds = self.f[name]
            if not isinstance(ds, h5py.Dataset):
                self.fail(f"/{name} is not a dataset")
                continue
            if ds.dtype != np.float64:
                self.fail(f"/{name} has dtype {ds.dtype}, expected float64")
            got = ds.attrs.get("units")
            if isinstance(got, bytes):
                got = got.decode()
            if got != unit:
                self.fail(f"/{name} units attribute is {got!r}, expected {unit!r}")

    def shapes(self):
        """Returns (nx, nl, nt, dx) from consistent shapes, or raises Problems."""
        f = self.f
        nx = f["grid/x"].shape[0] if f["grid/x"].ndim == 1 else -1
        for name in ("grid/x", "grid/b", "grid/h_bed"):
            if f[name].shape != (nx,):
                self.fail(f"/{name} has shape {f[name].shape}, expected ({nx},)")
        nl = int(f.attrs.get("layers", 0))
        if self.expect_layers is not None and nl != self.expect_layers:
            self.fail(f"layers attribute is {nl}, expected {self.expect_layers}")
        nt = f["snapshots/t"].shape[0] if f["snapshots/t"].ndim == 1 else -1
        expected = {
            "snapshots/t": (nt,),
            "snapshots/h": (nt, nx),
            "snapshots/u": (nt, nl, nx),
            "snapshots/w": (nt, nl, nx),
            "snapshots/p_nh": (nt, nl + 1, nx + 1),
            "snapshots/static_interface": (nt, nx),
            # Coordinates (dimension scales) of the snapshot axes.
            "snapshots/x": (nx,),
            "snapshots/layer": (nl,),
            "snapshots/level": (nl + 1,),
            "snapshots/x_face": (nx + 1,),
        }
        for name, shape in expected.items():
            if name in f and f[name].shape != shape:
                self.fail(f"/{name} has shape {f[name].shape}, expected {shape}")
        # Model-specific per-cell fields: one frame per snapshot, with units.
        for name, ds in f["snapshots"].items():
            path = f"snapshots/{name}"
            if path in expected or not isinstance(ds, h5py.Dataset):
                continue
            if ds.shape[:1] != (nt,):
                self.fail(f"/{path} has shape {ds.shape}, expected ({nt}, ...)")
            if "units" not in ds.attrs:
                self.fail(f"/{path} has no units attribute")
        pressure = f.attrs.get("pressure")
        if nt > 0 and (pressure == "nonhydrostatic") != ("snapshots/p_nh" in f):
            self.fail(f"pressure is {pressure!r} but /snapshots/p_nh is "
                      f"{'present' if 'snapshots/p_nh' in f else 'absent'}")
        n_diag = {f[f"diagnostics/{d}"].shape for d in DIAGNOSTICS}
        if len(n_diag) != 1 or len(next(iter(n_diag))) != 1:
            self.fail(f"/diagnostics arrays differ in shape: {sorted(n_diag)}")
        if f["front/t"].shape != f["front/x"].shape or f["front/t"].ndim != 1:
            self.fail(f"/front/t {f['front/t'].shape} and /front/x {f['front/x'].shape} differ")
        if "threshold" not in f["front"].attrs:
            self.fail("/front attribute 'threshold' is missing")
        if self.problems:
            raise Problems
        return nx, nl, nt

    def values(self, nx):
        f = self.f
        x = f["grid/x"][:]
        if nx > 1 and not np.all(np.diff(x) > 0):
            self.fail("/grid/x is not strictly increasing")
        h = f["snapshots/h"][:]
        u = f["snapshots/u"][:]
        for name, a in (("h", h), ("u", u)):
            if not np.isfinite(a).all():
                k = int(np.argwhere(~np.isfinite(a))[0][0])
                self.fail(f"/snapshots/{name} has non-finite values (first in snapshot {k})")
        if (h < 0).any():
            self.fail(f"/snapshots/h has negative values (min {np.nanmin(h):.3g})")
        if "snapshots/static_interface" in f:
            s = f["snapshots/static_interface"][:]
            if np.isnan(s).any() or (s < 0).any() or (s > h * (1 + 1e-12)).any():
                self.fail("/snapshots/static_interface is not within [0, h]")
        for d in DIAGNOSTICS:
            a = f[f"diagnostics/{d}"][:]
            if not np.isfinite(a).all():
                k = int(np.argwhere(~np.isfinite(a))[0][0])
                self.fail(f"/diagnostics/{d} has non-finite values (first at step {k})")
        for name in ("snapshots/t", "diagnostics/t", "front/t"):
            t = f[name][:]
            if np.isnan(t).any() or (np.diff(t) < 0).any():
                self.fail(f"/{name} is not a non-decreasing time series")
        if "gauges" in f:
            self.gauges(x)
        return x, h

    def gauges(self, x):
        """/gauges (runs with output.gauges): shapes, positions in the domain, finite
        values, increasing times, non-negative grain depth."""
        g = self.f["gauges"]
        missing = [n for n in ("x", "t", "eta", "h_grains") if n not in g]
        if missing:
            self.fail(f"/gauges lacks {missing}")
            return
        gx, t = g["x"][:], g["t"][:]
        n, nt = len(gx), len(t)
        for name in ("eta", "h_grains"):
            if g[name].shape != (nt, n):
                self.fail(f"/gauges/{name} has shape {g[name].shape}, expected ({nt}, {n})")
                return
            if not np.isfinite(g[name][:]).all():
                self.fail(f"/gauges/{name} has non-finite values")
        dx = x[1] - x[0] if len(x) > 1 else 0.0
        if n == 0 or (gx < x[0] - dx).any() or (gx > x[-1] + dx).any():
            self.fail(f"/gauges/x {gx} is empty or outside the domain")
        if np.isnan(t).any() or (np.diff(t) <= 0).any():
            self.fail("/gauges/t is not an increasing time series")
        if (g["h_grains"][:] < 0).any():
            self.fail("/gauges/h_grains has negative values")

    def mass(self, x, h, nx):
        """Mass = sum(h) dx at snapshot times that are also diagnostics times."""
        f = self.f
        model = f.attrs.get("model")
        if isinstance(model, bytes):
            model = model.decode()
        dilatant = model == "dilatant"
        if nx < 2:
            return 0
        if dilatant:
            # The dilatant mass is the grain volume, the integral of phi*h.
            if "snapshots/phi" not in f:
                self.fail("a dilatant run has no /snapshots/phi")
                return 0
            phi = f["snapshots/phi"][:]
            wet = h > 0
            if not ((phi[wet] > 0) & (phi[wet] < 1)).all():
                self.fail("/snapshots/phi leaves (0, 1) in a cell with h > 0")
            h = phi * h
        dx = np.diff(x)
        if not np.allclose(dx, dx[0], rtol=1e-9, atol=0):
            return 0  # the check assumes a uniform grid
        dx = (x[-1] - x[0]) / (nx - 1)
        td = f["diagnostics/t"][:]
        mass = f["diagnostics/mass"][:]
        checked = 0
        for k, t in enumerate(f["snapshots/t"][:]):
            hits = np.flatnonzero(np.abs(td - t) <= 1e-12 * max(1.0, abs(t)))
            if hits.size == 0:
                continue
            want = h[k].sum() * dx
            got = mass[hits[-1]]
            checked += 1
            if abs(got - want) > 1e-9 * max(abs(want), abs(got), np.finfo(float).tiny):
                what = "sum(phi*h)*dx" if dilatant else "sum(h)*dx"
                self.fail(f"/diagnostics/mass at t = {t:g} is {got:.15g}, "
                          f"but {what} of the snapshot is {want:.15g}")
        return checked

    def summary(self, nt):
        f = self.f
        if "summary" not in f:
            self.fail("group /summary is missing")
            return None
        status = f["summary"].attrs.get("status")
        if isinstance(status, bytes):
            status = status.decode()
        # The writer marks a file "unfinished" until finish(); a killed run keeps that
        # mark (older files have no status at all).
        if status in (None, "unfinished") and self.unfinished:
            return "unfinished"
        if status in (None, "unfinished"):
            self.fail("/summary: the run did not reach finish() "
                      "(pass --unfinished to check such a file)")
            return None
        self.attrs("/summary", f["summary"], SUMMARY_ATTRS)
        if status is not None and not (status in FINAL_STATUSES
                                       or status.startswith("failed")):
            self.fail(f"/summary status {status!r} is not "
                      f"{' | '.join(FINAL_STATUSES)} | failed: ...")
        if status in FINAL_STATUSES and nt == 0:
            self.fail(f"status is {status!r} but there are no snapshots")
        for name in f["summary"].attrs:
            if name.startswith("time_") and not name.endswith("_s"):
                self.fail(f"/summary stage time {name!r} should be named time_<stage>_s")
        return status

    def run_raster(self):
        """The checks of a raster run; returns the OK line."""
        f = self.f
        for group in ("grid", "snapshots", "front", "diagnostics", "summary"):
            if group not in f:
                self.fail(f"group /{group} is missing")
        if self.problems:
            raise Problems
        nx, ny = int(f.attrs.get("nx", -1)), int(f.attrs.get("ny", -1))
        nt = f["snapshots/t"].shape[0]
        expected = {
            "grid/x": (nx,), "grid/y": (ny,), "grid/b": (ny, nx), "grid/h_bed": (ny, nx),
            "snapshots/x": (nx,), "snapshots/y": (ny,), "snapshots/t": (nt,),
            "snapshots/h": (nt, ny, nx), "snapshots/u": (nt, ny, nx),
            "snapshots/v": (nt, ny, nx),
        }
        units = {"grid/x": "m", "grid/y": "m", "grid/b": "m", "grid/h_bed": "m",
                 "snapshots/h": "m", "snapshots/u": "m/s", "snapshots/v": "m/s",
                 "diagnostics/mass": "m^3", "diagnostics/kinetic_energy": "m^5/s^2"}
        for name, shape in expected.items():
            if name not in f:
                self.fail(f"dataset /{name} is missing")
            elif f[name].shape != shape:
                self.fail(f"/{name} has shape {f[name].shape}, expected {shape}")
        for name, unit in units.items():
            got = f[name].attrs.get("units") if name in f else None
            if isinstance(got, bytes):
                got = got.decode()
            if name in f and got != unit:
                self.fail(f"/{name} units attribute is {got!r}, expected {unit!r}")
        if self.problems:
            raise Problems
        x, y = f["grid/x"][:], f["grid/y"][:]
        for name, a in (("x", x), ("y", y)):
            if len(a) > 1 and not np.all(np.diff(a) > 0):
                self.fail(f"/grid/{name} is not strictly increasing")
        # Wall cells (nodata cells of the DEM) are NaN in /grid/b, the snapshots and
        # the maps by design; every other cell must be finite.
        walls = np.isnan(f["grid/b"][:])
        n_walls = int(walls.sum())
        stated = int(f["summary"].attrs.get("wall_cells", 0))
        if n_walls != stated and "wall_cells" in f["summary"].attrs:
            self.fail(f"/grid/b has {n_walls} NaN (wall) cells but /summary wall_cells "
                      f"is {stated}")
        self.walls = walls
        h = f["snapshots/h"][:]
        for name in ("h", "u", "v"):
            a = f[f"snapshots/{name}"][:]
            if not np.isfinite(a[:, ~walls]).all():
                self.fail(f"/snapshots/{name} has non-finite values off the wall cells")
            if n_walls and not np.isnan(a[:, walls]).all():
                self.fail(f"/snapshots/{name} has values on wall cells (NaN expected)")
        h = np.where(walls, 0.0, h)
        if (h < 0).any():
            self.fail(f"/snapshots/h has negative values (min {np.nanmin(h):.3g})")
        nl = int(f.attrs.get("layers", 1))
        if nl > 1:
            self.raster_layers(nt, nl, ny, nx, h)
        # The volume: sum(h) dx dy of each snapshot against /diagnostics/mass.
        dx = float(f.attrs["dx"]) if nx > 1 else np.nan
        dy = float(f.attrs["dy"]) if ny > 1 else np.nan
        td, mass = f["diagnostics/t"][:], f["diagnostics/mass"][:]
        checked = 0
        if np.isfinite(dx) and np.isfinite(dy):
            for k, t in enumerate(f["snapshots/t"][:]):
                hits = np.flatnonzero(np.abs(td - t) <= 1e-12 * max(1.0, abs(t)))
                if hits.size == 0:
                    continue
                want, got = h[k].sum() * dx * dy, mass[hits[-1]]
                checked += 1
                if abs(got - want) > 1e-9 * max(abs(want), abs(got), np.finfo(float).tiny):
                    self.fail(f"/diagnostics/mass at t = {t:g} is {got:.15g}, "
                              f"but sum(h)*dx*dy of the snapshot is {want:.15g}")
        status = self.summary(nt)
        if status not in (None, "unfinished"):
            self.maps(nx, ny, h)
        self.xdmf(nx, ny, nt)
        if self.problems:
            raise Problems
        return (f"model {f.attrs['model']} on a {nx} x {ny} raster, nt={nt} snapshots, "
                f"{len(td)} step records, mass checked at {checked} snapshot(s), "
                f"status {status}")

    def raster_layers(self, nt, nl, ny, nx, h):
        """A layered raster run: the velocity of every layer, whose depth mean is
        /snapshots/u, v (a convex combination: between the slowest and the fastest
        layer), and the static interface, between the bed and the top."""
        f = self.f
        for name, shape in (("u_layers", (nt, nl, ny, nx)), ("v_layers", (nt, nl, ny, nx)),
                            ("static_interface", (nt, ny, nx))):
            if f"snapshots/{name}" not in f:
                self.fail(f"dataset /snapshots/{name} is missing (layers = {nl})")
            elif f[f"snapshots/{name}"].shape != shape:
                self.fail(f"/snapshots/{name} has shape {f[f'snapshots/{name}'].shape}, "
                          f"expected {shape}")
        if self.problems:
            raise Problems
        for mean, layers in (("u", "u_layers"), ("v", "v_layers")):
            a, q = f[f"snapshots/{mean}"][:], f[f"snapshots/{layers}"][:]
            tol = 1e-12 * (1.0 + np.abs(q).max(initial=0.0))
            if (a < q.min(axis=1) - tol).any() or (a > q.max(axis=1) + tol).any():
                self.fail(f"/snapshots/{mean} is not a mean of /snapshots/{layers}")
        si = f["snapshots/static_interface"][:]
        if (si < 0).any() or (si > h * (1 + 1e-12)).any():
            self.fail("/snapshots/static_interface is not between the bed and the top")

    def maps(self, nx, ny, h):
        """/maps of a finished raster run."""
        f = self.f
        names = ("h_max", "speed_max", "ppr", "arrival_time", "deposit")
        missing = [n for n in names if f"maps/{n}" not in f]
        if missing:
            self.fail(f"/maps lacks {missing}")
            return
        m = {n: f[f"maps/{n}"][:] for n in names}
        for n, a in m.items():
            if a.shape != (ny, nx):
                self.fail(f"/maps/{n} has shape {a.shape}, expected {(ny, nx)}")
                return
        # Wall cells are NaN in every map; the checks below are on the other cells.
        walls = self.walls
        for n, a in m.items():
            if walls.any() and not np.isnan(a[walls]).all():
                self.fail(f"/maps/{n} has values on wall cells (NaN expected)")
            m[n] = a[~walls]
        h = h[:, ~walls]
        if not (m["h_max"] >= m["deposit"]).all():
            self.fail("/maps/h_max is below /maps/deposit somewhere")
        if len(h):
            # In the bed-normal frame the snapshots hold H, the thickness per horizontal
            # area, and the maps the thickness normal to the bed, cos θ · H, with
            # cos θ = 1/√(1 + |∇b|²) from centred differences of the cell-centre bed
            # (one-sided at the edges), as the solver forms it. Beside a wall (NaN bed)
            # the gradient is unknown here and the cell is skipped.
            # Over an erodible bed the maps count the flow above it, h − h_bed.
            peak = (h - f["grid/h_bed"][:][~walls]).max(axis=0)
            frame = f.attrs.get("coordinates", "")
            frame = frame.decode() if isinstance(frame, bytes) else str(frame)
            if frame == "bed_normal" and nx > 1 and ny > 1:
                by, bx = np.gradient(f["grid/b"][:], float(f.attrs["dy"]), float(f.attrs["dx"]))
                cos = 1.0 / np.sqrt(1.0 + bx**2 + by**2)
                peak = peak * (cos[~walls] if walls.any() else cos.ravel())
            known = np.isfinite(peak)
            if not (m["h_max"][known] >= peak[known] * (1.0 - 1e-12)).all():
                self.fail("/maps/h_max is below a snapshot's h somewhere")
        thr = float(f["front"].attrs["threshold"])
        reached = np.isfinite(m["arrival_time"])
        if (reached != (m["h_max"] > thr)).any():
            self.fail("/maps/arrival_time is not finite exactly where h_max > the threshold")
        t_end = float(f["summary"].attrs.get("t_end", np.inf))
        a = m["arrival_time"][reached]
        if a.size and (a.min() < 0 or a.max() > t_end * (1 + 1e-12)):
            self.fail("/maps/arrival_time leaves [0, t_end]")
        if (m["speed_max"] < 0).any() or not np.isfinite(m["speed_max"]).all():
            self.fail("/maps/speed_max is negative or not finite")
        # ppr = rho |u|^2 with one bulk density rho: zero exactly where speed_max is,
        # and ppr / speed_max^2 the same number elsewhere.
        moving = m["speed_max"] > 0
        if ((m["ppr"] > 0) != moving).any() or not np.isfinite(m["ppr"]).all():
            self.fail("/maps/ppr is not positive exactly where speed_max is")
        elif moving.any():
            rho = m["ppr"][moving] / m["speed_max"][moving] ** 2
            if np.ptp(rho) > 1e-9 * rho.max():
                self.fail("/maps/ppr is not one density times speed_max^2")
        area = f["diagnostics/area_reached"][:] if "diagnostics/area_reached" in f else None
        if area is None or area.shape != f["diagnostics/t"].shape:
            self.fail("/diagnostics/area_reached is missing or not one value per step")
        elif (np.diff(area) < 0).any():
            self.fail("/diagnostics/area_reached decreases")
        for name in ("area_reached", "runout_length", "travel_angle_deg"):
            if name not in f["summary"].attrs:
                self.fail(f"/summary attribute {name!r} is missing")

    def xdmf(self, nx, ny, nt):
        """The XDMF file beside the HDF5 file parses and names existing datasets."""
        path = os.path.splitext(self.f.filename)[0] + ".xmf"
        if not os.path.exists(path):
            self.fail(f"no XDMF file {path}")
            return
        try:
            root = ET.parse(path).getroot()
        except ET.ParseError as e:
            self.fail(f"{path} is not XML: {e}")
            return
        frames = root.findall("./Domain/Grid/Grid")
        if len(frames) != nt:
            self.fail(f"{path} lists {len(frames)} snapshots, the file has {nt}")
        for item in root.iter("DataItem"):
            if item.get("Format") != "HDF":
                continue
            name = item.text.strip().split(":", 1)[1].lstrip("/")
            dims = tuple(int(d) for d in item.get("Dimensions").split())
            if name not in self.f:
                self.fail(f"{path} names /{name}, which the file does not have")
            elif self.f[name].shape != dims:
                self.fail(f"{path} gives /{name} dimensions {dims}, "
                          f"the file {self.f[name].shape}")

    def run(self):
        f = self.f
        grid = f.attrs.get("grid")
        if isinstance(grid, bytes):
            grid = grid.decode()
        if grid == "raster":
            self.attrs("root", f, ROOT_ATTRS)
            return self.run_raster()
        self.attrs("root", f, ROOT_ATTRS)
        version = f.attrs.get("format_version")
        if version is not None and version != FORMAT_VERSION:
            self.fail(f"format_version is {version}, this checker knows {FORMAT_VERSION}")
        for group in ("grid", "snapshots", "front", "diagnostics", "summary"):
            if group not in f:
                self.fail(f"group /{group} is missing")
        self.datasets()
        if self.problems:
            raise Problems
        nx, nl, nt = self.shapes()
        x, h = self.values(nx)
        checked = self.mass(x, h, nx)
        status = self.summary(nt)
        if self.problems:
            raise Problems
        steps = f["diagnostics/t"].shape[0]
        return (f"model {f.attrs['model']} ({f.attrs['pressure']}, {f.attrs['coordinates']}), "
                f"nl={nl}, nx={nx}, nt={nt} snapshots, {steps} step records, "
                f"mass checked at {checked} snapshot(s), status {status}")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("file")
    parser.add_argument("--expect-layers", type=int, default=None)
    parser.add_argument("--unfinished", action="store_true",
                        help="accept a file without /summary attributes")
    args = parser.parse_args()
    try:
        f = h5py.File(args.file, "r")
    except OSError as e:
        print(f"FAIL {args.file}: cannot open as HDF5: {e}", file=sys.stderr)
        return 1
    with f:
        checker = Checker(f, args.expect_layers, args.unfinished)
        try:
            line = checker.run()
        except Problems:
            for problem in checker.problems:
                print(f"FAIL {args.file}: {problem}", file=sys.stderr)
            return 1
    print(f"OK {args.file}: {line}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
