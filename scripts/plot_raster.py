"""Maps of a raster (2-D) granflow run, drawn by plot_run.py (not a script of its own).

PREFIX.png, six panels over the hillshaded bed (matplotlib's LightSource, light from
the north-west), with the deposit outline (h = front threshold at the end, solid) and
the release outline (dashed) on each map:
  - the largest thickness over the run, /maps/h_max;
  - the deposit, /maps/deposit (the thickness at the end);
  - the largest speed, /maps/speed_max;
  - the arrival time, /maps/arrival_time (blank where the flow never came);
  - the bed elevation b with its contours;
  - the area reached and the kinetic energy against time (/diagnostics).
A run that did not finish has no /maps: they are then taken from the snapshots.
With --gif, PREFIX.gif: the thickness over the hillshade, one frame per snapshot.
"""

import h5py
import matplotlib.pyplot as plt
import numpy as np
from matplotlib import colors

import plot_common


def is_raster(path):
    """Whether the file holds a raster run (root attribute grid = "raster")."""
    with h5py.File(path, "r") as f:
        grid = f.attrs.get("grid")
    if isinstance(grid, bytes):
        grid = grid.decode()
    return grid == "raster"


class RasterRun:
    """The fields of a raster run that the maps need."""

    def __init__(self, path):
        with h5py.File(path, "r") as f:
            self.x = f["grid/x"][:]
            self.y = f["grid/y"][:]
            self.b = f["grid/b"][:]
            self.t = f["snapshots/t"][:]
            self.h = f["snapshots/h"][:]
            self.threshold = float(f["front"].attrs.get("threshold", 1e-3))
            self.td = f["diagnostics/t"][:]
            self.ke = f["diagnostics/kinetic_energy"][:]
            self.area = f["diagnostics/area_reached"][:] if "diagnostics/area_reached" in f else None
            if "maps" in f:
                self.maps = {k: f["maps"][k][:] for k in f["maps"]}
            else:
                u, v = f["snapshots/u"][:], f["snapshots/v"][:]
                wet = self.h > self.threshold
                speed = np.where(wet, np.hypot(u, v), 0.0)
                first = np.argmax(wet, axis=0).astype(float)
                arrival = np.where(wet.any(axis=0), self.t[first.astype(int)], np.nan)
                self.maps = {"h_max": self.h.max(axis=0), "deposit": self.h[-1],
                             "speed_max": speed.max(axis=0), "arrival_time": arrival}
            self.attrs = dict(f.attrs)
            self.summary = dict(f["summary"].attrs) if "summary" in f else {}
        dx = self.x[1] - self.x[0] if len(self.x) > 1 else 1.0
        dy = self.y[1] - self.y[0] if len(self.y) > 1 else dx
        self.extent = (self.x[0] - dx / 2, self.x[-1] + dx / 2,
                       self.y[0] - dy / 2, self.y[-1] + dy / 2)
        self.dx, self.dy = dx, dy

    def hillshade(self):
        ls = colors.LightSource(azdeg=315, altdeg=45)
        relief = np.ptp(self.b)
        if relief == 0:
            return np.full(self.b.shape, 0.8)
        return ls.hillshade(self.b, vert_exag=1.0, dx=self.dx, dy=self.dy)


def _background(ax, r, shade):
    ax.imshow(shade, origin="lower", extent=r.extent, cmap="gray", vmin=0, vmax=1)
    ax.set_aspect("equal")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")


def _outlines(ax, r):
    """The deposit (solid) and release (dashed) outlines, where they exist."""
    for field, style in ((r.maps["deposit"], "-"), (r.h[0], "--")):
        if (field > r.threshold).any() and (field <= r.threshold).any():
            ax.contour(r.x, r.y, field, levels=[r.threshold], colors="k",
                       linewidths=0.8, linestyles=style)


