#!/usr/bin/env python3
"""Checks of scripts/plot_hazard.py on a DEM as practitioners have them (run by .ci/run):

    python tests/python/test_plot_hazard.py GRANFLOW_BINARY

A synthetic DEM in map coordinates of six and seven digits (EPSG:32632), with a block of
nodata cells (walls) beside the path, a release polygon, one run and a two-run friction
sweep mapped against an observed footprint. Then:

1. the pft map has its contours (wall cells are NaN in the maps: the levels are found
   among the cells with data), a north arrow, coordinate labels that do not overlap, and
   the release outline drawn dark under a white dashed line (visible on a light shade);
2. the peak-pressure map is classed in kPa (1-10, 10-25, 25-50, > 50);
3. the profiles along the path (output.path) draw /path's maxima against s and the
   runout of /summary;
4. the probability map of the sweep draws the observed footprint;
5. every file written passes scripts/check_plot.py.
Needs h5py, numpy, matplotlib and pillow.
"""

import itertools
import pathlib
import subprocess
import sys
import tempfile

ROOT = pathlib.Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "scripts"))

import matplotlib  # noqa: E402

matplotlib.use("Agg")
import numpy as np  # noqa: E402

import plot_hazard  # noqa: E402

PY = sys.executable
X0, Y0, D = 612_300.0, 5_123_400.0, 5.0
NX, NY = 60, 30

SCENARIO = """[domain]
coordinates = "cartesian"

[bed]
b = { raster = "dem.asc" }

[rheology]
law = "coulomb"
mu_deg = 20.0

[initial]
h = { polygon = "release.geojson", thickness = 2.0, thickness_is = "vertical" }

[time]
t_end = 12.0

[output]
every = 4.0
path = { line = "path.geojson", field = "ppr", threshold = 1000.0, width = 100 }
"""


def run(*args):
    p = subprocess.run([str(a) for a in args], capture_output=True, text=True)
    assert p.returncode == 0, f"{args} failed ({p.returncode}):\n{p.stdout}\n{p.stderr}"
    return p


def rectangle(x0, x1, y0, y1):
    ring = [[x0, y0], [x1, y0], [x1, y1], [x0, y1], [x0, y0]]
    return ('{"type": "FeatureCollection", "crs": {"type": "name", "properties": '
            '{"name": "urn:ogc:def:crs:EPSG::32632"}}, "features": [{"type": "Feature", '
            '"properties": {}, "geometry": {"type": "Polygon", "coordinates": [%s]}}]}'
            % str(ring))


def write_inputs(d):
    rows = []
    for r in range(NY):
        row = []
        for c in range(NX):
            # A 30° slope falling east, flat beyond x = 150 m; nodata in the north-east.
            x = (c + 0.5) * D
            b = max(150.0 - x, 0.0) * np.tan(np.radians(30.0))
            row.append("-9999" if (c >= 45 and r < 6) else f"{b:.4f}")
        rows.append(" ".join(row))
    (d / "dem.asc").write_text(
        f"ncols {NX}\nnrows {NY}\nxllcorner {X0}\nyllcorner {Y0}\ncellsize {D}\n"
        "NODATA_value -9999\n" + "\n".join(rows) + "\n")
    (d / "release.geojson").write_text(rectangle(X0 + 20, X0 + 50, Y0 + 55, Y0 + 95))
    (d / "observed.geojson").write_text(rectangle(X0 + 15, X0 + 230, Y0 + 40, Y0 + 110))
    (d / "path.geojson").write_text(
        '{"type": "LineString", "coordinates": [[%r, %r], [%r, %r]]}'
        % (X0 + 10, Y0 + 75, X0 + 290, Y0 + 75))
    (d / "s.toml").write_text(SCENARIO)
    # The sweep's base names its files by absolute paths.
    (d / "base.toml").write_text(SCENARIO.replace('"dem.asc"', f'"{d / "dem.asc"}"')
                                 .replace('"release.geojson"', f'"{d / "release.geojson"}"')
                                 .replace('"path.geojson"', f'"{d / "path.geojson"}"'))
    (d / "sweep.toml").write_text('scenario = "base.toml"\n\n[axes]\nrheology.mu_deg = [18, 24]\n')


