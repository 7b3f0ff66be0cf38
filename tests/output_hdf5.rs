//! The HDF5 and CSV sinks against the output contract (`docs/output-format.md`):
//! synthetic runs written through the sinks and read back with rust-hdf5's reader.
//!
//! rust-hdf5 0.7.9 reads numeric attributes of datasets but not of groups or of the
//! root (only their names, and string values), so numeric root and `/summary` values
//! are checked through h5py in `python_reader_accepts_the_file`, which runs when
//! a Python with h5py and numpy is found (`common::python_with_h5py`; SKIPPED otherwise).
//! `GRANFLOW_KEEP_H5=path` keeps the file of `full_run_round_trips` for other checks.

use std::path::{Path, PathBuf};
use std::process::Command;

use granflow::grid::{GridSpec, LineGeometry};
use granflow::output::{
    create_run_sinks, front_csv_path, FrontCsvSink, GridData, Hdf5Sink, OutputSink, RunInfo,
    RunSummary, SnapshotView, StepRecord, FORMAT_VERSION,
};
use rust_hdf5::H5File;

const DX: f64 = 0.5;
const STEPS: usize = 10;
/// Steps after which a snapshot is taken (at the same time as the step record).
const SNAP_STEPS: [usize; 3] = [0, 4, 8];
const THRESHOLD: f64 = 1e-3;

/// A synthetic run: smooth fields with known values at every time.
struct Synth {
    nx: usize,
    nl: usize,
    nonhydrostatic: bool,
}

impl Synth {
    fn t(k: usize) -> f64 {
        k as f64 * 0.1
    }
    fn x(&self) -> Vec<f64> {
        (0..self.nx).map(|i| (i as f64 + 0.5) * DX).collect()
    }
    fn b(&self) -> Vec<f64> {
        self.x().iter().map(|x| -0.2 * x).collect()
    }
    fn h_bed(&self) -> Vec<f64> {
        (0..self.nx)
            .map(|i| if i > 4 { 0.05 } else { 0.0 })
            .collect()
    }
    fn h(&self, t: f64) -> Vec<f64> {
        self.x().iter().map(|x| 1.0 + 0.5 * (x - t).sin()).collect()
    }
    /// Layer-major, α·nx + i.
    fn layered(&self, t: f64, nl: usize, nx: usize, scale: f64) -> Vec<f64> {
        (0..nl * nx)
            .map(|k| scale * ((k / nx) as f64 * 10.0 + (k % nx) as f64 + t))
            .collect()
    }
    fn u(&self, t: f64) -> Vec<f64> {
        self.layered(t, self.nl, self.nx, 1.0)
    }
    fn w(&self, t: f64) -> Vec<f64> {
        self.layered(t, self.nl, self.nx, -0.01)
    }
    fn p_nh(&self, t: f64) -> Vec<f64> {
        self.layered(t, self.nl + 1, self.nx + 1, 3.0)
    }
    fn record(&self, k: usize) -> StepRecord {
        let t = Self::t(k);
        StepRecord {
            t,
            dt: 0.1,
            mass: self.h(t).iter().sum::<f64>() * DX,
            kinetic_energy: 0.5 * t * t,
            max_speed: 2.0 * t,
            front_x: if k == 0 { f64::NAN } else { 1.0 + t },
        }
    }
    fn info(&self) -> RunInfo {
        RunInfo {
            granflow_version: "0.1.0-test".into(),
            model: "granular".into(),
            pressure: if self.nonhydrostatic {
                "nonhydrostatic"
            } else {
                "hydrostatic"
            }
            .into(),
            layers: self.nl,
            coordinates: "local".into(),
            slope_deg: 31.5,
            scenario_toml: "[model]\nkind = \"granular\"\n# ünïcode\n".into(),
            front_threshold: THRESHOLD,
            raster: None,
        }
    }
    fn summary(&self, status: &str) -> RunSummary {
        RunSummary {
            runout: 1.25,
            stop_time: f64::NAN,
            settled_time: f64::NAN,
            settle_fraction: 1e-6,
            h_max_final: 1.5,
            t_end: Self::t(STEPS - 1),
            steps: STEPS as u64,
            wall_time_s: 0.75,
            status: status.into(),
            max_wave_amplitude: None,
            wet: None,
            spread: None,
            outflowed_fraction: 0.0,
            front_at_end_time: f64::NAN,
            max_speed_final: 0.0,
            stage_times: vec![("hyperbolic".into(), 0.5), ("friction".into(), 0.25)],
        }
    }

