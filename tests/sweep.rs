//! `granflow sweep` end to end: the binary on small sweeps of the collapse scenario
//! (coarse grid, short end time, so each run takes milliseconds).

use std::collections::BTreeMap;
use std::fs;
use std::path::{Path, PathBuf};
use std::time::SystemTime;

use assert_cmd::Command;
use tempfile::TempDir;

fn collapse() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/collapse.toml")
}

/// Base overrides that keep runs tiny.
const SMALL: &str = r#"set = ["domain.cells=60", "time.t_end=0.4", "output.every=0.1"]"#;

/// Writes a sweep file `name` in `dir` over the collapse scenario, with `body` after the
/// `scenario` and `set` keys.
fn sweep_file(dir: &Path, name: &str, body: &str) -> PathBuf {
    let path = dir.join(name);
    let text = format!(
        "scenario = {:?}\n{SMALL}\n{body}",
        collapse().display().to_string()
    );
    fs::write(&path, text).unwrap();
    path
}

fn granflow() -> Command {
    Command::cargo_bin("granflow").unwrap()
}

/// `granflow sweep FILE -o OUT ARGS…`, returning (exit code, stdout, stderr).
fn sweep(file: &Path, out: &Path, args: &[&str]) -> (i32, String, String) {
    let o = granflow()
        .arg("sweep")
        .arg(file)
        .arg("--output")
        .arg(out)
        .args(args)
        .output()
        .unwrap();
    (
        o.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&o.stdout).into_owned(),
        String::from_utf8_lossy(&o.stderr).into_owned(),
    )
}

fn merge(dir: &Path) -> (i32, String, String) {
    let o = granflow()
        .args(["sweep", "merge"])
        .arg(dir)
        .output()
        .unwrap();
    (
        o.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&o.stdout).into_owned(),
        String::from_utf8_lossy(&o.stderr).into_owned(),
    )
}

/// A parsed summary.csv: header and rows of fields (simple CSV with RFC 4180 quotes).
fn read_csv(path: &Path) -> (Vec<String>, Vec<Vec<String>>) {
    let text = fs::read_to_string(path).unwrap();
    let mut lines = text.lines().map(split_csv);
    let header = lines.next().unwrap();
    (header, lines.collect())
}

fn split_csv(line: &str) -> Vec<String> {
    let mut fields = vec![String::new()];
    let mut quoted = false;
    let mut chars = line.chars().peekable();
    while let Some(c) = chars.next() {
        match (c, quoted) {
            ('"', true) if chars.peek() == Some(&'"') => {
                chars.next();
                fields.last_mut().unwrap().push('"');
            }
            ('"', _) => quoted = !quoted,
            (',', false) => fields.push(String::new()),
            (c, _) => fields.last_mut().unwrap().push(c),
        }
    }
    fields
}

/// The summary without the wall-time column.
fn without_wall_time(path: &Path) -> Vec<Vec<String>> {
    let (header, rows) = read_csv(path);
    let wall = header.iter().position(|h| h == "wall_time_s").unwrap();
    std::iter::once(header)
        .chain(rows)
        .map(|mut r| {
            r.remove(wall);
            r
        })
        .collect()
}

fn column(path: &Path, name: &str) -> Vec<String> {
    let (header, rows) = read_csv(path);
    let c = header.iter().position(|h| h == name).unwrap();
    rows.into_iter().map(|r| r[c].clone()).collect()
}

fn mtimes(dir: &Path, suffix: &str) -> BTreeMap<String, SystemTime> {
    fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap())
        .filter(|e| e.file_name().to_string_lossy().ends_with(suffix))
        .map(|e| {
            (
                e.file_name().to_string_lossy().into_owned(),
                e.metadata().unwrap().modified().unwrap(),
            )
        })
        .collect()
}

/// Lets file modification times move on between two sweeps.
fn tick() {
    std::thread::sleep(std::time::Duration::from_millis(30));
}

const GRID: &str =
    "[axes]\ndomain.slope_deg = [16, 22]\ninitial.erodible_bed = [0, 1.4e-3, 2.5e-3]\n";

