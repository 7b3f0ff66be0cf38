//! Raster (2-D) runs from the outside: the scenario keys of a raster domain and their
//! errors (each names its key and line), raster profiles, the HDF5 layout read back
//! with h5py (shapes (nt, ny, nx), maps, the volume diagnostic), the XDMF file beside
//! it, the map plots, and the independence of the results from `--threads`.

use std::fs;
use std::path::{Path, PathBuf};
use std::process::Command;

use assert_cmd::prelude::*;
use granflow::scenario::load_str;

use crate::common::{assert_success, fails_at, load_in, python_with_h5py};

fn granflow() -> Command {
    Command::cargo_bin("granflow").unwrap()
}

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// A small raster scenario: a cylinder of 0.3 m on a flat bed in a box of walls.
const RADIAL: &str = r#"[domain]
x_min = -1.0
x_max = 1.0
y_min = -0.5
y_max = 0.5
cells = [24, 12]
coordinates = "cartesian"

[rheology]
law = "coulomb"
mu_deg = 27.0

[initial]
h = "if(x^2 + y^2 < 0.2^2, 0.3, 0)"

[time]
t_end = 0.4

[output]
every = 0.1
"#;

#[test]
fn a_raster_domain_loads_with_its_centres_row_major() {
    let dir = tempfile::tempdir().unwrap();
    let scn = load_in(RADIAL, dir.path()).unwrap();
    let plane = scn.domain.plane.as_ref().unwrap();
    assert_eq!((scn.domain.cells, plane.ny), (24, 12));
    assert_eq!(scn.domain.cell_count(), 288);
    assert_eq!(scn.sampled.h.len(), 288);
    // Cell (i, j) = (12, 6) is centred at (1/24, 1/24), inside the cylinder; the
    // corner cell is not.
    assert_eq!(scn.sampled.h[6 * 24 + 12], 0.3);
    assert_eq!(scn.sampled.h[0], 0.0);
}

#[test]
fn raster_keys_are_refused_with_their_key_and_line() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let with = |from: &str, to: &str| {
        assert!(RADIAL.contains(from), "{from}");
        RADIAL.replacen(from, to, 1)
    };
    // cells = [nx, ny]: wrong length, zero, a non-integer.
    let m = fails_at(&with("cells = [24, 12]", "cells = [24]"), d, "domain.cells");
    assert!(m.contains("[nx, ny]"), "{m}");
    let m = fails_at(
        &with("cells = [24, 12]", "cells = [24, 12, 3]"),
        d,
        "domain.cells",
    );
    assert!(m.contains("got 3 values"), "{m}");
    let m = fails_at(
        &with("cells = [24, 12]", "cells = [24, 0]"),
        d,
        "domain.cells",
    );
    assert!(m.contains("ny must be at least 1"), "{m}");
    fails_at(
        &with("cells = [24, 12]", "cells = [24, 1.5]"),
        d,
        "domain.cells",
    );
    let m = fails_at(&with("cells = [24, 12]", "cells = 24"), d, "domain.cells");
    assert!(m.contains("[nx, ny]"), "{m}");
    // y_min ≥ y_max, a missing y_max.
    let m = fails_at(&with("y_max = 0.5", "y_max = -0.5"), d, "domain.y_max");
    assert!(m.contains("greater than domain.y_min"), "{m}");
    fails_at(&with("y_max = 0.5\n", ""), d, "domain.y_max");
    // An unknown side, a side given twice, a side of a raster on a line.
    let m = fails_at(
        &format!("{RADIAL}\n[boundary]\nup = \"wall\"\n"),
        d,
        "boundary.up",
    );
    assert!(m.contains("unknown key 'up'"), "{m}");
    fails_at(
        &format!("{RADIAL}\n[boundary]\nleft = \"wall\"\nwest = \"outflow\"\n"),
        d,
        "boundary.west",
    );
    fails_at(
        &format!("{RADIAL}\n[boundary]\nsouth = \"open\"\n"),
        d,
        "boundary.south",
    );
    let line = "[domain]\nx_min = 0.0\nx_max = 1.0\ncells = 10\n[rheology]\nlaw = \"coulomb\"\nmu = 0.5\n[initial]\nh = 0.1\n[time]\nt_end = 1.0\n";
    fails_at(
        &format!("{line}[boundary]\nnorth = \"wall\"\n"),
        d,
        "boundary.north",
    );
    // y and initial.v need a raster domain.
    let m = fails_at(
        &line.replace("h = 0.1", "h = \"0.1 + 0*y\""),
        d,
        "initial.h",
    );
    assert!(m.contains("depends on y"), "{m}");
    fails_at(&line.replace("h = 0.1", "h = 0.1\nv = 1.0"), d, "initial.v");
    // The 1-D models' keys on a raster (the multilayer model runs there: its keys
    // are checked in multilayer_2d_scenario).
    fails_at(
        &format!("{RADIAL}\n[model]\npressure = \"nonhydrostatic\"\n"),
        d,
        "model.pressure",
    );
    fails_at(&with("h = \"", "w = 0.1\nh = \""), d, "initial.w");
    // Gauges are points inside the domain.
    fails_at(
        &with("every = 0.1", "every = 0.1\ngauges = [0.5]"),
        d,
        "output.gauges",
    );
    fails_at(
        &with("every = 0.1", "every = 0.1\ngauges = [[0.5, 0.9]]"),
        d,
        "output.gauges",
    );
}

