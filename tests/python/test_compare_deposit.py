#!/usr/bin/env python3
"""Checks of scripts/compare_deposit.py that can fail (run by .ci/run):

    python tests/python/test_compare_deposit.py GRANFLOW_BINARY

1. A run compared with its own final snapshot written as a CSV: all errors are 0.
2. The synthetic deposit of examples/lab in the along-slope and the horizontal frame
   (the same deposit): the same errors, to the rounding of the CSV (1e-6 m).
3. x,z data on a flat bed give the same errors as the x,h data.
4. A shifted copy of the run's deposit: the front error is the shift.
5. Bad input (header, frame) exits with code 2 and a message.
6. --sweep with a mapping file: one row per run in deposit_comparison.csv.
Needs h5py, numpy and matplotlib.
"""

import csv
import pathlib
import subprocess
import sys
import tempfile

ROOT = pathlib.Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "scripts"))

import numpy as np  # noqa: E402

from compare_deposit import compare  # noqa: E402
from granflow_io import Run  # noqa: E402

SCRIPT = ROOT / "scripts/compare_deposit.py"
LAB = ROOT / "examples/lab"


def write_csv(path, header, x, v):
    with open(path, "w") as f:
        f.write(header + "\n")
        for a, b in zip(x, v):
            f.write(f"{float(a)!r},{float(b)!r}\n")


def main():
    granflow = sys.argv[1]
    tmp = pathlib.Path(tempfile.mkdtemp())
    h5 = tmp / "c.h5"
    subprocess.run([granflow, "run", str(ROOT / "scenarios/collapse.toml"), "-q", "-o", str(h5),
                    "--set", "domain.cells=160"], check=True)
    run = Run(h5)

    own = tmp / "own.csv"
    write_csv(own, "x,h", run.x, run.h[-1])
    r = compare(run, own)
    assert r["L1"] == 0 and r["L2"] == 0, r
    assert r["front_error"] == 0 and r["h_max_error"] == 0, r

    a = compare(run, LAB / "synthetic_deposit_along_slope.csv")
    b = compare(run, LAB / "synthetic_deposit_horizontal.csv", frame="horizontal")
    c = compare(run, LAB / "synthetic_surface_along_slope.csv")
    for key in ("L1", "L2", "h_max_error"):
        assert abs(a[key] - b[key]) < 2e-6, (key, a[key], b[key])
        assert abs(a[key] - c[key]) < 1e-12, (key, a[key], c[key])
    assert abs(a["front_error"] - b["front_error"]) < 1e-5, (a, b)
    assert a["L1"] > 1e-3, "the synthetic deposit differs from the run"

    shifted = tmp / "shifted.csv"
    write_csv(shifted, "x,h", run.x - 0.1, run.h[-1])
    s = compare(run, shifted)
    assert abs(s["front_error"] - 0.1) < 1e-9, s["front_error"]

    bad = tmp / "bad.csv"
    bad.write_text("pos,thickness\n0,1\n1,2\n")
    for args in ([str(h5), str(bad)],
                 [str(h5), str(LAB / "synthetic_deposit_along_slope.csv"), "--frame", "up"],
                 [str(h5), str(LAB / "synthetic_surface_along_slope.csv"),
                  "--frame", "horizontal"]):
        p = subprocess.run([sys.executable, str(SCRIPT), *args], capture_output=True, text=True)
        assert p.returncode == 2, (args, p.returncode, p.stderr)
        assert "error" in p.stderr, p.stderr

    sweep = tmp / "s.toml"
    sweep.write_text(f'scenario = "{ROOT / "scenarios/collapse.toml"}"\n'
                     'set = ["domain.cells=160"]\n[axes]\ndomain.slope_deg = [19, 22]\n')
    subprocess.run([granflow, "sweep", str(sweep), "-q", "-o", str(tmp / "sw")], check=True)
    mapping = tmp / "map.csv"
    mapping.write_text("run,lab\nslope_deg=19,own.csv\nslope_deg=22,own.csv\n")
    subprocess.run([sys.executable, str(SCRIPT), "--sweep", str(tmp / "sw"), "--map",
                    str(mapping), "--plot-dir", str(tmp / "plots")], check=True,
                   capture_output=True)
    rows = list(csv.DictReader(open(tmp / "sw/deposit_comparison.csv")))
    assert [r["run"] for r in rows] == ["slope_deg=19", "slope_deg=22"], rows
    # own.csv is the 22° deposit at 160 cells: exact for that run, not for 19°.
    assert float(rows[1]["L1"]) == 0 and float(rows[0]["L1"]) > 1e-3, rows
    assert (tmp / "plots/slope_deg=22.png").is_file()
    print("OK compare_deposit: self 0, frames agree "
          f"(L1 {a['L1']:.4e} vs {b['L1']:.4e} m²), shift, bad input, sweep")
    return 0


if __name__ == "__main__":
    np.seterr(all="raise")
    sys.exit(main())