    fn begin(&self, sink: &mut impl OutputSink) {
        let (x, b, h_bed) = (self.x(), self.b(), self.h_bed());
        let spec = GridSpec::Line(LineGeometry::of_extent(self.nx, 0.0, self.nx as f64 * DX));
        let grid = GridData {
            spec: &spec,
            x: &x,
            y: None,
            shape: None,
            b: &b,
            h_bed: &h_bed,
        };
        sink.begin(&self.info(), &grid).unwrap();
    }

    fn snapshot(&self, sink: &mut impl OutputSink, k: usize) {
        let t = Self::t(k);
        let (h, u, w, p) = (self.h(t), self.u(t), self.w(t), self.p_nh(t));
        let nh = self.nonhydrostatic;
        sink.snapshot(&SnapshotView {
            t,
            h: &h,
            u: &u,
            v: None,
            shape: None,
            w: nh.then_some(&w[..]),
            p_nh: nh.then_some(&p[..]),
            layers: self.nl,
            extra: &[],
            layer_uv: None,
        })
        .unwrap();
    }

    /// Steps `from..to`, each followed by its snapshot when it has one.
    fn run_steps(&self, sink: &mut impl OutputSink, steps: std::ops::Range<usize>) {
        for k in steps {
            sink.step(&self.record(k)).unwrap();
            if SNAP_STEPS.contains(&k) {
                self.snapshot(sink, k);
            }
        }
    }

    fn write(&self, sink: &mut impl OutputSink) {
        self.begin(sink);
        self.run_steps(sink, 0..STEPS);
        sink.finish(&self.summary("completed")).unwrap();
    }
}

const FULL: Synth = Synth {
    nx: 7,
    nl: 2,
    nonhydrostatic: true,
};
const HYDRO: Synth = Synth {
    nx: 7,
    nl: 1,
    nonhydrostatic: false,
};

fn shape(f: &H5File, name: &str) -> Vec<usize> {
    f.dataset(name).unwrap().shape()
}

use crate::common::read_h5 as read;

fn units(f: &H5File, name: &str) -> String {
    let ds = f.dataset(name).unwrap();
    ds.attr("units").unwrap().read_string().unwrap()
}

/// Equal as bit patterns, so NaN matches NaN.
fn assert_same(got: &[f64], want: &[f64], what: &str) {
    let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
    assert_eq!(bits(got), bits(want), "{what}: {got:?} != {want:?}");
}

fn concat(parts: impl IntoIterator<Item = Vec<f64>>) -> Vec<f64> {
    parts.into_iter().flatten().collect()
}

/// Checks every dataset after `snaps` snapshots and `steps` step records.
fn check_data(f: &H5File, s: &Synth, snaps: &[usize], steps: usize) {
    let (nx, nl, nt) = (s.nx, s.nl, snaps.len());
    let ts: Vec<f64> = snaps.iter().map(|&k| Synth::t(k)).collect();
    assert_same(&read(f, "grid/x"), &s.x(), "grid/x");
    assert_same(&read(f, "grid/b"), &s.b(), "grid/b");
    assert_same(&read(f, "grid/h_bed"), &s.h_bed(), "grid/h_bed");
    assert_eq!(shape(f, "snapshots/t"), [nt]);
    assert_eq!(shape(f, "snapshots/h"), [nt, nx]);
    assert_eq!(shape(f, "snapshots/u"), [nt, nl, nx]);
    assert_same(&read(f, "snapshots/t"), &ts, "snapshots/t");
    assert_same(
        &read(f, "snapshots/h"),
        &concat(ts.iter().map(|&t| s.h(t))),
        "h",
    );
    assert_same(
        &read(f, "snapshots/u"),
        &concat(ts.iter().map(|&t| s.u(t))),
        "u",
    );
    if s.nonhydrostatic {
        assert_eq!(shape(f, "snapshots/w"), [nt, nl, nx]);
        assert_eq!(shape(f, "snapshots/p_nh"), [nt, nl + 1, nx + 1]);
        assert_same(
            &read(f, "snapshots/w"),
            &concat(ts.iter().map(|&t| s.w(t))),
            "w",
        );
        assert_same(
            &read(f, "snapshots/p_nh"),
            &concat(ts.iter().map(|&t| s.p_nh(t))),
            "p",
        );
    }
    let recs: Vec<StepRecord> = (0..steps).map(|k| s.record(k)).collect();
    let column = |f: fn(&StepRecord) -> f64| recs.iter().map(f).collect::<Vec<_>>();
    for (name, want) in [
        ("diagnostics/t", column(|r| r.t)),
        ("diagnostics/dt", column(|r| r.dt)),
        ("diagnostics/mass", column(|r| r.mass)),
        ("diagnostics/kinetic_energy", column(|r| r.kinetic_energy)),
        ("diagnostics/max_speed", column(|r| r.max_speed)),
        ("front/t", column(|r| r.t)),
        ("front/x", column(|r| r.front_x)),
    ] {
        assert_eq!(shape(f, name), [steps], "{name}");
        assert_same(&read(f, name), &want, name);
    }
}

