//! Hostile surroundings of the files granflow writes: links made to an output while it
//! is written, files planted at the names of its companions (lock, reserve, CSV), files
//! that only look like granflow's, a disk that fills, a process killed with `kill -9`.
//! Nothing a user did not ask to replace is touched, and nothing is left behind.

use std::fs;
use std::path::Path;
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use super::hostile::{bin, run_in, scenario, MINUTE};

/// `granflow run collapse.toml` for `t_end` seconds (never stopping at rest) into
/// `output`, with `extra` arguments.
fn collapse_args(t_end: &str, output: &str, extra: &[&str]) -> Vec<String> {
    let mut args: Vec<String> = [
        "run",
        scenario("collapse.toml").to_str().unwrap(),
        "-q",
        "--set",
        &format!("time.t_end={t_end}"),
        "--set",
        "time.stop_at_rest=false",
        "-o",
        output,
    ]
    .iter()
    .map(|s| s.to_string())
    .collect();
    args.extend(extra.iter().map(|s| s.to_string()));
    args
}

fn strs(args: &[String]) -> Vec<&str> {
    args.iter().map(String::as_str).collect()
}

/// A long run into `d/output`, returned once it holds its lock (its lock file is there
/// and describes it).
fn long_run(d: &Path, output: &str) -> Child {
    let child = Command::new(bin())
        .args(collapse_args("1000", output, &[]))
        .current_dir(d)
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let lock = d.join(format!("{output}.lock"));
    let start = Instant::now();
    while !fs::read_to_string(&lock).is_ok_and(|t| t.starts_with("pid = ")) {
        assert!(start.elapsed() < MINUTE, "the long run never locked");
        std::thread::sleep(Duration::from_millis(20));
    }
    child
}

/// A tmpfs of `size` (e.g. "3m") mounted on a temporary directory, unmounted on drop;
/// `None` (with a message saying the test is skipped) where mounting is refused.
struct SmallDisk {
    dir: tempfile::TempDir,
}

impl SmallDisk {
    fn mount(size: &str, test: &str) -> Option<SmallDisk> {
        let dir = tempfile::tempdir().unwrap();
        let mounted = Command::new("mount")
            .args(["-t", "tmpfs", "-o", &format!("size={size}"), "tmpfs"])
            .arg(dir.path())
            .stderr(Stdio::null())
            .status()
            .is_ok_and(|s| s.success());
        if !mounted {
            eprintln!("SKIPPED: {test} (mounting a tmpfs is not permitted here)");
            return None;
        }
        Some(SmallDisk { dir })
    }

    fn path(&self) -> &Path {
        self.dir.path()
    }

    /// Fills the disk but for about `left` bytes: writes until it is full, then gives
    /// `left` back.
    fn fill_leaving(&self, left: u64) {
        use std::io::Write;
        let path = self.path().join("filler");
        let mut file = fs::OpenOptions::new()
            .create(true)
            .append(true)
            .open(&path)
            .unwrap();
        let block = vec![1u8; 4096];
        while file.write_all(&block).and_then(|()| file.flush()).is_ok() {}
        let len = fs::metadata(&path).unwrap().len();
        file.set_len(len.saturating_sub(left)).unwrap();
    }
}

impl Drop for SmallDisk {
    fn drop(&mut self) {
        let _ = Command::new("umount").arg(self.dir.path()).status();
    }
}

#[cfg(unix)]
#[test]
fn a_hard_link_made_after_the_run_started_shares_its_lock() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let mut long = long_run(d, "a.h5");
    // The link is made while a.h5 has one name: no lock of a name can see it.
    fs::hard_link(d.join("a.h5"), d.join("c.h5")).unwrap();
    let (code, stderr) = run_in(d, &strs(&collapse_args("0.01", "c.h5", &[])), MINUTE);
    long.kill().unwrap();
    long.wait().unwrap();
    assert_eq!(code, 2, "{stderr}");
    assert!(stderr.contains("in use"), "{stderr}");
}

