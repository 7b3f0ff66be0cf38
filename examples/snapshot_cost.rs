//! What the HDF5 snapshots of a run cost: runs a scenario (with `--set` overrides)
//! into an HDF5 file and times the calls the run loop makes on the file's sink
//! (CPU time of the run's thread: run it with one thread), printing per snapshot the
//! time of the snapshot and of the maps written with it, then the file's size.
//!
//!     cargo run --release --example snapshot_cost -- SCENARIO [--threads N] [--out FILE] [KEY=VALUE …]

use std::path::{Path, PathBuf};
use std::time::Instant;

use granflow::output::{
    CellField, GaugeRecord, GridData, Hdf5Sink, OutputError, OutputSink, RunInfo, RunMaps,
    RunSummary, SnapshotView, StepRecord,
};

/// The HDF5 sink with a stopwatch on its snapshot and map writes.
struct Timed {
    inner: Hdf5Sink,
    /// (t, snapshot s, maps so far s) per snapshot.
    snapshots: Vec<(f64, f64, f64)>,
    steps_s: f64,
    finish_s: f64,
}

/// CPU time of the calling thread (s), from Linux's /proc/thread-self/schedstat (its
/// first number, in ns): on a loaded machine the wall time of a write says more about
/// the other jobs than about the write. NaN elsewhere.
fn thread_cpu_s() -> f64 {
    std::fs::read_to_string("/proc/thread-self/schedstat")
        .ok()
        .and_then(|s| s.split_whitespace().next()?.parse::<f64>().ok())
        .map_or(f64::NAN, |ns| 1e-9 * ns)
}

/// `f`'s result and the CPU time it took on this thread (s).
fn timed<T>(f: impl FnOnce() -> T) -> (T, f64) {
    let start = thread_cpu_s();
    let out = f();
    (out, thread_cpu_s() - start)
}

impl OutputSink for Timed {
    fn begin(&mut self, info: &RunInfo, grid: &GridData) -> Result<(), OutputError> {
        self.inner.begin(info, grid)
    }
    fn snapshot(&mut self, snap: &SnapshotView) -> Result<(), OutputError> {
        let (r, s) = timed(|| self.inner.snapshot(snap));
        self.snapshots.push((snap.t, s, 0.0));
        r
    }
    fn step(&mut self, rec: &StepRecord) -> Result<(), OutputError> {
        let (r, s) = timed(|| self.inner.step(rec));
        self.steps_s += s;
        r
    }
    fn finish(&mut self, summary: &RunSummary) -> Result<(), OutputError> {
        let (r, s) = timed(|| self.inner.finish(summary));
        self.finish_s += s;
        r
    }
    fn begin_gauges(&mut self, x: &[f64]) -> Result<(), OutputError> {
        self.inner.begin_gauges(x)
    }
    fn gauges_y(&mut self, y: &[f64]) -> Result<(), OutputError> {
        self.inner.gauges_y(y)
    }
    fn gauges(&mut self, rec: &GaugeRecord) -> Result<(), OutputError> {
        self.inner.gauges(rec)
    }
    fn maps(&mut self, maps: &RunMaps) -> Result<(), OutputError> {
        let (r, s) = timed(|| self.inner.maps(maps));
        self.finish_s += s;
        r
    }
    fn maps_so_far(&mut self, maps: &[CellField]) -> Result<(), OutputError> {
        let (r, s) = timed(|| self.inner.maps_so_far(maps));
        if let Some(last) = self.snapshots.last_mut() {
            last.2 += s;
        }
        r
    }
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let scenario = PathBuf::from(args.first().ok_or("usage: snapshot_cost SCENARIO …")?);
    let mut threads = 1;
    let mut out = std::env::temp_dir().join(format!("snapshot_cost_{}.h5", std::process::id()));
    let mut sets = Vec::new();
    let mut rest = args[1..].iter();
    while let Some(a) = rest.next() {
        match a.as_str() {
            "--threads" => threads = rest.next().ok_or("--threads N")?.parse()?,
            "--out" => out = PathBuf::from(rest.next().ok_or("--out FILE")?),
            _ => sets.push(a.clone()),
        }
    }
    let scn =
        granflow::scenario::load_file(Path::new(&scenario), &sets).map_err(|e| format!("{e:?}"))?;
    let mut run = granflow::setup::build_threads(&scn, threads);
    let mut sink = Timed {
        inner: Hdf5Sink::create(&out)?,
        snapshots: Vec::new(),
        steps_s: 0.0,
        finish_s: 0.0,
    };
    let (start, cpu0) = (Instant::now(), thread_cpu_s());
    let summary = run.run(&mut sink, &mut |_| {})?;
    let (wall, cpu) = (start.elapsed().as_secs_f64(), thread_cpu_s() - cpu0);
    println!(
        "cells {}, steps {}, status {}",
        run.cells(),
        summary.steps,
        summary.status
    );
    println!("snapshot        t (s)   write (ms CPU)   maps (ms CPU)");
    for (k, (t, s, m)) in sink.snapshots.iter().enumerate() {
        println!("{k:>8} {t:>12.4} {:>16.1} {:>15.1}", 1e3 * s, 1e3 * m);
    }
    let n = sink.snapshots.len() as f64;
    let total: f64 = sink.snapshots.iter().map(|(_, s, m)| s + m).sum();
    println!(
        "mean per snapshot {:.1} ms (snapshot + maps), step records {:.1} ms, finish and \
         final maps {:.1} ms (CPU); run {cpu:.2} s CPU on this thread, {wall:.2} s wall",
        1e3 * total / n,
        1e3 * sink.steps_s,
        1e3 * sink.finish_s,
    );
    let size = std::fs::metadata(&out)?.len();
    println!(
        "file {} bytes ({:.1} MB), {:.2} MB per snapshot",
        size,
        size as f64 / 1e6,
        size as f64 / 1e6 / n
    );
    Ok(())
}
