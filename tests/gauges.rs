//! Gauges (`output.gauges`, `output.gauge_every`): the series equal the snapshots'
//! fields interpolated the same way at snapshot times, the time rules hold without
//! changing the time steps, the HDF5 datasets and the CSV have their documented
//! shapes, bad keys are refused with exit code 2, and a lake at rest reads a constant
//! surface at every gauge.

use std::path::Path;

use assert_cmd::Command;
use granflow::gauges::interpolation;
use granflow::output::memory::MemorySink;
use granflow::scenario::{load_str, Scenario};
use granflow::setup::{build, build_granular, scenario_line};

const LAKE_FILE: &str = include_str!("../scenarios/lake_landslide.toml");
const COLLAPSE: &str = include_str!("../scenarios/collapse.toml");

/// The lake landslide without the gauges the scenario ships with.
static LAKE: std::sync::LazyLock<String> = std::sync::LazyLock::new(|| {
    LAKE_FILE
        .lines()
        .filter(|l| !l.starts_with("gauge"))
        .map(|l| format!("{l}\n"))
        .collect()
});

fn load(text: &str, sets: &[&str]) -> Scenario {
    let sets: Vec<String> = sets.iter().map(|s| s.to_string()).collect();
    load_str(text, Path::new("scenarios"), &sets).expect("valid scenario")
}

fn run(scn: &Scenario) -> MemorySink {
    let mut sink = MemorySink::default();
    build(scn).run(&mut sink, &mut |_| {}).expect("run");
    sink
}

/// The snapshot field `v` (nx) read at gauge `xg` the way the gauges read cells, with
/// the mesh's Δx `dx`.
fn at(x: &[f64], dx: f64, v: &[f64], xg: f64) -> f64 {
    let (i, w) = interpolation(x, dx, xg);
    if w == 0.0 {
        v[i]
    } else {
        (1.0 - w) * v[i] + w * v[i + 1]
    }
}

/// Every snapshot time has a gauge record, whose values are the snapshot's surface
/// and grain depth interpolated to the gauges; returns the number of comparisons.
fn gauges_match_snapshots(
    sink: &MemorySink,
    dx: f64,
    surface: impl Fn(usize, usize) -> f64,
) -> usize {
    let mut compared = 0;
    for (k, snap) in sink.snapshots.iter().enumerate() {
        let (_, eta, h) = sink
            .gauges
            .iter()
            .find(|(t, _, _)| (t - snap.t).abs() <= 1e-12 * snap.t.max(1.0))
            .unwrap_or_else(|| panic!("no gauge record at snapshot time {}", snap.t));
        let surf: Vec<f64> = (0..sink.x.len()).map(|i| surface(k, i)).collect();
        for (g, &xg) in sink.gauge_x.iter().enumerate() {
            assert_eq!(
                eta[g],
                at(&sink.x, dx, &surf, xg),
                "η at x = {xg}, t = {}",
                snap.t
            );
            assert_eq!(
                h[g],
                at(&sink.x, dx, &snap.h, xg),
                "h at x = {xg}, t = {}",
                snap.t
            );
            compared += 1;
        }
    }
    compared
}

#[test]
fn submarine_gauges_are_the_snapshot_surface_and_grain_depth() {
    // 6.025 is a cell centre (Δx = 0.05), 0.0 and 10.0 lie in the outer half cells.
    let gauges = "output.gauges=[0.0, 3.0, 4.51, 6.025, 8.0, 10.0]";
    for every in [None, Some("output.gauge_every=0.1")] {
        let mut sets = vec![gauges, "time.t_end=3"];
        sets.extend(every);
        let scn = load(&LAKE, &sets);
        let sink = run(&scn);
        let n = gauges_match_snapshots(&sink, scenario_line(&scn).dx, |k, i| {
            sink.snapshots[k].field("eta").expect("eta")[i]
        });
        assert_eq!(n, 7 * 6, "7 snapshots (0, 0.5, …, 3) × 6 gauges");
        // The slide has reached the lake: the surface moved at the deep gauges.
        let moved = sink
            .gauges
            .iter()
            .any(|(_, eta, _)| (eta[4] - 0.4).abs() > 1e-3);
        assert!(moved);
    }
}

#[test]
fn granular_gauges_read_the_top_of_the_flow_and_its_thickness() {
    let scn = load(COLLAPSE, &["output.gauges=[0.05, 0.3, 0.77]"]);
    let sink = run(&scn);
    let n = gauges_match_snapshots(&sink, scenario_line(&scn).dx, |k, i| {
        sink.b[i] + sink.snapshots[k].h[i]
    });
    assert_eq!(n, sink.snapshots.len() * 3);
    assert!(sink.snapshots.len() >= 3);
}

