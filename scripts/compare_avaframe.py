"""Side-by-side measures of AvaFrame's hockey-stick and helix avalanches: the runout
beyond the foot of the slope along the thalweg, the largest peak flow velocity (pfv)
and peak pressure (ppr), and the area where the peak flow thickness (pft) exceeds a
threshold, from

- a directory of AvaFrame com1DFA peak rasters (`*_pft.asc`, `*_pfv.asc`,
  `*_ppr.asc`, ppr in kPa; a com1DFA `Outputs/com1DFA/peakFiles` directory holding the
  files of one simulation), and/or
- granflow HDF5 runs of scenarios/hockey_channel.toml or scenarios/helix_channel.toml
  (their `/maps`: h_max, speed_max, ppr in Pa; docs/output-format.md), and/or
- the reference CSV of AvaFrame figures (rows of the case), e.g.
  tests/data/avaframe_reference.csv.

Both codes' rasters are in AvaFrame's map coordinates (the scenarios' x, y). The
measures, the same for every source:

- hockey stick: runout = the largest x of a cell centre with pft > threshold, minus the
  x where the 34° plane reaches the foreland's level, 1000 + 2200 / tan 34° (the DEM's
  x' = 0 is x = 1000);
- helix: runout = the largest arc length s = R (atan2(y', x') + π) (R = 1250 m,
  x' = x − 3500, y' = −5000 − y) of a cell centre with pft > threshold, minus the s
  where the parabola meets the foreland, fLen = 1000 / tan 34°;
- max pfv (m/s), max ppr (kPa) over the raster;
- area (m², horizontal) of the cells with pft > threshold.

With `--dem DEM.asc` (AvaFrame's DEM_HS_Topo.asc or DEM_HX_Topo.asc) it also prints the
largest |b − z| between each granflow run's bed (`/grid/b`) and the DEM at the cell
centres the two share.

Usage:
    python3 scripts/compare_avaframe.py --case hockey --granflow RUN.h5 [--granflow RUN2.h5]
        [--avaframe PEAKDIR] [--reference tests/data/avaframe_reference.csv] [--threshold 0.1]
        [--dem DEM.asc]
"""

import argparse
import csv
import math
import pathlib
import sys

import numpy as np

FOOT_HOCKEY_X = 1000.0 + 2200.0 / math.tan(math.radians(34.0))
HELIX_R = 1250.0
FOOT_HELIX_S = 1000.0 / math.tan(math.radians(34.0))


def read_asc(path):
    """An ESRI ASCII grid: (x centres, y centres ascending, values with row 0 south)."""
    header = {}
    with open(path) as f:
        lines = f.readlines()
    k = 0
    while k < len(lines) and lines[k].split() and lines[k].split()[0][0].isalpha():
        key, value = lines[k].split()[:2]
        header[key.lower()] = float(value)
        k += 1
    nx, ny, cell = int(header["ncols"]), int(header["nrows"]), header["cellsize"]
    if "xllcenter" in header:
        x0, y0 = header["xllcenter"], header["yllcenter"]
    else:
        x0, y0 = header["xllcorner"] + cell / 2, header["yllcorner"] + cell / 2
    values = np.array(" ".join(lines[k:]).split(), dtype=float).reshape(ny, nx)
    nodata = header.get("nodata_value")
    if nodata is not None and not math.isnan(nodata):
        values[values == nodata] = np.nan
    # The file's first row is the northern one.
    return x0 + cell * np.arange(nx), y0 + cell * np.arange(ny), values[::-1]


def runout(case, x, y, wet):
    """Runout beyond the foot of the slope of the wet cells (centres), m."""
    if not wet.any():
        return float("nan")
    xx, yy = np.meshgrid(x, y)
    if case == "hockey":
        return float(xx[wet].max() - FOOT_HOCKEY_X)
    # y' = −5000 − y is ≤ 0 in the DEM; −|y'| puts the southern row (y' = 0) at s = 0,
    # the top of the helix, rather than at the end of the circle.
    yp = -np.abs(-5000.0 - yy[wet])
    s = HELIX_R * (np.arctan2(yp, xx[wet] - 3500.0) + math.pi)
    return float(s.max() - FOOT_HELIX_S)


def measures(case, x, y, pft, pfv, ppr_kpa, threshold):
    wet = np.nan_to_num(pft) > threshold
    cell = abs(x[1] - x[0]) * abs(y[1] - y[0])
    return {
        "cell_m": abs(x[1] - x[0]),
        "runout_m": runout(case, x, y, wet),
        "max_pfv_ms": float(np.nanmax(pfv)),
        "max_ppr_kpa": float(np.nanmax(ppr_kpa)),
        "area_m2": float(wet.sum() * cell),
    }


def from_avaframe(case, directory, threshold):
    files = {}
    for field in ("pft", "pfv", "ppr"):
        found = sorted(pathlib.Path(directory).glob(f"*_{field}.asc"))
        if len(found) != 1:
            sys.exit(f"{directory}: expected one *_{field}.asc, found {len(found)}")
        files[field] = read_asc(found[0])
    x, y, pft = files["pft"]
    row = measures(case, x, y, pft, files["pfv"][2], files["ppr"][2], threshold)
    row["source"] = f"AvaFrame {pathlib.Path(directory)}"
    return row