fn check_metadata(f: &H5File, s: &Synth) {
    let mut root = f.attr_names().unwrap();
    root.sort();
    let mut want = vec![
        "coordinates",
        "format_version",
        "granflow_version",
        "layers",
        "model",
        "pressure",
        "scenario_toml",
        "slope_deg",
    ];
    want.sort();
    assert_eq!(root, want);
    let info = s.info();
    assert_eq!(
        f.attr_string("granflow_version").unwrap(),
        info.granflow_version
    );
    assert_eq!(f.attr_string("model").unwrap(), info.model);
    assert_eq!(f.attr_string("pressure").unwrap(), info.pressure);
    assert_eq!(f.attr_string("coordinates").unwrap(), info.coordinates);
    assert_eq!(f.attr_string("scenario_toml").unwrap(), info.scenario_toml);

    let mut expected_units = vec![
        ("grid/x", "m"),
        ("grid/b", "m"),
        ("grid/h_bed", "m"),
        ("snapshots/t", "s"),
        ("snapshots/h", "m"),
        ("snapshots/u", "m/s"),
        ("front/t", "s"),
        ("front/x", "m"),
        ("diagnostics/t", "s"),
        ("diagnostics/dt", "s"),
        ("diagnostics/mass", "m^2"),
        ("diagnostics/kinetic_energy", "m^4/s^2"),
        ("diagnostics/max_speed", "m/s"),
    ];
    if s.nonhydrostatic {
        expected_units.extend([("snapshots/w", "m/s"), ("snapshots/p_nh", "m^2/s^2")]);
    }
    for (name, unit) in expected_units {
        assert_eq!(units(f, name), unit, "units of {name}");
    }
    let x = f.dataset("front/x").unwrap();
    assert_eq!(
        x.attr("threshold").unwrap().read_numeric::<f64>().unwrap(),
        THRESHOLD
    );
    let front = f.root_group().group("front").unwrap();
    assert_eq!(front.attr_names().unwrap(), ["threshold"]);
}

fn check_summary(f: &H5File, status: &str) {
    let g = f.root_group().group("summary").unwrap();
    let mut names = g.attr_names().unwrap();
    names.sort();
    let mut want = vec![
        "front_at_end_time",
        "h_max_final",
        "max_speed_final",
        "outflowed_fraction",
        "runout",
        "settle_fraction",
        "settled_time",
        "status",
        "stop_reason",
        "steps",
        "stop_time",
        "t_end",
        "time_friction_s",
        "time_hyperbolic_s",
        "wall_time_s",
    ];
    want.sort();
    assert_eq!(names, want);
    assert_eq!(g.attr_string("status").unwrap(), status);
}

fn temp_h5(dir: &tempfile::TempDir, name: &str) -> PathBuf {
    dir.path().join("nested/out").join(name)
}

