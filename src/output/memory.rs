//! An in-memory sink: keeps every snapshot and step record. Used by tests and by
//! callers that post-process a run without touching the disk.

use super::{
    GaugeRecord, GridData, OutputError, OutputSink, RunInfo, RunMaps, RunSummary, SnapshotView,
    StepRecord,
};

/// One stored snapshot (owned copy of a [`SnapshotView`]).
#[derive(Debug, Clone, PartialEq)]
pub struct Snapshot {
    pub t: f64,
    pub h: Vec<f64>,
    /// Layer-major, α·nx + i.
    pub u: Vec<f64>,
    pub w: Option<Vec<f64>>,
    pub p_nh: Option<Vec<f64>>,
    /// Model-specific per-cell fields (name, nx values).
    pub extra: Vec<(String, Vec<f64>)>,
    /// The layer velocities (u_α, v_α) of a layered raster run, layer-major.
    pub layer_uv: Option<(Vec<f64>, Vec<f64>)>,
}

impl Snapshot {
    /// The per-cell field `name`, if the snapshot has it.
    pub fn field(&self, name: &str) -> Option<&[f64]> {
        self.extra
            .iter()
            .find(|(n, _)| n == name)
            .map(|(_, v)| v.as_slice())
    }
}

#[derive(Debug, Default, Clone)]
pub struct MemorySink {
    pub info: Option<RunInfo>,
    pub x: Vec<f64>,
    pub b: Vec<f64>,
    pub h_bed: Vec<f64>,
    pub snapshots: Vec<Snapshot>,
    pub steps: Vec<StepRecord>,
    pub summary: Option<RunSummary>,
    /// Gauge positions, empty without gauges.
    pub gauge_x: Vec<f64>,
    /// (t, η per gauge, grain depth per gauge) at every gauge time.
    pub gauges: Vec<(f64, Vec<f64>, Vec<f64>)>,
    /// The maps of a raster run (name, one value per cell), empty otherwise.
    pub maps: Vec<(String, Vec<f64>)>,
    /// Its summary numbers (name, value).
    pub map_scalars: Vec<(String, f64)>,
}

impl OutputSink for MemorySink {
    fn begin(&mut self, info: &RunInfo, grid: &GridData) -> Result<(), OutputError> {
        self.info = Some(info.clone());
        self.x = grid.x.to_vec();
        self.b = grid.b.to_vec();
        self.h_bed = grid.h_bed.to_vec();
        Ok(())
    }

    fn snapshot(&mut self, snap: &SnapshotView) -> Result<(), OutputError> {
        self.snapshots.push(Snapshot {
            t: snap.t,
            h: snap.h.to_vec(),
            u: snap.u.to_vec(),
            w: snap.w.map(<[f64]>::to_vec),
            p_nh: snap.p_nh.map(<[f64]>::to_vec),
            extra: snap
                .extra
                .iter()
                .map(|f| (f.name.to_string(), f.data.to_vec()))
                .collect(),
            layer_uv: snap.layer_uv.map(|(u, v)| (u.to_vec(), v.to_vec())),
        });
        Ok(())
    }

    fn step(&mut self, rec: &StepRecord) -> Result<(), OutputError> {
        self.steps.push(*rec);
        Ok(())
    }

    fn finish(&mut self, summary: &RunSummary) -> Result<(), OutputError> {
        self.summary = Some(summary.clone());
        Ok(())
    }

    fn begin_gauges(&mut self, x: &[f64]) -> Result<(), OutputError> {
        self.gauge_x = x.to_vec();
        Ok(())
    }

    fn gauges(&mut self, rec: &GaugeRecord) -> Result<(), OutputError> {
        self.gauges
            .push((rec.t, rec.eta.to_vec(), rec.h_grains.to_vec()));
        Ok(())
    }

    fn maps(&mut self, maps: &RunMaps) -> Result<(), OutputError> {
        self.maps = maps
            .maps
            .iter()
            .map(|f| (f.name.to_string(), f.data.to_vec()))
            .collect();
        self.map_scalars = maps
            .scalars
            .iter()
            .map(|&(n, v)| (n.to_string(), v))
            .collect();
        Ok(())
    }
}

/// Keeps only the summary handed to `finish` (and ignores everything else): the sink
/// for runs whose fields nobody reads (benchmarks, a sweep's summary capture).
#[derive(Debug, Default, Clone)]
pub struct SummarySink(pub Option<RunSummary>);

impl OutputSink for SummarySink {
    fn begin(&mut self, _: &RunInfo, _: &GridData) -> Result<(), OutputError> {
        Ok(())
    }
    fn snapshot(&mut self, _: &SnapshotView) -> Result<(), OutputError> {
        Ok(())
    }
    fn step(&mut self, _: &StepRecord) -> Result<(), OutputError> {
        Ok(())
    }
    fn finish(&mut self, summary: &RunSummary) -> Result<(), OutputError> {
        self.0 = Some(summary.clone());
        Ok(())
    }
}