def _map(fig, ax, r, shade, field, label, cmap, mask_below=None):
    _background(ax, r, shade)
    data = np.ma.masked_invalid(field)
    if mask_below is not None:
        data = np.ma.masked_where(~(field > mask_below), data)
    im = ax.imshow(data, origin="lower", extent=r.extent, cmap=cmap, alpha=0.85)
    fig.colorbar(im, ax=ax, shrink=0.8, label=label)
    _outlines(ax, r)
    ax.set_title(label)


def plot_maps(path, out, dpi, title):
    """Writes the six-panel map figure of the raster run `path` to `out`."""
    r = RasterRun(path)
    shade = r.hillshade()
    fig, axes = plt.subplots(2, 3, figsize=(15, 8.5))
    (a_hmax, a_dep, a_speed), (a_arr, a_bed, a_ts) = axes
    _map(fig, a_hmax, r, shade, r.maps["h_max"], "largest thickness h_max (m)",
         "viridis", r.threshold)
    _map(fig, a_dep, r, shade, r.maps["deposit"], "deposit h (m)", "viridis", r.threshold)
    _map(fig, a_speed, r, shade, r.maps["speed_max"], "largest speed (m/s)", "magma",
         0.0)
    _map(fig, a_arr, r, shade, r.maps["arrival_time"], "arrival time (s)", "plasma")
    _background(a_bed, r, shade)
    im = a_bed.imshow(r.b, origin="lower", extent=r.extent, cmap="terrain", alpha=0.6)
    fig.colorbar(im, ax=a_bed, shrink=0.8, label="bed b (m)")
    if np.ptp(r.b) > 0:
        a_bed.contour(r.x, r.y, r.b, levels=12, colors="0.3", linewidths=0.5)
    _outlines(a_bed, r)
    a_bed.set_title("bed, deposit (—) and release (--) outlines")
    a_ts.plot(r.td, r.ke, "tab:red", label="kinetic energy")
    a_ts.set_xlabel("t (s)")
    a_ts.set_ylabel("kinetic energy (m⁵/s²)", color="tab:red")
    a_ts.set_title("kinetic energy and area reached")
    if r.area is not None and len(r.area) == len(r.td):
        twin = a_ts.twinx()
        twin.plot(r.td, r.area, "tab:blue")
        twin.set_ylabel("area reached (m²)", color="tab:blue")
    a_ts.grid(alpha=0.3)
    s = r.summary
    if "runout_length" in s:
        fig.text(0.01, 0.01, f"runout {float(s['runout_length']):.4g} m, travel angle "
                 f"{float(s['travel_angle_deg']):.3g}°, area reached "
                 f"{float(s['area_reached']):.4g} m²", fontsize=9)
    fig.suptitle(title)
    fig.tight_layout()
    plot_common.save(fig, out, dpi)
    plt.close(fig)
    return r


def animate(r, out, fps, title):
    """PREFIX.gif: h over the hillshade, one frame per snapshot."""
    from matplotlib.animation import FuncAnimation, PillowWriter

    shade = r.hillshade()
    fig, ax = plt.subplots(figsize=(8, 6))
    _background(ax, r, shade)
    vmax = max(float(r.h.max()), 1e-12)
    frame0 = np.ma.masked_where(~(r.h[0] > r.threshold), r.h[0])
    im = ax.imshow(frame0, origin="lower", extent=r.extent, cmap="viridis",
                   vmin=0, vmax=vmax, alpha=0.85)
    fig.colorbar(im, ax=ax, shrink=0.8, label="h (m)")
    label = ax.set_title("")
    fig.suptitle(title, fontsize=9)

    def frame(k):
        im.set_data(np.ma.masked_where(~(r.h[k] > r.threshold), r.h[k]))
        label.set_text(f"t = {r.t[k]:.3f} s")
        return im, label

    anim = FuncAnimation(fig, frame, frames=len(r.t), blit=False)
    anim.save(out, writer=PillowWriter(fps=fps))
    plt.close(fig)
