"""Differences between the maps of runs and a reference run (the last argument):
largest |Δ pft|, cells where pft differs by more than 0.1 m, largest |Δ pfv|, the
volume of the deposit map and the final mass.

    python maps_diff.py RUN.h5 [RUN2.h5 …] REFERENCE.h5
"""
import sys

import h5py
import numpy as np

*runs, ref = sys.argv[1:]
r = h5py.File(ref, "r")
cell = abs(r["snapshots/x"][1] - r["snapshots/x"][0]) * abs(r["snapshots/y"][1] - r["snapshots/y"][0])
for name in runs + [ref]:
    a = h5py.File(name, "r")
    dh = np.abs(a["maps/h_max"][()] - r["maps/h_max"][()])
    dv = np.abs(a["maps/speed_max"][()] - r["maps/speed_max"][()])
    print(f"{name}: steps {a['summary'].attrs['steps']}, end {a['summary'].attrs['t_end']:.1f} s, "
          f"max |dpft| {np.nanmax(dh):.3f} m, cells |dpft| > 0.1 m {(dh > 0.1).sum()}, "
          f"max |dpfv| {np.nanmax(dv):.3f} m/s, deposit {np.nansum(a['maps/deposit'][()]) * cell:.5g} m3, "
          f"mass {a['diagnostics/mass'][-1]:.10g} (t=0: {a['diagnostics/mass'][0]:.10g})")
