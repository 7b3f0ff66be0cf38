"""Shared by the plotting scripts: output format and resolution, a check that every
panel holds data before a figure is saved, zooming on where the material went, and
readable log axes. Needs numpy and matplotlib."""

import sys

import numpy as np
from matplotlib import ticker
from matplotlib.collections import Collection
from matplotlib.image import AxesImage
from matplotlib.lines import Line2D

FORMATS = ("png", "pdf", "svg")


class EmptyPlot(Exception):
    """A figure (or one of its panels) would be saved without data."""


def add_output_options(parser, dpi=150):
    """--format and --dpi."""
    parser.add_argument("--format", choices=FORMATS, default="png",
                        help="file format of the plots (default png)")
    parser.add_argument("--dpi", type=int, default=dpi,
                        help=f"resolution of PNG plots (default {dpi})")


def _has_data(artist):
    if isinstance(artist, Line2D):
        x, y = (np.asarray(v, dtype=float) for v in artist.get_data())
        return x.size > 0 and bool(np.any(np.isfinite(x) & np.isfinite(y)))
    if isinstance(artist, AxesImage):
        a = np.asarray(artist.get_array(), dtype=float)
        return a.size > 0 and bool(np.any(np.isfinite(a)))
    if isinstance(artist, Collection):
        a = artist.get_array()
        if a is not None and np.size(a) > 0:
            return bool(np.any(np.isfinite(np.asarray(a, dtype=float))))
        offsets = np.asarray(artist.get_offsets(), dtype=float)
        if offsets.size > 0 and np.any(np.isfinite(offsets)):
            return True
        return any(len(p.vertices) > 0 for p in artist.get_paths())
    return False


def panels_without_data(fig):
    """Titles (or labels) of the data panels of `fig` that hold no data. Colour bars
    and panels marked with `mark_note` are not data panels."""
    empty = []
    for ax in fig.axes:
        if getattr(ax, "_colorbar", None) is not None or ax.get_label() == "<colorbar>":
            continue
        if getattr(ax, "granflow_note", False):
            continue
        artists = list(ax.lines) + list(ax.collections) + list(ax.images)
        if not any(_has_data(a) for a in artists):
            name = ax.get_title() or ax.get_ylabel() or f"panel {len(empty) + 1}"
            empty.append(name)
    return empty


def mark_note(ax, text):
    """A panel that says why it holds no data (counts as intended, not empty)."""
    ax.granflow_note = True
    ax.text(0.5, 0.5, text, transform=ax.transAxes, ha="center", va="center",
            fontsize=9, color="0.3", wrap=True)


STAMP = "granflow plot: every data panel holds data"


def save(fig, path, dpi=150):
    """Saves `fig` after checking that every data panel holds data (EmptyPlot if not),
    stamping the file with STAMP (PNG and SVG `Description`, PDF `Subject`), which
    scripts/check_plot.py looks for."""
    empty = panels_without_data(fig)
    if empty:
        raise EmptyPlot(f"{path}: no data in panel(s): {', '.join(empty)}")
    fmt = str(path).rsplit(".", 1)[-1]
    meta = {"Subject": STAMP} if fmt == "pdf" else {"Description": STAMP}
    fig.savefig(path, dpi=dpi if fmt == "png" else None, metadata=meta)


def fail_empty(e):
    print(f"error: {e}", file=sys.stderr)
    return 1


def extent(x, fields, threshold, margin=0.08):
    """The x range where any of `fields` (arrays (..., nx)) exceeds `threshold`, widened
    by `margin` of its length on each side and clipped to the domain; the whole domain
    when nothing does."""
    x = np.asarray(x, dtype=float)
    mask = np.zeros(x.shape, dtype=bool)
    for f in fields:
        f = np.asarray(f, dtype=float)
        mask |= np.any(f.reshape(-1, x.size) > threshold, axis=0)
    if not mask.any():
        return x[0], x[-1]
    i = np.nonzero(mask)[0]
    lo, hi = x[i[0]], x[i[-1]]
    pad = margin * max(hi - lo, 10 * (x[1] - x[0]) if x.size > 1 else 1.0)
    return max(x[0], lo - pad), min(x[-1], hi + pad)


def readable_log_axis(axis):
    """Major ticks at powers of ten only (at most ~6 labels), no minor labels: keeps the
    labels of a log axis from running into each other."""
    axis.set_major_locator(ticker.LogLocator(base=10, numticks=6))
    axis.set_major_formatter(ticker.LogFormatterSciNotation(base=10))
    axis.set_minor_locator(ticker.LogLocator(base=10, subs=np.arange(2, 10) * 0.1, numticks=12))
    axis.set_minor_formatter(ticker.NullFormatter())
