//! Hostile inputs: keys that would fill a disk or hang a step, outputs that would
//! replace the wrong file or be written by two runs at once, pipes and files that are
//! not what they seem. Every case ends with a clear exit code and message, never a
//! panic, a hang or a damaged file.

use std::fs;
use std::io::Read;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

pub(crate) fn bin() -> PathBuf {
    assert_cmd::cargo::cargo_bin("granflow")
}

pub(crate) fn scenario(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("scenarios")
        .join(name)
}

/// (exit code, stderr) of `granflow ARGS…` run in `cwd`, killed (and the test failed)
/// after `limit`; a panic fails the test too.
pub(crate) fn run_in(cwd: &Path, args: &[&str], limit: Duration) -> (i32, String) {
    let mut child = Command::new(bin())
        .args(args)
        .current_dir(cwd)
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let code = wait_for(&mut child, limit)
        .unwrap_or_else(|| panic!("granflow {args:?} still running after {limit:?}"));
    let mut stderr = String::new();
    child
        .stderr
        .take()
        .unwrap()
        .read_to_string(&mut stderr)
        .unwrap();
    assert!(!stderr.contains("panicked"), "{stderr}");
    (code, stderr)
}

/// The exit code, or `None` (the child killed) when it runs longer than `limit`.
pub(crate) fn wait_for(child: &mut Child, limit: Duration) -> Option<i32> {
    let start = Instant::now();
    loop {
        if let Some(status) = child.try_wait().unwrap() {
            return Some(status.code().unwrap_or(-1));
        }
        if start.elapsed() > limit {
            let _ = child.kill();
            let _ = child.wait();
            return None;
        }
        std::thread::sleep(Duration::from_millis(20));
    }
}

pub(crate) const MINUTE: Duration = Duration::from_secs(60);

#[test]
fn an_output_rate_that_would_fill_the_disk_is_refused_naming_the_key() {
    let dir = tempfile::tempdir().unwrap();
    let lake = scenario("lake_landslide.toml");
    let (code, stderr) = run_in(
        dir.path(),
        &[
            "run",
            lake.to_str().unwrap(),
            "--set",
            "output.gauge_every=1e-6",
            "-o",
            "l.h5",
        ],
        MINUTE,
    );
    assert_eq!(code, 2, "{stderr}");
    for needle in ["output.gauge_every", "GB", "--force"] {
        assert!(stderr.contains(needle), "'{needle}' in {stderr}");
    }
    assert_eq!(
        fs::read_dir(dir.path()).unwrap().count(),
        0,
        "nothing written"
    );
    // Snapshots too: many cells at a fine interval.
    let (code, stderr) = run_in(
        dir.path(),
        &[
            "check",
            lake.to_str().unwrap(),
            "--set",
            "domain.cells=100000",
            "--set",
            "output.every=0.001",
        ],
        MINUTE,
    );
    assert_eq!(code, 2, "{stderr}");
    assert!(stderr.contains("output.every"), "{stderr}");
}

#[test]
fn a_step_that_would_iterate_for_hours_is_refused_naming_the_key() {
    let dir = tempfile::tempdir().unwrap();
    let dense = scenario("dilatancy_dense.toml");
    let (code, stderr) = run_in(
        dir.path(),
        &[
            "run",
            dense.to_str().unwrap(),
            "--set",
            "dilatancy.xi=[1e300,1e300,1e300]",
            "-o",
            "d.h5",
        ],
        MINUTE,
    );
    assert_eq!(code, 2, "{stderr}");
    assert!(stderr.contains("key 'dilatancy.xi'"), "{stderr}");
    assert!(!dir.path().join("d.h5").exists());
}

#[test]
fn the_gauge_csv_of_another_program_is_not_replaced() {
    let dir = tempfile::tempdir().unwrap();
    let (code, stderr) = run_in(
        dir.path(),
        &["init", "lake", "--from", "lake_landslide"],
        MINUTE,
    );
    assert_eq!(code, 0, "{stderr}");
    let mine = "time,level\n0,1.5\n";
    fs::write(dir.path().join("lake_gauges.csv"), mine).unwrap();
    let args = ["run", "lake.toml", "--set", "time.t_end=0.05", "-q"];
    let (code, stderr) = run_in(dir.path(), &args, MINUTE);
    assert_eq!(code, 2, "{stderr}");
    assert!(stderr.contains("lake_gauges.csv"), "{stderr}");
    assert_eq!(
        fs::read_to_string(dir.path().join("lake_gauges.csv")).unwrap(),
        mine
    );
    // --force replaces it, and a later run replaces granflow's own gauge CSV.
    let forced = [
        "run",
        "lake.toml",
        "--set",
        "time.t_end=0.05",
        "-q",
        "--force",
    ];
    assert_eq!(run_in(dir.path(), &forced, MINUTE).0, 0);
    assert_eq!(run_in(dir.path(), &args, MINUTE).0, 0);
    let ours = fs::read_to_string(dir.path().join("lake_gauges.csv")).unwrap();
    assert!(ours.starts_with("t,eta_"), "{ours}");
}

