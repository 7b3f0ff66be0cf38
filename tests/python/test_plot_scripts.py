#!/usr/bin/env python3
"""Checks of the plotting scripts that can fail (run by .ci/run):

    python tests/python/test_plot_scripts.py GRANFLOW_BINARY

1. plot_sweep.py on a sweep whose runs all end `settled` (the slopes sweep, coarse):
   every panel holds data, the time panel included; the file passes check_plot.py.
2. plot_sweep.py on a sweep where no run has ended: exit 1 and a message, no file.
3. plot_sweep.py on a submarine sweep: a wave-height panel; on a zipped sweep the
   zipped keys are found and the runs are not joined into one line.
4. plot_run.py on a submarine run with gauges, a dilatant run and a granular run, in
   PNG, PDF and SVG: the water, φ and gauge figures exist and pass check_plot.py, and
   the spatial panels zoom on where the material went (--whole: the whole domain).
5. plot_common.save refuses a figure with an empty panel; check_plot.py refuses a file
   not saved through it.
Needs h5py, numpy, matplotlib and pillow.
"""

import csv
import pathlib
import subprocess
import sys
import tempfile

ROOT = pathlib.Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "scripts"))

import matplotlib  # noqa: E402

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

import plot_common  # noqa: E402
import plot_sweep  # noqa: E402

PY = sys.executable


def run(*args, ok=True):
    p = subprocess.run([str(a) for a in args], capture_output=True, text=True)
    if ok and p.returncode != 0:
        raise AssertionError(f"{args} failed ({p.returncode}):\n{p.stdout}\n{p.stderr}")
    return p


def check_plot(*files):
    run(PY, ROOT / "scripts/check_plot.py", *files)


def main():
    gf = pathlib.Path(sys.argv[1]).resolve()
    tmp = pathlib.Path(tempfile.mkdtemp())

    # 1. A sweep whose runs all end settled.
    slopes = tmp / "slopes"
    run(gf, "sweep", ROOT / "scenarios/sweeps/slopes.toml", "--quiet", "--output", slopes)
    with open(slopes / "summary.csv") as f:
        statuses = {r["status"] for r in csv.DictReader(f)}
    assert statuses == {"settled"}, statuses
    p = run(PY, ROOT / "scripts/plot_sweep.py", slopes)
    assert "left out" not in p.stdout, p.stdout
    check_plot(slopes / "sweep.png")

    # 2. Nothing ended: a failure, not an empty plot.
    failed = tmp / "failed"
    failed.mkdir()
    text = (slopes / "summary.csv").read_text().replace(",settled", ",failed: NaN")
    (failed / "summary.csv").write_text(text)
    p = run(PY, ROOT / "scripts/plot_sweep.py", failed, ok=False)
    assert p.returncode == 1 and "nothing to plot" in p.stderr, (p.returncode, p.stderr)
    assert not (failed / "sweep.png").exists()

    # 3. A submarine sweep (wave height) and a zipped one.
    sub = tmp / "sub"
    run(gf, "sweep", ROOT / "scenarios/sweeps/lake_landslide_friction.toml", "--quiet",
        "--output", sub, "--set", "domain.cells=100", "--set", "time.t_end=2")
    p = run(PY, ROOT / "scripts/plot_sweep.py", sub, "--format", "svg")
    check_plot(sub / "sweep.svg")
    assert "wave" in (sub / "sweep.svg").read_text(), "no wave-height panel"
    zipped = tmp / "zip"
    zip_sweep = tmp / "zip.toml"
    zip_sweep.write_text(
        f'scenario = "{ROOT / "scenarios/collapse.toml"}"\n'
        'set = ["domain.cells=60", "time.t_end=0.3"]\n'
        "[[zip]]\ndomain.slope_deg = [16, 16, 22, 22]\nrheology.mu_2_deg = [36, 40, 36, 40]\n")
    run(gf, "sweep", zip_sweep, "--quiet", "--output", zipped)
    assert plot_sweep.zip_groups(zipped) == [{"domain.slope_deg", "rheology.mu_2_deg"}]
    p = run(PY, ROOT / "scripts/plot_sweep.py", zipped)
    check_plot(zipped / "sweep.png")

    # 4. Every model's figures, in every format.
    sub_run = tmp / "lake.h5"
    run(gf, "run", ROOT / "scenarios/lake_landslide.toml", "--quiet", "--output", sub_run,
        "--set", "domain.cells=120", "--set", "time.t_end=3")
    dil_run = tmp / "dil.h5"
    run(gf, "run", ROOT / "scenarios/dilatancy_dense.toml", "--quiet", "--output", dil_run,
        "--set", "domain.cells=120", "--set", "time.t_end=0.5")
    for fmt in ("png", "pdf", "svg"):
        run(PY, ROOT / "scripts/plot_run.py", sub_run, "--format", fmt)
        files = [tmp / f"lake{s}.{fmt}" for s in ("", "_water", "_gauges")]
        run(PY, ROOT / "scripts/plot_run.py", dil_run, "--format", fmt)
        files += [tmp / f"dil{s}.{fmt}" for s in ("", "_phi")]
        check_plot(*files)

    # Zoom: the collapse's material stays in a part of its domain.
    import h5py
    import numpy as np
    from granflow_io import Run

    col = tmp / "col.h5"
    run(gf, "run", ROOT / "scenarios/collapse.toml", "--quiet", "--output", col,
        "--set", "domain.cells=160", "--set", "time.t_end=0.5")
    r = Run(col)
    lo, hi = plot_common.extent(r.x, [r.h], r.front_threshold)
    assert hi - lo < 0.8 * (r.x[-1] - r.x[0]), (lo, hi, r.x[0], r.x[-1])
    assert lo <= r.x[np.argmax(r.h[0] > 0)] and hi >= np.nanmax(r.front_x), (lo, hi)
    with h5py.File(col) as f:
        assert "summary" in f
    run(PY, ROOT / "scripts/plot_run.py", col, "--whole", "--dpi", "80")
    check_plot(tmp / "col.png")

    # 5. Empty panels and unchecked files are refused.
    fig, (a, b) = plt.subplots(1, 2)
    a.plot([0, 1], [0, 1])
    b.set_title("nothing here")
    try:
        plot_common.save(fig, tmp / "empty.png")
        raise AssertionError("an empty panel was saved")
    except plot_common.EmptyPlot as e:
        assert "nothing here" in str(e), e
    b.plot([0, 1], [1, 0])
    fig.savefig(tmp / "unchecked.png")
    p = run(PY, ROOT / "scripts/check_plot.py", tmp / "unchecked.png", ok=False)
    assert p.returncode == 1 and "not stamped" in p.stdout, p.stdout
    plt.close("all")
    print("test_plot_scripts: all checks passed")


if __name__ == "__main__":
    main()