#[test]
fn cells_from_the_command_line_name_the_override() {
    let dir = tempfile::tempdir().unwrap();
    let e = load_str(RADIAL, dir.path(), &["domain.cells=[3, 0]".into()]).unwrap_err();
    assert_eq!(e.key(), Some("domain.cells"));
    assert!(e.is_from_set(), "{e}");
    let scn = load_str(RADIAL, dir.path(), &["domain.cells=[8,4]".into()]).unwrap();
    assert_eq!(scn.domain.cell_count(), 32);
}

/// An ESRI ASCII grid of `ncols` × `nrows` cells of 0.1 m, lower-left corner (0, 0),
/// with value(col, row_from_top).
fn write_asc(path: &Path, ncols: usize, nrows: usize, value: impl Fn(usize, usize) -> f64) {
    let mut text = format!(
        "ncols {ncols}\nnrows {nrows}\nxllcorner 0.0\nyllcorner 0.0\ncellsize 0.1\nNODATA_value -9999\n"
    );
    for row in 0..nrows {
        let line: Vec<String> = (0..ncols).map(|c| format!("{}", value(c, row))).collect();
        text.push_str(&line.join(" "));
        text.push('\n');
    }
    fs::write(path, text).unwrap();
}

const RASTER_BED: &str = r#"[domain]
coordinates = "cartesian"

[bed]
b = { raster = "dem.asc" }

[rheology]
law = "coulomb"
mu = 0.5

[initial]
h = { raster = "h.asc" }

[time]
t_end = 0.1
"#;

