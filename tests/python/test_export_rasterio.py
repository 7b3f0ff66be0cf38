#!/usr/bin/env python3
"""`granflow export` and `granflow maps` files opened by real readers (run by .ci/run):

    python tests/python/test_export_rasterio.py GRANFLOW_BINARY

1. A 2-D run on a DEM written by rasterio (a GeoTIFF in UTM 32N, EPSG:32632, 10 m cells),
   exported as GeoTIFF (Float32, the default) and ESRI ASCII grids: rasterio opens
   RUN_pft.tif etc. with the run's origin (from /grid/x, /grid/y in the HDF5 file, read
   with h5py), cell size, CRS and the values of /maps (Float32-rounded in the GeoTIFF,
   exact in the grid), -9999 where the file holds NaN (the arrival time of cells never
   reached); each GeoTIFF band's description and units are those of its HDF5 map.
2. The NetCDF export opened by xarray: coordinates x, y (cell centres, north row
   first) and time, units, and values equal to /snapshots (Float32-rounded).
3. `granflow maps` over a two-run sweep: rasterio opens pft_probability.tif on the same
   grid and CRS, with 0.5 exactly where one of the two runs' pft exceeds the threshold.
Needs rasterio, xarray (with scipy), h5py and numpy.
"""

import pathlib
import subprocess
import sys
import tempfile

import h5py
import numpy as np
import rasterio
from rasterio.transform import from_origin
import xarray as xr

SCENARIO = """[domain]
coordinates = "cartesian"

[bed]
b = { raster = "dem.tif" }

[rheology]
law = "coulomb"
mu_deg = 15.0

[initial]
h = "if((x - 600045)^2 + (y - 5200070)^2 < 25^2, 3, 0)"

[time]
t_end = 4

[output]
every = 1
"""


def run(*args):
    out = subprocess.run([str(a) for a in args], capture_output=True, text=True)
    assert out.returncode == 0, f"{args}: {out.stderr}"
    return out.stdout


def north_up(a):
    return a[..., ::-1, :]


def main():
    gf = pathlib.Path(sys.argv[1]).resolve()
    with tempfile.TemporaryDirectory() as tmp:
        d = pathlib.Path(tmp)
        dem = np.tile(1000.0 - 4.0 * np.arange(20), (14, 1))
        with rasterio.open(d / "dem.tif", "w", driver="GTiff", width=20, height=14, count=1,
                           dtype="float64", crs="EPSG:32632",
                           transform=from_origin(600_000, 5_200_140, 10, 10)) as dst:
            dst.write(dem, 1)
        (d / "slope.toml").write_text(SCENARIO)
        h5 = d / "slope.h5"
        run(gf, "run", d / "slope.toml", "--quiet", "--output", h5)
        out = d / "out"
        run(gf, "export", h5, "-o", out)
        run(gf, "export", h5, "--format", "asc", "-o", out)
        run(gf, "export", h5, "--format", "netcdf", "-o", out)
        with h5py.File(h5, "r") as f:
            x, y = f["grid/x"][:], f["grid/y"][:]
            maps = {k: f["maps"][k][:] for k in f["maps"]}
            meta = {k: (f["maps"][k].attrs["units"], f["maps"][k].attrs["description"])
                    for k in f["maps"]}
            t = f["snapshots/t"][:]
            h = f["snapshots/h"][:]
            assert f.attrs["crs"] in ("EPSG:32632", b"EPSG:32632"), f.attrs["crs"]
        d_cell = x[1] - x[0]
        origin = (x[0] - d_cell / 2, y[-1] + d_cell / 2)
        assert origin == (600_000.0, 5_200_140.0), origin
        checked = 0
        for name, source in (("pft", "h_max"), ("pfv", "speed_max"), ("ppr", "ppr"),
                             ("deposit", "deposit"), ("arrival_time", "arrival_time")):
            want = north_up(maps[source])
            for ext in ("tif", "asc"):
                path = out / f"slope_{name}.{ext}"
                options = {"DATATYPE": "Float64"} if ext == "asc" else {}
                with rasterio.open(path, **options) as src:
                    assert (src.width, src.height) == (20, 14), path
                    t_ = src.transform
                    assert (t_.a, t_.b, t_.c, t_.d, t_.e, t_.f) == (
                        d_cell, 0.0, origin[0], 0.0, -d_cell, origin[1]), (path, t_)
                    if ext == "tif":
                        assert src.crs.to_epsg() == 32632, (path, src.crs)
                        # The band says what it is and its units, as the HDF5 map does.
                        units, description = (str(v.decode() if isinstance(v, bytes) else v)
                                              for v in meta[source])
                        assert src.units[0] == units, (path, src.units, units)
                        assert src.descriptions[0] == description, (path, src.descriptions)
                    if ext == "asc":
                        # The DEM's CRS is known by its code alone: the .prj is made.
                        assert src.crs is not None and src.crs.to_epsg() == 32632, (path, src.crs)
                    assert src.nodata == -9999.0, (path, src.nodata)
                    got = src.read(1).astype(np.float64)
                expect = want if ext == "asc" else want.astype(np.float32).astype(np.float64)
                expect = np.where(np.isnan(expect), -9999.0, expect)
                assert (got == expect).all(), f"{path}: {(got != expect).sum()} values differ"
                checked += 1
        assert np.nanmax(maps["h_max"]) > 0 and np.isnan(maps["arrival_time"]).any()
        ds = xr.open_dataset(out / "slope_snapshots.nc")
        assert ds.x.attrs["units"] == "m" and ds.h.attrs["units"] == "m", ds
        assert ds.speed.attrs["units"] == "m/s"
        assert np.array_equal(ds.x.values, x) and np.array_equal(ds.y.values, y[::-1])
        assert np.array_equal(ds.time.values, t), (ds.time.values, t)
        assert np.array_equal(ds.h.values, north_up(h).astype(np.float32)), "h differs"
        ds.close()
        m = xr.open_dataset(out / "slope_maps.nc")
        assert np.array_equal(m.pft.values[0], north_up(maps["h_max"]).astype(np.float32))
        m.close()
        print(f"OK export: {checked} rasters opened by rasterio with the run's grid, CRS and "
              f"values; NetCDF opened by xarray ({t.size} snapshots)")

        (d / "base.toml").write_text(SCENARIO.replace('"dem.tif"', f'"{d / "dem.tif"}"'))
        (d / "sweep.toml").write_text(
            'scenario = "base.toml"\n\n[axes]\nrheology.mu_deg = [12, 18]\n')
        runs = d / "runs"
        run(gf, "sweep", d / "sweep.toml", "--quiet", "--jobs", "1", "--output", runs)
        run(gf, "maps", runs, "--threshold", "0.05")
        reach = []
        for name in ("mu_deg=12", "mu_deg=18"):
            with h5py.File(runs / f"{name}.h5", "r") as f:
                reach.append(north_up(f["maps/h_max"][:]) > 0.05)
        with rasterio.open(runs / "maps" / "pft_probability.tif") as src:
            assert src.crs.to_epsg() == 32632 and src.transform.c == 600_000.0
            p = src.read(1)
        want = (reach[0].astype(float) + reach[1].astype(float)) / 2
        assert (p == want).all(), f"{(p != want).sum()} probabilities differ"
        assert (p == 0.5).any(), "the two runs reach the same cells"
        print(f"OK maps: P = 0.5 on exactly the {(p == 0.5).sum()} cells one run reaches")


if __name__ == "__main__":
    main()