#[test]
fn product_runs_are_named_and_summarised_in_sweep_order() {
    let tmp = TempDir::new().unwrap();
    let file = sweep_file(tmp.path(), "grid.toml", GRID);
    let out = tmp.path().join("out");
    let (code, stdout, stderr) = sweep(&file, &out, &["--jobs", "2"]);
    assert_eq!(code, 0, "{stdout}\n{stderr}");
    let runs = column(&out.join("summary.csv"), "run");
    assert_eq!(
        runs,
        [
            "slope_deg=16__erodible_bed=0",
            "slope_deg=16__erodible_bed=0.0014",
            "slope_deg=16__erodible_bed=0.0025",
            "slope_deg=22__erodible_bed=0",
            "slope_deg=22__erodible_bed=0.0014",
            "slope_deg=22__erodible_bed=0.0025",
        ]
    );
    for run in &runs {
        for ext in [".h5", "_front.csv", ".result.toml"] {
            assert!(out.join(format!("{run}{ext}")).is_file(), "{run}{ext}");
        }
    }
    let (header, _) = read_csv(&out.join("summary.csv"));
    assert_eq!(
        header,
        [
            "index",
            "run",
            "domain.slope_deg",
            "initial.erodible_bed",
            "runout",
            "stop_time",
            "settled_time",
            "h_max_final",
            "t_end",
            "steps",
            "wall_time_s",
            "status",
            "outflowed_fraction"
        ]
    );
    assert_eq!(
        column(&out.join("summary.csv"), "initial.erodible_bed"),
        ["0", "0.0014", "0.0025", "0", "0.0014", "0.0025"]
    );
    assert!(column(&out.join("summary.csv"), "status")
        .iter()
        .all(|s| s == "completed" || s == "stopped_at_rest" || s == "settled"));
    // The printed table has a line per run and the parameters.
    assert!(stdout.contains("slope_deg  erodible_bed"), "{stdout}");
    assert_eq!(stdout.lines().filter(|l| l.contains("0.0025")).count(), 2);
    // The erodible bed changes the result (the axis values reach the scenarios).
    let h = column(&out.join("summary.csv"), "h_max_final");
    assert_ne!(h[3], h[5]);
    assert!(out.join("sweep-plan.toml").is_file());
}

#[test]
fn zip_runs_values_together() {
    let tmp = TempDir::new().unwrap();
    let file = sweep_file(
        tmp.path(),
        "zip.toml",
        "[[zip]]\ndomain.slope_deg = [16, 19, 22]\ninitial.erodible_bed = [1.4e-3, 1.5e-3, 1.82e-3]\n",
    );
    let out = tmp.path().join("out");
    let (code, stdout, stderr) = sweep(&file, &out, &["-q"]);
    assert_eq!(code, 0, "{stdout}\n{stderr}");
    assert!(stdout.is_empty(), "--quiet prints nothing: {stdout}");
    assert_eq!(
        column(&out.join("summary.csv"), "run"),
        [
            "slope_deg=16__erodible_bed=0.0014",
            "slope_deg=19__erodible_bed=0.0015",
            "slope_deg=22__erodible_bed=0.00182"
        ]
    );
}

#[test]
fn zip_length_mismatch_is_bad_input_naming_key_and_line() {
    let tmp = TempDir::new().unwrap();
    let file = sweep_file(
        tmp.path(),
        "zip.toml",
        "[[zip]]\ndomain.slope_deg = [16, 19, 22]\ninitial.erodible_bed = [1.4e-3, 1.5e-3]\n",
    );
    let out = tmp.path().join("out");
    let (code, _, stderr) = sweep(&file, &out, &[]);
    assert_eq!(code, 2, "{stderr}");
    assert!(stderr.contains("at line 5"), "{stderr}");
    assert!(
        stderr.contains("key 'zip[0].initial.erodible_bed'"),
        "{stderr}"
    );
    assert!(stderr.contains("same number of values"), "{stderr}");
    assert!(!out.exists());
}

