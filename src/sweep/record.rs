//! The per-run result file, `<run>.result.toml`, and what "already done" means.
//!
//! The HDF5 file holds a run's `/summary`, but the HDF5 crate reads back only string
//! attributes, and a plain-text record is handy for scripts anyway. So each run, when it
//! ends (completed, at rest or failed), also writes this small TOML file next to its
//! HDF5 file: the parameters, runout, stop time, h_max_final, end time, steps, wall
//! time, status, and a hash of the exact scenario text that was run. It is written to a
//! temporary name, synced and renamed, so it is either absent or complete, and it is
//! removed before a run starts, so it never describes an older run of the same name.
//! Floats are written in the shortest form that reads back bit for bit (`nan` for a run
//! that never came to rest), so a summary rebuilt from these files (`sweep merge`) has
//! the same numbers as the one written by the sweep itself.
//!
//! A run counts as done (and is skipped on a re-run) when its result file says
//! `completed`, `stopped_at_rest` or `settled`, its scenario hash matches the scenario the sweep
//! would run now (same base file, `set`, `--set` and axis values), and its HDF5 file
//! reads as that run's: the same status in `/summary`, a `scenario_toml` attribute
//! with the same hash, and per-step series and snapshots that read with agreeing
//! lengths. Otherwise the run is run again.

use std::collections::BTreeMap;
use std::fs;
use std::io::Write;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::output::RunSummary;

/// Version of the result-file layout.
pub const RECORD_FORMAT: u32 = 1;

/// What one run produced, as stored in `<run>.result.toml`.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct RunRecord {
    pub format: u32,
    /// Position in sweep order.
    pub index: usize,
    pub name: String,
    /// FNV-1a of the scenario text that was run, 16 hex digits.
    pub scenario_hash: String,
    /// How the run ended (status, runout, stop time, …), as in the HDF5 `/summary`.
    #[serde(flatten)]
    pub summary: RunSummary,
    /// The HDF5 file, relative to the sweep directory.
    pub h5: String,
    /// Axis key → value, as in the summary.
    pub parameters: BTreeMap<String, String>,
}

impl RunRecord {
    /// A run that ended normally.
    pub fn is_ok(&self) -> bool {
        status_is_ok(&self.summary.status)
    }

    /// The numbers and status, ignoring the wall time (which differs between runs).
    pub fn same_result(&self, other: &RunRecord) -> bool {
        let same = |a: f64, b: f64| a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan());
        let (a, b) = (&self.summary, &other.summary);
        a.status == b.status
            && a.steps == b.steps
            && same(a.runout, b.runout)
            && same(a.stop_time, b.stop_time)
            && same(a.settled_time, b.settled_time)
            && same(a.h_max_final, b.h_max_final)
            && same(a.t_end, b.t_end)
    }
}

/// Runs that ended normally (`completed`, `stopped_at_rest`, `settled`, `outflowed`,
/// `no_mass`) are successes; anything else (`failed: …`, `interrupted`, `unfinished`) is
/// not.
pub fn status_is_ok(status: &str) -> bool {
    matches!(
        status,
        "completed" | "stopped_at_rest" | "settled" | "outflowed" | "no_mass"
    )
}

pub fn h5_path(dir: &Path, name: &str) -> PathBuf {
    dir.join(format!("{name}.h5"))
}

pub fn record_path(dir: &Path, name: &str) -> PathBuf {
    dir.join(format!("{name}.result.toml"))
}

/// Writes `text` to `path` atomically: a temporary file in the same directory, synced,
/// then renamed over `path`.
pub fn write_atomic(path: &Path, text: &str) -> std::io::Result<()> {
    let file_name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let tmp = path.with_file_name(format!(".{file_name}.tmp{}", std::process::id()));
    let result = (|| {
        let mut f = fs::File::create(&tmp)?;
        f.write_all(text.as_bytes())?;
        f.sync_all()?;
        fs::rename(&tmp, path)
    })();
    if result.is_err() {
        let _ = fs::remove_file(&tmp);
    }
    result
}

pub fn write(dir: &Path, record: &RunRecord) -> std::io::Result<()> {
    let body = toml::to_string(record)
        .map_err(|e| std::io::Error::other(format!("cannot encode the result: {e}")))?;
    let text =
        format!("# Result of one run of a granflow sweep, written when the run ended.\n{body}");
    write_atomic(&record_path(dir, &record.name), &text)
}

/// Reads a result file; `Ok(None)` when there is none.
pub fn read(dir: &Path, name: &str) -> Result<Option<RunRecord>, String> {
    let path = record_path(dir, name);
    let text = match fs::read_to_string(&path) {
        Ok(t) => t,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
        Err(e) => return Err(format!("cannot read {}: {e}", path.display())),
    };
    toml::from_str(&text)
        .map(Some)
        .map_err(|e| format!("cannot read {}: {}", path.display(), e.message()))
}

/// Removes a run's result file (before the run is redone).
pub fn remove(dir: &Path, name: &str) -> std::io::Result<()> {
    match fs::remove_file(record_path(dir, name)) {
        Err(e) if e.kind() != std::io::ErrorKind::NotFound => Err(e),
        _ => Ok(()),
    }
}

/// The `/summary` `status` attribute of an HDF5 file, if it can be read.
pub fn h5_status(path: &Path) -> Option<String> {
    let file = rust_hdf5::H5File::options().no_locking().open(path).ok()?;
    let status = file
        .root_group()
        .group("summary")
        .ok()?
        .attr_string("status");
    status.ok()
}