#[test]
fn full_run_round_trips() {
    let dir = tempfile::tempdir().unwrap();
    let path = temp_h5(&dir, "full.h5");
    let mut sink = Hdf5Sink::create(&path).unwrap();
    FULL.write(&mut sink);
    drop(sink);

    let f = H5File::open(&path).unwrap();
    check_metadata(&f, &FULL);
    check_data(&f, &FULL, &SNAP_STEPS, STEPS);
    check_summary(&f, "completed");
    let mut datasets = f.dataset_names();
    datasets.sort();
    let want = [
        "diagnostics/dt",
        "diagnostics/kinetic_energy",
        "diagnostics/mass",
        "diagnostics/max_speed",
        "diagnostics/t",
        "front/t",
        "front/x",
        "grid/b",
        "grid/h_bed",
        "grid/x",
        "snapshots/h",
        "snapshots/layer",
        "snapshots/level",
        "snapshots/p_nh",
        "snapshots/t",
        "snapshots/u",
        "snapshots/w",
        "snapshots/x",
        "snapshots/x_face",
    ];
    assert_eq!(datasets, want);

    if let Ok(keep) = std::env::var("GRANFLOW_KEEP_H5") {
        std::fs::copy(&path, &keep).unwrap();
    }
}

#[test]
fn hydrostatic_run_has_no_w_or_p_nh() {
    let dir = tempfile::tempdir().unwrap();
    let path = temp_h5(&dir, "hydro.h5");
    let mut sink = Hdf5Sink::create(&path).unwrap();
    HYDRO.write(&mut sink);
    drop(sink);

    let f = H5File::open(&path).unwrap();
    check_metadata(&f, &HYDRO);
    check_data(&f, &HYDRO, &SNAP_STEPS, STEPS);
    let names = f.dataset_names();
    assert!(
        !names
            .iter()
            .any(|n| n.ends_with("/w") || n.ends_with("p_nh")),
        "{names:?}"
    );
    assert!(f.dataset("snapshots/w").is_err());
    assert!(f.dataset("snapshots/p_nh").is_err());
}

#[test]
fn file_is_readable_after_each_snapshot() {
    let dir = tempfile::tempdir().unwrap();
    let path = temp_h5(&dir, "live.h5");
    let mut sink = Hdf5Sink::create(&path).unwrap();
    FULL.begin(&mut sink);
    FULL.run_steps(&mut sink, 0..SNAP_STEPS[1] + 1);

    // Second snapshot written, run still going: a second reader sees two snapshots
    // and every step record up to the snapshot.
    let reader = H5File::open(&path).unwrap();
    check_data(&reader, &FULL, &SNAP_STEPS[..2], SNAP_STEPS[1] + 1);
    check_metadata(&reader, &FULL);

    // A reader holding the file open does not stop the run.
    FULL.run_steps(&mut sink, SNAP_STEPS[1] + 1..STEPS);
    sink.finish(&FULL.summary("completed")).unwrap();
    drop(reader);
    let f = H5File::open(&path).unwrap();
    check_data(&f, &FULL, &SNAP_STEPS, STEPS);
}

/// Child half of `killed_run_keeps_its_snapshots`: writes two snapshots and a few
/// more steps, then dies without unwinding.
fn write_then_abort(path: &Path) -> ! {
    let mut sink = Hdf5Sink::create(path).unwrap();
    FULL.begin(&mut sink);
    FULL.run_steps(&mut sink, 0..SNAP_STEPS[1] + 3);
    std::process::abort();
}

#[test]
fn killed_run_keeps_its_snapshots() {
    if let Ok(path) = std::env::var("GRANFLOW_TEST_ABORT_CHILD") {
        write_then_abort(Path::new(&path));
    }
    let dir = tempfile::tempdir().unwrap();
    let path = temp_h5(&dir, "killed.h5");
    let child = Command::new(std::env::current_exe().unwrap())
        .args([
            "--exact",
            "output_hdf5::killed_run_keeps_its_snapshots",
            "--test-threads=1",
        ])
        .env("GRANFLOW_TEST_ABORT_CHILD", &path)
        .output()
        .unwrap();
    assert!(!child.status.success(), "child should have aborted");

    let f = H5File::open(&path).unwrap();
    check_metadata(&f, &FULL);
    // Steps after the last snapshot were only in memory.
    check_data(&f, &FULL, &SNAP_STEPS[..2], SNAP_STEPS[1] + 1);
}

#[test]
fn finish_after_a_failure_mid_run_keeps_the_last_steps() {
    let dir = tempfile::tempdir().unwrap();
    let path = temp_h5(&dir, "failed.h5");
    let mut sink = Hdf5Sink::create(&path).unwrap();
    FULL.begin(&mut sink);
    FULL.run_steps(&mut sink, 0..6);
    let status = "failed: non-finite h at x = 2.25";
    sink.finish(&FULL.summary(status)).unwrap();

    let f = H5File::open(&path).unwrap();
    check_data(&f, &FULL, &SNAP_STEPS[..2], 6);
    check_summary(&f, status);
}

