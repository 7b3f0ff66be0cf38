#!/usr/bin/env python3
"""Hazard maps of granflow raster (2-D) runs, in map coordinates.

    python scripts/plot_hazard.py RUN.h5 [--levels 0.01 0.1 1] [--out PREFIX] [--format png]
    python scripts/plot_hazard.py SWEEP_DIR [--out PREFIX] [--format png]

A run file gives PREFIX_hazard.png (default: next to RUN.h5): the hillshaded bed
(matplotlib's LightSource, light from the north-west), the peak flow thickness pft
(/maps/h_max) in colour with its contours at --levels (m), the release outline (the
first snapshot's h at the front threshold, dashed), the runout point (/summary
runout_x, runout_y) and the cells reached, a scale bar, and the coordinate reference
system named (root attributes crs and crs_wkt; "no CRS" when the inputs had none).

A sweep directory, after `granflow maps SWEEP_DIR`, gives SWEEP_DIR/maps/probability.png
(default): P(pft > threshold) from maps/pft_probability.asc (or .tif, read with
rasterio when installed) over the hillshaded bed of the sweep's first run, with the
contours P = 0.5 and 1, a scale bar and the CRS.

Needs h5py, numpy and matplotlib.
"""

import argparse
import pathlib
import sys

import h5py
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib import colors  # noqa: E402

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
import plot_common  # noqa: E402


def text(v):
    return v.decode() if isinstance(v, bytes) else str(v)


class Run:
    """The grid, bed, CRS and maps of a raster run file."""

    def __init__(self, path):
        with h5py.File(path, "r") as f:
            if text(f.attrs.get("grid", "")) != "raster":
                raise SystemExit(f"error: {path}: not a raster (2-D) run")
            self.x, self.y, self.b = f["grid/x"][:], f["grid/y"][:], f["grid/b"][:]
            self.h0 = f["snapshots/h"][0]
            self.threshold = float(f["front"].attrs.get("threshold", 1e-3))
            if "maps/h_max" not in f:
                raise SystemExit(f"error: {path}: no /maps (the run wrote no snapshot)")
            self.pft = f["maps/h_max"][:]
            self.summary = dict(f["summary"].attrs) if "summary" in f else {}
            self.crs = crs_name(f.attrs)
        d = self.x[1] - self.x[0] if len(self.x) > 1 else self.y[1] - self.y[0]
        self.d = d
        self.extent = (self.x[0] - d / 2, self.x[-1] + d / 2,
                       self.y[0] - d / 2, self.y[-1] + d / 2)

    def hillshade(self):
        if np.ptp(self.b) == 0:
            return np.full(self.b.shape, 0.8)
        ls = colors.LightSource(azdeg=315, altdeg=45)
        return ls.hillshade(self.b, vert_exag=1.0, dx=self.d, dy=self.d)


def crs_name(attrs):
    """The CRS as the run file names it: EPSG code, else the WKT's name."""
    if "crs" in attrs:
        return text(attrs["crs"])
    if "crs_epsg" in attrs:
        return f"EPSG:{int(attrs['crs_epsg'])}"
    if "crs_wkt" in attrs:
        wkt = text(attrs["crs_wkt"])
        name = wkt.split('"')[1] if '"' in wkt else wkt[:40]
        return f"CRS {name}"
    return "no CRS (coordinates of the scenario)"


def scale_bar(ax, extent):
    """A bar of a round length, about a fifth of the map's width, bottom left."""
    width = extent[1] - extent[0]
    raw = width / 5
    k = 10 ** np.floor(np.log10(raw))
    length = max(m * k for m in (1, 2, 5) if m * k <= raw)
    x0 = extent[0] + 0.05 * width
    y0 = extent[2] + 0.06 * (extent[3] - extent[2])
    ax.plot([x0, x0 + length], [y0, y0], color="k", lw=3, solid_capstyle="butt")
    label = f"{length:g} m" if length < 1000 else f"{length / 1000:g} km"
    ax.text(x0 + length / 2, y0, label, ha="center", va="bottom", fontsize=8)


def figure(run):
    """A figure whose height follows the map's aspect ratio."""
    e = run.extent
    aspect = (e[3] - e[2]) / (e[1] - e[0])
    return plt.subplots(figsize=(8, max(3.5, min(9.0, 6.0 * aspect + 1.5))),
                        constrained_layout=True)


def background(ax, run):
    ax.imshow(run.hillshade(), origin="lower", extent=run.extent, cmap="gray",
              vmin=0, vmax=1)
    ax.set_aspect("equal")
    ax.set_xlabel(f"x (m), {run.crs}")
    ax.set_ylabel("y (m)")
    ax.ticklabel_format(useOffset=False, style="plain")