#[test]
fn without_gauge_every_every_step_is_recorded() {
    let sink = run(&load(&LAKE, &["output.gauges=[5.0]", "time.t_end=1"]));
    let t_steps: Vec<f64> = sink.steps.iter().map(|r| r.t).collect();
    let t_gauges: Vec<f64> = sink.gauges.iter().map(|g| g.0).collect();
    assert_eq!(t_gauges, t_steps);
}

#[test]
fn gauge_every_sets_the_record_times_not_the_time_steps() {
    let base = run(&load(&LAKE, &["time.t_end=2"]));
    assert!(base.gauges.is_empty() && base.gauge_x.is_empty());
    for (every, records) in [(0.25, 9), (0.01, 201), (0.3, 8)] {
        let set = format!("output.gauge_every={every}");
        let sink = run(&load(
            &LAKE,
            &["time.t_end=2", "output.gauges=[5.0, 7.0]", &set],
        ));
        // The same steps as without gauges, to the bit.
        assert_eq!(sink.steps, base.steps, "gauge_every = {every}");
        let t: Vec<f64> = sink.gauges.iter().map(|g| g.0).collect();
        assert_eq!(t.len(), records, "gauge_every = {every}: {t:?}");
        for (k, &tk) in t.iter().enumerate().take(records - 1) {
            assert_eq!(tk, k as f64 * every);
        }
        // The last state of the run closes the series (2.0 is not a multiple of 0.3).
        assert_eq!(*t.last().unwrap(), 2.0);
        // Interpolated values lie between those of the two steps around them: check
        // on the grain-free surface at 7 m against the per-step series.
        let steps = run(&load(&LAKE, &["time.t_end=2", "output.gauges=[5.0, 7.0]"]));
        for (tk, eta, _) in &sink.gauges {
            let n = steps.gauges.partition_point(|g| g.0 < *tk);
            let (hi, lo) = (&steps.gauges[n], &steps.gauges[n.saturating_sub(1)]);
            let (a, b) = (lo.1[1].min(hi.1[1]), lo.1[1].max(hi.1[1]));
            assert!(eta[1] >= a - 1e-15 && eta[1] <= b + 1e-15, "t = {tk}");
        }
    }
}

#[test]
fn a_lake_at_rest_reads_a_constant_surface_at_every_gauge() {
    // A grain deposit 5 cm thick at rest (slope 11.3° < δ₀ = 25°) under a lake whose
    // shore is at x = 3.25; gauges on the dry deposit, at the shoreline, beyond it and
    // over the flat floor.
    let scn = load(
        &LAKE,
        &[
            "rheology.mu_deg=25",
            "initial.h=0.05",
            "time.t_end=2",
            "output.gauges=[2.0, 3.25, 3.3, 4.0, 7.5]",
        ],
    );
    let sink = run(&scn);
    assert!(sink.gauges.len() > 50, "{} records", sink.gauges.len());
    let (_, eta0, h0) = &sink.gauges[0];
    assert!((eta0[4] - 0.4).abs() < 1e-15 && (eta0[0] - (0.6 + 0.05)).abs() < 1e-14);
    let mut worst = 0.0f64;
    for (_, eta, h) in &sink.gauges {
        for g in 0..eta.len() {
            worst = worst
                .max((eta[g] - eta0[g]).abs())
                .max((h[g] - h0[g]).abs());
        }
    }
    assert!(worst <= 1e-14, "largest change {worst:e}");
    let amp = sink.summary.unwrap().max_wave_amplitude.expect("submarine");
    assert!(amp <= 1e-14, "{amp:e}");
}

#[test]
fn the_wave_amplitude_is_in_the_submarine_summary_only() {
    let sink = run(&load(&LAKE, &["time.t_end=3"]));
    let amp = sink.summary.unwrap().max_wave_amplitude.unwrap();
    // The surface at the gauges moved by up to … ≤ the amplitude over all wet cells.
    let with = run(&load(
        &LAKE,
        &["time.t_end=3", "output.gauges=[5, 6, 7, 8, 9]"],
    ));
    let seen = with
        .gauges
        .iter()
        .flat_map(|g| g.1.iter().map(|e| (e - 0.4).abs()))
        .fold(0.0f64, f64::max);
    assert!(seen > 1e-3 && seen <= amp, "gauges {seen}, summary {amp}");
    let granular = build_granular(&load(COLLAPSE, &[]))
        .run(&mut MemorySink::default(), &mut |_| {})
        .unwrap();
    assert_eq!(granular.max_wave_amplitude, None);
}

