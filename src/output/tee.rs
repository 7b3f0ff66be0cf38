//! Fan-out of one run to two sinks, e.g. the HDF5 file and the front CSV.

use super::{
    CellField, GaugeRecord, GridData, OutputError, OutputSink, RunInfo, RunMaps, RunSummary,
    SnapshotView, StepRecord,
};

/// Forwards every call to `a`, then to `b`. Both are called even when `a` fails, so
/// one broken output does not starve the other; the first error is returned.
/// Nest for more sinks: `Tee::new(a, Tee::new(b, c))`.
#[derive(Debug)]
pub struct Tee<A, B> {
    pub a: A,
    pub b: B,
}

impl<A, B> Tee<A, B> {
    pub fn new(a: A, b: B) -> Self {
        Tee { a, b }
    }

    pub fn into_inner(self) -> (A, B) {
        (self.a, self.b)
    }
}

fn both(
    first: Result<(), OutputError>,
    second: Result<(), OutputError>,
) -> Result<(), OutputError> {
    first.and(second)
}

impl<A: OutputSink, B: OutputSink> OutputSink for Tee<A, B> {
    fn begin(&mut self, info: &RunInfo, grid: &GridData) -> Result<(), OutputError> {
        both(self.a.begin(info, grid), self.b.begin(info, grid))
    }

    fn snapshot(&mut self, snap: &SnapshotView) -> Result<(), OutputError> {
        both(self.a.snapshot(snap), self.b.snapshot(snap))
    }

    fn step(&mut self, rec: &StepRecord) -> Result<(), OutputError> {
        both(self.a.step(rec), self.b.step(rec))
    }

    fn finish(&mut self, summary: &RunSummary) -> Result<(), OutputError> {
        both(self.a.finish(summary), self.b.finish(summary))
    }

    fn begin_gauges(&mut self, x: &[f64]) -> Result<(), OutputError> {
        both(self.a.begin_gauges(x), self.b.begin_gauges(x))
    }

    fn gauges_y(&mut self, y: &[f64]) -> Result<(), OutputError> {
        both(self.a.gauges_y(y), self.b.gauges_y(y))
    }

    fn maps(&mut self, maps: &RunMaps) -> Result<(), OutputError> {
        both(self.a.maps(maps), self.b.maps(maps))
    }

    fn maps_so_far(&mut self, maps: &[CellField]) -> Result<(), OutputError> {
        both(self.a.maps_so_far(maps), self.b.maps_so_far(maps))
    }

    fn gauges(&mut self, rec: &GaugeRecord) -> Result<(), OutputError> {
        both(self.a.gauges(rec), self.b.gauges(rec))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::output::memory::MemorySink;

    #[test]
    fn both_sides_see_every_call() {
        let mut tee = Tee::new(MemorySink::default(), MemorySink::default());
        let rec = StepRecord {
            t: 0.5,
            dt: 0.1,
            mass: 1.0,
            kinetic_energy: 0.0,
            max_speed: 0.0,
            front_x: f64::NAN,
        };
        tee.step(&rec).unwrap();
        tee.step(&rec).unwrap();
        let (a, b) = tee.into_inner();
        assert_eq!(a.steps.len(), 2);
        assert_eq!(b.steps.len(), 2);
    }
}