#[test]
fn a_raster_bed_gives_its_grid_and_its_values_north_up() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // 4 columns, 3 rows: the bed is 10·row_from_top + col.
    write_asc(&d.join("dem.asc"), 4, 3, |c, r| (10 * r + c) as f64);
    write_asc(
        &d.join("h.asc"),
        4,
        3,
        |c, _| if c == 0 { 0.2 } else { 0.0 },
    );
    let scn = load_in(RASTER_BED, d).unwrap();
    let plane = scn.domain.plane.as_ref().unwrap();
    assert_eq!((scn.domain.cells, plane.ny), (4, 3));
    assert_eq!((scn.domain.x_min, scn.domain.x_max), (0.0, 0.4));
    assert!((plane.y_max - 0.3).abs() < 1e-12);
    // Row j = 0 of the domain (south) is the raster's bottom row (row 2 from the top).
    assert_eq!(&scn.sampled.b[..4], &[20.0, 21.0, 22.0, 23.0]);
    assert_eq!(&scn.sampled.b[8..], &[0.0, 1.0, 2.0, 3.0]);
    assert_eq!(scn.sampled.h[4], 0.2);

    // A raster of another shape, or no file at all, is refused at its key.
    write_asc(&d.join("h.asc"), 3, 3, |_, _| 0.1);
    let m = fails_at(RASTER_BED, d, "initial.h");
    assert!(m.contains("3 × 3") && m.contains("4 × 3"), "{m}");
    fs::remove_file(d.join("h.asc")).unwrap();
    let m = fails_at(RASTER_BED, d, "initial.h");
    assert!(m.contains("h.asc"), "{m}");
    // An explicit domain larger than the raster.
    write_asc(&d.join("h.asc"), 4, 3, |_, _| 0.1);
    let text = RASTER_BED.replace(
        "coordinates = \"cartesian\"",
        "coordinates = \"cartesian\"\nx_min = 0.0\nx_max = 1.0\ny_min = 0.0\ny_max = 0.3\ncells = [10, 3]",
    );
    let m = fails_at(&text, d, "bed.b");
    assert!(m.contains("covers"), "{m}");
}

/// Runs `scenario` (text) in `dir` with extra arguments; returns the HDF5 path.
fn run(dir: &Path, name: &str, scenario: &str, args: &[&str]) -> PathBuf {
    let file = dir.join(format!("{name}.toml"));
    fs::write(&file, scenario).unwrap();
    let h5 = dir.join(format!("{name}.h5"));
    let out = granflow()
        .arg("run")
        .arg(&file)
        .arg("--quiet")
        .arg("--output")
        .arg(&h5)
        .args(args)
        .output()
        .unwrap();
    assert_success(&out);
    h5
}

fn python(python: &str, code: &str, args: &[&Path]) -> String {
    let out = Command::new(python)
        .arg("-c")
        .arg(code)
        .args(args)
        .output()
        .unwrap();
    assert_success(&out)
}

/// The layout of a raster run read back with h5py: shapes, maxima, arrival times,
/// the conserved volume; check_output.py accepts the file and its XDMF.
#[test]
fn a_raster_run_reads_back_with_h5py() {
    let Some(py) = python_with_h5py() else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let h5 = run(dir.path(), "radial", RADIAL, &["--threads", "1"]);
    let code = r#"
import sys, h5py, numpy as np
f = h5py.File(sys.argv[1], "r")
nx, ny = int(f.attrs["nx"]), int(f.attrs["ny"])
nt = f["snapshots/t"].shape[0]
assert (nx, ny) == (24, 12), (nx, ny)
assert nt == 5, nt
for name in ("h", "u", "v"):
    assert f["snapshots/" + name].shape == (nt, ny, nx), (name, f["snapshots/" + name].shape)
assert f["grid/b"].shape == (ny, nx) and f["grid/x"].shape == (nx,) and f["grid/y"].shape == (ny,)
h = f["snapshots/h"][:]
m = {k: f["maps/" + k][:] for k in ("h_max", "speed_max", "arrival_time", "deposit")}
assert (m["h_max"] >= m["deposit"]).all()
assert (m["h_max"] >= h.max(axis=0)).all()
assert np.array_equal(m["deposit"], h[-1])
reached = np.isfinite(m["arrival_time"])
thr = f["front"].attrs["threshold"]
assert (reached == (m["h_max"] > thr)).all()
assert not reached.all(), "every cell reached: the test needs dry corners"
assert reached.any()
assert np.isnan(m["arrival_time"][0, 0])
assert (m["arrival_time"][h[0] > thr] == 0).all()
mass = f["diagnostics/mass"][:]
assert abs(mass[-1] - mass[0]) <= 1e-12 * mass[0], (mass[0], mass[-1])
dx, dy = f.attrs["dx"], f.attrs["dy"]
assert abs(h[0].sum() * dx * dy - mass[0]) <= 1e-12 * mass[0]
area = f["diagnostics/area_reached"][:]
assert area.shape == mass.shape and (np.diff(area) >= 0).all()
s = f["summary"].attrs
assert abs(s["area_reached"] - reached.sum() * dx * dy) <= 1e-12 * s["area_reached"]
assert np.isfinite(s["runout_length"]) and s["runout_length"] > 0.2
assert abs(s["travel_angle_deg"]) < 1e-9, s["travel_angle_deg"]  # a flat bed
print("ok")
"#;
    assert_eq!(python(&py, code, &[&h5]).trim(), "ok");
    let check = Command::new(&py)
        .arg(root().join("scripts/check_output.py"))
        .arg(&h5)
        .output()
        .unwrap();
    let line = assert_success(&check);
    assert!(line.contains("24 x 12 raster"), "{line}");
}

