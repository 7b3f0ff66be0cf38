#!/usr/bin/env python3
"""Checks of granflow's GIS files against real readers (run by .ci/run):

    python tests/python/test_gis_rasterio.py GIS_ROUNDTRIP_BINARY

GIS_ROUNDTRIP_BINARY is the example `target/release/examples/gis_roundtrip`.

1. Files written by granflow (ESRI ASCII grid + .prj, GeoTIFF Float64 uncompressed and
   LZW, Float32 Deflate, a geographic Float32 with NaN nodata) opened with rasterio
   (GDAL inside the wheel): same size, origin, cell size, EPSG code, nodata and values,
   bit for bit.
2. The CF NetCDF time series opened with xarray (scipy and netCDF4 engines): dimensions,
   coordinates (cell centres), CF attributes, the grid mapping, times and values (NaN on
   the grid's nodata cells); and by rasterio through GDAL's netCDF driver when the wheel
   has it (origin, cell size, CRS).
3. GeoTIFFs written by rasterio (Deflate/LZW/PackBits/uncompressed, striped and tiled,
   predictor 2, Float32/Float64/Int16/UInt16/UInt8, nodata, PixelIsPoint) read by
   granflow: the same grid, EPSG code, nodata and values.
Needs rasterio, xarray, scipy and numpy (netCDF4 too, for its engine, if installed).
"""

import json
import math
import pathlib
import subprocess
import sys
import tempfile

import numpy as np
import rasterio
from rasterio.transform import from_origin
import xarray as xr


def values(desc):
    return np.array([math.nan if v is None else v for v in desc["values"]],
                    dtype=np.float64).reshape(desc["ny"], desc["nx"])


def same(a, b):
    a = np.asarray(a, dtype=np.float64)
    b = np.asarray(b, dtype=np.float64)
    assert a.shape == b.shape, (a.shape, b.shape)
    both_nan = np.isnan(a) & np.isnan(b)
    ok = both_nan | (a == b)
    assert ok.all(), f"{(~ok).sum()} values differ, first at {np.argwhere(~ok)[0]}"


def nodata_of(desc):
    nd = desc["nodata"]
    return math.nan if nd == "nan" else nd


def check_rasterio_reads(path, desc):
    # GDAL reads ASCII grids as Float32 unless told otherwise.
    options = {"DATATYPE": "Float64"} if path.suffix == ".asc" else {}
    with rasterio.open(path, **options) as src:
        assert (src.width, src.height) == (desc["nx"], desc["ny"]), path
        t = src.transform
        assert (t.a, t.b, t.c) == (desc["cell_size"], 0.0, desc["x_left"]), (path, t)
        assert (t.d, t.e, t.f) == (0.0, -desc["cell_size"], desc["y_top"]), (path, t)
        assert src.crs is not None and src.crs.to_epsg() == desc["epsg"], (path, src.crs)
        nd = nodata_of(desc)
        if nd is None:
            assert src.nodata is None, (path, src.nodata)
        elif math.isnan(nd):
            assert math.isnan(src.nodata), (path, src.nodata)
        else:
            assert src.nodata == nd, (path, src.nodata)
        try:
            same(src.read(1).astype(np.float64), values(desc))
        except AssertionError as e:
            raise AssertionError(f"{path.name}: {e}") from None
    print(f"ok: rasterio reads {path.name}")


def check_netcdf(path, exp):
    grid = exp["grid"]
    d, x0, y0 = grid["cell_size"], grid["x_left"], grid["y_top"]
    xs = x0 + (np.arange(grid["nx"]) + 0.5) * d
    ys = y0 - (np.arange(grid["ny"]) + 0.5) * d
    engines = ["scipy"]
    try:
        import netCDF4  # noqa: F401
        engines.append("netcdf4")
    except ImportError:
        print("skip: no netCDF4 module, xarray's netcdf4 engine not checked")
    for engine in engines:
        with xr.open_dataset(path, engine=engine) as ds:
            assert ds.attrs["Conventions"] == "CF-1.8", ds.attrs
            assert dict(ds.sizes) == {"time": 3, "y": grid["ny"], "x": grid["nx"]}, ds.sizes
            assert ds["h"].dims == ("time", "y", "x")
            np.testing.assert_array_equal(ds["x"].values, xs)
            np.testing.assert_array_equal(ds["y"].values, ys)
            assert ds["x"].attrs["axis"] == "X" and ds["y"].attrs["axis"] == "Y"
            assert ds["x"].attrs["standard_name"] == "projection_x_coordinate"
            assert ds["y"].attrs["units"] == "m"
            assert ds["time"].attrs["axis"] == "T" and ds["time"].attrs["units"] == "s"
            assert ds["h"].attrs["units"] == "m" and ds["h"].attrs["grid_mapping"] == "crs"
            assert ds["speed"].attrs["long_name"] == "depth-averaged speed"
            assert ds["crs"].attrs["crs_wkt"] == exp["wkt"]
            assert ds["crs"].attrs["spatial_ref"] == exp["wkt"]
            np.testing.assert_array_equal(ds["time"].values,
                                          [f["time"] for f in exp["frames"]])
            for k, frame in enumerate(exp["frames"]):
                for name in ["h", "speed"]:
                    want = np.array([math.nan if v is None else v for v in frame[name]])
                    same(ds[name].values[k].astype(np.float64),
                         want.reshape(grid["ny"], grid["nx"]))
        print(f"ok: xarray ({engine}) reads {path.name}")
    try:
        src = rasterio.open(f"netcdf:{path}:h")
    except rasterio.errors.RasterioIOError as e:
        print(f"skip: this rasterio has no netCDF driver ({e})")
        return
    with src:
        t = src.transform
        assert (src.width, src.height, src.count) == (grid["nx"], grid["ny"], 3)
        assert math.isclose(t.a, d) and math.isclose(t.e, -d), t
        assert math.isclose(t.c, x0) and math.isclose(t.f, y0), t
        assert src.crs is not None and src.crs.to_epsg() == grid["epsg"], src.crs
    print(f"ok: rasterio (GDAL netCDF driver) reads {path.name}")


