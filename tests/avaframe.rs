//! AvaFrame's standard avalanches (Tonnel et al. 2023): the bundled
//! `scenarios/hockey_channel.toml` and `scenarios/helix_channel.toml` are AvaFrame's
//! hockey-stick and helix examples (avaframe/data/avaHockeyChannel and
//! avaHelixChannel: DEM and release area). Checked here: the beds equal AvaFrame's
//! DEMs at their cell centres, and a coarse run's runout, peak speed and affected
//! area against AvaFrame com1DFA's (docs/validation.md, "AvaFrame's standard
//! avalanches", where the full-size comparison and its commands are).

use std::path::{Path, PathBuf};
use std::process::Command;

use assert_cmd::prelude::*;
use granflow::scenario::{load_file, raster_centres};

use crate::common::{assert_success, read_h5};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// The bed of a bundled scenario at AvaFrame's DEM points (x, y, z), on the scenario's
/// own grid (the DEM's cell centres): the largest |b − z|.
fn bed_against_dem(file: &str, dem: &[(f64, f64, f64)]) -> f64 {
    let scn = load_file(&root().join("scenarios").join(file), &[]).unwrap();
    let plane = scn.domain.plane.as_ref().expect("a raster domain");
    let centres = raster_centres(&scn.domain, plane);
    let mut worst: f64 = 0.0;
    for &(x, y, z) in dem {
        let k = centres
            .iter()
            .position(|&(cx, cy)| cx == x && cy == y)
            .unwrap_or_else(|| panic!("{file}: no cell centred at ({x}, {y})"));
        let b = scn.sampled.b[k];
        println!("{file}: ({x}, {y}) b = {b:.6}, AvaFrame {z:.6}");
        worst = worst.max((b - z).abs());
    }
    worst
}

/// AvaFrame's DEMs at points on the slope, in the channel and on its flanks, in the
/// rounded corner and on the foreland. Hockey stick: DEM_HS_Topo.asc as AvaFrame 2.1's
/// in3Utils/generateTopo writes it (type HS, its defaults, yEnd = 2000 m: the example's
/// 1001 × 401 cells), full precision; helix: the example's DEM_HX_Topo.asc, which has 6
/// decimals (the generator reproduces it to them).
const HOCKEY_DEM: &[(f64, f64, f64)] = &[
    (1000.0, -5000.0, 2201.130984903039),
    (1500.0, -4000.0, 1862.7457415787867),
    (2600.0, -4000.0, 1120.7863730521174),
    (2600.0, -3900.0, 1219.2890601528043),
    (3800.0, -4050.0, 315.1085340252189),
    (3805.0, -3905.0, 322.019279569384),
    (4230.0, -4000.0, 22.822625451944617),
    (4300.0, -3000.0, 7.179483934797574),
    (6000.0, -4000.0, 0.0),
];
const HELIX_DEM: &[(f64, f64, f64)] = &[
    (2250.0, -5000.0, 1000.0),
    (2250.0, -4995.0, 993.266325),
    (2300.0, -4800.0, 741.935527),
    (1600.0, -4400.0, 648.942661),
    (2500.0, -3750.0, 99.574746),
    (3500.0, -3250.0, 0.002175),
    (4400.0, -3900.0, 0.0),
    (1000.0, -3000.0, 279.862462),
    (3495.0, -5000.0, 1000.0),
    (3500.0, -5000.0, 0.0),
];

#[test]
fn the_hockey_and_helix_beds_are_avaframes_dems() {
    // Round-off of the same formulas for the hockey stick; the file's last decimal
    // (half of 1e-6) for the helix.
    let hockey = bed_against_dem("hockey_channel.toml", HOCKEY_DEM);
    let helix = bed_against_dem("helix_channel.toml", HELIX_DEM);
    println!("max |b - z|: hockey {hockey:.2e} m, helix {helix:.2e} m");
    assert!(hockey < 1e-9, "hockey stick: {hockey}");
    assert!(helix <= 5.0e-7 + 1e-9, "helix: {helix}");
}

/// The measures of docs/validation.md ("AvaFrame's standard avalanches") and
/// scripts/compare_avaframe.py, from the peak maps of a run.
#[derive(Debug, Clone, Copy)]
struct Measures {
    /// Runout beyond the foot of the slope along the thalweg, m.
    runout: f64,
    /// Largest peak flow velocity, m/s.
    max_pfv: f64,
    /// Horizontal area with peak flow thickness above 0.1 m, m².
    area: f64,
}

/// AvaFrame's thickness threshold of a hazard map, m.
const PFT_THRESHOLD: f64 = 0.1;

/// The 34° plane of the hockey stick reaches the foreland's level at
/// x = 1000 + 2200 / tan 34° (the DEM's x' = 0 is x = 1000).
fn hockey_foot() -> f64 {
    1000.0 + 2200.0 / 34f64.to_radians().tan()
}

/// The helix's thalweg: the arc length s = R (atan2(y', x') + π) about its axis
/// (x' = x − 3500, y' = −5000 − y, R = 1250 m) beyond the foot s = 1000 / tan 34°,
/// where the parabola meets the foreland.
fn helix_beyond_foot(x: f64, y: f64) -> f64 {
    let (xp, yp) = (x - 3500.0, -5000.0 - y);
    1250.0 * (yp.atan2(xp) + std::f64::consts::PI) - 1000.0 / 34f64.to_radians().tan()
}