#[test]
fn invalid_generated_scenario_stops_everything_before_any_run() {
    let tmp = TempDir::new().unwrap();
    let file = sweep_file(
        tmp.path(),
        "bad.toml",
        "[axes]\ndomain.slope_deg = [16, 22]\ninitial.erodible_bed = [0, -1e-3]\n",
    );
    let out = tmp.path().join("out");
    let (code, _, stderr) = sweep(&file, &out, &[]);
    assert_eq!(code, 2, "{stderr}");
    assert!(
        stderr.contains("axis 'initial.erodible_bed' = -0.001 (line 5"),
        "{stderr}"
    );
    assert!(stderr.contains("must be at least 0"), "{stderr}");
    assert!(stderr.contains("2 of 4 runs"), "{stderr}");
    assert!(!out.exists(), "nothing may be written");

    // An unknown key in the sweep file, and a --set that fights an axis.
    let file = sweep_file(
        tmp.path(),
        "unknown.toml",
        "jobs = 3\n[axes]\ndomain.slope_deg = [16]\n",
    );
    let (code, _, stderr) = sweep(&file, &out, &[]);
    assert_eq!(code, 2);
    assert!(
        stderr.contains("at line 3, key 'jobs': unknown key"),
        "{stderr}"
    );
    let file = sweep_file(tmp.path(), "grid.toml", GRID);
    let (code, _, stderr) = sweep(&file, &out, &["--set", "domain.slope_deg=3"]);
    assert_eq!(code, 2);
    assert!(stderr.contains("axis 'domain.slope_deg'"), "{stderr}");
    // A --set that breaks every run.
    let (code, _, stderr) = sweep(&file, &out, &["--set", "domain.cells=0"]);
    assert_eq!(code, 2);
    assert!(stderr.contains("6 of 6 runs"), "{stderr}");
    assert!(
        stderr.contains("key 'domain.cells' from --set: must be at least 1"),
        "{stderr}"
    );
    // The same mistake in the sweep file's `set` points at its line.
    let file = tmp.path().join("set.toml");
    fs::write(
        &file,
        format!(
            "scenario = {:?}\n\nset = [\"domain.cells=0\"]\n[axes]\ndomain.slope_deg = [16]\n",
            collapse().display().to_string()
        ),
    )
    .unwrap();
    let (code, _, stderr) = sweep(&file, &out, &[]);
    assert_eq!(code, 2);
    assert!(
        stderr.contains("key 'domain.cells' from set = [...] (line 3"),
        "{stderr}"
    );
    assert!(!out.exists());
}

#[test]
fn shards_merge_to_the_unsharded_summary() {
    let tmp = TempDir::new().unwrap();
    let file = sweep_file(tmp.path(), "grid.toml", GRID);
    let whole = tmp.path().join("whole");
    let split = tmp.path().join("split");
    let (code, _, stderr) = sweep(&file, &whole, &["-q"]);
    assert_eq!(code, 0, "{stderr}");

    // Merging before every shard ran: the missing runs are listed, exit code 1.
    let (code, _, stderr) = sweep(&file, &split, &["-q", "--shard", "1/4"]);
    assert_eq!(code, 0, "{stderr}");
    let shard_rows = column(&split.join("summary.shard-1-of-4.csv"), "index");
    assert_eq!(shard_rows, ["1", "5"]);
    let (code, _, _) = merge(&split);
    assert_eq!(code, 1);
    let status = column(&split.join("summary.csv"), "status");
    assert_eq!(status.iter().filter(|s| *s == "missing").count(), 4);

    for k in [0, 2, 3] {
        let shard = format!("{k}/4");
        let (code, _, stderr) = sweep(&file, &split, &["-q", "--jobs", "1", "--shard", &shard]);
        assert_eq!(code, 0, "{stderr}");
    }
    let (code, stdout, stderr) = merge(&split);
    assert_eq!(code, 0, "{stdout}\n{stderr}");
    assert!(stdout.contains("6 runs"), "{stdout}");
    assert_eq!(
        without_wall_time(&split.join("summary.csv")),
        without_wall_time(&whole.join("summary.csv"))
    );
    // Merging the unsharded directory reproduces its summary byte for byte.
    let before = fs::read_to_string(whole.join("summary.csv")).unwrap();
    assert_eq!(merge(&whole).0, 0);
    assert_eq!(
        fs::read_to_string(whole.join("summary.csv")).unwrap(),
        before
    );
    // The plan is the same whoever wrote it.
    assert_eq!(
        fs::read_to_string(whole.join("sweep-plan.toml")).unwrap(),
        fs::read_to_string(split.join("sweep-plan.toml")).unwrap()
    );
}

