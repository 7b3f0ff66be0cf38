#!/usr/bin/env python3
"""Hazard maps of granflow raster (2-D) runs, in map coordinates.

    python scripts/plot_hazard.py RUN.h5 [--levels 0.01 0.1 1] [--classes 1 10 25 50]
                                  [--out PREFIX] [--format png]
    python scripts/plot_hazard.py SWEEP_DIR [--out PREFIX] [--format png]

A run file gives two maps (default: next to RUN.h5):

- PREFIX_hazard.png: the hillshaded bed (matplotlib's LightSource, light from the
  north-west), the peak flow thickness pft (/maps/h_max) in colour with its contours at
  --levels (m), the release outline (the first snapshot's h at the front threshold,
  white dashed on a black line, visible on any shade), the runout point (/summary
  runout_x, runout_y);
- PREFIX_ppr.png: the peak pressure ppr (/maps/ppr, stored in Pa) in classes of kPa,
  as practitioners read them (--classes, default 1, 10, 25 and 50 kPa: below 1 not
  drawn, then 1-10, 10-25, 25-50 and above 50), over the same bed and release.

A run with `output.path` draws its thalweg line on both maps and gives a third figure:

- PREFIX_path.png: the profiles along the path against s (/path): the thalweg's
  elevation z with the top of the release, the runout point and the line between them
  at the runout angle (/summary path_release_top_s, path_runout_s,
  path_runout_angle_deg), then the largest pft (m), pfv (m/s) and ppr (kPa) across the
  path's band at each station (AIMEC's cross-section maxima), the runout marked on each.

Both have a scale bar, a north arrow, at most five coordinate labels per axis (map
coordinates of six or seven digits do not run into each other) and the coordinate
reference system named (root attributes crs and crs_wkt; "no CRS" when the inputs had
none). Wall (nodata) cells are NaN in the maps and left blank.

A sweep directory, after `granflow maps SWEEP_DIR`, gives SWEEP_DIR/maps/probability.png
(default): P(pft > threshold) from maps/pft_probability.asc (or .tif, read with
rasterio when installed) over the hillshaded bed of the sweep's first run, with the
contours P = 0.5 and 1, and, when the maps were made with --observed, the observed
footprint's outline (maps/observed.asc or .tif), a scale bar, a north arrow and the CRS.

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
from matplotlib import colors, ticker  # noqa: E402
from matplotlib import patheffects  # noqa: E402

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
            self.ppr = f["maps/ppr"][:] if "maps/ppr" in f else None
            self.summary = dict(f["summary"].attrs) if "summary" in f else {}
            self.path = ({k: f["path"][k][:] for k in f["path"]} if "path" in f else None)
            self.crs = crs_name(f.attrs)
        d = self.x[1] - self.x[0] if len(self.x) > 1 else self.y[1] - self.y[0]
        self.d = d
        self.extent = (self.x[0] - d / 2, self.x[-1] + d / 2,
                       self.y[0] - d / 2, self.y[-1] + d / 2)

    def hillshade(self):
        b = np.asarray(self.b, dtype=float)
        valid = np.isfinite(b)
        if not valid.any() or np.ptp(b[valid]) == 0:
            return np.full(b.shape, 0.8)
        # Wall (nodata) cells: shaded as the mean, then blanked.
        filled = np.where(valid, b, np.nanmean(b))
        ls = colors.LightSource(azdeg=315, altdeg=45)
        shade = ls.hillshade(filled, vert_exag=1.0, dx=self.d, dy=self.d)
        return np.ma.masked_where(~valid, shade)


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


def north_arrow(ax):
    """An arrow pointing north (up: the maps are north-up), top left."""
    ax.annotate("N", xy=(0.06, 0.95), xytext=(0.06, 0.82), xycoords="axes fraction",
                ha="center", va="center", fontsize=11, fontweight="bold",
                arrowprops=dict(facecolor="k", edgecolor="w", width=3, headwidth=9),
                path_effects=[patheffects.withStroke(linewidth=2.5, foreground="w")])


def readable_ticks(ax):
    """At most five labels per axis, without offset or scientific notation, so that
    map coordinates of six or seven digits stay apart."""
    for axis in (ax.xaxis, ax.yaxis):
        axis.set_major_locator(ticker.MaxNLocator(nbins=4, steps=[1, 2, 2.5, 5, 10]))
        axis.set_major_formatter(ticker.FuncFormatter(lambda v, _: f"{v:.10g}"))


def release_outline(ax, run):
    """The release (h0 above the front threshold): a white dashed line on a black one,
    visible on a light and on a dark hillshade."""
    if not ((run.h0 > run.threshold).any() and (run.h0 <= run.threshold).any()):
        return
    for colour, width, style in (("k", 2.6, "-"), ("w", 1.3, "--")):
        ax.contour(run.x, run.y, run.h0, levels=[run.threshold], colors=colour,
                   linewidths=width, linestyles=style)
    ax.plot([], [], "w--", lw=1.3, label="release",
            path_effects=[patheffects.withStroke(linewidth=2.6, foreground="k")])


def finish(ax, run):
    """Scale bar, north arrow, readable ticks and the legend."""
    if ax.get_legend_handles_labels()[0]:
        ax.legend(loc="upper right", fontsize=8, facecolor="0.85")
    scale_bar(ax, run.extent)
    north_arrow(ax)
    readable_ticks(ax)


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


def draw_run(run, levels, name):
    """The pft map of `run` (a Run); returns (fig, ax, contour set or None)."""
    fig, ax = figure(run)
    background(ax, run)
    reached = run.pft > run.threshold
    data = np.ma.masked_where(~reached, run.pft)
    im = ax.imshow(data, origin="lower", extent=run.extent, cmap="viridis", alpha=0.8)
    fig.colorbar(im, ax=ax, shrink=0.8, label="peak flow thickness pft (m)")
    # NaN on wall (nodata) cells: the range is that of the cells with data.
    lo, hi = np.nanmin(run.pft), np.nanmax(run.pft)
    levels = [v for v in sorted(levels) if lo < v < hi]
    cs = None
    if levels:
        cs = ax.contour(run.x, run.y, run.pft, levels=levels, colors="k", linewidths=0.8)
        ax.clabel(cs, fmt=lambda v: f"{v:g} m", fontsize=7)
    release_outline(ax, run)
    rx, ry = run.summary.get("runout_x"), run.summary.get("runout_y")
    if rx is not None and np.isfinite(rx) and np.isfinite(ry):
        ax.plot([rx], [ry], "r*", ms=12, label=f"runout ({run.summary['runout_length']:.4g} m)")
    path_line(ax, run)
    finish(ax, run)
    ax.set_title(f"{name}: peak flow thickness, {run.crs}", fontsize=10)
    return fig, ax, cs


def draw_ppr(run, classes_kpa, name):
    """The classed peak-pressure map of `run`; returns (fig, ax, colour bar)."""
    if run.ppr is None:
        raise SystemExit("error: the run file has no /maps/ppr (written by an older granflow)")
    fig, ax = figure(run)
    background(ax, run)
    kpa = np.asarray(run.ppr, dtype=float) / 1000.0
    bounds = sorted(classes_kpa)
    top = max(np.nanmax(kpa) if np.isfinite(kpa).any() else 0.0, bounds[-1]) * 1.01 + 1e-9
    edges = bounds + [top]
    cmap = plt.get_cmap("YlOrRd", len(bounds))
    norm = colors.BoundaryNorm(edges, cmap.N)
    data = np.ma.masked_where(~(kpa >= bounds[0]), kpa)
    im = ax.imshow(data, origin="lower", extent=run.extent, cmap=cmap, norm=norm, alpha=0.9,
                   interpolation="nearest")
    labels = [f"{a:g}–{b:g}" for a, b in zip(bounds[:-1], bounds[1:])] + [f"> {bounds[-1]:g}"]
    cb = fig.colorbar(im, ax=ax, shrink=0.8, ticks=[(a + b) / 2 for a, b in zip(edges[:-1], edges[1:])],
                      label="peak pressure ppr (kPa)")
    cb.ax.set_yticklabels(labels)
    release_outline(ax, run)
    if not (kpa >= bounds[0]).any():
        plot_common.mark_note(ax, f"ppr below {bounds[0]:g} kPa everywhere")
    path_line(ax, run)
    finish(ax, run)
    ax.set_title(f"{name}: peak pressure classes, {run.crs}", fontsize=10)
    return fig, ax, cb


def path_line(ax, run):
    """The thalweg line of `output.path` (its stations' points), when there is one."""
    if run.path is None:
        return
    ax.plot(run.path["x"], run.path["y"], color="tab:cyan", lw=1.4, label="path",
            path_effects=[patheffects.withStroke(linewidth=2.8, foreground="k")])


def draw_path(run, name):
    """The profiles along the path of `run`; returns (fig, axes): elevation, pft,
    pfv, ppr against s."""
    if run.path is None:
        raise SystemExit("error: the run has no /path (the scenario has no output.path)")
    p, s = run.path, run.path["s"]
    fig, axes = plt.subplots(4, 1, sharex=True, figsize=(8, 9), constrained_layout=True,
                             gridspec_kw={"height_ratios": [2, 1, 1, 1]})
    z = np.asarray(p["z"], dtype=float)
    ok = np.isfinite(z)
    axes[0].plot(s[ok], z[ok], "k-", lw=1.2, label="thalweg bed")
    top, end = run.summary.get("path_release_top_s"), run.summary.get("path_runout_s")
    angle = run.summary.get("path_runout_angle_deg")
    marks = top is not None and end is not None and np.isfinite(end) and ok.any()
    if marks:
        zt, ze = np.interp([top, end], s[ok], z[ok])
        axes[0].plot([top, end], [zt, ze], "r--", lw=1,
                     label=f"runout angle {angle:.3g}°")
        axes[0].plot([top], [zt], "k^", ms=8, label="top of the release")
        axes[0].plot([end], [ze], "r*", ms=12,
                     label=f"runout (s = {end:.4g} m, {end - top:.4g} m from the top)")
    axes[0].set_ylabel("elevation (m)")
    axes[0].legend(fontsize=8)
    for ax, key, scale, label in ((axes[1], "pft_max", 1.0, "max pft (m)"),
                                  (axes[2], "pfv_max", 1.0, "max pfv (m/s)"),
                                  (axes[3], "ppr_max", 1e-3, "max ppr (kPa)")):
        ax.plot(s, np.asarray(p[key], dtype=float) * scale, "-", color="tab:blue", lw=1.2)
        ax.set_ylabel(label)
        if marks:
            ax.axvline(end, color="r", ls=":", lw=1)
        ax.grid(alpha=0.3)
    axes[-1].set_xlabel("s along the path (m)")
    axes[0].set_title(f"{name}: along the path (maxima across its band), {run.crs}",
                      fontsize=10)
    return fig, axes


def plot_run(path, prefix, fmt, levels, classes, dpi):
    run = Run(path)
    name = pathlib.Path(path).name
    fig, _, _ = draw_run(run, levels, name)
    out = f"{prefix}_hazard.{fmt}"
    plot_common.save(fig, out, dpi)
    print(f"wrote {out}")
    fig, _, _ = draw_ppr(run, classes, name)
    out = f"{prefix}_ppr.{fmt}"
    plot_common.save(fig, out, dpi)
    print(f"wrote {out}")
    if run.path is not None:
        fig, _ = draw_path(run, name)
        out = f"{prefix}_path.{fmt}"
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


def read_map(maps, name):
    """maps/NAME.asc, or NAME.tif with rasterio; None when neither exists."""
    asc = maps / f"{name}.asc"
    if asc.exists():
        return read_asc(asc)
    tif = maps / f"{name}.tif"
    if not tif.exists():
        return None
    try:
        import rasterio
    except ImportError:
        raise SystemExit(f"error: {tif} needs rasterio; or run `granflow maps --format asc`")
    with rasterio.open(tif) as src:
        return src.read(1, masked=True)


def read_probability(maps):
    p = read_map(maps, "pft_probability")
    if p is None:
        raise SystemExit(f"error: no pft_probability.asc or .tif in {maps}")
    return p


def draw_sweep(sweep):
    """The probability map of `sweep`; returns (fig, ax, whether the observed footprint
    was drawn)."""
    maps = sweep / "maps"
    if not (maps / "ensemble.toml").exists():
        raise SystemExit(f"error: {maps}/ensemble.toml not found: run `granflow maps {sweep}` first")
    meta = dict(line.split(" = ", 1) for line in (maps / "ensemble.toml").read_text().splitlines()
                if " = " in line and not line.startswith("#"))
    # Rows south first; nodata (wall cells) as NaN.
    p = np.ma.filled(np.ma.asarray(read_probability(maps), dtype=float), np.nan)[::-1]
    first = sorted(sweep.glob("*.h5"))
    if not first:
        raise SystemExit(f"error: no run file in {sweep}")
    run = Run(first[0])
    if p.shape != run.pft.shape:
        raise SystemExit(f"error: the maps ({p.shape}) are not on the runs' grid {run.pft.shape}")
    fig, ax = figure(run)
    background(ax, run)
    im = ax.imshow(np.ma.masked_where(~(p > 0), p), origin="lower", extent=run.extent,
                   cmap="magma_r", vmin=0, vmax=1, alpha=0.85)
    thr = meta.get("threshold", "?")
    fig.colorbar(im, ax=ax, shrink=0.8, label=f"P(pft > {thr} m)")
    lo, hi = np.nanmin(p), np.nanmax(p)
    levels = [v for v in (0.5, 1.0) if lo < v <= hi]
    if levels and lo < hi:
        cs = ax.contour(run.x, run.y, p, levels=[v - 1e-9 for v in levels], colors="k",
                        linewidths=0.8)
        ax.clabel(cs, fmt=lambda v: f"P = {v:.2g}", fontsize=7)
    observed = read_map(maps, "observed") if "observed" in meta else None
    if observed is not None:
        o = np.asarray(np.ma.filled(observed, 0.0), dtype=float)[::-1]
        if (o > 0.5).any() and (o <= 0.5).any():
            for colour, width, style in (("w", 2.6, "-"), ("tab:blue", 1.4, "-")):
                ax.contour(run.x, run.y, o, levels=[0.5], colors=colour, linewidths=width,
                           linestyles=style)
            ax.plot([], [], color="tab:blue", lw=1.4, label="observed footprint")
        else:
            observed = None
    release_outline(ax, run)
    finish(ax, run)
    ax.set_title(f"{sweep.name}: {meta.get('runs', '?')} runs, P(pft > {thr} m), {run.crs}",
                 fontsize=10)
    return fig, ax, observed is not None


def plot_sweep(sweep, out, dpi):
    fig, _, _ = draw_sweep(sweep)
    plot_common.save(fig, out, dpi)
    print(f"wrote {out}")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("path", type=pathlib.Path, help="RUN.h5 of a raster run, or SWEEP_DIR")
    ap.add_argument("--levels", type=float, nargs="+", default=[0.01, 0.1, 1.0],
                    help="pft contours (m)")
    ap.add_argument("--classes", type=float, nargs="+", default=[1.0, 10.0, 25.0, 50.0],
                    help="lower bounds of the ppr classes (kPa)")
    ap.add_argument("--out", type=pathlib.Path, help="output file prefix")
    plot_common.add_output_options(ap)
    a = ap.parse_args()
    try:
        if a.path.is_dir():
            prefix = a.out or a.path / "maps" / "probability"
            plot_sweep(a.path, f"{prefix}.{a.format}", a.dpi)
        else:
            prefix = a.out or a.path.with_suffix("")
            plot_run(a.path, prefix, a.format, a.levels, a.classes, a.dpi)
    except plot_common.EmptyPlot as e:
        return plot_common.fail_empty(e)
    return 0


if __name__ == "__main__":
    sys.exit(main())
