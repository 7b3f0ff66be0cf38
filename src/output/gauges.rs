//! Gauge series as CSV (`<stem>_gauges.csv`), the way tide gauges are tabulated: one
//! row per gauge time, wide format
//!
//! ```text
//! t,eta_<x1>,…,eta_<xn>,h_grains_<x1>,…,h_grains_<xn>
//! ```
//!
//! with each position written as in the front CSV (shortest round-trip digits); on a
//! raster each column names the gauge's point, `eta_<x>_<y>` and `h_grains_<x>_<y>`
//! (the y from [`OutputSink::gauges_y`]). The file exists only for runs with gauges:
//! it is created at [`OutputSink::begin_gauges`], its header written at the first of
//! `gauges_y`, the first record, a snapshot or the end. Rows go through a 64 KiB buffer flushed at every
//! snapshot and at finish (also after a failure), like the front CSV.

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

use super::csv::number;
use super::{
    GaugeRecord, GridData, OutputError, OutputSink, RunInfo, RunSummary, SnapshotView, StepRecord,
};

/// `<dir>/<stem>_gauges.csv` next to the HDF5 file `h5`.
pub fn gauge_csv_path(h5: &Path) -> PathBuf {
    super::companion_path(h5, "_gauges.csv")
}

/// Writes the gauge series of a run, if it has gauges.
#[derive(Debug)]
pub struct GaugeCsvSink {
    path: PathBuf,
    /// `None` until `begin_gauges` (and for runs without gauges).
    out: Option<BufWriter<File>>,
    n: usize,
    line: String,
    /// The gauges' x while the header is not written yet.
    pending: Option<Vec<f64>>,
}

impl GaugeCsvSink {
    /// A sink for `path`; nothing is created before `begin_gauges`.
    pub fn new(path: &Path) -> Self {
        GaugeCsvSink {
            path: path.to_path_buf(),
            out: None,
            n: 0,
            line: String::new(),
            pending: None,
        }
    }

    /// The file written, when the run has gauges.
    pub fn path(&self) -> Option<&Path> {
        self.out.as_ref().map(|_| self.path.as_path())
    }

    fn err(&self, e: impl std::fmt::Display) -> OutputError {
        OutputError::Io {
            path: self.path.display().to_string(),
            message: e.to_string(),
        }
    }

    /// Writes the header if it is still pending: the gauges' x, and their y on a
    /// raster.
    fn header(&mut self, y: Option<&[f64]>) -> Result<(), OutputError> {
        let Some(x) = self.pending.take() else {
            return Ok(());
        };
        let mut header = String::from("t");
        for name in ["eta", "h_grains"] {
            for (k, &xg) in x.iter().enumerate() {
                header.push_str(&format!(",{name}_{}", number(xg)));
                if let Some(&yg) = y.and_then(|y| y.get(k)) {
                    header.push_str(&format!("_{}", number(yg)));
                }
            }
        }
        header.push('\n');
        let written = match self.out.as_mut() {
            Some(out) => out.write_all(header.as_bytes()).and_then(|()| out.flush()),
            None => Ok(()),
        };
        written.map_err(|e| self.err(e))
    }

    fn flush(&mut self) -> Result<(), OutputError> {
        self.header(None)?;
        match self.out.as_mut().map(Write::flush) {
            Some(Err(e)) => Err(self.err(e)),
            _ => Ok(()),
        }
    }
}

impl OutputSink for GaugeCsvSink {
    fn begin(&mut self, _info: &RunInfo, _grid: &GridData) -> Result<(), OutputError> {
        Ok(())
    }

    fn snapshot(&mut self, _snap: &SnapshotView) -> Result<(), OutputError> {
        self.flush()
    }

    fn step(&mut self, _rec: &StepRecord) -> Result<(), OutputError> {
        Ok(())
    }

    fn finish(&mut self, _summary: &RunSummary) -> Result<(), OutputError> {
        self.flush()
    }