#[test]
fn finish_before_begin_records_the_status() {
    let dir = tempfile::tempdir().unwrap();
    let path = temp_h5(&dir, "early.h5");
    let mut sink = Hdf5Sink::create(&path).unwrap();
    sink.finish(&FULL.summary("failed: bad scenario")).unwrap();
    let f = H5File::open(&path).unwrap();
    check_summary(&f, "failed: bad scenario");
    assert_eq!(f.attr_names().unwrap(), ["format_version"]);
    assert!(f.dataset_names().is_empty());
}

#[test]
fn bad_calls_are_errors() {
    let dir = tempfile::tempdir().unwrap();
    let path = temp_h5(&dir, "bad.h5");
    let mut sink = Hdf5Sink::create(&path).unwrap();
    assert!(sink.step(&FULL.record(0)).is_err(), "step before begin");
    FULL.begin(&mut sink);
    let h = vec![1.0; FULL.nx];
    let short_u = vec![0.0; FULL.nx];
    let view = SnapshotView {
        t: 0.0,
        h: &h,
        u: &short_u,
        v: None,
        shape: None,
        w: None,
        p_nh: None,
        layers: FULL.nl,
        extra: &[],
        layer_uv: None,
    };
    let err = sink.snapshot(&view).unwrap_err().to_string();
    assert!(err.contains("u has 7 values, expected 14"), "{err}");
    sink.finish(&FULL.summary("completed")).unwrap();
    assert!(sink.step(&FULL.record(1)).is_err(), "step after finish");
    assert!(
        sink.finish(&FULL.summary("completed")).is_err(),
        "finish twice"
    );
}

#[test]
fn optional_fields_cannot_change_between_snapshots() {
    let dir = tempfile::tempdir().unwrap();
    let path = temp_h5(&dir, "changing.h5");
    let mut sink = Hdf5Sink::create(&path).unwrap();
    FULL.begin(&mut sink);
    let (h, u, w) = (FULL.h(0.0), FULL.u(0.0), FULL.w(0.0));
    let mut view = SnapshotView {
        t: 0.0,
        h: &h,
        u: &u,
        v: None,
        shape: None,
        w: None,
        p_nh: None,
        layers: FULL.nl,
        extra: &[],
        layer_uv: None,
    };
    sink.snapshot(&view).unwrap();
    view.w = Some(&w);
    let err = sink.snapshot(&view).unwrap_err().to_string();
    assert!(err.contains("w is present but was absent"), "{err}");
}

#[test]
fn overwrites_an_existing_file() {
    let dir = tempfile::tempdir().unwrap();
    let path = temp_h5(&dir, "again.h5");
    for s in [&FULL, &HYDRO] {
        let mut sink = Hdf5Sink::create(&path).unwrap();
        s.write(&mut sink);
    }
    let f = H5File::open(&path).unwrap();
    check_data(&f, &HYDRO, &SNAP_STEPS, STEPS);
}

fn read_csv(path: &Path) -> Vec<String> {
    std::fs::read_to_string(path)
        .unwrap()
        .lines()
        .map(str::to_string)
        .collect()
}

#[test]
fn front_csv_is_flushed_at_snapshots() {
    let dir = tempfile::tempdir().unwrap();
    let path = front_csv_path(&temp_h5(&dir, "run.h5"));
    assert!(path.ends_with("nested/out/run_front.csv"));
    let mut sink = FrontCsvSink::create(&path).unwrap();
    assert_eq!(read_csv(&path), ["t,x"]);
    HYDRO.begin(&mut sink);
    HYDRO.run_steps(&mut sink, 0..SNAP_STEPS[1] + 1);
    let lines = read_csv(&path);
    assert_eq!(lines.len(), 1 + SNAP_STEPS[1] + 1);
    assert_eq!(lines[1], "0,nan");
    assert_eq!(lines[2], "0.1,1.1");

    HYDRO.run_steps(&mut sink, SNAP_STEPS[1] + 1..STEPS);
    sink.finish(&HYDRO.summary("completed")).unwrap();
    let lines = read_csv(&path);
    assert_eq!(lines.len(), 1 + STEPS);
    for (k, line) in lines[1..].iter().enumerate() {
        let rec = HYDRO.record(k);
        let (t, x) = line.split_once(',').unwrap();
        assert_eq!(t.parse::<f64>().unwrap(), rec.t);
        assert_same(&[x.parse::<f64>().unwrap()], &[rec.front_x], line);
    }
}