def from_granflow(case, path, threshold):
    """The measures of a granflow run; for a run in Cartesian coordinates, whose h is
    the vertical thickness, a second row with the thickness normal to the bed,
    h cos θ (θ the bed's slope from central differences of /grid/b), as AvaFrame's
    pft is."""
    import h5py

    with h5py.File(path, "r") as f:
        if f.attrs.get("grid") not in ("raster", b"raster"):
            sys.exit(f"{path}: not a raster run")
        x, y, b = f["grid/x"][:], f["grid/y"][:], f["grid/b"][:]
        pft, pfv, ppr = f["maps/h_max"][:], f["maps/speed_max"][:], f["maps/ppr"][:] / 1e3
        frame = f.attrs.get("coordinates", "")
        frame = frame.decode() if isinstance(frame, bytes) else str(frame)
        summary = dict(f["summary"].attrs) if "summary" in f else {}
    row = measures(case, x, y, pft, pfv, ppr, threshold)
    row["source"] = f"granflow {path}"
    for key, name in (("end_time_s", "t_end"), ("wall_s", "wall_time_s")):
        if name in summary:
            row[key] = float(summary[name])
    rows = [row]
    if frame == "cartesian":
        by, bx = np.gradient(b, y, x)
        normal = pft / np.sqrt(1.0 + bx**2 + by**2)
        row = dict(row, **measures(case, x, y, normal, pfv, ppr, threshold))
        row["source"] = f"granflow {path}, pft × cos θ"
        rows.append(row)
    return rows


def from_reference(case, path, threshold):
    rows = []
    with open(path) as f:
        for r in csv.DictReader(line for line in f if not line.startswith("#")):
            if r["case"] != case or float(r["threshold_m"]) != threshold:
                continue
            row = {k: float(r[k]) for k in ("cell_m", "runout_m", "max_pfv_ms",
                                             "max_ppr_kpa", "area_m2")}
            row["source"] = f"{r['code']} (curvature {r['curvature']}, {path})"
            for key in ("end_time_s", "wall_s"):
                if r.get(key):
                    row[key] = float(r[key])
            rows.append(row)
    return rows


def dem_difference(path, dem):
    """Largest |b − z| of a run's bed against a DEM at their common cell centres."""
    import h5py

    xd, yd, zd = dem
    with h5py.File(path, "r") as f:
        x, y, b = f["grid/x"][:], f["grid/y"][:], f["grid/b"][:]
    # Cell centres are multiples of the cell sizes from the two origins: match them
    # to a millimetre.
    ix = {round(v * 1000): i for i, v in enumerate(xd)}
    iy = {round(v * 1000): j for j, v in enumerate(yd)}
    cols = [(i, ix[round(v * 1000)]) for i, v in enumerate(x) if round(v * 1000) in ix]
    rows = [(j, iy[round(v * 1000)]) for j, v in enumerate(y) if round(v * 1000) in iy]
    if not cols or not rows:
        sys.exit(f"{path}: no cell centre in common with the DEM")
    ours = b[np.ix_([j for j, _ in rows], [i for i, _ in cols])]
    theirs = zd[np.ix_([j for _, j in rows], [i for _, i in cols])]
    diff = np.abs(ours - theirs)
    j, i = np.unravel_index(np.argmax(diff), diff.shape)
    return diff.max(), len(rows) * len(cols), (x[cols[i][0]], y[rows[j][0]])


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--case", choices=("hockey", "helix"), required=True)
    ap.add_argument("--avaframe", action="append", default=[], metavar="PEAKDIR")
    ap.add_argument("--granflow", action="append", default=[], metavar="RUN.h5")
    ap.add_argument("--reference", metavar="CSV")
    ap.add_argument("--threshold", type=float, default=0.1, help="pft threshold, m")
    ap.add_argument("--dem", metavar="DEM.asc", help="AvaFrame's DEM, to compare the beds")
    args = ap.parse_args()
    if args.dem:
        dem = read_asc(args.dem)
        for p in args.granflow:
            worst, n, at = dem_difference(p, dem)
            print(f"{p}: bed against {args.dem} at {n} common cell centres: "
                  f"max |b - z| = {worst:.3g} m (at x = {at[0]:g}, y = {at[1]:g})")
    rows = []
    if args.reference:
        rows += from_reference(args.case, args.reference, args.threshold)
    rows += [from_avaframe(args.case, d, args.threshold) for d in args.avaframe]
    for p in args.granflow:
        rows += from_granflow(args.case, p, args.threshold)
    if not rows:
        if args.dem:
            return
        sys.exit("nothing to compare: give --avaframe, --granflow or --reference")
    print(f"{args.case}: runout beyond the foot along the thalweg, area with pft > "
          f"{args.threshold} m")
    print("| source | cell (m) | runout (m) | max pfv (m/s) | max ppr (kPa) | area (m²) "
          "| end time (s) | wall (s) |")
    print("|---|---|---|---|---|---|---|---|")
    for r in rows:
        end = f"{r['end_time_s']:.1f}" if "end_time_s" in r else "–"
        wall = f"{r['wall_s']:.0f}" if "wall_s" in r else "–"
        print(f"| {r['source']} | {r['cell_m']:g} | {r['runout_m']:.0f} | "
              f"{r['max_pfv_ms']:.1f} | {r['max_ppr_kpa']:.0f} | {r['area_m2']:.4g} | "
              f"{end} | {wall} |")


if __name__ == "__main__":
    main()
