//! A bound on what one run writes. Every output rate is a scenario key (`output.every`,
//! `output.gauge_every`, and the time step itself for the step records), so a small
//! value can fill a disk in seconds. A run states its bound up front: an
//! [`OutputEstimate`] (`Scenario::output_estimate`) counts what the keys force it to
//! write, validation refuses an estimate above [`OUTPUT_LIMIT`] (naming the key), and
//! [`Budgeted`] holds the run to the limit while it goes, for what no estimate
//! foresees (the number of CFL steps). `--force` lifts both.
//!
//! The step records, and the gauge rows of a run recording its gauges at every step
//! (no `output.gauge_every`), come at the pace of the time step, which no key fixes:
//! the estimate counts one per snapshot, a lower bound. So [`Budgeted`] also watches
//! that pace: once [`PACE_STEPS`] steps have run, it extrapolates the bytes per
//! simulated second of those records to `t_end`, and when that passes the limit it
//! warns at once, rather than let the run stop at the limit hours later. A warning,
//! not a refusal: the time step usually grows as a flow slows, so the extrapolation
//! is an upper estimate.

use super::{
    CellField, GaugeRecord, GridData, OutputError, OutputSink, RunInfo, RunMaps, RunSummary,
    SnapshotView, StepRecord,
};

/// Largest output of one run without `--force` (bytes): 1 GiB.
pub const OUTPUT_LIMIT: u64 = 1 << 30;

/// Bytes counted for one step record: six numbers in the HDF5 file, a row of the front
/// CSV.
const STEP_BYTES: u64 = 6 * 8 + 48;
/// Bytes counted for each number of a gauge row: 8 in the HDF5 file, up to 24 as CSV
/// text.
const GAUGE_VALUE_BYTES: u64 = 8 + 24;

/// What the keys of a scenario make a run write, counted up front.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OutputEstimate {
    pub snapshots: f64,
    /// Bytes of one snapshot.
    pub snapshot_bytes: f64,
    /// Gauge rows recorded at fixed times (`output.gauge_every`).
    pub gauge_rows: f64,
    pub gauge_row_bytes: f64,
    /// Step records at least (one per snapshot time).
    pub steps: f64,
}

impl OutputEstimate {
    /// The estimate for `cells` cells, `values_per_cell` numbers per cell in a snapshot
    /// (all fields), `extra_values` more numbers per snapshot, a run of `t_end` seconds
    /// with snapshots every `every` seconds and `gauges` gauges recorded every
    /// `gauge_every` seconds (`None`: at every step).
    pub fn new(
        cells: usize,
        values_per_cell: usize,
        extra_values: usize,
        t_end: f64,
        every: f64,
        gauges: usize,
        gauge_every: Option<f64>,
    ) -> OutputEstimate {
        let snapshots = (t_end / every).floor() + 2.0;
        let gauge_row_bytes = ((1 + 2 * gauges) as u64 * GAUGE_VALUE_BYTES) as f64;
        let gauge_rows = match gauge_every {
            Some(g) if gauges > 0 => (t_end / g).floor() + 2.0,
            _ => 0.0,
        };
        OutputEstimate {
            snapshots,
            snapshot_bytes: 8.0 * (1.0 + (cells * values_per_cell + extra_values) as f64),
            gauge_rows,
            gauge_row_bytes,
            steps: snapshots,
        }
    }

    pub fn snapshot_total(&self) -> f64 {
        self.snapshots * self.snapshot_bytes
    }

    pub fn gauge_total(&self) -> f64 {
        self.gauge_rows * self.gauge_row_bytes
    }

    /// Bytes in all.
    pub fn bytes(&self) -> f64 {
        self.snapshot_total() + self.gauge_total() + self.steps * STEP_BYTES as f64
    }

    /// The key whose rate makes most of the output.
    pub fn key(&self) -> &'static str {
        if self.gauge_total() > self.snapshot_total() {
            "output.gauge_every"
        } else {
            "output.every"
        }
    }

    /// "about 4.6 GB (2.0e7 gauge rows of 224 B, 42 snapshots of 3.2 kB)" (the larger
    /// part first).
    pub fn describe(&self) -> String {
        let snapshots = format!(
            "{} snapshots of {}",
            count(self.snapshots),
            size(self.snapshot_bytes)
        );
        let mut parts = vec![snapshots];
        if self.gauge_rows > 0.0 {
            let rows = format!(
                "{} gauge rows of {}",
                count(self.gauge_rows),
                size(self.gauge_row_bytes)
            );
            if self.gauge_total() > self.snapshot_total() {
                parts.insert(0, rows);
            } else {
                parts.push(rows);
            }
        }
        format!("about {} ({})", size(self.bytes()), parts.join(", "))
    }
}