/// The XDMF file parses as XML and names the datasets with their dimensions.
#[test]
fn the_xdmf_file_names_the_datasets_and_their_dimensions() {
    let dir = tempfile::tempdir().unwrap();
    let h5 = run(dir.path(), "xdmf", RADIAL, &["--threads", "1"]);
    let text = fs::read_to_string(h5.with_extension("xmf")).unwrap();
    // Five snapshots of (ny, nx) = (12, 24) cells on (13, 25) nodes.
    assert_eq!(text.matches("<Grid Name=\"t").count(), 5, "{text}");
    assert!(text.contains("TopologyType=\"2DCoRectMesh\" Dimensions=\"13 25\""));
    for field in ["h", "u", "v"] {
        let item = format!("Dimensions=\"5 12 24\">xdmf.h5:/snapshots/{field}</DataItem>");
        assert!(text.contains(&item), "{field}: {text}");
    }
    for map in ["h_max", "speed_max", "ppr", "arrival_time", "deposit"] {
        assert!(text.contains(&format!("xdmf.h5:/maps/{map}<")), "{map}");
    }
    let Some(py) = python_with_h5py() else {
        return;
    };
    let code = r#"
import sys, h5py, xml.etree.ElementTree as ET
root = ET.parse(sys.argv[1]).getroot()
f = h5py.File(sys.argv[2], "r")
n = 0
for item in root.iter("DataItem"):
    if item.get("Format") == "HDF":
        name = item.text.strip().split(":", 1)[1]
        dims = tuple(int(d) for d in item.get("Dimensions").split())
        assert f[name].shape == dims, (name, f[name].shape, dims)
        n += 1
print(n)
"#;
    let n: usize = python(&py, code, &[&h5.with_extension("xmf"), &h5])
        .trim()
        .parse()
        .unwrap();
    assert!(n > 20, "{n}");
}

/// The data of a raster run are the same bits on 1 and 2 threads (only the wall
/// times differ).
#[test]
fn one_and_two_threads_write_the_same_data() {
    let Some(py) = python_with_h5py() else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let text = RADIAL.replace("cells = [24, 12]", "cells = [40, 36]");
    let one = run(dir.path(), "one", &text, &["--threads", "1"]);
    let two = run(dir.path(), "two", &text, &["--threads", "2"]);
    let code = r#"
import sys, h5py, numpy as np
a, b = h5py.File(sys.argv[1], "r"), h5py.File(sys.argv[2], "r")
names = []
a.visit(lambda n: names.append(n) if isinstance(a[n], h5py.Dataset) else None)
for n in names:
    x, y = a[n][()], b[n][()]
    assert x.shape == y.shape and x.tobytes() == y.tobytes(), n
for k, v in a["summary"].attrs.items():
    # Wall-clock times and the rates counted on them differ from run to run.
    if not (k.startswith("time_") or k == "wall_time_s" or k.endswith("_per_s")):
        w = b["summary"].attrs[k]
        assert (v == w) or (v != v and w != w), k
print(len(names))
"#;
    let n: usize = python(&py, code, &[&one, &two]).trim().parse().unwrap();
    assert!(n >= 20, "{n}");
}