#[test]
fn merge_needs_a_sweep_directory() {
    let tmp = TempDir::new().unwrap();
    let (code, _, stderr) = merge(tmp.path());
    assert_eq!(code, 2);
    assert!(stderr.contains("sweep-plan.toml"), "{stderr}");
}

#[test]
fn rerun_skips_completed_runs_and_force_reruns_them() {
    let tmp = TempDir::new().unwrap();
    let file = sweep_file(tmp.path(), "grid.toml", GRID);
    let out = tmp.path().join("out");
    assert_eq!(sweep(&file, &out, &["-q"]).0, 0);
    let h5 = mtimes(&out, ".h5");
    let results = mtimes(&out, ".result.toml");
    assert_eq!(h5.len(), 6);
    let summary = without_wall_time(&out.join("summary.csv"));

    tick();
    let (code, stdout, _) = sweep(&file, &out, &[]);
    assert_eq!(code, 0);
    assert!(stdout.contains("(0 run now, 6 already done)"), "{stdout}");
    assert_eq!(mtimes(&out, ".h5"), h5, "no file may be rewritten");
    assert_eq!(mtimes(&out, ".result.toml"), results);
    assert_eq!(without_wall_time(&out.join("summary.csv")), summary);

    // A run interrupted before its end has no result file: only it runs again.
    let lost = "slope_deg=22__erodible_bed=0.0014";
    fs::remove_file(out.join(format!("{lost}.result.toml"))).unwrap();
    tick();
    let (code, stdout, _) = sweep(&file, &out, &[]);
    assert_eq!(code, 0);
    assert!(stdout.contains("(1 run now, 5 already done)"), "{stdout}");
    let after = mtimes(&out, ".h5");
    for (name, t) in &after {
        assert_eq!(*t != h5[name], name == &format!("{lost}.h5"), "{name}");
    }
    assert_eq!(without_wall_time(&out.join("summary.csv")), summary);

    // A different scenario (here a --set) is not "already done".
    tick();
    let (code, stdout, _) = sweep(&file, &out, &["--set", "time.cfl=0.4"]);
    assert_eq!(code, 0);
    assert!(stdout.contains("(6 run now, 0 already done)"), "{stdout}");

    // --force runs everything again.
    let before = mtimes(&out, ".h5");
    tick();
    let (code, stdout, _) = sweep(&file, &out, &["--set", "time.cfl=0.4", "--force"]);
    assert_eq!(code, 0);
    assert!(stdout.contains("(6 run now, 0 already done)"), "{stdout}");
    let after = mtimes(&out, ".h5");
    assert!(after.iter().all(|(n, t)| *t != before[n]));
}