fn granflow() -> Command {
    Command::cargo_bin("granflow").unwrap()
}

#[test]
fn the_files_hold_the_documented_shapes() {
    let dir = tempfile::tempdir().unwrap();
    let h5 = dir.path().join("lake.h5");
    let out = granflow()
        .args(["run", "scenarios/lake_landslide.toml", "--quiet"])
        .args(["--output", h5.to_str().unwrap()])
        .args([
            "--set",
            "time.t_end=1",
            "--set",
            "output.gauges=[4.5, 6, 8]",
        ])
        .args(["--set", "output.gauge_every=0.1"])
        .output()
        .unwrap();
    crate::common::assert_success(&out);
    let f = rust_hdf5::H5File::open(&h5).unwrap();
    let read = |name: &str| f.dataset(name).unwrap().read_raw::<f64>().unwrap();
    let shape = |name: &str| f.dataset(name).unwrap().shape();
    assert_eq!(read("gauges/x"), [4.5, 6.0, 8.0]);
    assert_eq!(shape("gauges/t"), [11]);
    assert_eq!(shape("gauges/eta"), [11, 3]);
    assert_eq!(shape("gauges/h_grains"), [11, 3]);
    let (t, eta, h) = (
        read("gauges/t"),
        read("gauges/eta"),
        read("gauges/h_grains"),
    );
    let csv = std::fs::read_to_string(dir.path().join("lake_gauges.csv")).unwrap();
    let mut lines = csv.lines();
    assert_eq!(
        lines.next(),
        Some("t,eta_4.5,eta_6,eta_8,h_grains_4.5,h_grains_6,h_grains_8")
    );
    let rows: Vec<Vec<f64>> = lines
        .map(|l| l.split(',').map(|v| v.parse().unwrap()).collect())
        .collect();
    assert_eq!(rows.len(), 11);
    for (k, row) in rows.iter().enumerate() {
        assert_eq!(row[0], t[k]);
        assert_eq!(row[1..4], eta[3 * k..3 * k + 3]);
        assert_eq!(row[4..7], h[3 * k..3 * k + 3]);
    }
    // A run without gauges writes neither.
    let plain = dir.path().join("plain.h5");
    let scenario = dir.path().join("plain.toml");
    std::fs::write(&scenario, LAKE.as_str()).unwrap();
    let out = granflow()
        .args(["run", scenario.to_str().unwrap(), "--quiet"])
        .args([
            "--output",
            plain.to_str().unwrap(),
            "--set",
            "time.t_end=0.1",
        ])
        .output()
        .unwrap();
    crate::common::assert_success(&out);
    assert!(!dir.path().join("plain_gauges.csv").exists());
    let f = rust_hdf5::H5File::open(&plain).unwrap();
    assert!(f.dataset("gauges/t").is_err());
}

#[test]
fn bad_gauge_keys_exit_2_naming_the_key_and_line() {
    let cases = [
        (
            "gauges = [1.0, 12.0]",
            "output.gauges",
            "outside the domain",
        ),
        ("gauges = [-0.5]", "output.gauges", "outside the domain"),
        ("gauges = [nan]", "output.gauges", "finite"),
        ("gauges = [2.0, 2.0]", "output.gauges", "twice"),
        ("gauges = \"2.0\"", "output.gauges", ""),
        (
            "gauges = [2.0]\ngauge_every = 0",
            "output.gauge_every",
            "greater than 0",
        ),
        (
            "gauges = [2.0]\ngauge_every = inf",
            "output.gauge_every",
            "finite",
        ),
        (
            "gauge_every = 0.1",
            "output.gauge_every",
            "needs output.gauges",
        ),
    ];
    let dir = tempfile::tempdir().unwrap();
    for (k, (keys, key, message)) in cases.into_iter().enumerate() {
        let text = LAKE.replace("every = 0.5", &format!("every = 0.5\n{keys}"));
        let line = text
            .lines()
            .position(|l| l.starts_with(key.trim_start_matches("output.")))
            .unwrap()
            + 1;
        let path = dir.path().join(format!("bad{k}.toml"));
        std::fs::write(&path, &text).unwrap();
        let out = granflow()
            .args(["check", path.to_str().unwrap()])
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{keys}: {stderr}");
        for needle in [key, message, &format!("line {line}")] {
            assert!(
                stderr.contains(needle),
                "{keys}: '{needle}' not in {stderr}"
            );
        }
        assert!(!stderr.contains("panicked"), "{stderr}");
    }
}