#[cfg(unix)]
#[test]
fn planted_lock_and_reserve_files_are_neither_followed_nor_replaced() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let precious = "a user's data\n";
    let run = |extra: &[&str]| run_in(d, &strs(&collapse_args("0.01", "a.h5", extra)), MINUTE);
    // A symbolic link at the lock file's name, and a file granflow did not write.
    fs::write(d.join("victim"), precious).unwrap();
    std::os::unix::fs::symlink("victim", d.join("a.h5.lock")).unwrap();
    let (code, stderr) = run(&[]);
    assert_eq!(code, 2, "{stderr}");
    assert!(
        stderr.contains("a.h5.lock") && stderr.contains("symbolic link"),
        "{stderr}"
    );
    assert_eq!(fs::read_to_string(d.join("victim")).unwrap(), precious);
    fs::remove_file(d.join("a.h5.lock")).unwrap();
    fs::write(d.join("a.h5.lock"), precious).unwrap();
    let (code, stderr) = run(&["--force"]);
    assert_eq!(code, 2, "{stderr}");
    assert!(stderr.contains("not a granflow lock file"), "{stderr}");
    assert_eq!(fs::read_to_string(d.join("a.h5.lock")).unwrap(), precious);
    fs::remove_file(d.join("a.h5.lock")).unwrap();
    // A symbolic link at the reserve's name: refused; with --force the link goes,
    // never what it points to.
    std::os::unix::fs::symlink("victim", d.join("a.h5.reserve")).unwrap();
    let (code, stderr) = run(&[]);
    assert_eq!(code, 2, "{stderr}");
    assert!(stderr.contains("a.h5.reserve"), "{stderr}");
    assert_eq!(fs::read_to_string(d.join("victim")).unwrap(), precious);
    let (code, stderr) = run(&["--force"]);
    assert_eq!(code, 0, "{stderr}");
    assert_eq!(fs::read_to_string(d.join("victim")).unwrap(), precious);
    assert!(fs::symlink_metadata(d.join("a.h5.reserve")).is_err());
    // A reserve of zeros left by an earlier run is taken over.
    fs::write(d.join("a.h5.reserve"), vec![0u8; 65536]).unwrap();
    let (code, stderr) = run(&[]);
    assert_eq!(code, 0, "{stderr}");
    assert!(fs::symlink_metadata(d.join("a.h5.reserve")).is_err());
}

#[test]
fn only_an_hdf5_file_with_granflow_s_root_attribute_is_replaced() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // A user's file that copied a run's attributes onto one of its groups.
    {
        let f = rust_hdf5::H5File::create(d.join("user.h5")).unwrap();
        let g = f.create_group("copied_from_a_run").unwrap();
        g.set_attr_string("granflow_version", "0.1.0").unwrap();
        g.set_attr_string("model", "savage_hutter").unwrap();
    }
    let theirs = fs::read(d.join("user.h5")).unwrap();
    let (code, stderr) = run_in(d, &strs(&collapse_args("0.01", "user.h5", &[])), MINUTE);
    assert_eq!(code, 2, "{stderr}");
    assert!(stderr.contains("did not write"), "{stderr}");
    assert_eq!(fs::read(d.join("user.h5")).unwrap(), theirs);
    // An HDF5 file whose root carries the mark more than 4 MiB from both ends (as a
    // large raster run's does) is granflow's, and is replaced.
    {
        let f = rust_hdf5::H5File::create(d.join("big.h5")).unwrap();
        let zeros = vec![0.0f64; 700_000];
        f.new_dataset::<f64>()
            .shape([zeros.len()])
            .create("a")
            .unwrap()
            .write_raw(&zeros)
            .unwrap();
        f.set_attr_string("granflow_version", "0.1.0").unwrap();
        f.close().unwrap();
        // Appended to later, as a run's file is at every snapshot.
        let f = rust_hdf5::H5File::options()
            .no_locking()
            .open_rw(d.join("big.h5"))
            .unwrap();
        f.new_dataset::<f64>()
            .shape([zeros.len()])
            .create("b")
            .unwrap()
            .write_raw(&zeros)
            .unwrap();
        f.close().unwrap();
    }
    let bytes = fs::read(d.join("big.h5")).unwrap();
    let at = bytes
        .windows(16)
        .position(|w| w == b"granflow_version")
        .expect("the mark is in the file");
    assert!(
        at > 4 << 20 && bytes.len() - at > 4 << 20,
        "the mark at {at} of {} bytes",
        bytes.len()
    );
    let (code, stderr) = run_in(d, &strs(&collapse_args("0.01", "big.h5", &[])), MINUTE);
    assert_eq!(code, 0, "{stderr}");
}