/// Runs a bundled scenario with `sets` and measures its peak maps, the runout beyond
/// the foot along the thalweg by `beyond(x, y)`.
fn run_and_measure(
    dir: &Path,
    file: &str,
    sets: &[&str],
    beyond: impl Fn(f64, f64) -> f64,
) -> Measures {
    let h5 = dir.join(file.replace(".toml", ".h5"));
    let mut cmd = Command::cargo_bin("granflow").unwrap();
    cmd.arg("run")
        .arg(root().join("scenarios").join(file))
        .args(["--quiet", "--threads", "2", "--output"])
        .arg(&h5);
    for s in sets {
        cmd.args(["--set", s]);
    }
    assert_success(&cmd.output().unwrap());
    let f = rust_hdf5::H5File::open(&h5).unwrap();
    let (x, y) = (read_h5(&f, "grid/x"), read_h5(&f, "grid/y"));
    let (pft, pfv) = (read_h5(&f, "maps/h_max"), read_h5(&f, "maps/speed_max"));
    let cell = (x[1] - x[0]) * (y[1] - y[0]);
    let mut m = Measures {
        runout: f64::NEG_INFINITY,
        max_pfv: 0.0,
        area: 0.0,
    };
    for (j, &yc) in y.iter().enumerate() {
        for (i, &xc) in x.iter().enumerate() {
            let k = j * x.len() + i;
            m.max_pfv = m.max_pfv.max(pfv[k]);
            if pft[k] > PFT_THRESHOLD {
                m.area += cell;
                m.runout = m.runout.max(beyond(xc, yc));
            }
        }
    }
    m
}

/// A row of tests/data/avaframe_reference.csv: AvaFrame com1DFA's measures.
fn avaframe_reference(case: &str, cell: f64, curvature: &str) -> Measures {
    let text = std::fs::read_to_string(root().join("tests/data/avaframe_reference.csv")).unwrap();
    let mut lines = text.lines().filter(|l| !l.starts_with('#'));
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
    for line in lines {
        let v: Vec<&str> = line.split(',').collect();
        let num = |name: &str| v[col(name)].parse::<f64>().unwrap();
        if v[col("case")] == case
            && v[col("code")] == "AvaFrame com1DFA"
            && num("cell_m") == cell
            && v[col("curvature")] == curvature
            && num("threshold_m") == PFT_THRESHOLD
        {
            return Measures {
                runout: num("runout_m"),
                max_pfv: num("max_pfv_ms"),
                area: num("area_m2"),
            };
        }
    }
    panic!("no AvaFrame row for {case} at {cell} m, curvature {curvature}");
}

/// The CI-sized side by side: the hockey stick on cells of 20 m (a quarter of a
/// minute's CPU at most) against AvaFrame com1DFA 2.1 on its own 5 m DEM, curvature in
/// the friction as AvaFrame's default (tests/data/avaframe_reference.csv: runout
/// 428.4 m beyond the foot, max pfv 69.56 m/s, 4.330e5 m² with pft > 0.1 m). Checked:
/// each of the three within 10 % of AvaFrame's (the target of the comparison in
/// docs/validation.md). In the Cartesian frame it fails: runout 498 m (+16 %).
#[test]
fn hockey_stick_on_20_m_cells_is_within_10_percent_of_avaframe() {
    let dir = tempfile::tempdir().unwrap();
    let sets = [
        "domain.x_min=990",
        "domain.x_max=6010",
        "domain.y_min=-5010",
        "domain.y_max=-2990",
        "domain.cells=[251,101]",
    ];
    let beyond = |x: f64, _: f64| x - hockey_foot();
    let ours = run_and_measure(dir.path(), "hockey_channel.toml", &sets, beyond);
    let theirs = avaframe_reference("hockey", 5.0, "on");
    within_10_percent("granflow 20 m", &ours, &theirs);
}

/// Prints the three measures against AvaFrame's 5 m figures and asserts each within
/// 10 %.
fn within_10_percent(what: &str, ours: &Measures, theirs: &Measures) {
    let rel = |a: f64, b: f64| (a - b) / b;
    let diffs = [
        ("runout beyond the foot (m)", ours.runout, theirs.runout),
        ("max pfv (m/s)", ours.max_pfv, theirs.max_pfv),
        ("area with pft > 0.1 m (m²)", ours.area, theirs.area),
    ];
    for (measure, a, b) in diffs {
        println!(
            "{measure}: {what} {a:.1}, AvaFrame 5 m {b:.1}, {:+.1} %",
            100.0 * rel(a, b)
        );
    }
    for (measure, a, b) in diffs {
        assert!(
            rel(a, b).abs() <= 0.10,
            "{measure}: {a} against AvaFrame's {b}"
        );
    }
}

/// The helix on 10 m cells (AvaFrame's 10 m centres) at order 2 against AvaFrame
/// com1DFA 2.1 on 5 m cells (tests/data/avaframe_reference.csv: runout 329.8 m along
/// the arc beyond the foot, max pfv 69.35 m/s, 9.673e5 m² with pft > 0.1 m): each
/// within 10 %. At order 1 the runout fails it: 116 m on these cells (−65 %), the
/// first-order scheme's diffusion of the stream that leaves the fading channel
/// obliquely to the grid (docs/validation.md, "AvaFrame's standard avalanches").
#[test]
fn helix_at_order_2_on_10_m_cells_is_within_10_percent_of_avaframe() {
    let dir = tempfile::tempdir().unwrap();
    let sets = [
        "domain.x_min=995",
        "domain.x_max=6005",
        "domain.y_min=-5005",
        "domain.y_max=-2995",
        "domain.cells=[501,201]",
        "numerics.order=2",
    ];
    let ours = run_and_measure(dir.path(), "helix_channel.toml", &sets, helix_beyond_foot);
    let theirs = avaframe_reference("helix", 5.0, "on");
    within_10_percent("granflow order 2, 10 m", &ours, &theirs);
}