#[test]
fn a_failing_run_is_recorded_and_the_others_go_on() {
    let tmp = TempDir::new().unwrap();
    // A run of 1e9 s that no stop rule can end is valid input, but at the CFL step of
    // about 2e-3 s it would take 5e11 steps: it fails at its first step.
    let file = tmp.path().join("fail.toml");
    let text = format!(
        "scenario = {:?}\nset = [\"domain.cells=60\"]\n[[zip]]\ntime.t_end = [0.4, 1e9, 0.3]\noutput.every = [0.1, 1e9, 0.1]\ntime.stop_at_rest = [true, false, true]\ntime.stop_when_settled = [true, false, true]\n",
        collapse().display().to_string()
    );
    fs::write(&file, text).unwrap();
    let out = tmp.path().join("out");
    let (code, _, stderr) = sweep(&file, &out, &["--jobs", "2"]);
    assert_eq!(code, 1, "{stderr}");
    assert!(stderr.contains("1 of 3 runs did not complete"), "{stderr}");
    let status = column(&out.join("summary.csv"), "status");
    assert!(
        ["stopped_at_rest", "settled", "completed"].contains(&status[0].as_str()),
        "{status:?}"
    );
    assert!(
        status[1].starts_with("failed: at the CFL step"),
        "{status:?}"
    );
    assert!(
        ["stopped_at_rest", "settled", "completed"].contains(&status[2].as_str()),
        "{status:?}"
    );
    let failed = column(&out.join("summary.csv"), "run")[1].clone();
    let record = fs::read_to_string(out.join(format!("{failed}.result.toml"))).unwrap();
    assert!(
        record.contains("status = \"failed: at the CFL step"),
        "{record}"
    );

    // Re-running retries the failed run only (and it fails again).
    let (code, stdout, _) = sweep(&file, &out, &[]);
    assert_eq!(code, 1);
    assert!(stdout.contains("(1 run now, 2 already done)"), "{stdout}");
}

#[test]
fn an_unwritable_output_file_fails_that_run_only() {
    let tmp = TempDir::new().unwrap();
    let file = sweep_file(tmp.path(), "grid.toml", GRID);
    let out = tmp.path().join("out");
    // A directory where one run's HDF5 file must go (works even for root).
    let blocked = "slope_deg=16__erodible_bed=0.0025";
    fs::create_dir_all(out.join(format!("{blocked}.h5"))).unwrap();
    let (code, _, stderr) = sweep(&file, &out, &["-q"]);
    assert_eq!(code, 1, "{stderr}");
    let runs = column(&out.join("summary.csv"), "run");
    let status = column(&out.join("summary.csv"), "status");
    for (run, status) in runs.iter().zip(&status) {
        if run == blocked {
            assert!(
                status.starts_with("failed: cannot write output file"),
                "{status}"
            );
        } else {
            assert!(!status.starts_with("failed"), "{run}: {status}");
        }
    }
}

#[test]
fn one_and_two_jobs_give_identical_numbers() {
    let tmp = TempDir::new().unwrap();
    let file = sweep_file(
        tmp.path(),
        "grid.toml",
        "[axes]\ndomain.slope_deg = [0, 9.78, 16, 19, 22]\ninitial.erodible_bed = [0, 1.82e-3]\n",
    );
    let one = tmp.path().join("one");
    let two = tmp.path().join("two");
    assert_eq!(sweep(&file, &one, &["-q", "--jobs", "1"]).0, 0);
    assert_eq!(sweep(&file, &two, &["-q", "--jobs", "2"]).0, 0);
    let a = without_wall_time(&one.join("summary.csv"));
    assert_eq!(a.len(), 11);
    assert_eq!(a, without_wall_time(&two.join("summary.csv")));
}

#[test]
fn command_line_errors_exit_2() {
    let tmp = TempDir::new().unwrap();
    let file = sweep_file(tmp.path(), "grid.toml", GRID);
    let out = tmp.path().join("out");
    for args in [
        vec!["--shard", "4/4"],
        vec!["--shard", "x"],
        vec!["--jobs", "0"],
    ] {
        assert_eq!(sweep(&file, &out, &args).0, 2, "{args:?}");
    }
    assert_eq!(sweep(&tmp.path().join("none.toml"), &out, &[]).0, 2);
    granflow().arg("sweep").assert().code(2);
    assert!(!out.exists());
}