#[cfg(unix)]
#[test]
fn kill_9_leaves_no_reserve_beside_the_output() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let mut long = long_run(d, "a.h5");
    long.kill().unwrap(); // SIGKILL
    long.wait().unwrap();
    assert!(
        fs::symlink_metadata(d.join("a.h5.reserve")).is_err(),
        "a.h5.reserve left behind"
    );
    // The stale lock file is taken over, and removed at the end of the next run.
    let (code, stderr) = run_in(d, &strs(&collapse_args("0.01", "a.h5", &[])), MINUTE);
    assert_eq!(code, 0, "{stderr}");
    assert!(!d.join("a.h5.lock").exists());
}

#[cfg(unix)]
#[test]
fn a_dangling_link_at_a_companion_s_name_is_refused_before_anything_is_written() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::os::unix::fs::symlink("missing/elsewhere.csv", d.join("RUN_front.csv")).unwrap();
    let (code, stderr) = run_in(d, &strs(&collapse_args("0.01", "RUN.h5", &[])), MINUTE);
    assert_eq!(code, 2, "{stderr}");
    assert!(stderr.contains("RUN_front.csv"), "{stderr}");
    assert!(!d.join("RUN.h5").exists());
    assert!(!d.join("RUN.h5.lock").exists());
}

#[cfg(unix)]
#[test]
fn a_full_disk_leaves_no_empty_lock_file() {
    let Some(disk) = SmallDisk::mount("3m", "a_full_disk_leaves_no_empty_lock_file") else {
        return;
    };
    disk.fill_leaving(0);
    let out = disk.path().join("RUN.h5");
    let (code, stderr) = run_in(
        disk.path(),
        &strs(&collapse_args("0.01", out.to_str().unwrap(), &[])),
        MINUTE,
    );
    assert_ne!(code, 0, "{stderr}");
    let left: Vec<_> = fs::read_dir(disk.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n != "filler" && n != "lost+found")
        .collect();
    assert!(left.is_empty(), "left behind: {left:?}; {stderr}");
}

/// A cylinder collapsing on a flat bed, `nx` × `ny` square cells of 2.4/`nx` m, no CRS.
fn radial(nx: usize, ny: usize, t_end: &str) -> String {
    let dx = 2.4 / nx as f64;
    format!(
        r#"[domain]
x_min = -1.2
x_max = 1.2
y_min = 0
y_max = {}
cells = [{nx}, {ny}]
coordinates = "cartesian"

[rheology]
law = "coulomb"
mu_deg = 27.0

[initial]
h = "if(x^2 + (y - {})^2 < 0.3^2, 0.4, 0)"

[time]
t_end = {t_end}
stop_at_rest = false

[output]
every = 0.1
"#,
        dx * ny as f64,
        0.5 * dx * ny as f64
    )
}

/// Runs `text` as `d/radial.toml` into `d/radial.h5`.
fn run_radial(d: &Path, text: &str) {
    fs::write(d.join("radial.toml"), text).unwrap();
    let (code, stderr) = run_in(
        d,
        &[
            "run",
            "radial.toml",
            "-q",
            "-o",
            "radial.h5",
            "--threads",
            "1",
        ],
        MINUTE,
    );
    assert_eq!(code, 0, "{stderr}");
}

/// The files of `dir` (name → bytes).
fn contents(dir: &Path) -> std::collections::BTreeMap<String, Vec<u8>> {
    fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap())
        .filter(|e| e.file_type().unwrap().is_file())
        .map(|e| {
            (
                e.file_name().to_string_lossy().into_owned(),
                fs::read(e.path()).unwrap(),
            )
        })
        .collect()
}

