#!/usr/bin/env python3
"""Checks of scripts/compare_gauges.py that can fail (run by .ci/run):

    python tests/python/test_compare_gauges.py GRANFLOW_BINARY

1. A run compared with its own gauges and slide surfaces written as lab CSVs (full
   precision): every error is 0 and the arrival times agree exactly.
2. The same gauges recorded 0.75 s later: the arrival difference is −0.75 s (run −
   lab) and the peak error 0.
3. The shipped SYNTHETIC data of examples/lab_gauges against the scenario as shipped:
   small, non-zero errors (the data come from a finer mesh).
4. Bad input exits with code 2 and a message: wrong header, a gauge the run does not
   have, a slide time without a snapshot, a run without gauges, an empty directory.
Needs h5py, numpy and matplotlib.
"""

import pathlib
import subprocess
import sys
import tempfile

ROOT = pathlib.Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "scripts"))

import h5py  # noqa: E402
import numpy as np  # noqa: E402

from compare_gauges import compare  # noqa: E402

SCRIPT = ROOT / "scripts/compare_gauges.py"
SCENARIO = ROOT / "scenarios/lake_landslide.toml"
GAUGES = [4.5, 6.0, 8.0]


def write(path, header, a, b):
    with open(path, "w") as f:
        f.write("# test data\n" + header + "\n")
        for u, v in zip(a, b):
            f.write(f"{float(u)!r},{float(v)!r}\n")


def run(granflow, out, *sets, scenario=SCENARIO):
    args = [granflow, "run", str(scenario), "--quiet", "--output", str(out),
            "--set", "time.t_end=6"]
    for s in sets:
        args += ["--set", s]
    subprocess.run(args, check=True)


def script(*args):
    return subprocess.run([sys.executable, str(SCRIPT), *map(str, args)],
                          capture_output=True, text=True)


def expect_exit_2(h5, lab, needle):
    p = script(h5, lab, "--no-plot")
    assert p.returncode == 2, (p.returncode, p.stdout, p.stderr)
    assert needle in p.stderr, (needle, p.stderr)
    assert "Traceback" not in p.stderr, p.stderr


def main():
    granflow = sys.argv[1]
    with tempfile.TemporaryDirectory() as tmp:
        tmp = pathlib.Path(tmp)
        h5 = tmp / "lake.h5"
        run(granflow, h5)  # the scenario's gauges: 4.5, 6 and 8 m every 0.05 s
        with h5py.File(h5, "r") as f:
            t, eta = f["gauges/t"][:], f["gauges/eta"][:]
            x, ts, top = f["grid/x"][:], f["snapshots/t"][:], f["snapshots/interface"][:]

        # 1. Its own data: zero error.
        own = tmp / "own"
        own.mkdir()
        for k, xg in enumerate(GAUGES):
            write(own / f"gauge_{xg:g}.csv", "t,eta", t, eta[:, k])
        write(own / "slide_t2.csv", "x,y", x, top[int(np.argmin(abs(ts - 2)))])
        g, s = compare(h5, own)
        assert len(g) == 3 and len(s) == 1
        for r in g:
            assert r["rms"] == 0 and r["peak_err"] == 0 and r["arrival_diff"] == 0, r
            assert r["peak_run"] > 0.01 and np.isfinite(r["arrival_run"]), r
        assert s[0]["rms"] == 0 and s[0]["max_err"] == 0, s
        p = script(h5, own, "--plot", tmp / "own.png")
        assert p.returncode == 0, p.stderr
        assert (tmp / "own.png").stat().st_size > 0

        # 2. Recorded 0.75 s later (the lab clock started 0.75 s early).
        late = tmp / "late"
        late.mkdir()
        for k, xg in enumerate(GAUGES):
            write(late / f"gauge_{xg:g}.csv", "t,eta", t + 0.75, eta[:, k])
        for threshold in (1e-3, 5e-3):
            for r in compare(h5, late, threshold)[0]:
                assert abs(r["arrival_diff"] + 0.75) < 1e-12, r
                assert r["peak_err"] == 0 and r["rms"] > 1e-3, r

        # 3. The shipped synthetic data: small but not zero errors.
        g, s = compare(h5, ROOT / "examples/lab_gauges")
        for r in g:
            assert 1e-5 < r["rms"] < 5e-3 and abs(r["arrival_diff"]) < 0.2, r
        for r in s:
            assert 1e-5 < r["rms"] < 2e-2, r
        p = script(h5, ROOT / "examples/lab_gauges", "--plot", tmp / "synthetic.png")
        assert p.returncode == 0 and "rms" in p.stdout, p.stderr

        # 4. Bad input: exit code 2 with a message.
        bad = tmp / "bad"
        bad.mkdir()
        expect_exit_2(h5, bad, "no gauge_<x>.csv")
        (bad / "gauge_6.csv").write_text("time,eta\n0,0.4\n1,0.4\n")
        expect_exit_2(h5, bad, "header must be 't,eta'")
        (bad / "gauge_6.csv").write_text("t,eta\n0,0.4\n1,nan\n")
        expect_exit_2(h5, bad, "not a finite number")
        (bad / "gauge_6.csv").unlink()
        write(bad / "gauge_7.csv", "t,eta", t, eta[:, 0])
        expect_exit_2(h5, bad, "no gauge at x = 7")
        (bad / "gauge_7.csv").unlink()
        write(bad / "slide_t2.2.csv", "x,y", x, top[0])
        expect_exit_2(h5, bad, "no snapshot at t = 2.2")
        plain = tmp / "plain.h5"
        run(granflow, plain, scenario=ROOT / "scenarios/collapse.toml")
        expect_exit_2(plain, own, "no gauges")
        expect_exit_2(tmp / "missing.h5", own, "missing.h5")
        p = script(h5, own, "--threshold", "-1", "--no-plot")
        assert p.returncode == 2 and "--threshold" in p.stderr, p.stderr
    print("compare_gauges: all checks passed")


if __name__ == "__main__":
    main()
