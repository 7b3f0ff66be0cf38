//! A new user's first commands: `granflow scenarios`, `init`, `completions`, `--help`
//! and the progress display, run from a directory outside the repository (as an
//! installed binary would be).

use std::path::Path;

use assert_cmd::Command;
use granflow::catalog::{self, BUNDLED};

fn granflow(dir: &Path) -> Command {
    let mut c = Command::cargo_bin("granflow").unwrap();
    c.current_dir(dir);
    c
}

fn ok(c: &mut Command) -> (String, String) {
    let out = c.output().unwrap();
    let (o, e) = (
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    );
    assert!(out.status.success(), "{c:?}\nstdout: {o}\nstderr: {e}");
    (o, e)
}

/// Every `scenarios/*.toml` is bundled (a new scenario cannot be forgotten), with the
/// same text, and every bundled data file is the repository's.
#[test]
fn bundle_matches_the_scenarios_directory() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios");
    let mut on_disk: Vec<String> = std::fs::read_dir(&dir)
        .unwrap()
        .filter_map(|e| {
            let p = e.unwrap().path();
            (p.extension()? == "toml").then(|| p.file_stem().unwrap().to_string_lossy().into())
        })
        .collect();
    on_disk.sort();
    let bundled: Vec<String> = BUNDLED.iter().map(|b| b.name.to_owned()).collect();
    assert_eq!(bundled, on_disk);
    for b in BUNDLED {
        let text = std::fs::read_to_string(dir.join(format!("{}.toml", b.name))).unwrap();
        assert_eq!(text, b.toml, "{}", b.name);
        // A scenario that reads a table must bundle it.
        for line in text.lines().filter(|l| l.contains("table =")) {
            let rel = line.split('"').nth(1).unwrap();
            assert!(
                b.data.iter().any(|(p, _)| *p == rel),
                "{} reads {rel} but does not bundle it",
                b.name
            );
        }
        for (rel, data) in b.data {
            assert_eq!(std::fs::read_to_string(dir.join(rel)).unwrap(), *data);
        }
    }
}

#[test]
fn scenarios_lists_every_case_with_its_description() {
    let tmp = tempfile::tempdir().unwrap();
    let (out, _) = ok(granflow(tmp.path()).arg("scenarios"));
    for b in BUNDLED {
        let line = out
            .lines()
            .find(|l| l.split_whitespace().next() == Some(b.name))
            .unwrap_or_else(|| panic!("{} missing from\n{out}", b.name));
        assert!(line.ends_with(&b.description()), "{line}");
    }
    let (shown, _) = ok(granflow(tmp.path()).args(["scenarios", "--show", "collapse"]));
    assert_eq!(shown, catalog::find("collapse").unwrap().toml);
    let out = granflow(tmp.path())
        .args(["scenarios", "--show", "colapse"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
}

/// `init` outside the repository: every bundled case, tables included, passes `check`,
/// and its output file is named after the new scenario.
#[test]
fn every_bundled_case_can_be_initialised_and_checked_anywhere() {
    let tmp = tempfile::tempdir().unwrap();
    for b in BUNDLED {
        let name = format!("my_{}", b.name);
        ok(granflow(tmp.path()).args(["init", &name, "--from", b.name]));
        let (out, _) = ok(granflow(tmp.path()).args(["check", &format!("{name}.toml")]));
        assert!(out.contains(": ok ("), "{out}");
        let text = std::fs::read_to_string(tmp.path().join(format!("{name}.toml"))).unwrap();
        assert!(!text.contains(&format!("\"{}.h5\"", b.name)), "{name}");
    }
    // The tables sit where the scenario looks for them, shared by a second copy.
    assert!(tmp
        .path()
        .join("data/complex_topography_local_b.csv")
        .is_file());
    let sub = tmp.path().join("sub/dir");
    ok(granflow(tmp.path()).args([
        "init",
        "sub/dir/local",
        "--from",
        "nh_complex_topography_local.toml",
    ]));
    assert!(sub.join("data/complex_topography_local_h.csv").is_file());
    ok(granflow(tmp.path()).args(["check", "sub/dir/local.toml"]));
}

#[test]
fn the_starter_scenario_runs_as_is() {
    let tmp = tempfile::tempdir().unwrap();
    let (out, _) = ok(granflow(tmp.path()).args(["init", "first"]));
    assert!(out.contains("granflow run first.toml"), "{out}");
    let text = std::fs::read_to_string(tmp.path().join("first.toml")).unwrap();
    assert!(text.contains("granflow run first.toml"));
    let (out, _) = ok(granflow(tmp.path()).args(["run", "first.toml"]));
    // The μ(I) column settles (it would creep on to t_end).
    assert!(out.contains("granflow: settled at"), "{out}");
    assert!(tmp.path().join("first.h5").is_file());
    assert!(tmp.path().join("first_front.csv").is_file());
}

#[test]
fn init_never_overwrites_without_force() {
    let tmp = tempfile::tempdir().unwrap();
    std::fs::create_dir(tmp.path().join("data")).unwrap();
    let table = tmp.path().join("data/complex_topography_local_b.csv");
    std::fs::write(&table, "x,b\n0,1\n").unwrap();
    let out = granflow(tmp.path())
        .args(["init", "loc", "--from", "nh_complex_topography_local"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("already exists"));
    // Nothing written: not the scenario, not the other table.
    assert!(!tmp.path().join("loc.toml").exists());
    assert!(!tmp
        .path()
        .join("data/complex_topography_local_h.csv")
        .exists());
    assert_eq!(std::fs::read_to_string(&table).unwrap(), "x,b\n0,1\n");
    ok(granflow(tmp.path()).args([
        "init",
        "loc",
        "--from",
        "nh_complex_topography_local",
        "--force",
    ]));
    assert_ne!(std::fs::read_to_string(&table).unwrap(), "x,b\n0,1\n");
    let out = granflow(tmp.path())
        .args(["init", "x", "--from", "no_such_case"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
}

#[test]
fn completions_and_long_help() {
    let tmp = tempfile::tempdir().unwrap();
    for shell in ["bash", "zsh", "fish"] {
        let (out, _) = ok(granflow(tmp.path()).args(["completions", shell]));
        assert!(
            out.contains("granflow") && out.contains("scenarios"),
            "{shell}"
        );
    }
    let (out, _) = ok(granflow(tmp.path()).arg("--help"));
    assert!(out.contains("granflow init my_flow") && out.contains("Exit codes"));
}

const TINY: &[&str] = &["--set", "domain.cells=40", "--set", "time.t_end=0.3"];

#[test]
fn progress_lines_in_a_pipe() {
    let tmp = tempfile::tempdir().unwrap();
    ok(granflow(tmp.path()).args(["init", "p"]));
    // Forced lines at every step.
    let (_, err) = ok(granflow(tmp.path())
        .args([
            "run",
            "p.toml",
            "--progress",
            "lines",
            "--progress-every",
            "0",
        ])
        .args(TINY));
    assert!(err.lines().count() > 3, "{err}");
    assert!(
        err.lines().all(|l| l.starts_with("granflow: t = ")),
        "{err}"
    );
    // A short run in a pipe (auto) prints no progress line, and neither does --progress none.
    for mode in ["auto", "none"] {
        let (out, err) = ok(granflow(tmp.path())
            .args(["run", "p.toml", "--progress", mode])
            .args(TINY));
        assert_eq!(err, "", "{mode}");
        assert!(out.contains("runout"));
    }
}