#[test]
fn an_export_on_a_full_disk_leaves_the_previous_export_whole() {
    let Some(disk) = SmallDisk::mount(
        "3m",
        "an_export_on_a_full_disk_leaves_the_previous_export_whole",
    ) else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let out = disk.path().join("export");
    let o = out.to_str().unwrap();
    // A first export of a run that barely moved: short numbers.
    run_radial(d, &radial(200, 100, "0.01"));
    let (code, stderr) = run_in(
        d,
        &["export", "radial.h5", "--format", "asc", "-o", o],
        MINUTE,
    );
    assert_eq!(code, 0, "{stderr}");
    let good = contents(&out);
    assert_eq!(good.len(), 5, "{:?}", good.keys());
    // The run again, longer: its grids hold longer numbers and need more room than
    // the disk has left.
    run_radial(d, &radial(200, 100, "0.3"));
    disk.fill_leaving(64 * 1024);
    let (code, stderr) = run_in(
        d,
        &["export", "radial.h5", "--format", "asc", "-o", o],
        MINUTE,
    );
    assert_eq!(code, 1, "{stderr}");
    assert!(
        stderr.contains("No space left") || stderr.contains("space"),
        "{stderr}"
    );
    let after = contents(&out);
    assert_eq!(
        after.keys().collect::<Vec<_>>(),
        good.keys().collect::<Vec<_>>(),
        "files left: {:?}",
        after.keys()
    );
    assert!(after == good, "the previous export was changed");
}

#[test]
fn export_replaces_only_its_own_files_and_keeps_a_user_s_prj() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    run_radial(d, &radial(24, 16, "0.2"));
    let export =
        |extra: &[&str]| run_in(d, &[&["export", "radial.h5"][..], extra].concat(), MINUTE);
    // The run has no CRS: a user's .prj beside the grid is neither removed nor left to
    // give the grid a CRS.
    let wkt = "PROJCS[\"a user's projection\"]\n";
    fs::write(d.join("radial_pft.prj"), wkt).unwrap();
    let (code, stderr) = export(&["--format", "asc"]);
    assert_eq!(code, 2, "{stderr}");
    assert!(stderr.contains("radial_pft.prj"), "{stderr}");
    assert_eq!(fs::read_to_string(d.join("radial_pft.prj")).unwrap(), wkt);
    assert!(!d.join("radial_pft.asc").exists());
    fs::remove_file(d.join("radial_pft.prj")).unwrap();
    // A user's GeoTIFF of the same name is not replaced without --force.
    let theirs = b"II*\0 a user's raster".to_vec();
    fs::write(d.join("radial_pfv.tif"), &theirs).unwrap();
    let (code, stderr) = export(&[]);
    assert_eq!(code, 2, "{stderr}");
    assert!(
        stderr.contains("radial_pfv.tif") && stderr.contains("--force"),
        "{stderr}"
    );
    assert_eq!(fs::read(d.join("radial_pfv.tif")).unwrap(), theirs);
    assert!(
        !d.join("radial_pft.tif").exists(),
        "written before the refusal"
    );
    let (code, stderr) = export(&["--force"]);
    assert_eq!(code, 0, "{stderr}");
    assert_ne!(fs::read(d.join("radial_pfv.tif")).unwrap(), theirs);
    // Its own earlier exports are replaced, in every format.
    for format in ["geotiff", "asc", "netcdf"] {
        for _ in 0..2 {
            let (code, stderr) = export(&["--format", format]);
            assert_eq!(code, 0, "{format}: {stderr}");
        }
    }
    // Also those of the same run on another grid.
    run_radial(d, &radial(30, 20, "0.2"));
    for format in ["geotiff", "asc", "netcdf"] {
        let (code, stderr) = export(&["--format", format]);
        assert_eq!(code, 0, "{format} on another grid: {stderr}");
    }
    let hidden: Vec<_> = fs::read_dir(d)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with('.'))
        .collect();
    assert!(hidden.is_empty(), "temporary files left: {hidden:?}");
}

