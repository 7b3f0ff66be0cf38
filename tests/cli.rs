//! The command line as a user meets it: exit codes 0 / 1 / 2 and error messages that
//! name the offending key (and its line).

use std::fs;
use std::path::Path;

use assert_cmd::Command;

use crate::common::read_h5;

use crate::common::MINIMAL;

fn granflow() -> Command {
    Command::cargo_bin("granflow").unwrap()
}

fn write(dir: &Path, name: &str, text: &str) -> String {
    let path = dir.join(name);
    fs::write(&path, text).unwrap();
    path.to_string_lossy().into_owned()
}

/// Runs `check` on `text` and asserts exit code 2 with `needle` in stderr.
fn rejects(text: &str, needle: &str) {
    let dir = tempfile::tempdir().unwrap();
    let path = write(dir.path(), "bad.toml", text);
    let out = granflow().args(["check", &path]).output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "stderr: {stderr}");
    assert!(stderr.contains(needle), "expected '{needle}' in: {stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
}

#[test]
fn valid_scenario_checks_ok() {
    let dir = tempfile::tempdir().unwrap();
    let path = write(dir.path(), "ok.toml", MINIMAL);
    let out = granflow().args(["check", &path]).output().unwrap();
    assert!(out.status.success());
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(stdout.contains("hyperbolic → friction"), "{stdout}");
}

#[test]
fn unknown_key_is_named_with_its_line() {
    rejects(&MINIMAL.replace("cells = 60", "cels = 60"), "line 4");
    rejects(&MINIMAL.replace("cells = 60", "cels = 60"), "cels");
}

#[test]
fn wrong_type_is_named() {
    rejects(
        &MINIMAL.replace("cells = 60", "cells = \"sixty\""),
        "domain.cells",
    );
}

#[test]
fn zero_cells_is_named() {
    rejects(&MINIMAL.replace("cells = 60", "cells = 0"), "domain.cells");
}

#[test]
fn inverted_domain_is_named() {
    rejects(
        &MINIMAL.replace("x_max = 1.0", "x_max = -0.5"),
        "domain.x_max",
    );
}

#[test]
fn missing_table_file_is_named() {
    rejects(
        &MINIMAL.replace(
            "h = \"if(x <= 0, 0.14, 0)\"",
            "h = { table = \"nowhere.csv\" }",
        ),
        "initial.h",
    );
}

#[test]
fn mu2_below_mu_s_is_named() {
    rejects(
        &MINIMAL.replace("mu_2_deg = 36", "mu_2_deg = 20"),
        "rheology.mu_2",
    );
}

#[test]
fn negative_thickness_is_named() {
    rejects(&MINIMAL.replace("0.14, 0)", "0.14, -0.01)"), "initial.h");
}

#[test]
fn nan_is_named() {
    rejects(
        &MINIMAL.replace("slope_deg = 22", "slope_deg = nan"),
        "domain.slope_deg",
    );
}