fn count(n: f64) -> String {
    if n < 1e6 {
        format!("{n}")
    } else {
        format!("{n:.1e}")
    }
}

/// A byte count with a decimal unit: "3.2 kB", "4.6 GB".
pub fn size(bytes: f64) -> String {
    let units = ["B", "kB", "MB", "GB", "TB", "PB"];
    let mut v = bytes;
    let mut k = 0;
    while v >= 1000.0 && k + 1 < units.len() {
        v /= 1000.0;
        k += 1;
    }
    if k == 0 {
        format!("{v:.0} {}", units[k])
    } else if v >= 1000.0 {
        format!("{v:.1e} {}", units[k])
    } else {
        format!("{v:.1} {}", units[k])
    }
}

/// Steps after which the pace of the per-step records is extrapolated (module docs).
pub const PACE_STEPS: u64 = 200;

/// Passes everything to `inner` while the bytes counted stay within `limit`; the call
/// that would pass it fails instead, and the run ends with that error (the file is
/// finished as after any output failure). `finish` always goes through.
#[derive(Debug)]
pub struct Budgeted<S> {
    pub inner: S,
    limit: Option<u64>,
    written: u64,
    path: String,
    /// The run's end time, for the extrapolation of the per-step records (module docs).
    t_end: Option<f64>,
    steps: u64,
    /// Bytes of step records and gauge rows so far.
    per_step: u64,
    /// Bytes of gauge rows so far.
    gauge_rows: u64,
    /// The warning of the extrapolation, once given.
    warning: Option<String>,
}

impl<S> Budgeted<S> {
    /// `limit` in bytes (`None`: no limit); `path` names the output in the error.
    pub fn new(inner: S, limit: Option<u64>, path: &std::path::Path) -> Self {
        Budgeted {
            inner,
            limit,
            written: 0,
            path: path.display().to_string(),
            t_end: None,
            steps: 0,
            per_step: 0,
            gauge_rows: 0,
            warning: None,
        }
    }

    /// Extrapolates the per-step records of a run ending at `t_end` and warns on
    /// stderr when they would pass the limit (module docs).
    pub fn watching_pace(mut self, t_end: f64) -> Self {
        self.t_end = Some(t_end);
        self
    }

    /// The warning given when the pace of the per-step records would pass the limit.
    pub fn pace_warning(&self) -> Option<&str> {
        self.warning.as_deref()
    }

    /// After a step at time `t`: the extrapolation, once [`PACE_STEPS`] steps have run.
    fn watch_pace(&mut self, t: f64) {
        let (Some(limit), Some(t_end)) = (self.limit, self.t_end) else {
            return;
        };
        if self.steps != PACE_STEPS || !(t > 0.0 && t < t_end) {
            return;
        }
        let rest = self.per_step as f64 / t * (t_end - t);
        if self.written as f64 + rest <= limit as f64 {
            return;
        }
        let cure = if 2 * self.gauge_rows > self.per_step {
            "record the gauges at fixed times (output.gauge_every)"
        } else {
            "use a coarser grid or a shorter time.t_end"
        };
        let text = format!(
            "warning: at the pace of its first {PACE_STEPS} steps (t = {t:.3e} s), this run's step records and gauge rows would come to about {} by t_end = {t_end} s, more than the output limit of {}: it will stop with a write error when it reaches the limit; {cure}, or pass --force to lift the limit",
            size(self.written as f64 + rest),
            size(limit as f64)
        );
        crate::terminal::print_err(&format!("{text}\n"));
        self.warning = Some(text);
    }

    fn spend(&mut self, bytes: u64) -> Result<(), OutputError> {
        self.written = self.written.saturating_add(bytes);
        match self.limit {
            Some(limit) if self.written > limit => Err(OutputError::Io {
                path: self.path.clone(),
                message: format!(
                    "the run has reached the output limit of {} (every output rate is bounded; use larger output.every or output.gauge_every, or pass --force to lift the limit)",
                    size(limit as f64)
                ),
            }),
            _ => Ok(()),
        }
    }
}