def dump(binary, path):
    out = path.with_suffix(".json")
    p = subprocess.run([binary, "dump", str(path), str(out)], capture_output=True, text=True)
    assert p.returncode == 0, (path, p.stderr)
    return json.loads(out.read_text())


def check_granflow_reads(binary, tmp):
    rng = np.random.default_rng(12345)
    cases = [
        # name, dtype, nodata, creation options, tags
        ("f32_deflate_tiled", "float32", -9999.0,
         dict(compress="deflate", tiled=True, blockxsize=16, blockysize=16), {}),
        ("f32_lzw", "float32", -3.4028234663852886e38, dict(compress="lzw"), {}),
        ("f32_nan", "float32", math.nan, dict(compress="deflate", zlevel=9), {}),
        ("f64_deflate", "float64", -9999.0, dict(compress="deflate"), {}),
        ("f32_deflate_pred3", "float32", -9999.0, dict(compress="deflate", predictor=3), {}),
        ("i16_packbits", "int16", -32768, dict(compress="packbits"), {}),
        ("u16_lzw_pred2", "uint16", 0, dict(compress="lzw", predictor=2), {}),
        ("u8_none", "uint8", 255, dict(), {}),
        ("f32_point", "float32", -9999.0, dict(compress="deflate"), {"AREA_OR_POINT": "Point"}),
    ]
    transform = from_origin(2_600_000.5, 1_200_100.25, 2.0, 2.0)
    for name, dtype, nodata, options, tags in cases:
        ny, nx = 45, 61
        if dtype.startswith("float"):
            data = (rng.standard_normal((ny, nx)) * 100 + 1500).astype(dtype)
        else:
            info = np.iinfo(dtype)
            data = rng.integers(info.min, info.max, (ny, nx), endpoint=False).astype(dtype)
        data[3, 4] = nodata
        data[-1, -1] = nodata
        path = tmp / f"rio_{name}.tif"
        with rasterio.open(path, "w", driver="GTiff", width=nx, height=ny, count=1,
                           dtype=dtype, crs="EPSG:2056", transform=transform,
                           nodata=nodata, **options) as dst:
            dst.write(data, 1)
            if tags:
                dst.update_tags(**tags)
        with rasterio.open(path) as src:
            if tags:
                # GDAL stored PixelIsPoint (its tiepoint is the centre of pixel (0, 0)).
                assert src.tags().get("AREA_OR_POINT") == "Point", src.tags()
            want_transform = src.transform
            want_nodata = src.nodata
            want = src.read(1).astype(np.float64)
        got = dump(binary, path)
        assert (got["nx"], got["ny"]) == (nx, ny), name
        assert got["cell_size"] == want_transform.a, (name, got["cell_size"])
        assert (got["x_left"], got["y_top"]) == (want_transform.c, want_transform.f), \
            (name, got["x_left"], got["y_top"], want_transform)
        assert got["epsg"] == 2056, (name, got["epsg"])
        gnd = nodata_of(got)
        if math.isnan(want_nodata):
            assert math.isnan(gnd), (name, gnd)
        else:
            assert gnd == want_nodata, (name, gnd, want_nodata)
        same(values(got), want)
        print(f"ok: granflow reads rasterio's {path.name}")


def main():
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    binary = sys.argv[1]
    with tempfile.TemporaryDirectory() as tmp:
        tmp = pathlib.Path(tmp)
        out = tmp / "granflow"
        subprocess.run([binary, "write", str(out)], check=True)
        expected = json.loads((out / "expected.json").read_text())
        for name, desc in expected.items():
            if name.endswith((".tif", ".asc")):
                check_rasterio_reads(out / name, desc)
        check_netcdf(out / "series.nc", expected["series.nc"])
        check_granflow_reads(binary, tmp)
        # A granflow .asc read back by granflow after rasterio rewrote it as GeoTIFF.
        src_asc = out / "dem.asc"
        with rasterio.open(src_asc, DATATYPE="Float64") as src:
            profile = src.profile
            profile.update(driver="GTiff", compress="lzw")
            with rasterio.open(tmp / "asc_to.tif", "w", **profile) as dst:
                dst.write(src.read(1), 1)
        got = dump(binary, tmp / "asc_to.tif")
        want = expected["dem.asc"]
        for key in ["nx", "ny", "x_left", "y_top", "cell_size", "nodata", "epsg"]:
            assert got[key] == want[key], (key, got[key], want[key])
        same(values(got), values(want))
        print("ok: granflow .asc -> rasterio GeoTIFF -> granflow")
    print("all GIS reader checks passed")


if __name__ == "__main__":
    main()
