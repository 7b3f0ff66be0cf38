//! A real run through `granflow run`: every dataset of the output contract is present
//! and consistent with the run (docs/output-format.md).

use std::path::Path;

use assert_cmd::Command;
use rust_hdf5::H5File;

use crate::common::read_h5 as read;

fn shape(f: &H5File, name: &str) -> Vec<usize> {
    f.dataset(name).unwrap().shape()
}

#[test]
fn collapse_output_honours_the_contract() {
    let scenario = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/collapse.toml");
    let dir = tempfile::tempdir().unwrap();
    let h5 = dir.path().join("collapse.h5");
    let out = Command::cargo_bin("granflow")
        .unwrap()
        .args([
            "run",
            scenario.to_str().unwrap(),
            "-q",
            "-o",
            h5.to_str().unwrap(),
        ])
        .output()
        .unwrap();
    crate::common::assert_success(&out);
    let f = H5File::open(&h5).unwrap();

    // Root attributes.
    assert_eq!(f.attr_string("model").unwrap(), "granular");
    assert_eq!(f.attr_string("pressure").unwrap(), "hydrostatic");
    assert_eq!(f.attr_string("coordinates").unwrap(), "local");
    let toml = std::fs::read_to_string(&scenario).unwrap();
    assert_eq!(f.attr_string("scenario_toml").unwrap(), toml);
    let summary = f.root_group().group("summary").unwrap();
    // μ(I) creeps: collapse.toml ends when the mass has settled.
    assert_eq!(summary.attr_string("status").unwrap(), "settled");
    // The file says why, with the fraction the run stopped at (the default 1e-6).
    let why = summary.attr_string("stop_reason").unwrap();
    assert!(
        why.starts_with("the kinetic energy fell to 1e-6 × its peak (time.settle_fraction"),
        "{why}"
    );
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(stdout.is_empty(), "-q prints no report: {stdout}");

    // Grid.
    let nx = 640;
    let x = read(&f, "grid/x");
    assert_eq!(x.len(), nx);
    let dx = 3.2 / nx as f64;
    for (i, xi) in x.iter().enumerate() {
        assert!((xi - (-0.2 + (i as f64 + 0.5) * dx)).abs() < 1e-12);
    }
    assert_eq!(read(&f, "grid/b"), vec![0.0; nx]);
    assert_eq!(read(&f, "grid/h_bed"), vec![0.0; nx]);

    // Snapshots: every 0.05 s, plus the final, settled state.
    let t = read(&f, "snapshots/t");
    let nt = t.len();
    assert_eq!(t[0], 0.0);
    assert!(t.windows(2).all(|w| w[1] > w[0]));
    assert!((t[1] - 0.05).abs() < 1e-15 && (t[10] - 0.5).abs() < 1e-14);
    assert_eq!(shape(&f, "snapshots/h"), vec![nt, nx]);
    assert_eq!(shape(&f, "snapshots/u"), vec![nt, 1, nx]);
    assert!(f.dataset("snapshots/w").is_err() && f.dataset("snapshots/p_nh").is_err());
    let h = read(&f, "snapshots/h");
    let u = read(&f, "snapshots/u");
    assert!(h.iter().all(|&v| v >= 0.0 && v.is_finite()));
    // Settled (kinetic energy, below), not at exact rest: the μ(I) front creeps
    // (up to 1.6 cm/s in the thinnest front cells here).
    let u_last = u[(nt - 1) * nx..]
        .iter()
        .fold(0.0f64, |m, v| m.max(v.abs()));
    assert!(
        u_last > 0.0 && u_last.is_finite(),
        "final max |u| = {u_last}"
    );

    // Diagnostics: one row per step plus t = 0; mass conserved (nothing reaches the
    // outflow) and equal to ∫h dx of the snapshots.
    let td = read(&f, "diagnostics/t");
    let n = td.len();
    for name in ["dt", "mass", "kinetic_energy", "max_speed"] {
        assert_eq!(read(&f, &format!("diagnostics/{name}")).len(), n, "{name}");
    }
    assert_eq!(*td.last().unwrap(), *t.last().unwrap());
    let mass = read(&f, "diagnostics/mass");
    assert!(mass.iter().all(|m| (m - 0.028).abs() < 1e-13));
    for (k, tk) in t.iter().enumerate() {
        let row = td
            .iter()
            .position(|v| v == tk)
            .expect("snapshot time is a step time");
        let integral: f64 = h[k * nx..(k + 1) * nx].iter().sum::<f64>() * dx;
        assert!((integral - mass[row]).abs() < 1e-14);
    }
    let dt = read(&f, "diagnostics/dt");
    for k in 1..n {
        assert!(
            (td[k] - td[k - 1] - dt[k]).abs() < 1e-12,
            "t and dt agree at {k}"
        );
    }
    let ke = read(&f, "diagnostics/kinetic_energy");
    assert_eq!(ke[0], 0.0);
    assert!(ke.iter().cloned().fold(0.0, f64::max) > 0.0);
    let peak = ke.iter().cloned().fold(0.0, f64::max);
    assert!(*ke.last().unwrap() <= 1e-6 * peak);
    assert!(
        ke[ke.len() - 2] > 1e-6 * peak,
        "the run ends at the first settled step"
    );

    // Front: every step; starts at the column's edge, ends at the runout.
    assert_eq!(read(&f, "front/t"), td);
    let front = read(&f, "front/x");
    assert_eq!(front[0], x[39], "last cell of the column (x ≤ 0)");
    // Runout 1.090 m until the μ(I) friction became backward Euler and the run ends
    // when settled (tests/scenarios.rs collapse_regression_norms).
    assert!((front.last().unwrap() - front[0] - 1.105).abs() < 1e-9);
    let csv = std::fs::read_to_string(dir.path().join("collapse_front.csv")).unwrap();
    assert_eq!(csv.lines().count(), n + 1);
}
