#!/usr/bin/env python3
"""xarray opens a run's snapshots with named dimensions and coordinates (run by
.ci/run, with the real xarray and h5netcdf):

    python tests/python/test_xarray_snapshots.py GRANFLOW_BINARY

For a monolayer, a multilayer non-hydrostatic, a submarine and a dilatant run,
`xarray.open_dataset(RUN.h5, engine="h5netcdf", group="snapshots")` (no phony_dims
option: an unlabelled axis is an error there) gives every field its dimensions by name
((t, x), (t, layer, x), (t, level, x_face) for p_nh), with t, x, layer (and level,
x_face) as coordinates equal to /snapshots/t, /grid/x and the layer indices, and the
values equal to h5py's. Also: selecting by coordinate works (ds.h.sel(x=…)).
Needs h5py, numpy, xarray and h5netcdf.
"""

import pathlib
import subprocess
import sys
import tempfile

import h5py
import numpy as np
import xarray as xr

ROOT = pathlib.Path(__file__).resolve().parents[2]

RUNS = {
    "mono": ("collapse.toml", ["time.t_end=0.2"]),
    "nh": ("collapse_nh.toml", ["time.t_end=0.05", "model.layers=3", "domain.cells=120"]),
    "sub": ("lake_landslide.toml", ["time.t_end=0.5"]),
    "dil": ("dilatancy_dense.toml", ["time.t_end=0.1"]),
}


def main():
    gf = pathlib.Path(sys.argv[1]).resolve()
    tmp = pathlib.Path(tempfile.mkdtemp())
    for name, (scenario, sets) in RUNS.items():
        h5 = tmp / f"{name}.h5"
        args = [gf, "run", ROOT / "scenarios" / scenario, "--quiet", "--output", h5]
        for s in sets:
            args += ["--set", s]
        subprocess.run([str(a) for a in args], check=True)
        ds = xr.open_dataset(h5, engine="h5netcdf", group="snapshots")
        with h5py.File(h5) as f:
            snaps = f["snapshots"]
            nl = int(f.attrs["layers"])
            assert np.array_equal(ds["t"].values, snaps["t"][:]), name
            assert np.array_equal(ds["x"].values, f["grid/x"][:]), name
            assert np.array_equal(ds["layer"].values, np.arange(nl)), name
            for var in ("t", "x", "layer"):
                assert var in ds.coords, (name, var, list(ds.coords))
            for field, da in ds.data_vars.items():
                want = {2: ("t", "x"), 3: ("t", "layer", "x")}[da.ndim]
                if field == "p_nh":
                    want = ("t", "level", "x_face")
                assert da.dims == want, (name, field, da.dims)
                assert np.array_equal(da.values, snaps[field][:], equal_nan=True), (name, field)
            assert set(ds.data_vars) >= {"h", "u"}, (name, list(ds.data_vars))
            if name == "nh":
                assert "p_nh" in ds.data_vars and ds.sizes["level"] == nl + 1
                assert ds.sizes["x_face"] == ds.sizes["x"] + 1
                faces = ds["x_face"].values
                assert np.allclose(0.5 * (faces[:-1] + faces[1:]), ds["x"].values)
            if name == "sub":
                assert {"eta", "h_water"} <= set(ds.data_vars)
            if name == "dil":
                assert "phi" in ds.data_vars
            mid = float(ds["x"].values[len(ds["x"]) // 2])
            col = ds["h"].sel(x=mid)
            assert col.dims == ("t",) and np.array_equal(
                col.values, snaps["h"][:, len(ds["x"]) // 2]), name
        ds.close()
        print(f"ok {name}: {dict(ds.sizes)}")
    print("test_xarray_snapshots: all checks passed")


if __name__ == "__main__":
    main()