    fn begin_gauges(&mut self, x: &[f64]) -> Result<(), OutputError> {
        if self.out.is_some() {
            return Err(self.err("begin_gauges called twice"));
        }
        if let Some(dir) = self.path.parent().filter(|d| !d.as_os_str().is_empty()) {
            std::fs::create_dir_all(dir).map_err(|e| self.err(e))?;
        }
        let file = File::create(&self.path).map_err(|e| self.err(e))?;
        self.out = Some(BufWriter::with_capacity(1 << 16, file));
        self.pending = Some(x.to_vec());
        self.n = x.len();
        Ok(())
    }

    fn gauges_y(&mut self, y: &[f64]) -> Result<(), OutputError> {
        if y.len() != self.n || self.pending.is_none() {
            return Err(self.err(format!(
                "gauges_y with {} values for {} gauges, after the header",
                y.len(),
                self.n
            )));
        }
        self.header(Some(y))
    }

    fn gauges(&mut self, rec: &GaugeRecord) -> Result<(), OutputError> {
        if rec.eta.len() != self.n || rec.h_grains.len() != self.n {
            return Err(self.err(format!(
                "gauge record at t = {} has {} and {} values, expected {}",
                rec.t,
                rec.eta.len(),
                rec.h_grains.len(),
                self.n
            )));
        }
        self.header(None)?;
        let mut line = std::mem::take(&mut self.line);
        line.clear();
        line.push_str(&number(rec.t));
        for &v in rec.eta.iter().chain(rec.h_grains) {
            line.push(',');
            line.push_str(&number(v));
        }
        line.push('\n');
        let written = match self.out.as_mut() {
            Some(out) => out.write_all(line.as_bytes()).map_err(|e| e.to_string()),
            None => Err("gauges before begin_gauges".to_string()),
        };
        self.line = line;
        written.map_err(|e| self.err(e))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wide_rows_with_positions_in_the_header() {
        let dir = tempfile::tempdir().unwrap();
        let h5 = dir.path().join("run.h5");
        let path = gauge_csv_path(&h5);
        assert_eq!(path, dir.path().join("run_gauges.csv"));
        let mut sink = GaugeCsvSink::new(&path);
        assert!(sink.path().is_none());
        sink.begin_gauges(&[1.5, 30.0]).unwrap();
        for t in [0.0, 0.25] {
            let rec = GaugeRecord {
                t,
                eta: &[t, 1.0],
                h_grains: &[0.1, -0.0],
            };
            sink.gauges(&rec).unwrap();
        }
        let bad = GaugeRecord {
            t: 1.0,
            eta: &[1.0],
            h_grains: &[1.0],
        };
        assert!(sink.gauges(&bad).is_err());
        sink.finish(&RunSummary::not_run("completed".into(), 0.0))
            .unwrap();
        let text = std::fs::read_to_string(&path).unwrap();
        assert_eq!(
            text,
            "t,eta_1.5,eta_30,h_grains_1.5,h_grains_30\n0,0,1,0.1,-0\n0.25,0.25,1,0.1,-0\n"
        );
    }

    #[test]
    fn raster_gauges_name_their_point_in_the_header() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("run_gauges.csv");
        let mut sink = GaugeCsvSink::new(&path);
        sink.begin_gauges(&[1.5, 1.5]).unwrap();
        assert!(sink.gauges_y(&[-0.25]).is_err());
        sink.gauges_y(&[-0.25, 2.0]).unwrap();
        sink.gauges(&GaugeRecord {
            t: 0.0,
            eta: &[1.0, 2.0],
            h_grains: &[0.5, 0.0],
        })
        .unwrap();
        assert!(sink.gauges_y(&[0.0, 0.0]).is_err());
        sink.finish(&RunSummary::not_run("completed".into(), 0.0))
            .unwrap();
        let text = std::fs::read_to_string(&path).unwrap();
        assert_eq!(
            text,
            "t,eta_1.5_-0.25,eta_1.5_2,h_grains_1.5_-0.25,h_grains_1.5_2\n0,1,2,0.5,0\n"
        );
    }

    #[test]
    fn a_run_without_records_still_gets_its_header() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("run_gauges.csv");
        let mut sink = GaugeCsvSink::new(&path);
        sink.begin_gauges(&[2.0]).unwrap();
        sink.finish(&RunSummary::not_run("failed".into(), 0.0))
            .unwrap();
        let text = std::fs::read_to_string(&path).unwrap();
        assert_eq!(text, "t,eta_2,h_grains_2\n");
    }
}
