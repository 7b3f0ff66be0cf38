#!/usr/bin/env python3
"""Plot one granflow run: free surface and thickness, front, x–t diagram, and for
multilayer or non-hydrostatic runs the velocity profiles u(z), the static/flowing
interface and the non-hydrostatic pressure; the water surface and layer of submarine
runs, the volume fraction φ of dilatant runs, the gauge series of runs with gauges;
optionally an animation.

    python scripts/plot_run.py RUN.h5 [--out PREFIX] [--every K]
                               [--x X ...] [--times T ...] [--gif] [--fps N]
                               [--format png|pdf|svg] [--dpi N] [--whole]

Spatial panels show where the material went (where h, or for submarine runs also the
water's motion, exceeds the front threshold at some time, plus a margin); --whole
shows the whole domain. Writes PREFIX.png (default: RUN.png next to RUN.h5; .pdf or
.svg with --format):
  - bed and free surface b + h at every K-th snapshot (one colour per time from a
    sequential colour map, with a colour bar, so no two curves share a colour);
  - the thickness h alone, so thin deposits stay visible over high relief;
  - the front position against time;
  - an x–t diagram: h as colour over (x, t), the front line on top.
For multilayer runs (layers > 1) or non-hydrostatic runs, also PREFIX_layers.png:
  - u(z) profiles at the positions --x (default: 1/4, 1/2, 3/4 of the mass) and
    the times --times (default: four snapshots after t = 0), z the height above the
    bed (normal to the reference plane in local coordinates) at each layer's middle;
  - the static/flowing interface (multilayer runs) under the free surface;
  - the basal non-hydrostatic pressure p_nh (non-hydrostatic runs).
For submarine runs, PREFIX_water.png: bed, grain/water interface and water surface η
at every K-th snapshot, the water thickness, and the wave η − η₀ as an x–t diagram.
For dilatant runs, PREFIX_phi.png: φ(x) where there is material at every K-th
snapshot, and φ over (x, t). For runs with gauges (output.gauges), PREFIX_gauges.png:
η(t) − η(0) and the grain depth h(t) at each gauge (compare_gauges.py compares them
with measurements). A figure with a panel that holds no data is not written: the
script fails naming it (scripts/plot_common.py).
With --gif, PREFIX.gif: the flow over the bed, one frame per snapshot (matplotlib's
PillowWriter; needs pillow). Prints the summary attributes.
A raster (2-D) run is drawn as maps instead (scripts/plot_raster.py): PREFIX.png with
the largest thickness, the deposit, the largest speed, the arrival time and the bed,
over the hillshaded bed with the deposit and release outlines, and the kinetic energy
and area reached against time; --gif animates the thickness over the hillshade.
Needs h5py, numpy and matplotlib.
"""

import argparse
import pathlib
import sys

import matplotlib
import numpy as np

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from matplotlib import cm, colors  # noqa: E402

import h5py  # noqa: E402

import plot_common  # noqa: E402
import plot_raster  # noqa: E402
from granflow_io import Run  # noqa: E402

CMAP = "viridis"


def title(r, path):
    a = r.attrs
    return (f"{pathlib.Path(path).name}: {a.get('model')}, {a.get('pressure')}, "
            f"{a.get('layers')} layer(s), {a.get('coordinates')}, θ = {a.get('slope_deg')}°")