#[test]
fn run_sinks_write_both_files() {
    let dir = tempfile::tempdir().unwrap();
    let path = temp_h5(&dir, "both.h5");
    let mut sinks = create_run_sinks(&path).unwrap();
    FULL.write(&mut sinks);
    let f = H5File::open(&path).unwrap();
    check_data(&f, &FULL, &SNAP_STEPS, STEPS);
    assert_eq!(read_csv(&front_csv_path(&path)).len(), 1 + STEPS);
}

/// Runs `scripts/check_output.py` and an attribute check through h5py, when
/// a Python with h5py and numpy is found (SKIPPED otherwise).
#[test]
fn python_reader_accepts_the_file() {
    let Some(python) = crate::common::python_with_h5py() else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    for (s, name) in [(&FULL, "full.h5"), (&HYDRO, "hydro.h5")] {
        let path = temp_h5(&dir, name);
        let mut sink = Hdf5Sink::create(&path).unwrap();
        s.write(&mut sink);
        let stdout = crate::common::check_output_with_h5py(&path, s.nl).expect("python set");
        assert!(stdout.starts_with("OK"), "{stdout}");

        let attrs = format!(
            r#"
import sys, h5py, math
f = h5py.File(sys.argv[1], "r")
a, s = f.attrs, f["summary"].attrs
assert a["format_version"] == {FORMAT_VERSION} and a["layers"] == {nl}, dict(a)
assert a["slope_deg"] == 31.5 and a["model"] == "granular", dict(a)
assert s["runout"] == 1.25 and math.isnan(s["stop_time"]) and s["steps"] == 10, dict(s)
assert s["h_max_final"] == 1.5 and s["wall_time_s"] == 0.75 and s["t_end"] == {t_end:?}, dict(s)
assert s["time_hyperbolic_s"] == 0.5 and s["time_friction_s"] == 0.25, dict(s)
assert f["front"].attrs["threshold"] == {THRESHOLD:e}
"#,
            nl = s.nl,
            t_end = Synth::t(STEPS - 1),
        );
        let out = Command::new(&python)
            .args(["-c", &attrs])
            .arg(&path)
            .output()
            .unwrap();
        crate::common::assert_success(&out);
    }
}

/// A disk that fills mid-run (a [`LimitedDisk`] of 560 kB: the layout, the first step
/// chunks and a few snapshots of the collapse fit) stops the run with a write error
/// and leaves a file that reads: every per-step series with the same number of rows,
/// every snapshot dataset with the same number of frames, and the status saying why.
#[test]
fn a_full_disk_leaves_a_consistent_file_whose_status_says_why() {
    use granflow::output::hdf5::space::LimitedDisk;
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("full.h5");
    let collapse = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/collapse.toml");
    let scn = granflow::scenario::load_file(&collapse, &["output.every=0.002".into()]).unwrap();
    let mut sim = granflow::setup::build(&scn);
    let mut sink = Hdf5Sink::create_with_space(&path, Box::new(LimitedDisk::new(560_000))).unwrap();
    let err = sim.run(&mut sink, &mut |_| {}).unwrap_err();
    assert!(err.to_string().contains("write error"), "{err}");
    drop(sink);
    let file = H5File::open(&path).unwrap();
    let status = file
        .root_group()
        .group("summary")
        .unwrap()
        .attr_string("status")
        .unwrap();
    assert!(
        status.starts_with("failed: ") && status.contains("write error: no space left"),
        "{status}"
    );
    let rows: Vec<usize> = [
        "diagnostics/t",
        "diagnostics/dt",
        "diagnostics/mass",
        "diagnostics/kinetic_energy",
        "diagnostics/max_speed",
        "front/t",
        "front/x",
    ]
    .iter()
    .map(|name| file.dataset(name).unwrap().read_raw::<f64>().unwrap().len())
    .collect();
    assert!(
        rows.iter().all(|&n| n == rows[0]) && rows[0] > 1,
        "{rows:?}"
    );
    let t = file
        .dataset("snapshots/t")
        .unwrap()
        .read_raw::<f64>()
        .unwrap();
    assert!(t.len() > 1, "{t:?}");
    for name in ["snapshots/h", "snapshots/u"] {
        let ds = file.dataset(name).unwrap();
        assert_eq!(ds.shape()[0], t.len(), "{name}");
        assert!(ds.read_raw::<f64>().unwrap().iter().all(|v| v.is_finite()));
    }
    // The last snapshot is no later than the last step record.
    let steps = file
        .dataset("diagnostics/t")
        .unwrap()
        .read_raw::<f64>()
        .unwrap();
    assert!(t.last() <= steps.last(), "{t:?} {steps:?}");
    drop(file);
    let Some(python) = crate::common::python_with_h5py() else {
        return;
    };
    let script = "import sys, h5py\n\
        f = h5py.File(sys.argv[1], 'r')\n\
        n = {len(f[k]) for k in ('diagnostics/t', 'diagnostics/dt', 'diagnostics/mass', \
        'diagnostics/kinetic_energy', 'diagnostics/max_speed', 'front/t', 'front/x')}\n\
        m = {len(f[k]) for k in ('snapshots/t', 'snapshots/h', 'snapshots/u')}\n\
        assert len(n) == 1 and len(m) == 1, (n, m)\n\
        print(f['summary'].attrs['status'])\n";
    let out = Command::new(python)
        .args(["-c", script])
        .arg(&path)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(String::from_utf8_lossy(&out.stdout).contains("write error"));
}