/// The `/summary` `status` of the HDF5 file of a run of the scenario whose hash is
/// `hash`, if the file reads as one: its `scenario_toml` attribute hashes to `hash`
/// (a file of another run copied over it does not), every per-step series reads with
/// one length, and the snapshot times read with as many values as the snapshot
/// frames (a damaged file does not).
pub fn h5_status_of_run(path: &Path, hash: &str) -> Option<String> {
    let file = rust_hdf5::H5File::options().no_locking().open(path).ok()?;
    let root = file.root_group();
    let text = root.attr_string("scenario_toml").ok()?;
    if format!("{:016x}", super::naming::fnv1a(text.as_bytes())) != hash {
        return None;
    }
    let read = |name: &str| file.dataset(name).ok()?.read_raw::<f64>().ok();
    let mut rows = None;
    for name in [
        "diagnostics/t",
        "diagnostics/dt",
        "diagnostics/mass",
        "diagnostics/kinetic_energy",
        "diagnostics/max_speed",
        "front/t",
        "front/x",
    ] {
        let n = read(name)?.len();
        if *rows.get_or_insert(n) != n {
            return None;
        }
    }
    let times = read("snapshots/t")?.len();
    let frames = file.dataset("snapshots/h").ok()?.shape();
    if frames.first() != Some(&times) {
        return None;
    }
    root.group("summary").ok()?.attr_string("status").ok()
}

/// The stored result of run `name`, if it is done and was run with the scenario whose
/// hash is `hash` (see the module docs).
pub fn done(dir: &Path, name: &str, hash: &str) -> Option<RunRecord> {
    let record = read(dir, name).ok()??;
    if !record.is_ok() || record.name != name || record.scenario_hash != hash {
        return None;
    }
    let status = h5_status_of_run(&dir.join(&record.h5), hash)?;
    (status == record.summary.status).then_some(record)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn record() -> RunRecord {
        RunRecord {
            format: RECORD_FORMAT,
            index: 3,
            name: "slope_deg=16".into(),
            scenario_hash: "0123456789abcdef".into(),
            summary: RunSummary {
                status: "failed: x, \"y\"".into(),
                runout: 0.1 + 0.2,
                stop_time: f64::NAN,
                settled_time: f64::NAN,
                settle_fraction: 1e-6,
                h_max_final: 1.0 / 3.0,
                t_end: 1e300,
                steps: 12,
                wall_time_s: 2.5e-7,
                max_wave_amplitude: None,
                wet: None,
                spread: Some(crate::output::Spread {
                    runout_length: 2852.25,
                    travel_angle_deg: f64::NAN,
                    area_reached: 1.0 / 3.0,
                    path_runout_length: Some(2956.5),
                    path_runout_angle_deg: None,
                    path_max: Some([2.5, 31.0, 1.5e6]),
                }),
                outflowed_fraction: 0.0,
                front_at_end_time: f64::NAN,
                max_speed_final: 0.0,
                stage_times: Vec::new(),
            },
            h5: "slope_deg=16.h5".into(),
            parameters: [("domain.slope_deg".to_string(), "16".to_string())].into(),
        }
    }

    #[test]
    fn round_trips_bit_for_bit() {
        let dir = tempfile::tempdir().unwrap();
        let r = record();
        write(dir.path(), &r).unwrap();
        let back = read(dir.path(), &r.name).unwrap().unwrap();
        assert!(back.same_result(&r), "{back:?}");
        assert_eq!(
            back.summary.wall_time_s.to_bits(),
            r.summary.wall_time_s.to_bits()
        );
        assert_eq!(back.parameters, r.parameters);
        let (a, b) = (back.summary.spread.unwrap(), r.summary.spread.unwrap());
        assert_eq!(
            (a.runout_length, a.area_reached, a.path_runout_length),
            (b.runout_length, b.area_reached, b.path_runout_length)
        );
        assert!(a.travel_angle_deg.is_nan() && a.path_runout_angle_deg.is_none());
        assert_eq!(a.path_max, b.path_max);
        assert!(!back.is_ok());
        // No temporary file left behind.
        let names: Vec<_> = fs::read_dir(dir.path()).unwrap().collect();
        assert_eq!(names.len(), 1);
        assert_eq!(read(dir.path(), "other").unwrap().map(|r| r.name), None);
        remove(dir.path(), &r.name).unwrap();
        remove(dir.path(), &r.name).unwrap();
        assert!(read(dir.path(), &r.name).unwrap().is_none());
    }

    #[test]
    fn done_needs_ok_status_matching_hash_and_h5() {
        let dir = tempfile::tempdir().unwrap();
        let mut r = record();
        r.summary.status = "completed".into();
        write(dir.path(), &r).unwrap();
        // No HDF5 file: not done.
        assert!(done(dir.path(), &r.name, &r.scenario_hash).is_none());
        fs::write(h5_path(dir.path(), &r.name), b"not hdf5").unwrap();
        assert!(done(dir.path(), &r.name, &r.scenario_hash).is_none());
        fs::write(record_path(dir.path(), &r.name), "garbage").unwrap();
        assert!(read(dir.path(), &r.name).is_err());
        assert!(done(dir.path(), &r.name, &r.scenario_hash).is_none());
    }

    #[test]
    fn every_normal_end_is_ok() {
        for status in [
            "completed",
            "stopped_at_rest",
            "settled",
            "outflowed",
            "no_mass",
        ] {
            assert!(status_is_ok(status), "{status}");
        }
        for status in ["interrupted", "unfinished", "failed: x", "pending"] {
            assert!(!status_is_ok(status), "{status}");
        }
    }
}
