//! The submarine model (`model.kind = "submarine"`, Fernández-Nieto et al. 2008) end to end: its keys are
//! checked and named, it reduces to the granular Savage–Hutter model without water, a
//! run writes the two layers' fields, and the CLI rejects inconsistent scenarios with
//! exit code 2.

use std::path::Path;

use assert_cmd::Command;
use granflow::output::memory::MemorySink;
use granflow::scenario::load_str;
use granflow::setup::{build_granular, build_submarine};

const SUBMARINE: &str = r#"
[domain]
x_min = -1.0
x_max = 3.0
cells = 200
coordinates = "cartesian"

[rheology]
law = "coulomb"
mu_deg = 20.0

[model]
kind = "submarine"

[submarine]
r = 0.0

[initial]
h = "if(x <= 0, 0.3, 0)"

[boundary]
left = "wall"
right = "outflow"

[time]
t_end = 0.8
cfl = 0.8
stop_at_rest = false

[output]
every = 0.8
"#;

fn load(text: &str, sets: &[&str]) -> granflow::scenario::Scenario {
    let sets: Vec<String> = sets.iter().map(|s| s.to_string()).collect();
    load_str(text, Path::new("."), &sets).expect("valid scenario")
}

/// L1 distance between the final thicknesses of the submarine model without water
/// (r = 0) and the granular Savage–Hutter model on the same collapse, and the two
/// fronts (last cell thicker than 1 cm), on `cells` cells.
fn sh_difference(cells: usize, sets: &[&str]) -> (f64, f64, f64, f64) {
    let cells_key = format!("domain.cells={cells}");
    let mut all = vec![cells_key.as_str()];
    all.extend_from_slice(sets);
    let sub = load(SUBMARINE, &all);
    let gran_text = SUBMARINE
        .replace("kind = \"submarine\"", "kind = \"granular\"")
        .replace("[submarine]\nr = 0.0\n", "");
    let gran = load(&gran_text, &all);
    let mut a = build_submarine(&sub);
    let mut b = build_granular(&gran);
    let (mut sa, mut sb) = (MemorySink::default(), MemorySink::default());
    a.run(&mut sa, &mut |_| {}).unwrap();
    b.run(&mut sb, &mut |_| {}).unwrap();
    let (ha, hb) = (
        &sa.snapshots.last().unwrap().h,
        &sb.snapshots.last().unwrap().h,
    );
    let dx = 4.0 / cells as f64;
    let mass: f64 = hb.iter().sum::<f64>() * dx;
    let l1: f64 = ha.iter().zip(hb).map(|(a, b)| (a - b).abs()).sum::<f64>() * dx;
    let front = |h: &[f64]| sa.x[h.iter().rposition(|&v| v > 1e-2).unwrap()];
    (l1 / mass, front(ha), front(hb), dx)
}

/// Without water and with r = 0 the grain layer is the Savage–Hutter Coulomb model:
/// the same collapse on a flat bed run by the granular model (its own scheme) gives
/// deposits that converge to each other under refinement.
#[test]
fn without_water_the_grains_are_the_savage_hutter_model() {
    let (d200, fa200, fb200, _) = sh_difference(200, &[]);
    let (d400, fa400, fb400, dx) = sh_difference(400, &[]);
    eprintln!("relative L1 difference {d200:.3e} (200 cells), {d400:.3e} (400); fronts {fa200}/{fb200}, {fa400}/{fb400}");
    assert!(d400 < 0.01 && d400 < 0.75 * d200, "{d200} → {d400}");
    assert!((fa400 - fb400).abs() <= 4.0 * dx);
    // Friction matters (the test can fail): with δ0 = 30° the front stops earlier.
    let (_, fa30, _, _) = sh_difference(400, &["rheology.mu_deg=30"]);
    assert!(fa30 < fa400 - 0.1, "{fa30} vs {fa400}");
}

#[test]
fn a_run_writes_both_layers_and_the_free_surface() {
    let scn = load(
        SUBMARINE,
        &[
            "initial.eta=0.5",
            "submarine.r=0.2",
            "time.t_end=0.2",
            "output.every=0.1",
        ],
    );
    let mut sim = build_submarine(&scn);
    let mut sink = MemorySink::default();
    sim.run(&mut sink, &mut |_| {}).unwrap();
    let last = sink.snapshots.last().unwrap();
    for name in ["h_water", "u_water", "eta", "interface"] {
        assert!(
            last.extra.iter().any(|(n, v)| n == name && v.len() == 200),
            "{name}"
        );
    }
    let get = |n: &str| &last.extra.iter().find(|(k, _)| k == n).unwrap().1;
    // Free surface above the interface above the bed, everywhere.
    for i in 0..200 {
        assert!(
            get("eta")[i] >= get("interface")[i] - 1e-12
                && get("interface")[i] >= sink.b[i] - 1e-12
        );
    }
}

fn rejects(text: &str, needle: &str) {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("bad.toml");
    std::fs::write(&path, text).unwrap();
    let out = Command::cargo_bin("granflow")
        .unwrap()
        .args(["check", path.to_str().unwrap()])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "stderr: {stderr}");
    assert!(stderr.contains(needle), "expected '{needle}' in: {stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
}

#[test]
fn inconsistent_submarine_scenarios_are_rejected_with_the_key() {
    rejects(
        &SUBMARINE.replace("coordinates = \"cartesian\"\n", ""),
        "domain.coordinates",
    );
    rejects(&SUBMARINE.replace("r = 0.0", "r = 1.5"), "submarine.r");
    rejects(&SUBMARINE.replace("r = 0.0", "k_in = 0.1"), "submarine.r");
    rejects(
        &SUBMARINE.replace("r = 0.0", "r = 0.2\nk_in = 0.1"),
        "submarine.k_in",
    );
    rejects(
        &SUBMARINE.replace("r = 0.0", "r = 0.2\nbuoyancy = \"air\""),
        "submarine.buoyancy",
    );
    rejects(
        &SUBMARINE.replace(
            "law = \"coulomb\"\nmu_deg = 20.0",
            "law = \"mu_i\"\nmu_s_deg = 20\nmu_2_deg = 30\ni0 = 0.3",
        ),
        "rheology.law",
    );
    rejects(
        &SUBMARINE.replace("kind = \"submarine\"", "kind = \"granular\""),
        "submarine",
    );
    rejects(
        &SUBMARINE.replace("h = \"if(x <= 0, 0.3, 0)\"", "h = 0.1\neta = \"ln(x)\""),
        "initial.eta",
    );
}