#[cfg(unix)]
#[test]
fn the_maps_of_a_killed_run_are_exported_with_a_warning() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    fs::write(d.join("radial.toml"), radial(24, 16, "1000")).unwrap();
    let mut child = Command::new(bin())
        .args([
            "run",
            "radial.toml",
            "-q",
            "-o",
            "radial.h5",
            "--threads",
            "1",
        ])
        .current_dir(d)
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    // Exported once the run has written maps (at its first snapshots).
    let start = Instant::now();
    let (code, stderr) = loop {
        let got = run_in(d, &["export", "radial.h5", "--fields", "deposit"], MINUTE);
        if got.0 == 0 || start.elapsed() > MINUTE {
            break got;
        }
        std::thread::sleep(Duration::from_millis(100));
    };
    child.kill().unwrap(); // SIGKILL: the file keeps status `unfinished`
    child.wait().unwrap();
    assert_eq!(code, 0, "{stderr}");
    assert!(
        stderr.contains("did not end normally"),
        "while running: {stderr}"
    );
    let (code, stderr) = run_in(d, &["export", "radial.h5", "--fields", "deposit"], MINUTE);
    assert_eq!(code, 0, "{stderr}");
    assert!(
        stderr.contains("did not end normally") && stderr.contains("killed"),
        "{stderr}"
    );
    // A finished run's export says nothing of its status (only that it has no CRS).
    run_radial(d, &radial(24, 16, "0.2"));
    let (code, stderr) = run_in(d, &["export", "radial.h5", "--fields", "deposit"], MINUTE);
    assert_eq!(code, 0, "{stderr}");
    assert!(
        !stderr.contains("did not end normally") && !stderr.contains("status"),
        "{stderr}"
    );
}

#[test]
fn progress_intervals_beyond_reason_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    for bad in ["inf", "1e20", "-5", "NaN"] {
        let every = format!("--progress-every={bad}");
        let args = collapse_args("0.01", "a.h5", &["--progress", "lines", &every]);
        let (code, stderr) = run_in(dir.path(), &strs(&args), MINUTE);
        assert_eq!(code, 2, "{bad}: {stderr}");
        assert!(stderr.contains("--progress-every"), "{bad}: {stderr}");
    }
    let args = collapse_args(
        "0.01",
        "a.h5",
        &["--progress", "lines", "--progress-every", "0"],
    );
    assert_eq!(run_in(dir.path(), &strs(&args), MINUTE).0, 0);
}

#[test]
fn a_thread_count_beyond_the_machine_is_bounded_with_a_note() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    fs::write(d.join("radial.toml"), radial(24, 16, "0.05")).unwrap();
    let cores = std::thread::available_parallelism().map_or(1, usize::from);
    let (code, stderr) = run_in(
        d,
        &[
            "run",
            "radial.toml",
            "-q",
            "-o",
            "radial.h5",
            "--threads",
            "5000",
        ],
        MINUTE,
    );
    assert_eq!(code, 0, "{stderr}");
    assert!(
        stderr.contains("--threads 5000") && stderr.contains(&format!("using {cores}")),
        "{stderr}"
    );
}

#[test]
fn an_error_quoting_a_megabyte_key_is_cut() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let key = "k".repeat(1 << 20);
    let text = format!(
        "{}\n[time]\n{key} = 1\n",
        "[domain]\nx_min = 0\nx_max = 1\ncells = 10\n"
    );
    fs::write(d.join("s.toml"), text).unwrap();
    // Read as it comes (a message of megabytes would fill the pipe).
    let out = Command::new(bin())
        .args(["check", "s.toml"])
        .current_dir(d)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(
        out.status.code(),
        Some(2),
        "{}",
        &stderr[..stderr.len().min(2000)]
    );
    assert!(stderr.len() < 4000, "{} bytes of error", stderr.len());
    assert!(stderr.contains("characters cut"), "{stderr}");
}

#[cfg(unix)]
#[test]
fn a_failed_write_to_stdout_is_not_a_success() {
    // stdout on a full device. (A closed stdout cannot be told from /dev/null: the
    // Rust runtime opens /dev/null in its place before `main`.)
    {
        let redirect = "> /dev/full";
        let status = Command::new("sh")
            .arg("-c")
            .arg(format!("exec \"$0\" scenarios {redirect}"))
            .arg(bin())
            .stderr(Stdio::piped())
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&status.stderr);
        assert_eq!(status.status.code(), Some(1), "{redirect}: {stderr}");
        assert!(
            stderr.contains("cannot write to stdout"),
            "{redirect}: {stderr}"
        );
    }
    // A reader that went away is not an error.
    let status = Command::new("sh")
        .arg("-c")
        .arg("\"$0\" scenarios | head -c 1 > /dev/null")
        .arg(bin())
        .status()
        .unwrap();
    assert!(status.success());
}

