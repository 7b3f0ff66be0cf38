#!/usr/bin/env python3
"""The `.prj` granflow writes for a CRS known only by its EPSG code resolves, in GDAL
(rasterio), to the same CRS as the EPSG registry's (run by .ci/run):

    python tests/python/test_prj_epsg.py GIS_ROUNDTRIP_BINARY

The gis_roundtrip example (`prj DIR`) writes epsg_<code>.asc with its .prj for one code
of each family granflow knows. For each, rasterio opens the grid and must (1) read the
code back, and (2) with the root AUTHORITY removed from the WKT (so that GDAL cannot
take the code's definition instead of the parameters written), project points of the
system's area exactly as EPSG:<code> does: from the geographic CRS of the same datum,
to within 1 mm, and identify the WKT as EPSG:<code>.
Needs rasterio.
"""

import pathlib
import re
import subprocess
import sys
import tempfile

import rasterio
from rasterio.crs import CRS
from rasterio.warp import transform

# code: (geographic CRS of its datum, a point (lon, lat) in its area)
CASES = {
    4326: (4326, (9.0, 46.0)),
    32601: (4326, (-177.0, 10.0)), 32632: (4326, (9.5, 46.5)), 32660: (4326, (177.0, 60.0)),
    32701: (4326, (-177.0, -10.0)), 32719: (4326, (-69.0, -33.0)), 32760: (4326, (177.0, -40.0)),
    25828: (4258, (-15.0, 40.0)), 25833: (4258, (15.0, 50.0)), 25838: (4258, (45.0, 50.0)),
    26901: (4269, (-177.0, 52.0)), 26911: (4269, (-117.0, 40.0)), 26923: (4269, (-45.0, 50.0)),
    3035: (4258, (11.0, 47.0)),
    2056: (4150, (7.5, 46.8)), 21781: (4149, (8.5, 47.2)),
    31254: (4312, (10.5, 47.2)), 31255: (4312, (13.5, 47.5)), 31256: (4312, (16.2, 48.0)),
    31257: (4312, (10.5, 47.2)), 31258: (4312, (13.5, 47.5)), 31259: (4312, (16.2, 48.0)),
    31287: (4312, (13.3, 47.5)),
    2154: (4171, (3.0, 46.0)),
    31466: (4314, (6.5, 51.0)), 31467: (4314, (9.0, 50.0)), 31468: (4314, (12.0, 48.5)),
    31469: (4314, (14.0, 52.0)),
    3003: (4265, (9.0, 44.0)), 3004: (4265, (15.0, 41.0)),
    28992: (4289, (5.4, 52.2)),
}


def strip_root_authority(wkt):
    """The WKT without its last (root) AUTHORITY node."""
    i = wkt.rindex(',AUTHORITY["EPSG"')
    return wkt[:i] + "]"


def main():
    binary = pathlib.Path(sys.argv[1]).resolve()
    d = pathlib.Path(tempfile.mkdtemp())
    subprocess.run([str(binary), "prj", str(d)], check=True)
    bad = []
    for code, (geog, (lon, lat)) in CASES.items():
        asc = d / f"epsg_{code}.asc"
        with rasterio.open(asc) as src:
            if src.crs is None or src.crs.to_epsg() != code:
                bad.append(f"{code}: rasterio reads {src.crs and src.crs.to_epsg()}")
                continue
        wkt = (d / f"epsg_{code}.prj").read_text().strip()
        if code == 4326:
            continue
        ours = CRS.from_wkt(strip_root_authority(wkt))
        if ours.to_epsg(confidence_threshold=70) != code:
            bad.append(f"{code}: the parameters identify as {ours.to_epsg(confidence_threshold=70)}")
        lons, lats = [lon, lon + 0.3, lon - 0.2], [lat, lat + 0.2, lat - 0.3]
        want = transform(CRS.from_epsg(geog), CRS.from_epsg(code), lons, lats)
        got = transform(CRS.from_epsg(geog), ours, lons, lats)
        err = max(max(abs(a - b) for a, b in zip(want[k], got[k])) for k in (0, 1))
        if not err <= 1e-3:
            bad.append(f"{code}: points differ by {err:.3g} m from EPSG:{code}")
    for b in bad:
        print(f"test_prj_epsg: {b}", file=sys.stderr)
    if bad:
        sys.exit(1)
    print(f"test_prj_epsg: {len(CASES)} codes, each .prj the registry's CRS")


if __name__ == "__main__":
    main()