def overlapping(labels):
    boxes = [t.get_window_extent() for t in labels if t.get_visible() and t.get_text()]
    return [(a, b) for a, b in itertools.combinations(boxes, 2) if a.overlaps(b)]


def main():
    gf = pathlib.Path(sys.argv[1]).resolve()
    d = pathlib.Path(tempfile.mkdtemp())
    write_inputs(d)
    h5 = d / "s.h5"
    run(gf, "run", d / "s.toml", "--quiet", "--output", h5)
    r = plot_hazard.Run(h5)
    assert np.isnan(r.pft).any(), "the DEM's nodata cells should be NaN in the maps"

    # 1. pft: contours, north arrow, labels apart, a release outline that shows.
    fig, ax, cs = plot_hazard.draw_run(r, [0.01, 0.1, 1.0], "s.h5")
    assert cs is not None and len(cs.levels) >= 2, "no pft contours"
    assert any(t.get_text() == "N" for t in ax.texts), "no north arrow"
    fig.canvas.draw()
    for axis in (ax.get_xticklabels(), ax.get_yticklabels()):
        assert not overlapping(axis), [t.get_text() for t in axis]
    assert any(t.get_text().startswith("6123") for t in ax.get_xticklabels()), \
        [t.get_text() for t in ax.get_xticklabels()]
    dark = [c for c in ax.collections
            if list(getattr(c, "levels", [])) == [r.threshold]
            and np.allclose(np.asarray(c.get_edgecolor())[0][:3], 0.0)]
    assert dark, "the release outline has no dark line under it"

    # 2. ppr in classes of kPa.
    fig, ax, cb = plot_hazard.draw_ppr(r, [1, 10, 25, 50], "s.h5")
    labels = [t.get_text() for t in cb.ax.get_yticklabels()]
    assert labels == ["1–10", "10–25", "25–50", "> 50"], labels
    assert "kPa" in cb.ax.get_ylabel(), cb.ax.get_ylabel()

    # 3. The profiles along the path: the maxima of /path against s, the runout marked
    # where the summary puts it.
    fig, axes = plot_hazard.draw_path(r, "s.h5")
    assert len(axes) == 4
    line = axes[3].get_lines()[0]
    np.testing.assert_array_equal(line.get_xdata(), r.path["s"])
    np.testing.assert_array_equal(line.get_ydata(), r.path["ppr_max"] * 1e-3)
    labels = axes[0].get_legend_handles_labels()[1]
    assert any(t.startswith("runout angle") for t in labels), labels
    assert any(t.startswith("runout (s = %.4g" % r.summary["path_runout_s"]) for t in labels), \
        labels

    # 4. The sweep's probability with the observed footprint.
    runs = d / "runs"
    run(gf, "sweep", d / "sweep.toml", "--quiet", "--output", runs)
    run(gf, "maps", runs, "--threshold", "0.05", "--format", "asc", "--observed",
        d / "observed.geojson")
    assert (runs / "maps" / "observed.asc").exists()
    fig, ax, drawn = plot_hazard.draw_sweep(runs)
    assert drawn, "the observed footprint was not drawn"
    assert "observed footprint" in ax.get_legend_handles_labels()[1]

    # 5. The files, through the command line.
    run(PY, ROOT / "scripts/plot_hazard.py", h5)
    run(PY, ROOT / "scripts/plot_hazard.py", runs)
    run(PY, ROOT / "scripts/check_plot.py", d / "s_hazard.png", d / "s_ppr.png",
        d / "s_path.png", runs / "maps" / "probability.png")
    print("test_plot_hazard: all checks passed")


if __name__ == "__main__":
    main()