def chosen_snapshots(r, every):
    every = every or max(1, len(r.t) // 10)
    return sorted(set(range(0, len(r.t), every)) | {len(r.t) - 1})


def time_colours(r):
    norm = colors.Normalize(vmin=r.t[0], vmax=max(r.t[-1], r.t[0] + 1e-12))
    return norm, cm.ScalarMappable(norm=norm, cmap=CMAP)


def zoom(r, whole):
    """x range of the spatial panels: where the material (and the water's motion) went."""
    if whole:
        return r.x[0], r.x[-1]
    fields = [r.h - (r.h_bed if r.h_bed is not None else 0.0)]
    if r.eta is not None:
        fields.append(np.abs(r.eta - r.eta[0]))
    return plot_common.extent(r.x, fields, r.front_threshold)


def plot_main(r, path, every, out, xlim, dpi):
    ks = chosen_snapshots(r, every)
    norm, sm = time_colours(r)
    fig, ax = plt.subplots(2, 2, figsize=(13, 8))
    (a_surf, a_h), (a_front, a_xt) = ax

    a_surf.fill_between(r.x, r.b.min() - 0.02 * np.ptp(r.b + r.h[0]) - 1e-9, r.b,
                        color="0.85", lw=0)
    a_surf.plot(r.x, r.b, "k-", lw=1, label="bed b")
    for k in ks:
        a_surf.plot(r.x, r.b + r.h[k], lw=1.2, color=sm.to_rgba(r.t[k]))
        a_h.plot(r.x, r.h[k], lw=1.2, color=sm.to_rgba(r.t[k]))
    a_surf.set_xlabel("x (m)")
    a_surf.set_ylabel("b + h (m)")
    a_surf.legend(loc="upper right", fontsize=8)
    a_h.set_xlabel("x (m)")
    a_h.set_ylabel("thickness h (m)")
    a_h.set_ylim(bottom=0)
    for a in (a_surf, a_h):
        fig.colorbar(sm, ax=a, label="t (s)")

    a_front.plot(r.front_t, r.front_x, "k-", lw=1.2)
    a_front.set_xlabel("t (s)")
    a_front.set_ylabel("front position (m)")
    stop = r.summary.get("stop_time")
    settled = r.summary.get("settled_time")
    if stop is not None and np.isfinite(stop):
        a_front.axvline(stop, color="0.5", ls="--", lw=1, label=f"at rest, t = {stop:.3f} s")
    if settled is not None and np.isfinite(settled):
        a_front.axvline(settled, color="0.5", ls=":", lw=1, label=f"settled, t = {settled:.3f} s")
    if any(v is not None and np.isfinite(v) for v in (stop, settled)):
        a_front.legend(fontsize=8)

    plot_xt(a_xt, r, fig)
    for a in (a_surf, a_h, a_xt):
        a.set_xlim(*xlim)
    inside = (r.x >= xlim[0]) & (r.x <= xlim[1])
    top = (r.b + r.h)[:, inside]
    lo, hi = min(r.b[inside].min(), top.min()), top.max()
    a_surf.set_ylim(lo - 0.03 * (hi - lo + 1e-12), hi + 0.05 * (hi - lo + 1e-12))
    fig.suptitle(title(r, path))
    fig.tight_layout()
    plot_common.save(fig, out, dpi)
    plt.close(fig)


def plot_xt(a, r, fig):
    """h as colour over (x, t), the front on top."""
    if len(r.t) > 1:
        mesh = a.pcolormesh(r.x, r.t, r.h, shading="nearest", cmap="magma_r")
        fig.colorbar(mesh, ax=a, label="h (m)")
    a.plot(r.front_x, r.front_t, color="tab:cyan", lw=1.5, label="front")
    a.set_xlabel("x (m)")
    a.set_ylabel("t (s)")
    a.set_ylim(r.t[0], r.t[-1])
    a.legend(loc="lower right", fontsize=8)
    a.set_title("x–t diagram", fontsize=10)


def default_positions(r, k):
    """Three points at 1/4, 1/2 and 3/4 of the mass at snapshot k (where h exceeds a
    tenth of its maximum, so that an erodible-bed film does not count)."""
    thick = np.nonzero(r.h[k] > 0.1 * max(r.h[k].max(), 1e-12))[0]
    if len(thick) == 0:
        return [r.x[len(r.x) // 2]]
    lo, hi = r.x[thick[0]], r.x[thick[-1]]
    return sorted({r.x[r.cell(lo + f * (hi - lo))] for f in (0.25, 0.5, 0.75)})


def layer_heights(r, k, i):
    """Height above the bed of each layer's middle at snapshot k, cell i."""
    f = r.layer_fractions()
    return r.h[k, i] * (np.cumsum(f) - 0.5 * f)


def plot_layers(r, path, xs, times, out, xlim, dpi):
    multilayer = r.layers > 1
    nh = r.p_nh is not None
    panels = [p for p, on in (("u", multilayer), ("interface", r.static_interface is not None),
                              ("p_nh", nh)) if on]
    if not panels:
        return None
    ks = ([r.snapshot(t) for t in times] if times
          else sorted(set(np.linspace(min(1, len(r.t) - 1), len(r.t) - 1, 4)
                          .round().astype(int))))
    norm, sm = time_colours(r)
    fig, axs = plt.subplots(1, len(panels), figsize=(5.2 * len(panels), 4.3), squeeze=False)
    axs = axs[0]
    for a, panel in zip(axs, panels):
        if panel == "u":
            xs = xs or default_positions(r, ks[len(ks) // 2])
            styles = ["-", "--", ":", "-."]
            for j, x in enumerate(xs):
                i = r.cell(x)
                for k in ks:
                    if r.h[k, i] <= 0:
                        continue
                    z = layer_heights(r, k, i)
                    a.plot(r.u[k, :, i], z, styles[j % len(styles)], marker=".",
                           color=sm.to_rgba(r.t[k]), lw=1.2)
                a.plot([], [], "k" + styles[j % len(styles)], label=f"x = {r.x[i]:.3g} m")
            a.set_xlabel("u (m/s)")
            a.set_ylabel("z above the bed (m)")
            a.set_title("velocity profiles u(z)", fontsize=10)
            a.legend(fontsize=8)
            fig.colorbar(sm, ax=a, label="t (s)")
        elif panel == "interface":
            for k in ks:
                c = sm.to_rgba(r.t[k])
                a.plot(r.x, r.h[k], "-", color=c, lw=1.2)
                a.plot(r.x, r.static_interface[k], "--", color=c, lw=1.2)
            a.plot([], [], "k-", label="free surface h")
            a.plot([], [], "k--", label="static/flowing interface")
            a.set_xlabel("x (m)")
            a.set_ylabel("height above the bed (m)")
            a.set_title("static/flowing interface", fontsize=10)
            a.legend(fontsize=8)
            fig.colorbar(sm, ax=a, label="t (s)")
        else:
            faces = np.concatenate([[r.x[0] - r.dx / 2], r.x + r.dx / 2])
            for k in ks:
                a.plot(faces, r.p_nh[k, 0], color=sm.to_rgba(r.t[k]), lw=1.2)
            a.set_xlabel("x (m)")
            a.set_ylabel("basal p_nh / ρ (m²/s²)")
            a.set_title("non-hydrostatic pressure at the bed", fontsize=10)
            fig.colorbar(sm, ax=a, label="t (s)")
        if panel != "u":
            a.set_xlim(*xlim)
    fig.suptitle(title(r, path))
    fig.tight_layout()
    plot_common.save(fig, out, dpi)
    plt.close(fig)
    return out


def plot_water(r, path, every, out, xlim, dpi):
    """Submarine runs: the water surface over the grains, the water layer, the wave."""
    ks = chosen_snapshots(r, every)
    norm, sm = time_colours(r)
    fig, (a_s, a_w, a_xt) = plt.subplots(1, 3, figsize=(16, 4.4))
    a_s.fill_between(r.x, r.b.min() - 1e-9, r.b, color="0.85", lw=0)
    a_s.plot(r.x, r.b, "k-", lw=1, label="bed b")
    for k in ks:
        c = sm.to_rgba(r.t[k])
        a_s.plot(r.x, r.eta[k], "-", color=c, lw=1.2)
        a_s.plot(r.x, r.interface[k], "--", color=c, lw=1.2)
        a_w.plot(r.x, r.h_water[k], "-", color=c, lw=1.2)
    a_s.plot([], [], "k-", label="water surface η")
    a_s.plot([], [], "k--", label="top of the grains")
    a_s.set_ylabel("elevation (m)")
    a_s.set_title("water surface and grains", fontsize=10)
    a_s.legend(fontsize=8, loc="lower left")
    a_w.set_ylabel("water thickness H₁ (m)")
    a_w.set_title("water layer", fontsize=10)
    for a in (a_s, a_w):
        a.set_xlabel("x (m)")
        a.set_xlim(*xlim)
        fig.colorbar(sm, ax=a, label="t (s)")
    wave = r.eta - r.eta[0]
    wave = np.where(r.h_water > r.front_threshold, wave, np.nan)
    lim = np.nanmax(np.abs(wave)) if np.isfinite(wave).any() else 1.0
    if len(r.t) > 1:
        mesh = a_xt.pcolormesh(r.x, r.t, wave, shading="nearest", cmap="RdBu_r",
                               vmin=-lim, vmax=lim)
        fig.colorbar(mesh, ax=a_xt, label="η − η₀ (m)")
    a_xt.set_xlabel("x (m)")
    a_xt.set_ylabel("t (s)")
    a_xt.set_title("wave η − η₀ (where there is water)", fontsize=10)
    fig.suptitle(title(r, path))
    fig.tight_layout()
    plot_common.save(fig, out, dpi)
    plt.close(fig)
    return out


def plot_phi(r, path, every, out, xlim, dpi):
    """Dilatant runs: the solid volume fraction φ where there is material."""
    ks = chosen_snapshots(r, every)
    norm, sm = time_colours(r)
    wet = r.h > r.front_threshold
    phi = np.where(wet, r.phi, np.nan)
    fig, (a_p, a_xt) = plt.subplots(1, 2, figsize=(13, 4.4))
    for k in ks:
        a_p.plot(r.x, phi[k], "-", color=sm.to_rgba(r.t[k]), lw=1.2)
    a_p.set_xlabel("x (m)")
    a_p.set_ylabel("solid volume fraction φ")
    a_p.set_title(f"φ where h > {r.front_threshold:g} m", fontsize=10)
    fig.colorbar(sm, ax=a_p, label="t (s)")
    if len(r.t) > 1:
        mesh = a_xt.pcolormesh(r.x, r.t, phi, shading="nearest", cmap="cividis")
        fig.colorbar(mesh, ax=a_xt, label="φ")
    a_xt.set_xlabel("x (m)")
    a_xt.set_ylabel("t (s)")
    a_xt.set_title("φ over (x, t)", fontsize=10)
    for a in (a_p, a_xt):
        a.set_xlim(*xlim)
    fig.suptitle(title(r, path))
    fig.tight_layout()
    plot_common.save(fig, out, dpi)
    plt.close(fig)
    return out


def plot_gauges(r, path, out, dpi):
    """Gauge series: η(t) − η(0) and the grain depth at each gauge."""
    g = r.gauges
    fig, (a_e, a_h) = plt.subplots(2, 1, figsize=(10, 6.4), sharex=True)
    cmap = plt.get_cmap("tab10")
    for j, x in enumerate(g["x"]):
        c = cmap(j % 10)
        a_e.plot(g["t"], g["eta"][:, j] - g["eta"][0, j], color=c, lw=1.2, label=f"x = {x:g} m")
        a_h.plot(g["t"], g["h_grains"][:, j], color=c, lw=1.2)
    a_e.set_ylabel("η − η(t = 0) (m)")
    a_e.set_title("free surface at the gauges", fontsize=10)
    a_e.legend(fontsize=8, ncol=min(4, len(g["x"])))
    a_h.set_ylabel("grain depth (m)")
    a_h.set_xlabel("t (s)")
    a_h.set_title("grain depth at the gauges", fontsize=10)
    for a in (a_e, a_h):
        a.grid(alpha=0.3)
    fig.suptitle(title(r, path))
    fig.tight_layout()
    plot_common.save(fig, out, dpi)
    plt.close(fig)
    return out


def animate(r, path, out, fps):
    from matplotlib.animation import FuncAnimation, PillowWriter

    fig, (a1, a2) = plt.subplots(2, 1, figsize=(8, 6), sharex=True)
    a1.plot(r.x, r.b, "k-", lw=1)
    surf, = a1.plot(r.x, r.b + r.h[0], "tab:orange", lw=1.5)
    thick, = a2.plot(r.x, r.h[0], "tab:orange", lw=1.5)
    front = a2.axvline(r.front_x[0] if len(r.front_x) else r.x[0], color="0.4", ls="--")
    a1.set_ylim(min(r.b.min(), (r.b + r.h).min()),
                1.05 * (r.b + r.h).max() + 1e-12)
    a2.set_ylim(0, 1.05 * r.h.max() + 1e-12)
    a1.set_ylabel("b + h (m)")
    a2.set_ylabel("h (m)")
    a2.set_xlabel("x (m)")
    label = a1.set_title("")
    fig.suptitle(title(r, path), fontsize=9)

    def frame(k):
        surf.set_ydata(r.b + r.h[k])
        thick.set_ydata(r.h[k])
        j = min(np.searchsorted(r.front_t, r.t[k]), len(r.front_x) - 1)
        fx = r.front_x[j]
        front.set_xdata([fx, fx])
        label.set_text(f"t = {r.t[k]:.3f} s")
        return surf, thick, front, label

    anim = FuncAnimation(fig, frame, frames=len(r.t), blit=False)
    anim.save(out, writer=PillowWriter(fps=fps))
    plt.close(fig)


def main_raster(args, prefix, ext, dpi):
    """The maps of a raster run (plot_raster.py)."""
    with h5py.File(args.run, "r") as f:
        a = {k: (v.decode() if isinstance(v, bytes) else v) for k, v in f.attrs.items()}
    name = pathlib.Path(args.run).name
    heading = (f"{name}: {a.get('model')} on a {a.get('nx')} × {a.get('ny')} raster, "
               f"{a.get('coordinates')}")
    written = [f"{prefix}.{ext}"]
    try:
        r = plot_raster.plot_maps(args.run, written[0], dpi, heading)
    except plot_common.EmptyPlot as e:
        return plot_common.fail_empty(e)
    if args.gif:
        written.append(f"{prefix}.gif")
        plot_raster.animate(r, written[-1], args.fps, heading)
    for k, v in sorted(r.summary.items()):
        print(f"{k:>22}: {v}")
    print("plot: " + ", ".join(written))
    return 0


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("run")
    p.add_argument("--out", help="prefix of the output files (default: RUN without .h5)")
    p.add_argument("--every", type=int, default=0, help="plot every K-th snapshot")
    p.add_argument("--x", type=float, nargs="+", help="positions of the u(z) profiles (m)")
    p.add_argument("--times", type=float, nargs="+",
                   help="times of the profiles (s; the nearest snapshots)")
    p.add_argument("--gif", action="store_true", help="also write an animation PREFIX.gif")
    p.add_argument("--fps", type=int, default=8)
    p.add_argument("--whole", action="store_true",
                   help="spatial panels over the whole domain (default: where the material went)")
    plot_common.add_output_options(p)
    args = p.parse_args()
    prefix = pathlib.Path(args.out) if args.out else pathlib.Path(args.run).with_suffix("")
    prefix.parent.mkdir(parents=True, exist_ok=True)
    ext, dpi = args.format, args.dpi
    if plot_raster.is_raster(args.run):
        return main_raster(args, prefix, ext, dpi)
    r = Run(args.run)
    xlim = zoom(r, args.whole)
    written = [f"{prefix}.{ext}"]
    try:
        plot_main(r, args.run, args.every, written[0], xlim, dpi)
        layers = plot_layers(r, args.run, args.x, args.times, f"{prefix}_layers.{ext}", xlim, dpi)
        if layers:
            written.append(layers)
        if r.eta is not None and r.h_water is not None:
            written.append(plot_water(r, args.run, args.every, f"{prefix}_water.{ext}", xlim, dpi))
        if r.phi is not None:
            written.append(plot_phi(r, args.run, args.every, f"{prefix}_phi.{ext}", xlim, dpi))
        if r.gauges is not None:
            written.append(plot_gauges(r, args.run, f"{prefix}_gauges.{ext}", dpi))
    except plot_common.EmptyPlot as e:
        return plot_common.fail_empty(e)
    if args.gif:
        written.append(f"{prefix}.gif")
        animate(r, args.run, written[-1], args.fps)
    for k, v in sorted(r.summary.items()):
        print(f"{k:>22}: {v}")
    print("plot: " + ", ".join(written))
    return 0


if __name__ == "__main__":
    sys.exit(main())