/// plot_run.py draws a raster run as maps (and an animation), each figure holding
/// data (check_plot.py).
#[test]
fn plot_run_draws_a_raster_run_as_maps() {
    let Some(py) = python_with_h5py() else {
        return;
    };
    let has_mpl = Command::new(&py)
        .args(["-c", "import matplotlib, PIL"])
        .output()
        .is_ok_and(|o| o.status.success());
    if !has_mpl {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let h5 = run(dir.path(), "maps", RADIAL, &["--threads", "1"]);
    let out = Command::new(&py)
        .arg(root().join("scripts/plot_run.py"))
        .arg(&h5)
        .arg("--gif")
        .output()
        .unwrap();
    assert_success(&out);
    let png = dir.path().join("maps.png");
    let gif = dir.path().join("maps.gif");
    assert!(gif.exists() && fs::metadata(&gif).unwrap().len() > 0);
    let check = Command::new(&py)
        .arg(root().join("scripts/check_plot.py"))
        .arg(&png)
        .output()
        .unwrap();
    assert_success(&check);
}

#[test]
fn voellmy_keys_are_checked_by_name() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let voellmy = RADIAL.replace(
        "law = \"coulomb\"\nmu_deg = 27.0",
        "law = \"voellmy\"\nmu = 0.155\nxi = 4000.0",
    );
    let scn = load_in(&voellmy, d).unwrap();
    assert_eq!(
        scn.friction,
        granflow::scenario::FrictionLaw::Voellmy {
            mu: 0.155,
            xi: 4000.0
        }
    );
    let m = fails_at(&voellmy.replace("xi = 4000.0\n", ""), d, "rheology.xi");
    assert!(m.contains("missing"), "{m}");
    fails_at(
        &voellmy.replace("xi = 4000.0", "xi = 0.0"),
        d,
        "rheology.xi",
    );
    fails_at(&voellmy.replace("mu = 0.155\n", ""), d, "rheology.mu");
    let m = fails_at(
        &RADIAL.replace("mu_deg = 27.0", "mu_deg = 27.0\nxi = 4000.0"),
        d,
        "rheology.xi",
    );
    assert!(m.contains("only used by law = \"voellmy\""), "{m}");
    // A line takes the law too, and needs no raster key for it.
    let line = "[domain]\nx_min = 0.0\nx_max = 1.0\ncells = 10\n[rheology]\nlaw = \"voellmy\"\nmu = 0.2\nxi = 500\n[initial]\nh = 0.1\n[time]\nt_end = 1.0\n";
    assert!(load_in(line, d).is_ok());
    // Voellmy is a basal law of the depth-averaged flow: no multilayer column takes it.
    let layered = line.replace("[initial]", "[model]\nlayers = 4\n[initial]");
    let m = fails_at(&layered, d, "rheology.law");
    assert!(m.contains("model.layers = 1"), "{m}");
}

#[test]
fn a_file_in_the_way_of_the_xdmf_file_is_not_replaced_without_force() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("mine.toml");
    fs::write(&file, RADIAL).unwrap();
    let h5 = dir.path().join("mine.h5");
    let xmf = dir.path().join("mine.xmf");
    fs::write(&xmf, "my own notes\n").unwrap();
    let out = granflow()
        .args(["run", "--quiet", "--threads", "1"])
        .arg(&file)
        .arg("--output")
        .arg(&h5)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("XDMF"));
    assert_eq!(fs::read_to_string(&xmf).unwrap(), "my own notes\n");
    // Its own earlier XDMF file it replaces.
    fs::remove_file(&xmf).unwrap();
    for _ in 0..2 {
        let out = granflow()
            .args(["run", "--quiet", "--threads", "1"])
            .arg(&file)
            .arg("--output")
            .arg(&h5)
            .output()
            .unwrap();
        assert_success(&out);
    }
}