/// `scripts/check_output.py` refuses a file with a non-finite value in `/diagnostics`
/// or in a snapshot, naming the dataset.
#[test]
fn the_checker_refuses_non_finite_diagnostics_and_snapshots() {
    let Some(python) = crate::common::python_with_h5py() else {
        return;
    };
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("scripts/check_output.py");
    let dir = tempfile::tempdir().unwrap();
    for (k, (speed, h0, needle)) in [
        (
            f64::INFINITY,
            0.1,
            "/diagnostics/max_speed has non-finite values",
        ),
        (1.0, f64::INFINITY, "/snapshots/h has non-finite values"),
        (1.0, 0.1, ""),
    ]
    .into_iter()
    .enumerate()
    {
        let path = dir.path().join(format!("c{k}.h5"));
        let mut sink = Hdf5Sink::create(&path).unwrap();
        let x = [0.25, 0.75];
        let info = RunInfo {
            granflow_version: "test".into(),
            model: "granular".into(),
            pressure: "hydrostatic".into(),
            layers: 1,
            coordinates: "cartesian".into(),
            slope_deg: 0.0,
            scenario_toml: String::new(),
            front_threshold: THRESHOLD,
            raster: None,
        };
        let grid = GridData {
            spec: &GridSpec::Line(LineGeometry::of_extent(2, 0.0, 1.0)),
            x: &x,
            y: None,
            b: &[0.0; 2],
            h_bed: &[0.0; 2],
            shape: None,
        };
        sink.begin(&info, &grid).unwrap();
        let h = [h0, 0.1];
        let u = [0.0, 0.0];
        for t in [0.0, 1.0] {
            sink.step(&StepRecord {
                t,
                dt: if t == 0.0 { 0.0 } else { 1.0 },
                mass: 0.5 * (h0.min(1e300) + 0.1),
                kinetic_energy: 0.0,
                max_speed: if t == 0.0 { 0.0 } else { speed },
                front_x: 0.75,
            })
            .unwrap();
            sink.snapshot(&SnapshotView {
                t,
                h: &h,
                u: &u,
                v: None,
                w: None,
                p_nh: None,
                layers: 1,
                extra: &[],
                layer_uv: None,
                shape: None,
            })
            .unwrap();
        }
        let mut summary = RunSummary::not_run("completed".into(), 0.0);
        summary.t_end = 1.0;
        sink.finish(&summary).unwrap();
        let out = Command::new(&python)
            .arg(&script)
            .arg(&path)
            .output()
            .unwrap();
        let said = format!(
            "{}{}",
            String::from_utf8_lossy(&out.stdout),
            String::from_utf8_lossy(&out.stderr)
        );
        if needle.is_empty() {
            assert!(out.status.success(), "{said}");
        } else {
            assert!(!out.status.success(), "{said}");
            assert!(said.contains(needle), "{said}");
        }
    }
}