#[test]
fn a_whole_sweep_and_a_shard_never_share_a_directory() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let collapse = scenario("collapse.toml");
    let sweep_file = |name: &str, t_end: &str| {
        fs::write(
            d.join(name),
            format!(
                "scenario = {:?}\nset = [\"time.t_end={t_end}\", \"time.stop_at_rest=false\"]\n[axes]\ndomain.slope_deg = [30, 31]\n",
                collapse.display().to_string()
            ),
        )
        .unwrap();
    };
    sweep_file("long.toml", "1000");
    sweep_file("short.toml", "0.01");
    for (first, second) in [
        (&[][..], &["--shard", "0/2"][..]),
        (&["--shard", "1/2"][..], &[][..]),
    ] {
        let out = d.join(format!("out{}", first.len()));
        let o = out.to_str().unwrap();
        let mut long = Command::new(bin())
            .args([&["sweep", "long.toml", "-q", "-o", o][..], first].concat())
            .current_dir(d)
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .unwrap();
        let start = Instant::now();
        while !fs::read_to_string(out.join("sweep.lock")).is_ok_and(|t| t.starts_with("pid = ")) {
            assert!(start.elapsed() < MINUTE, "the long sweep never locked");
            std::thread::sleep(Duration::from_millis(20));
        }
        let (code, stderr) = run_in(
            d,
            &[&["sweep", "short.toml", "-q", "-o", o][..], second].concat(),
            MINUTE,
        );
        long.kill().unwrap();
        long.wait().unwrap();
        assert_eq!(code, 2, "{first:?} then {second:?}: {stderr}");
        assert!(stderr.contains("in use"), "{stderr}");
    }
    // Two shards share it.
    let out = d.join("shards");
    let o = out.to_str().unwrap();
    let mut long = Command::new(bin())
        .args(["sweep", "long.toml", "-q", "-o", o, "--shard", "0/2"])
        .current_dir(d)
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let start = Instant::now();
    while !out.join("sweep.shard-0-of-2.lock").exists() {
        assert!(start.elapsed() < MINUTE, "the shard never locked");
        std::thread::sleep(Duration::from_millis(20));
    }
    let (code, stderr) = run_in(
        d,
        &["sweep", "short.toml", "-q", "-o", o, "--shard", "1/2"],
        MINUTE,
    );
    long.kill().unwrap();
    long.wait().unwrap();
    assert_eq!(code, 0, "{stderr}");
}

#[test]
fn per_step_records_beyond_the_limit_are_warned_about_at_the_start() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // 200 gauges recorded at every step: 12.8 kB a step, past 1 GiB after some 80 000
    // steps of the hundreds of thousands to t_end.
    let gauges: Vec<String> = (0..200).map(|k| format!("{}", 0.01 * k as f64)).collect();
    let gauges = format!("output.gauges=[{}]", gauges.join(","));
    let mut child = Command::new(bin())
        .args(collapse_args(
            "1000",
            "a.h5",
            &["--set", &gauges, "--progress", "none"],
        ))
        .current_dir(d)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let stderr = child.stderr.take().unwrap();
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        use std::io::BufRead;
        for line in std::io::BufReader::new(stderr)
            .lines()
            .map_while(Result::ok)
        {
            if tx.send(line).is_err() {
                break;
            }
        }
    });
    // Other warnings (the run's length) may come first.
    let start = Instant::now();
    let mut warned = None;
    while let Some(left) = MINUTE.checked_sub(start.elapsed()) {
        match rx.recv_timeout(left) {
            Ok(line) if line.contains("output limit") => {
                warned = Some(line);
                break;
            }
            Ok(_) => {}
            Err(_) => break,
        }
    }
    child.kill().unwrap();
    child.wait().unwrap();
    let line = warned.expect("no warning of the output limit within a minute");
    assert!(
        line.contains("warning: at the pace") && line.contains("output.gauge_every"),
        "{line}"
    );
}
