//! Front series as CSV (`<stem>_front.csv`, columns `t,x`), for spreadsheets and quick
//! plots. One row per step record; a step without a front (NaN) is written `nan`.
//! Rows go through a buffer that is flushed at every snapshot and at finish, so the
//! file is as current as the HDF5 file.

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

use super::{GridData, OutputError, OutputSink, RunInfo, RunSummary, SnapshotView, StepRecord};

/// `<dir>/<stem>_front.csv` next to the HDF5 file `h5`.
pub fn front_csv_path(h5: &Path) -> PathBuf {
    super::companion_path(h5, "_front.csv")
}

/// Writes the `t,x` front series of a run.
#[derive(Debug)]
pub struct FrontCsvSink {
    path: PathBuf,
    out: BufWriter<File>,
}

impl FrontCsvSink {
    /// Creates (or truncates) `path` and its parent directories and writes the header.
    pub fn create(path: &Path) -> Result<Self, OutputError> {
        let err = |e: std::io::Error| OutputError::Io {
            path: path.display().to_string(),
            message: e.to_string(),
        };
        if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
            std::fs::create_dir_all(dir).map_err(err)?;
        }
        let mut out = BufWriter::with_capacity(1 << 16, File::create(path).map_err(err)?);
        out.write_all(b"t,x\n").map_err(err)?;
        out.flush().map_err(err)?;
        Ok(FrontCsvSink {
            path: path.to_path_buf(),
            out,
        })
    }

    /// The file being written.
    pub fn path(&self) -> &Path {
        &self.path
    }

    fn err(&self, e: std::io::Error) -> OutputError {
        OutputError::Io {
            path: self.path.display().to_string(),
            message: e.to_string(),
        }
    }

    fn flush(&mut self) -> Result<(), OutputError> {
        self.out.flush().map_err(|e| self.err(e))
    }
}

impl OutputSink for FrontCsvSink {
    fn begin(&mut self, _info: &RunInfo, _grid: &GridData) -> Result<(), OutputError> {
        Ok(())
    }

    fn snapshot(&mut self, _snap: &SnapshotView) -> Result<(), OutputError> {
        self.flush()
    }

    fn step(&mut self, rec: &StepRecord) -> Result<(), OutputError> {
        let line = format!("{},{}\n", number(rec.t), number(rec.front_x));
        self.out.write_all(line.as_bytes()).map_err(|e| self.err(e))
    }

    fn finish(&mut self, _summary: &RunSummary) -> Result<(), OutputError> {
        self.flush()
    }
}

/// A float that reads back exactly: shortest round-trip digits, in exponent form
/// outside [1e-4, 1e15) so tiny or huge values stay short; `nan`, `inf`, `-inf`.
pub(super) fn number(v: f64) -> String {
    if v.is_nan() {
        "nan".to_string()
    } else if v == 0.0 || v.is_infinite() || (1e-4..1e15).contains(&v.abs()) {
        format!("{v}")
    } else {
        format!("{v:e}")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_round_trip() {
        for v in [0.0, -0.0, 1.5, 0.1, 1e-4, 3.25e-7, -2e20, 123456.789] {
            let s = number(v);
            assert_eq!(s.parse::<f64>().unwrap().to_bits(), v.to_bits(), "{s}");
        }
        assert_eq!(number(f64::NAN), "nan");
        assert_eq!(number(f64::INFINITY), "inf");
        assert_eq!(number(1e-7), "1e-7");
    }

    #[test]
    fn csv_path_sits_next_to_the_h5_file() {
        assert_eq!(
            front_csv_path(Path::new("out/run.h5")),
            PathBuf::from("out/run_front.csv")
        );
        assert_eq!(
            front_csv_path(Path::new("run")),
            PathBuf::from("run_front.csv")
        );
        assert_eq!(
            front_csv_path(Path::new("out/run.HDF5")),
            PathBuf::from("out/run_front.csv")
        );
    }

    #[test]
    fn runs_named_after_a_dot_keep_their_own_csv() {
        // `file_stem` would cut both at the dot: `x_0_front.csv` for each.
        let a = front_csv_path(Path::new("/tmp/x_0.0046"));
        let b = front_csv_path(Path::new("/tmp/x_0.00182"));
        assert_eq!(a, PathBuf::from("/tmp/x_0.0046_front.csv"));
        assert_eq!(b, PathBuf::from("/tmp/x_0.00182_front.csv"));
        assert_eq!(
            front_csv_path(Path::new("/tmp/x_0.0046.h5")),
            PathBuf::from("/tmp/x_0.0046_front.csv")
        );
    }
}