#[test]
fn shipped_sweeps_expand_and_run() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/sweeps");
    let tmp = TempDir::new().unwrap();
    for (file, runs) in [
        ("slopes.toml", 5),
        ("erodible_bed.toml", 12),
        ("dilatancy.toml", 15),
    ] {
        let out = tmp.path().join(file);
        let (code, stdout, stderr) = sweep(
            &root.join(file),
            &out,
            &[
                "--set",
                "domain.cells=40",
                "--set",
                "time.t_end=0.05",
                "--set",
                "output.every=0.05",
            ],
        );
        assert_eq!(code, 0, "{file}: {stdout}\n{stderr}");
        assert_eq!(
            column(&out.join("summary.csv"), "run").len(),
            runs,
            "{file}"
        );
    }
    let slopes = column(
        &tmp.path().join("slopes.toml/summary.csv"),
        "domain.slope_deg",
    );
    assert_eq!(slopes, ["0", "9.78", "16", "19", "22"]);
}

/// Runs are handed out the expected-longest first (the steepest slope here), while the
/// summary keeps the sweep order and the names.
#[test]
fn the_expected_longest_run_starts_first_and_the_summary_keeps_its_order() {
    let dir = TempDir::new().unwrap();
    let file = sweep_file(
        dir.path(),
        "slopes.toml",
        "[axes]\ndomain.slope_deg = [0, 9.78, 16, 19, 22]\n",
    );
    let out = dir.path().join("out");
    let (code, _, stderr) = sweep(&file, &out, &["--jobs", "1"]);
    assert_eq!(code, 0, "{stderr}");
    // One job: runs finish in the order they started.
    let finished: Vec<&str> = stderr
        .lines()
        .filter(|l| l.starts_with('['))
        .map(|l| l.split_whitespace().nth(1).unwrap().trim_end_matches(':'))
        .collect();
    assert_eq!(
        finished,
        [
            "slope_deg=22",
            "slope_deg=19",
            "slope_deg=16",
            "slope_deg=9.78",
            "slope_deg=0"
        ],
        "{stderr}"
    );
    let summary = fs::read_to_string(out.join("summary.csv")).unwrap();
    let runs: Vec<&str> = summary
        .lines()
        .skip(1)
        .map(|l| l.split(',').nth(1).unwrap())
        .collect();
    assert_eq!(
        runs,
        [
            "slope_deg=0",
            "slope_deg=9.78",
            "slope_deg=16",
            "slope_deg=19",
            "slope_deg=22"
        ]
    );
}

#[test]
fn resume_reruns_a_run_whose_file_is_another_runs_or_damaged() {
    let tmp = TempDir::new().unwrap();
    let file = sweep_file(
        tmp.path(),
        "slopes.toml",
        "[axes]\ndomain.slope_deg = [16, 19, 22]\n",
    );
    let out = tmp.path().join("out");
    assert_eq!(sweep(&file, &out, &["-q"]).0, 0);
    let runout = column(&out.join("summary.csv"), "runout");
    assert!(runout[0] != runout[2], "{runout:?}");
    let h5 = |slope: &str| out.join(format!("slope_deg={slope}.h5"));
    // The 16° file replaced by the 22° one (another run, status "completed" too), the
    // 19° file scrambled (its bytes reversed), the 22° one cut in half.
    fs::copy(h5("22"), h5("16")).unwrap();
    let mut bytes = fs::read(h5("19")).unwrap();
    bytes.reverse();
    fs::write(h5("19"), bytes).unwrap();
    let full = fs::read(h5("22")).unwrap();
    fs::write(h5("22"), &full[..full.len() / 2]).unwrap();
    let (code, stdout, stderr) = sweep(&file, &out, &[]);
    assert_eq!(code, 0, "{stderr}");
    assert!(stdout.contains("(3 run now, 0 already done)"), "{stdout}");
    // The files are each run's own again: merge reports the numbers of the first sweep.
    fs::remove_file(out.join("summary.csv")).unwrap();
    let (code, _, stderr) = merge(&out);
    assert_eq!(code, 0, "{stderr}");
    assert_eq!(column(&out.join("summary.csv"), "runout"), runout);
    let (code, stdout, _) = sweep(&file, &out, &[]);
    assert_eq!(code, 0);
    assert!(stdout.contains("(0 run now, 3 already done)"), "{stdout}");
}
