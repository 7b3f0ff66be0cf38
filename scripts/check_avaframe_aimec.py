#!/usr/bin/env python3
"""Check that AvaFrame's AIMEC reads a granflow export as it is (a local check; needs
AvaFrame installed in the Python that runs it).

    python scripts/check_avaframe_aimec.py GRANFLOW_BINARY [--keep DIR]

Builds an AvaFrame avalanche directory from the bundled synthetic example
(scenarios/data: the DEM as Inputs/synthetic_dem.asc, the thalweg as
Inputs/LINES/path_aimec.shp), runs scenarios/dem_release.toml with the same line as
output.path, exports it with `granflow export --layout avaframe --format asc` into the
avalanche directory, and runs AvaFrame's ana3AIMEC (its default settings: ppr > 1 kPa
defines the runout, a 600 m wide domain) on it. It then checks that AIMEC found the run
with its three peak files and compares AIMEC's numbers with granflow's /summary and
/path: the runout s along the line (to within two cells: AIMEC interpolates the maps
onto its own s-l grid) and the largest pft, pfv and ppr (kPa) along the path (to within
5 %, for the same reason). Exits 1 naming what differs.
"""

import argparse
import logging
import pathlib
import shutil
import subprocess
import sys
import tempfile

import h5py
import numpy as np
import shapefile

ROOT = pathlib.Path(__file__).resolve().parents[1]
DATA = ROOT / "scenarios" / "data"


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("granflow", type=pathlib.Path)
    ap.add_argument("--keep", type=pathlib.Path, help="work directory to use and keep")
    a = ap.parse_args()
    from avaframe.ana3AIMEC import ana3AIMEC
    from avaframe.in3Utils import cfgUtils

    logging.basicConfig(level=logging.WARNING)
    work = a.keep or pathlib.Path(tempfile.mkdtemp())
    ava = work / "avaSynthetic"
    if ava.exists():
        shutil.rmtree(ava)
    (ava / "Inputs" / "LINES").mkdir(parents=True)
    shutil.copy(DATA / "synthetic_dem.asc", ava / "Inputs")
    shutil.copy(DATA / "synthetic_dem.prj", ava / "Inputs")
    x0, y0 = 2600000.0, 1200000.0
    line = [[x0 + 10.0, y0 + 150.0], [x0 + 590.0, y0 + 150.0]]
    with shapefile.Writer(str(ava / "Inputs" / "LINES" / "path_aimec"),
                          shapeType=shapefile.POLYLINE) as w:
        w.field("name", "C")
        w.line([line])
        w.record("path")
    shutil.copy(DATA / "synthetic_dem.prj", ava / "Inputs" / "LINES" / "path_aimec.prj")

    h5 = work / "synthetic.h5"
    path = str(DATA / "synthetic_path.geojson")
    subprocess.run([str(a.granflow), "run", str(ROOT / "scenarios" / "dem_release.toml"),
                    "--set", f'output.path={{ line = "{path}", field = "ppr", threshold = 1000.0, width = 600.0 }}',
                    "--set", "time.stop_when_settled=true", "--set", "time.settle_fraction=0.01",
                    "--output", str(h5), "--quiet", "--force"], check=True)
    subprocess.run([str(a.granflow), "export", str(h5), "--layout", "avaframe", "--format", "asc",
                    "--output", str(ava), "--force"], check=True)

    cfg = cfgUtils.getModuleConfig(ana3AIMEC, ava)
    cfg["FLAGS"]["flagMass"] = "False"
    _, res, _, _, _ = ana3AIMEC.fullAimecAnalysis(ava, cfg)
    problems = []
    if len(res) != 1:
        problems.append(f"AIMEC found {len(res)} simulations, expected 1")
    row = res.iloc[0]
    with h5py.File(h5) as f:
        s = f["summary"].attrs
        d = float(f.attrs["dx"])
        ours = {"sRunout": float(s["path_runout_s"]),
                "maxpftCrossMax": float(s["path_max_pft"]),
                "maxpfvCrossMax": float(s["path_max_pfv"]),
                "maxpprCrossMax": float(s["path_max_ppr"]) / 1000.0}
    print(f"{'':16} {'AIMEC':>12} {'granflow':>12}")
    for key, value in ours.items():
        theirs = float(row[key])
        print(f"{key:16} {theirs:12.4f} {value:12.4f}")
        tol = 2 * d if key == "sRunout" else 0.05 * abs(value)
        if not abs(theirs - value) <= tol:
            problems.append(f"{key}: AIMEC {theirs}, granflow {value} (tolerance {tol})")
    for p in problems:
        print(f"check_avaframe_aimec: {p}", file=sys.stderr)
    if problems:
        return 1
    print("check_avaframe_aimec: AIMEC read the export; its runout and maxima agree")
    return 0


if __name__ == "__main__":
    sys.exit(main())
