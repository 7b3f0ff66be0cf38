#!/usr/bin/env python3
"""Write the synthetic DEM and release polygon of scenarios/dem_release.toml.

    python scripts/synthetic_dem.py DIR

writes DIR/synthetic_dem.asc (+ .prj), DIR/synthetic_release.geojson and
DIR/synthetic_path.geojson (the files in scenarios/data/ are its output). Plain Python, no packages.

The terrain, in Swiss LV95 coordinates (EPSG:2056) from the lower-left corner
(2 600 000, 1 200 000), 120 × 60 cells of 5 m: along x a 30° slope over 250 m, a
transition over 100 m in which the slope falls linearly to 0, then a flat runout,
with a shallow valley across y (0.002 (y − y_c)² m). A block of 6 × 8 cells in the
runout (x from 420 to 450 m, y from 170 to 210 m from the corner) has no data: a
building, a wall of the run. The release is a pentagon on the slope, 1.5 m thick
normal to it. The path (thalweg, for `output.path`) runs down the valley's axis,
y = 150 m from the corner, from x = 10 m to x = 590 m.
"""

import json
import math
import pathlib
import sys

NX, NY, D = 120, 60, 5.0
X0, Y0 = 2600000.0, 1200000.0
NODATA = -9999.0
TAN30 = math.tan(math.radians(30.0))
WKT = (
    'PROJCS["CH1903+ / LV95",GEOGCS["CH1903+",DATUM["CH1903+",SPHEROID["Bessel 1841",'
    '6377397.155,299.1528128]],PRIMEM["Greenwich",0],UNIT["degree",0.0174532925199433]],'
    'PROJECTION["Hotine_Oblique_Mercator_Azimuth_Center"],UNIT["metre",1],'
    'AUTHORITY["EPSG","2056"]]'
)


def elevation(s, t):
    """Elevation at s (m along x from the left edge) and t (m along y from the bottom)."""
    if s < 250.0:
        z = 400.0 - s * TAN30
    elif s < 350.0:
        u = s - 250.0
        z = 400.0 - 250.0 * TAN30 - TAN30 * (u - u * u / 200.0)
    else:
        z = 400.0 - 300.0 * TAN30
    return z + 0.002 * (t - 150.0) ** 2


def main(out):
    out.mkdir(parents=True, exist_ok=True)
    lines = [
        f"ncols {NX}",
        f"nrows {NY}",
        f"xllcorner {X0}",
        f"yllcorner {Y0}",
        f"cellsize {D}",
        f"NODATA_value {NODATA:g}",
    ]
    for row in range(NY):
        t = (NY - row - 0.5) * D
        values = []
        for col in range(NX):
            s = (col + 0.5) * D
            if 420.0 < s < 450.0 and 170.0 < t < 210.0:
                values.append(f"{NODATA:g}")
            else:
                values.append(f"{elevation(s, t):.3f}")
        lines.append(" ".join(values))
    (out / "synthetic_dem.asc").write_text("\n".join(lines) + "\n")
    (out / "synthetic_dem.prj").write_text(WKT + "\n")
    ring = [(40.0, 120.0), (95.0, 105.0), (115.0, 150.0), (95.0, 195.0), (40.0, 180.0)]
    ring = [[X0 + s, Y0 + t] for s, t in ring] + [[X0 + ring[0][0], Y0 + ring[0][1]]]
    release = {
        "type": "FeatureCollection",
        "crs": {"type": "name", "properties": {"name": "urn:ogc:def:crs:EPSG::2056"}},
        "features": [
            {
                "type": "Feature",
                "properties": {"name": "release", "d": 1.5},
                "geometry": {"type": "Polygon", "coordinates": [ring]},
            }
        ],
    }
    (out / "synthetic_release.geojson").write_text(json.dumps(release, indent=1) + "\n")
    path = {
        "type": "FeatureCollection",
        "crs": {"type": "name", "properties": {"name": "urn:ogc:def:crs:EPSG::2056"}},
        "features": [
            {
                "type": "Feature",
                "properties": {"name": "thalweg"},
                "geometry": {
                    "type": "LineString",
                    "coordinates": [[X0 + 10.0, Y0 + 150.0], [X0 + 590.0, Y0 + 150.0]],
                },
            }
        ],
    }
    (out / "synthetic_path.geojson").write_text(json.dumps(path, indent=1) + "\n")


if __name__ == "__main__":
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    main(pathlib.Path(sys.argv[1]))