def plot_run(path, out, levels, dpi):
    run = Run(path)
    fig, ax = figure(run)
    background(ax, run)
    reached = run.pft > run.threshold
    data = np.ma.masked_where(~reached, run.pft)
    im = ax.imshow(data, origin="lower", extent=run.extent, cmap="viridis", alpha=0.8)
    fig.colorbar(im, ax=ax, shrink=0.8, label="peak flow thickness pft (m)")
    levels = [v for v in sorted(levels) if run.pft.min() < v < run.pft.max()]
    if levels:
        cs = ax.contour(run.x, run.y, run.pft, levels=levels, colors="k", linewidths=0.8)
        ax.clabel(cs, fmt=lambda v: f"{v:g} m", fontsize=7)
    if (run.h0 > run.threshold).any() and (run.h0 <= run.threshold).any():
        ax.contour(run.x, run.y, run.h0, levels=[run.threshold], colors="w",
                   linewidths=1.2, linestyles="--")
        ax.plot([], [], "w--", label="release")
    rx, ry = run.summary.get("runout_x"), run.summary.get("runout_y")
    if rx is not None and np.isfinite(rx) and np.isfinite(ry):
        ax.plot([rx], [ry], "r*", ms=12, label=f"runout ({run.summary['runout_length']:.4g} m)")
    if ax.get_legend_handles_labels()[0]:
        ax.legend(loc="upper right", fontsize=8, facecolor="0.85")
    scale_bar(ax, run.extent)
    ax.set_title(f"{pathlib.Path(path).name}: peak flow thickness, {run.crs}", fontsize=10)
    plot_common.save(fig, out, dpi)
    print(f"wrote {out}")


def read_asc(path):
    """An ESRI ASCII grid: (values north row first, nodata masked, (x_left, y_bottom, d))."""
    header = {}
    with open(path) as f:
        for _ in range(6):
            pos = f.tell()
            parts = f.readline().split()
            if not parts or not parts[0][0].isalpha():
                f.seek(pos)
                break
            header[parts[0].lower()] = float(parts[1])
        values = np.loadtxt(f, ndmin=2)
    nd = header.get("nodata_value")
    values = np.ma.masked_equal(values, nd) if nd is not None else np.ma.asarray(values)
    return values


def read_probability(maps):
    asc = maps / "pft_probability.asc"
    if asc.exists():
        return read_asc(asc)
    tif = maps / "pft_probability.tif"
    try:
        import rasterio
    except ImportError:
        raise SystemExit(f"error: {tif} needs rasterio; or run `granflow maps --format asc`")
    with rasterio.open(tif) as src:
        return src.read(1, masked=True)


def plot_sweep(sweep, out, dpi):
    maps = sweep / "maps"
    if not (maps / "ensemble.toml").exists():
        raise SystemExit(f"error: {maps}/ensemble.toml not found: run `granflow maps {sweep}` first")
    meta = dict(line.split(" = ", 1) for line in (maps / "ensemble.toml").read_text().splitlines()
                if " = " in line and not line.startswith("#"))
    p = np.asarray(read_probability(maps), dtype=float)[::-1]  # rows south first
    first = sorted(sweep.glob("*.h5"))
    if not first:
        raise SystemExit(f"error: no run file in {sweep}")
    run = Run(first[0])
    if p.shape != run.pft.shape:
        raise SystemExit(f"error: the maps ({p.shape}) are not on the runs' grid {run.pft.shape}")
    fig, ax = figure(run)
    background(ax, run)
    im = ax.imshow(np.ma.masked_where(p <= 0, p), origin="lower", extent=run.extent,
                   cmap="magma_r", vmin=0, vmax=1, alpha=0.85)
    thr = meta.get("threshold", "?")
    fig.colorbar(im, ax=ax, shrink=0.8, label=f"P(pft > {thr} m)")
    levels = [v for v in (0.5, 1.0) if p.min() < v <= p.max()]
    if levels and p.min() < p.max():
        cs = ax.contour(run.x, run.y, p, levels=[v - 1e-9 for v in levels], colors="k",
                        linewidths=0.8)
        ax.clabel(cs, fmt=lambda v: f"P = {v:.2g}", fontsize=7)
    scale_bar(ax, run.extent)
    ax.set_title(f"{sweep.name}: {meta.get('runs', '?')} runs, P(pft > {thr} m), {run.crs}",
                 fontsize=10)
    plot_common.save(fig, out, dpi)
    print(f"wrote {out}")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("path", type=pathlib.Path, help="RUN.h5 of a raster run, or SWEEP_DIR")
    ap.add_argument("--levels", type=float, nargs="+", default=[0.01, 0.1, 1.0],
                    help="pft contours (m)")
    ap.add_argument("--out", type=pathlib.Path, help="output file prefix")
    plot_common.add_output_options(ap)
    a = ap.parse_args()
    try:
        if a.path.is_dir():
            prefix = a.out or a.path / "maps" / "probability"
            plot_sweep(a.path, f"{prefix}.{a.format}", a.dpi)
        else:
            prefix = a.out or a.path.with_suffix("")
            suffix = "_hazard" if a.out is None else ""
            plot_run(a.path, f"{prefix}{suffix}.{a.format}", a.levels, a.dpi)
    except plot_common.EmptyPlot as e:
        return plot_common.fail_empty(e)
    return 0


if __name__ == "__main__":
    sys.exit(main())
