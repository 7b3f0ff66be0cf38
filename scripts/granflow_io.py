"""Small helpers shared by the comparison scripts: read a granflow HDF5 file."""

import h5py
import numpy as np


class Run:
    """The arrays and summary of one granflow output file."""

    def __init__(self, path):
        with h5py.File(path, "r") as f:
            self.path = str(path)
            self.x = f["grid/x"][:]
            self.b = f["grid/b"][:]
            self.t = f["snapshots/t"][:]
            self.h = f["snapshots/h"][:]
            self.u = f["snapshots/u"][:]
            # Volume fraction of the dilatant model (seed 002), None for the others.
            self.phi = f["snapshots/phi"][:] if "snapshots/phi" in f else None
            self.front_t = f["front/t"][:]
            self.front_x = f["front/x"][:]
            self.summary = {k: _plain(v) for k, v in f["summary"].attrs.items()}
            self.attrs = {k: _plain(v) for k, v in f.attrs.items()}
        self.dx = self.x[1] - self.x[0]

    @property
    def wall_time(self):
        return float(self.summary["wall_time_s"])


def _plain(v):
    if isinstance(v, bytes):
        return v.decode()
    if isinstance(v, np.generic):
        return v.item()
    return v