impl<S: OutputSink> OutputSink for Budgeted<S> {
    fn begin(&mut self, info: &RunInfo, grid: &GridData) -> Result<(), OutputError> {
        let bytes = info.scenario_toml.len() + 8 * (grid.x.len() + grid.b.len() + grid.h_bed.len());
        self.spend(bytes as u64)?;
        self.inner.begin(info, grid)
    }

    fn snapshot(&mut self, snap: &SnapshotView) -> Result<(), OutputError> {
        let values = 1
            + snap.h.len()
            + snap.u.len()
            + snap.w.map_or(0, <[f64]>::len)
            + snap.p_nh.map_or(0, <[f64]>::len)
            + snap.extra.iter().map(|f| f.data.len()).sum::<usize>();
        self.spend(8 * values as u64)?;
        self.inner.snapshot(snap)
    }

    fn step(&mut self, rec: &StepRecord) -> Result<(), OutputError> {
        self.spend(STEP_BYTES)?;
        self.steps += 1;
        self.per_step += STEP_BYTES;
        self.watch_pace(rec.t);
        self.inner.step(rec)
    }

    fn finish(&mut self, summary: &RunSummary) -> Result<(), OutputError> {
        self.inner.finish(summary)
    }

    fn begin_gauges(&mut self, x: &[f64]) -> Result<(), OutputError> {
        self.spend(GAUGE_VALUE_BYTES * x.len() as u64)?;
        self.inner.begin_gauges(x)
    }

    fn gauges_y(&mut self, y: &[f64]) -> Result<(), OutputError> {
        self.spend(GAUGE_VALUE_BYTES * y.len() as u64)?;
        self.inner.gauges_y(y)
    }

    fn maps(&mut self, maps: &RunMaps) -> Result<(), OutputError> {
        let values = maps.maps.iter().map(|f| f.data.len()).sum::<usize>()
            + maps.series.iter().map(|s| s.2.len()).sum::<usize>()
            + maps.profile.iter().map(|s| s.2.len()).sum::<usize>();
        self.spend(8 * values as u64)?;
        self.inner.maps(maps)
    }

    /// Rewritten in place at every snapshot: the bytes are counted once, by `maps`.
    fn maps_so_far(&mut self, maps: &[CellField]) -> Result<(), OutputError> {
        self.inner.maps_so_far(maps)
    }

    fn gauges(&mut self, rec: &GaugeRecord) -> Result<(), OutputError> {
        let values = 1 + rec.eta.len() + rec.h_grains.len();
        let bytes = GAUGE_VALUE_BYTES * values as u64;
        self.spend(bytes)?;
        self.per_step += bytes;
        self.gauge_rows += bytes;
        self.inner.gauges(rec)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::output::memory::MemorySink;

    #[test]
    fn sizes_read_as_decimal_units() {
        assert_eq!(size(512.0), "512 B");
        assert_eq!(size(3200.0), "3.2 kB");
        assert_eq!(size(4.6e9), "4.6 GB");
    }

    #[test]
    fn the_key_is_the_larger_rate() {
        let e = OutputEstimate::new(200, 2, 0, 20.0, 0.5, 3, Some(1e-6));
        assert_eq!(e.key(), "output.gauge_every");
        assert!(e.bytes() > OUTPUT_LIMIT as f64, "{}", e.describe());
        let e = OutputEstimate::new(200, 2, 0, 20.0, 0.5, 3, Some(0.05));
        assert_eq!(e.key(), "output.every");
        assert!(e.bytes() < 1e6, "{}", e.describe());
    }

    #[test]
    fn a_budgeted_sink_fails_the_call_that_passes_the_limit() {
        let mut sink = Budgeted::new(MemorySink::default(), Some(1000), "x.h5".as_ref());
        let rec = StepRecord {
            t: 0.0,
            dt: 0.0,
            mass: 0.0,
            kinetic_energy: 0.0,
            max_speed: 0.0,
            front_x: 0.0,
        };
        let passed = (0..100).take_while(|_| sink.step(&rec).is_ok()).count();
        assert_eq!(passed as u64, 1000 / STEP_BYTES);
        let e = sink.step(&rec).unwrap_err().to_string();
        assert!(e.contains("output limit") && e.contains("--force"), "{e}");
    }
}