#[test]
fn a_closed_stderr_does_not_stop_the_run() {
    let dir = tempfile::tempdir().unwrap();
    let collapse = scenario("nh_multilayer_collapse.toml");
    let mut child = Command::new(bin())
        .args([
            "run",
            collapse.to_str().unwrap(),
            "--set",
            "time.t_end=0.05",
            "--progress",
            "lines",
            "--progress-every",
            "0",
            "-o",
            "nh.h5",
        ])
        .current_dir(dir.path())
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    drop(child.stderr.take());
    let code = wait_for(&mut child, MINUTE).expect("the run ends");
    assert_eq!(code, 0);
}

#[cfg(unix)]
#[test]
fn two_names_of_one_output_file_share_its_lock() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let collapse = scenario("collapse.toml");
    let short = [
        "run",
        collapse.to_str().unwrap(),
        "-q",
        "--set",
        "time.t_end=0.01",
        "-o",
    ];
    // a.h5 exists (a granflow output), b.h5 is a symbolic link to it, c.h5 a hard link.
    let (code, stderr) = run_in(d, &[&short[..], &["a.h5"]].concat(), MINUTE);
    assert_eq!(code, 0, "{stderr}");
    std::os::unix::fs::symlink("a.h5", d.join("b.h5")).unwrap();
    fs::hard_link(d.join("a.h5"), d.join("c.h5")).unwrap();
    let mut long = Command::new(bin())
        .args([
            "run",
            collapse.to_str().unwrap(),
            "-q",
            "--set",
            "time.t_end=1000",
            "--set",
            "time.stop_at_rest=false",
            "-o",
            "a.h5",
        ])
        .current_dir(d)
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    // The holder has locked once its lock file is there.
    let start = Instant::now();
    while !d.join("a.h5.lock").exists() && start.elapsed() < MINUTE {
        std::thread::sleep(Duration::from_millis(20));
    }
    for other in ["b.h5", "c.h5"] {
        let (code, stderr) = run_in(d, &[&short[..], &[other]].concat(), MINUTE);
        assert_eq!(code, 2, "{other}: {stderr}");
        assert!(stderr.contains("in use"), "{other}: {stderr}");
    }
    long.kill().unwrap();
    long.wait().unwrap();
}

#[test]
fn a_single_cell_is_refused_where_the_model_needs_more() {
    let dir = tempfile::tempdir().unwrap();
    let sub = scenario("submarine_landslide.toml");
    for command in ["check", "run"] {
        let (code, stderr) = run_in(
            dir.path(),
            &[command, sub.to_str().unwrap(), "--set", "domain.cells=1"],
            MINUTE,
        );
        assert_eq!(code, 2, "{stderr}");
        assert!(stderr.contains("domain.cells"), "{stderr}");
    }
}

#[test]
fn an_hdf5_file_granflow_did_not_write_is_not_replaced() {
    let dir = tempfile::tempdir().unwrap();
    let theirs: Vec<u8> = b"\x89HDF\r\n\x1a\n"
        .iter()
        .copied()
        .chain(std::iter::repeat_n(0u8, 4096))
        .collect();
    fs::write(dir.path().join("user.h5"), &theirs).unwrap();
    let collapse = scenario("collapse.toml");
    let args = [
        "run",
        collapse.to_str().unwrap(),
        "-q",
        "--set",
        "time.t_end=0.01",
        "-o",
        "user.h5",
    ];
    let (code, stderr) = run_in(dir.path(), &args, MINUTE);
    assert_eq!(code, 2, "{stderr}");
    assert!(stderr.contains("did not write"), "{stderr}");
    assert_eq!(fs::read(dir.path().join("user.h5")).unwrap(), theirs);
    // granflow's own output is replaced, as before.
    let (code, stderr) = run_in(dir.path(), &[&args[..], &["--force"]].concat(), MINUTE);
    assert_eq!(code, 0, "{stderr}");
    assert_eq!(run_in(dir.path(), &args, MINUTE).0, 0);
}

#[test]
fn a_sweep_of_a_million_runs_is_counted_and_refused() {
    let dir = tempfile::tempdir().unwrap();
    let values = |n: usize| {
        let v: Vec<String> = (0..n)
            .map(|i| format!("{}", 10.0 + i as f64 * 1e-3))
            .collect();
        format!("[{}]", v.join(", "))
    };
    let text = format!(
        "scenario = {:?}\n[axes]\ndomain.slope_deg = {}\ntime.t_end = {}\nmaterial.phi = {}\noutput.front_threshold = {}\n",
        scenario("collapse.toml").to_str().unwrap(),
        values(1000),
        values(1000),
        values(1000),
        values(1000)
    );
    fs::write(dir.path().join("big.toml"), text).unwrap();
    for (extra, needle) in [
        (None, "needs --force"),
        (Some("--force"), "even with --force"),
    ] {
        let mut args = vec!["sweep", "big.toml", "-o", "out"];
        args.extend(extra);
        let (code, stderr) = run_in(dir.path(), &args, MINUTE);
        assert_eq!(code, 2, "{stderr}");
        assert!(stderr.contains("1000000000000 runs"), "{stderr}");
        assert!(
            stderr.contains(needle) && stderr.contains("writing about"),
            "{stderr}"
        );
    }
    assert!(!dir.path().join("out").exists());
}