#[test]
fn unknown_override_is_named() {
    let dir = tempfile::tempdir().unwrap();
    let path = write(dir.path(), "ok.toml", MINIMAL);
    let out = granflow()
        .args(["check", &path, "--set", "domain.slope=3"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("domain.slope"));
}

#[test]
fn missing_file_is_bad_input() {
    let out = granflow()
        .args(["check", "no/such/file.toml"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("no/such/file.toml"));
}

#[test]
fn run_writes_hdf5_and_front_csv_and_prints_a_summary() {
    let dir = tempfile::tempdir().unwrap();
    let path = write(dir.path(), "ok.toml", MINIMAL);
    let h5 = dir.path().join("out/run.h5");
    let out = granflow()
        .args(["run", &path, "--output", h5.to_str().unwrap()])
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    crate::common::assert_success(&out);
    assert!(stdout.contains("runout"), "{stdout}");
    assert!(stdout.contains("stage times   hyperbolic"), "{stdout}");
    assert!(h5.exists());
    let csv = fs::read_to_string(dir.path().join("out/run_front.csv")).unwrap();
    assert!(csv.starts_with("t,x\n"));
    assert!(csv.lines().count() > 10);
}

#[test]
fn quiet_run_prints_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let path = write(dir.path(), "ok.toml", MINIMAL);
    let h5 = dir.path().join("q.h5");
    let out = granflow()
        .args(["run", &path, "-q", "-o", h5.to_str().unwrap()])
        .output()
        .unwrap();
    assert!(out.status.success());
    assert!(out.stdout.is_empty() && out.stderr.is_empty());
}

#[test]
fn solver_blow_up_exits_1_naming_when_and_keeps_the_file() {
    // The submarine scheme with a huge interlayer coefficient K is unstable: its speeds
    // jump to about 1e3 m/s in the first step, beyond the physical bound of a mass on a
    // 2 m relief under 2.7 m of water.
    let dir = tempfile::tempdir().unwrap();
    let scn = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/submarine_landslide.toml");
    let h5 = dir.path().join("blowup.h5");
    let out = granflow()
        .arg("run")
        .arg(&scn)
        .args(["-o", h5.to_str().unwrap(), "--set", "submarine.k=1e6"])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(stderr.contains("exceeds the physical bound"), "{stderr}");
    // The fastest cell is named by its x.
    assert!(stderr.contains(", at x = "), "{stderr}");
    assert!(
        stderr.contains("at t = ") && stderr.contains("(step 1)"),
        "{stderr}"
    );
    let f = rust_hdf5::H5File::open(&h5).unwrap();
    let t = read_h5(&f, "snapshots/t");
    assert_eq!(t, vec![0.0], "only the valid initial snapshot");
    let h = read_h5(&f, "snapshots/h");
    assert!(h.iter().all(|v| v.is_finite()));
    let status = f
        .root_group()
        .group("summary")
        .unwrap()
        .attr_string("status")
        .unwrap();
    assert!(status.starts_with("failed: the largest speed"), "{status}");
}

#[test]
fn non_physical_magnitudes_are_refused_naming_the_key() {
    for (set, key) in [
        ("initial.u=1e300", "initial.u"),
        ("initial.u=-2000", "initial.u"),
        ("initial.h=\"if(x <= 0, 1e300, 0)\"", "initial.h"),
        ("initial.erodible_bed=2e4", "initial.erodible_bed"),
        ("bed.b=\"1e6 * x\"", "bed.b"),
    ] {
        let dir = tempfile::tempdir().unwrap();
        let path = write(dir.path(), "ok.toml", MINIMAL);
        let out = granflow()
            .args(["check", &path, "--set", set])
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{set}: {stderr}");
        assert!(stderr.contains(&format!("key '{key}'")), "{set}: {stderr}");
        assert!(stderr.contains("physical bound"), "{set}: {stderr}");
    }
    let scenarios = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios");
    for (file, sets, key) in [
        (
            "dilatancy_dense.toml",
            &["dilatancy.alpha=1e300"][..],
            "dilatancy.alpha",
        ),
        (
            "dilatancy_dense.toml",
            &["initial.phi=1e-300"],
            "initial.phi",
        ),
        (
            "dilatancy_dense.toml",
            &["dilatancy.phi_stat=1e-300"],
            "dilatancy.phi_stat",
        ),
        (
            "submarine_landslide.toml",
            &["initial.eta=1e300"],
            "initial.eta",
        ),
        (
            "erodible_bed.toml",
            &["model.layers=2", "model.layer_fractions=[1e-300, 1]"],
            "model.layer_fractions",
        ),
        ("collapse_nh.toml", &["initial.w=1e200"], "initial.w"),
    ] {
        let mut cmd = granflow();
        cmd.arg("check").arg(scenarios.join(file));
        for s in sets {
            cmd.args(["--set", s]);
        }
        let out = cmd.output().unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{sets:?}: {stderr}");
        assert!(
            stderr.contains(&format!("key '{key}'")),
            "{sets:?}: {stderr}"
        );
    }
}

#[test]
fn set_overrides_change_the_run() {
    let dir = tempfile::tempdir().unwrap();
    let path = write(dir.path(), "ok.toml", MINIMAL);
    let h5 = dir.path().join("s.h5");
    let out = granflow()
        .args([
            "run",
            &path,
            "-o",
            h5.to_str().unwrap(),
            "--set",
            "domain.cells=30",
        ])
        .output()
        .unwrap();
    assert!(out.status.success());
    let f = rust_hdf5::H5File::open(&h5).unwrap();
    assert_eq!(f.dataset("grid/x").unwrap().shape(), vec![30]);
}

#[test]
fn bed_from_a_csv_table_is_interpolated_relative_to_the_scenario_file() {
    let dir = tempfile::tempdir().unwrap();
    fs::create_dir(dir.path().join("data")).unwrap();
    write(dir.path(), "data/bed.csv", "x,value\n-0.2,0.0\n1.0,0.12\n");
    let text = MINIMAL.replace(
        "[rheology]",
        "[bed]\nb = { table = \"data/bed.csv\" }\n\n[rheology]",
    );
    let path = write(dir.path(), "table.toml", &text);
    let h5 = dir.path().join("t.h5");
    let out = granflow()
        .args(["run", &path, "-q", "-o", h5.to_str().unwrap()])
        .current_dir("/")
        .output()
        .unwrap();
    crate::common::assert_success(&out);
    let f = rust_hdf5::H5File::open(&h5).unwrap();
    let x = read_h5(&f, "grid/x");
    let b = read_h5(&f, "grid/b");
    for (x, b) in x.iter().zip(&b) {
        assert!((b - 0.1 * (x + 0.2)).abs() < 1e-12, "x = {x}: b = {b}");
    }
}

#[test]
fn a_run_too_long_for_its_time_step_fails_instead_of_running_forever() {
    // A run of 1e9 s at the collapse's CFL step (about 2e-3 s) would take 5e11 steps,
    // and no stop rule can end it earlier: it fails at its first step, saying so,
    // instead of crawling on, filling memory and the front CSV.
    let dir = tempfile::tempdir().unwrap();
    let path = write(dir.path(), "ok.toml", MINIMAL);
    let h5 = dir.path().join("crawl.h5");
    let out = granflow()
        .args(["run", &path, "-o", h5.to_str().unwrap()])
        .args(["--set", "time.t_end=1e9", "--set", "output.every=1e9"])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.contains("more steps to reach time.t_end = 1e9 s"),
        "{stderr}"
    );
    assert!(!stderr.contains("collapsed"), "{stderr}");
    assert!(
        !stderr.contains("solver failure: solver failure"),
        "{stderr}"
    );
}

