"""Small helpers shared by the comparison and plotting scripts: read a granflow HDF5
file (layout: docs/output-format.md)."""

import h5py
import numpy as np

try:
    import tomllib
except ImportError:  # Python < 3.11: layer fractions fall back to equal layers
    tomllib = None


class Run:
    """The arrays and summary of one granflow output file.

    Optional datasets (`w`, `p_nh`, `static_interface`, `h_bed`) are None when the
    file has none.
    """

    def __init__(self, path):
        with h5py.File(path, "r") as f:
            self.path = str(path)
            self.x = f["grid/x"][:]
            self.b = f["grid/b"][:]
            self.h_bed = f["grid/h_bed"][:] if "grid/h_bed" in f else None
            self.t = f["snapshots/t"][:]
            self.h = f["snapshots/h"][:]
            self.u = f["snapshots/u"][:]
            snaps = f["snapshots"]
            self.w = snaps["w"][:] if "w" in snaps else None
            self.p_nh = snaps["p_nh"][:] if "p_nh" in snaps else None
            self.static_interface = (snaps["static_interface"][:]
                                     if "static_interface" in snaps else None)
            # Volume fraction of the dilatant model (Bouchut et al. 2021), None for the others.
            self.phi = f["snapshots/phi"][:] if "snapshots/phi" in f else None
            # The submarine model's water layer, None for the others.
            for name in ("h_water", "u_water", "eta", "interface"):
                setattr(self, name, snaps[name][:] if name in snaps else None)
            # Gauge series (runs with output.gauges), None without.
            if "gauges" in f:
                g = f["gauges"]
                self.gauges = {k: g[k][:] for k in ("x", "t", "eta", "h_grains")}
            else:
                self.gauges = None
            self.front_t = f["front/t"][:]
            self.front_x = f["front/x"][:]
            self.front_threshold = float(f["front"].attrs.get("threshold", 1e-3))
            self.summary = ({k: _plain(v) for k, v in f["summary"].attrs.items()}
                            if "summary" in f else {})
            self.attrs = {k: _plain(v) for k, v in f.attrs.items()}
        self.dx = self.x[1] - self.x[0] if len(self.x) > 1 else 1.0

    @property
    def wall_time(self):
        return float(self.summary["wall_time_s"])

    @property
    def layers(self):
        return self.u.shape[1]

    @property
    def scenario(self):
        """The scenario as run (dict), or {} when it cannot be parsed."""
        text = self.attrs.get("scenario_toml", "")
        if tomllib is None or not text:
            return {}
        try:
            return tomllib.loads(text)
        except tomllib.TOMLDecodeError:
            return {}

    def layer_fractions(self):
        """Thickness fraction of each layer, bottom first (model.layer_fractions)."""
        f = self.scenario.get("model", {}).get("layer_fractions")
        n = self.layers
        return np.asarray(f, dtype=float) if f else np.full(n, 1.0 / n)

    def cell(self, x):
        """Index of the cell whose centre is nearest to x."""
        return int(np.argmin(np.abs(self.x - x)))

    def snapshot(self, t):
        """Index of the snapshot nearest to time t."""
        return int(np.argmin(np.abs(self.t - t)))


def _plain(v):
    if isinstance(v, bytes):
        return v.decode()
    if isinstance(v, np.generic):
        return v.item()
    return v