#[test]
fn an_output_name_ending_in_a_slash_creates_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let collapse = scenario("collapse.toml");
    let (code, stderr) = run_in(
        dir.path(),
        &["run", collapse.to_str().unwrap(), "-o", "newdir/"],
        MINUTE,
    );
    assert_eq!(code, 2, "{stderr}");
    assert!(stderr.contains("names a directory"), "{stderr}");
    assert!(!dir.path().join("newdir").exists());
}

#[cfg(unix)]
#[test]
fn a_fifo_is_not_read_as_a_scenario_or_a_table() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let made = Command::new("mkfifo").arg(d.join("pipe")).status();
    if !made.is_ok_and(|s| s.success()) {
        return; // no mkfifo here
    }
    let (code, stderr) = run_in(d, &["check", "pipe"], MINUTE);
    assert_eq!(code, 2, "{stderr}");
    assert!(stderr.contains("not a regular file"), "{stderr}");
    let text =
        crate::common::MINIMAL.replace("h = \"if(x <= 0, 0.14, 0)\"", "h = { table = \"pipe\" }");
    fs::write(d.join("s.toml"), text).unwrap();
    let (code, stderr) = run_in(d, &["check", "s.toml"], MINUTE);
    assert_eq!(code, 2, "{stderr}");
    assert!(
        stderr.contains("initial.h") && stderr.contains("not a regular file"),
        "{stderr}"
    );
    fs::write(
        d.join("sweep.toml"),
        "scenario = \"pipe\"\n[axes]\ndomain.slope_deg = [1, 2]\n",
    )
    .unwrap();
    let (code, stderr) = run_in(d, &["sweep", "sweep.toml", "-o", "out"], MINUTE);
    assert_eq!(code, 2, "{stderr}");
    assert!(stderr.contains("not a regular file"), "{stderr}");
}

#[test]
fn huge_numbers_are_printed_short_and_arrays_of_tables_named() {
    let dir = tempfile::tempdir().unwrap();
    let collapse = scenario("collapse.toml");
    let (code, stderr) = run_in(
        dir.path(),
        &[
            "check",
            collapse.to_str().unwrap(),
            "--set",
            "material.phi=1e300",
        ],
        MINUTE,
    );
    assert_eq!(code, 2, "{stderr}");
    assert!(
        stderr.contains("got 1e300") && stderr.len() < 200,
        "{stderr}"
    );
    let dense = fs::read_to_string(scenario("dilatancy_dense.toml")).unwrap();
    assert!(dense.contains("\n[dilatancy]\n"));
    fs::write(
        dir.path().join("d.toml"),
        dense.replace("\n[dilatancy]\n", "\n[[dilatancy]]\n"),
    )
    .unwrap();
    let (code, stderr) = run_in(dir.path(), &["check", "d.toml"], MINUTE);
    assert_eq!(code, 2, "{stderr}");
    assert!(
        stderr.contains("key 'dilatancy'") && stderr.contains("not an array of tables"),
        "{stderr}"
    );
}

/// A run file of 2 MB may declare a grid of 200 000 × 50 000 cells (80 GB of maps):
/// `export` refuses it by its sizes, read from the header, before reading any field.
#[test]
fn an_export_of_a_file_declaring_a_huge_grid_is_refused_by_its_sizes() {
    let dir = tempfile::tempdir().unwrap();
    let h5 = dir.path().join("crafted.h5");
    {
        let f = rust_hdf5::H5File::create(&h5).unwrap();
        f.set_attr_string("granflow_version", "0.1.0").unwrap();
        f.set_attr_string("grid", "raster").unwrap();
        let g = f.create_group("grid").unwrap();
        for (name, n) in [("x", 200_000usize), ("y", 50_000)] {
            let axis: Vec<f64> = (0..n).map(|i| i as f64 + 0.5).collect();
            let ds = g.new_dataset::<f64>().shape([n]).create(name).unwrap();
            ds.write_raw(&axis).unwrap();
        }
        let s = f.create_group("snapshots").unwrap();
        let t = s.new_dataset::<f64>().shape([1]).create("t").unwrap();
        t.write_raw(&[0.0]).unwrap();
    }
    let (code, stderr) = run_in(dir.path(), &["export", h5.to_str().unwrap()], MINUTE);
    assert_eq!(code, 2, "{stderr}");
    assert!(stderr.contains("crafted.h5"), "{stderr}");
    assert!(stderr.contains("200000 x 50000 cells"), "{stderr}");
}