#[test]
fn long_help_names_the_five_model_families_and_the_1d_profile() {
    let out = granflow().arg("--help").output().unwrap();
    let help = crate::common::assert_success(&out);
    for needle in [
        "five model families",
        "Savage–Hutter monolayer",
        "multilayer μ(I)",
        "non-hydrostatic",
        "submarine",
        "dilatancy",
        "1-D",
    ] {
        assert!(help.contains(needle), "'{needle}' not in: {help}");
    }
}

/// The long help describes the 2-D side too: runs over a DEM from release polygons,
/// the hazard maps and their export, and how to try one outside the clone.
#[test]
fn long_help_describes_the_2d_runs_over_terrain() {
    let out = granflow().arg("--help").output().unwrap();
    let help = crate::common::assert_success(&out);
    for needle in [
        "in 2-D over terrain",
        "DEM",
        "release",
        "peak flow thickness pft",
        "runout along the flow",
        "GeoTIFF",
        "granflow init dem --from dem_release",
    ] {
        assert!(help.contains(needle), "'{needle}' not in: {help}");
    }
}

/// `cargo install` ignores Cargo.lock unless told: the README's install command must
/// build the versions the tests ran with.
#[test]
fn readme_installs_with_the_lock_file() {
    let readme =
        fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("README.md")).unwrap();
    let installs: Vec<&str> = readme
        .lines()
        .filter(|l| l.trim_start().starts_with("cargo install"))
        .collect();
    assert!(!installs.is_empty());
    for line in installs {
        assert!(line.contains("--locked"), "{line}");
    }
}
