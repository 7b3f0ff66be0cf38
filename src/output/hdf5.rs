//! HDF5 sink: the layout of `docs/output-format.md`, written with the pure-Rust
//! `rust-hdf5` crate (no system libhdf5).
//!
//! # Progressive writing: reopen, append, close
//!
//! Every group and dataset is created in [`OutputSink::begin`]; growing data lives in
//! chunked datasets whose first axis is unlimited. Each [`OutputSink::snapshot`] call
//! reopens the file, appends the step records buffered since the previous snapshot
//! and the snapshot itself, and closes the file again, which rewrites the object
//! headers and the superblock. Between two snapshots the file on disk is therefore a
//! complete, cleanly closed HDF5 file that any reader (h5py, libhdf5, rust-hdf5) opens
//! the ordinary way, and a run killed later keeps everything up to its last snapshot.
//!
//! Alternatives considered:
//! - rust-hdf5's SWMR writer keeps the file open and publishes appends with ordered
//!   flushes. It works, but a file whose writer was killed keeps the "open for SWMR
//!   write" superblock flags, and libhdf5 (so h5py) then refuses a plain open until
//!   `h5clear -s` is run or the file is opened with `swmr=True`. Scripts reading a
//!   crashed run would all need to know that.
//! - `H5File::flush` only hands buffered bytes to the OS: headers and superblock are
//!   written at close, so an open writer's file is unreadable.
//! - Rewriting a complete file to a temporary name and renaming it is atomic but costs
//!   the whole file at every snapshot, quadratic over a run.
//!
//! Cost: reopening parses a few object headers and the close rewrites them, so a
//! snapshot costs about a millisecond on top of its own bytes, independent of how much
//! the file already holds (nx = 10⁴, nl = 1, after 100 snapshots and with 5000 step
//! records per snapshot: 1–5 ms; `examples/output_bench.rs`). Snapshots close with
//! `close_no_sync`: the bytes are with the OS, which is all a process kill needs;
//! [`OutputSink::finish`] closes with an fsync for durability.
//!
//! A kill during that millisecond can leave the last snapshot half-published. Killing
//! a write-bound synthetic run with SIGKILL at 129 random moments never produced a
//! file h5py could not open or whose snapshots and step records disagreed.
//!
//! Step records are kept in memory and appended at each snapshot and at finish, never
//! one disk write per step, and on their own whenever 8192 of them are pending. File locking is disabled for the writer so that a reader
//! holding the file open (a notebook, say) cannot make the run fail at its next
//! snapshot; such a reader may see stale metadata and should reopen the file.
//!
//! A full disk: every batch first claims the room it can take ([`space`]), so a disk
//! that fills stops the run with a write error while the file is still the consistent
//! one of the previous batch (every series with its rows, every snapshot whole), and
//! a reserve held since `begin` is given back to write the status
//! `failed: … write error: …` at finish. A batch that fails anyway (another process
//! took the room) is reported and the file is not touched again.
//!
//! Layered fields arrive layer-major (α·nx + i), which is the C order of the
//! (nt, nl, nx) datasets, so each snapshot is one contiguous frame.

mod layout;
pub mod space;

use std::path::{Path, PathBuf};

use rust_hdf5::H5File;

pub use layout::{stage_attr_name, UNFINISHED};

use layout::GaugeRows;
use space::{DiskSpace, Space};

use super::{
    CellField, GaugeRecord, GridData, OutputError, OutputSink, RunInfo, RunMaps, RunSummary,
    SnapshotView, StepRecord,
};

/// Writes one run to an HDF5 file, progressively (see the module docs).
#[derive(Debug)]
pub struct Hdf5Sink {
    path: PathBuf,
    /// Fixed by `begin`; `None` before.
    shape: Option<Shape>,
    /// Step records not yet on disk.
    pending: Vec<StepRecord>,
    /// Number of gauges once `begin_gauges` ran.
    gauges: Option<usize>,
    /// Gauge rows not yet on disk: written with the step records, or on their own
    /// once they hold [`GAUGE_BUFFER_VALUES`] values.
    pending_gauges: GaugeRows,
    finished: bool,
    /// Times of the snapshots written (raster runs: listed in the XDMF file).
    times: Vec<f64>,
    /// Whether the final `/maps` were written (raster runs).
    has_maps: bool,
    /// The names of the `/maps` datasets once created (by the first call of
    /// `maps_so_far` or by `maps`).
    map_names: Option<Vec<&'static str>>,
    /// Where batches claim their room ([`space`]).
    space: Box<dyn Space>,
    /// Step records and gauge rows on disk.
    steps_written: u64,
    gauge_rows_written: u64,
    /// A batch failed half-way: the file is left as it is.
    damaged: bool,
    /// A claim failed: the disk is full.
    full: bool,
}

/// Room for what a batch rewrites besides its data: object headers, chunk indices,
/// the global heap of the string attributes.
const HEADER_BYTES: u64 = 16 * 1024;

/// Bound on the buffered gauge values (4 MiB): a run with gauges at every step and
/// rare snapshots writes them in pieces of this size.
const GAUGE_BUFFER_VALUES: usize = 1 << 19;

/// What `begin` and the first snapshot fix about the file.
#[derive(Debug, Clone)]
struct Shape {
    nx: usize,
    nl: usize,
    /// Whether snapshots carry `w` / `p_nh`; `None` until the first snapshot.
    has_w: Option<bool>,
    has_p_nh: Option<bool>,
    /// Names of the per-cell fields; `None` until the first snapshot.
    extra: Option<Vec<&'static str>>,
    /// (nx, ny) of a raster run (`nx` above is then nx·ny).
    raster: Option<(usize, usize)>,
    /// The raster's origin (lower-left corner) and spacing, for the XDMF file.
    origin: (f64, f64),
    spacing: (f64, f64),
}

/// Step records kept in memory at most (~56 bytes each): beyond, they are appended on
/// their own, so a run with rare snapshots neither grows its memory without bound nor
/// loses more than this many records when killed. One chunk of the step datasets.
const MAX_PENDING_STEPS: usize = 8192;

/// Names of `/snapshots` datasets that a per-cell field may not take.
const FIXED_SNAPSHOT_NAMES: [&str; 10] = [
    "t", "h", "u", "v", "w", "p_nh", "x", "y", "u_layers", "v_layers",
];

impl Shape {
    /// Checks the lengths of a snapshot's arrays.
    fn check_lengths(&self, snap: &SnapshotView) -> Result<(), String> {
        let (nx, nl) = (self.nx, self.nl);
        let expect = |what: &str, got: Option<usize>, want: usize| match got {
            Some(got) if got != want => Err(format!("{what} has {got} values, expected {want}")),
            _ => Ok(()),
        };
        expect("layer count", Some(snap.layers), nl)?;
        expect("h", Some(snap.h.len()), nx)?;
        // A raster's `u` is one value per cell (a layered raster's depth mean).
        let u_values = if self.raster.is_some() { nx } else { nl * nx };
        expect("u", Some(snap.u.len()), u_values)?;
        match (self.raster, snap.v) {
            (Some(_), None) => return Err("a raster snapshot without v".into()),
            (None, Some(_)) => return Err("v in a snapshot that is not on a raster".into()),
            _ => expect("v", snap.v.map(<[f64]>::len), nx)?,
        }
        if let (Some((rx, ry)), Some((ny, nx))) = (self.raster, snap.shape) {
            if (rx, ry) != (nx, ny) {
                return Err(format!(
                    "snapshot of shape (ny, nx) = ({ny}, {nx}) on a {rx} × {ry} raster"
                ));
            }
        }
        match (self.raster.is_some() && nl > 1, snap.layer_uv) {
            (true, None) => return Err("a layered raster snapshot without layer velocities".into()),
            (false, Some(_)) => {
                return Err("layer velocities in a snapshot that is not of a layered raster".into())
            }
            (_, uv) => {
                expect("u_layers", uv.map(|uv| uv.0.len()), nl * nx)?;
                expect("v_layers", uv.map(|uv| uv.1.len()), nl * nx)?;
            }
        }
        expect("w", snap.w.map(<[f64]>::len), nl * nx)?;
        expect("p_nh", snap.p_nh.map(<[f64]>::len), (nl + 1) * (nx + 1))?;
        for (k, field) in snap.extra.iter().enumerate() {
            let name = field.name;
            let plain =
                !name.is_empty() && name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_');
            if !plain || FIXED_SNAPSHOT_NAMES.contains(&name) {
                return Err(format!("per-cell field name {name:?} is not allowed"));
            }
            if snap.extra[..k].iter().any(|f| f.name == name) {
                return Err(format!("per-cell field {name:?} given twice"));
            }
            expect(name, Some(field.data.len()), nx)?;
        }
        Ok(())
    }

    /// Fixes at the first snapshot which per-cell fields are written, and holds later
    /// snapshots to the same names. Returns the fields to create now.
    fn fix_extra<'s>(&mut self, snap: &'s SnapshotView) -> Result<Vec<CellField<'s>>, String> {
        let names: Vec<&'static str> = snap.extra.iter().map(|f| f.name).collect();
        match &self.extra {
            Some(before) if *before != names => Err(format!(
                "per-cell fields are {names:?} but were {before:?} in earlier snapshots"
            )),
            Some(_) => Ok(Vec::new()),
            None => {
                self.extra = Some(names);
                Ok(snap.extra.to_vec())
            }
        }
    }

    /// Fixes at the first snapshot whether `w` and `p_nh` are written, and holds later
    /// snapshots to it. Returns the datasets to create now.
    fn fix_optional(&mut self, snap: &SnapshotView) -> Result<(bool, bool), String> {
        let first = self.has_w.is_none();
        for (field, known, now) in [
            ("w", &mut self.has_w, snap.w.is_some()),
            ("p_nh", &mut self.has_p_nh, snap.p_nh.is_some()),
        ] {
            match *known {
                Some(before) if before != now => {
                    return Err(format!(
                        "{field} is {} but was {} in earlier snapshots",
                        present(now),
                        present(before)
                    ))
                }
                _ => *known = Some(now),
            }
        }
        Ok((first && snap.w.is_some(), first && snap.p_nh.is_some()))
    }
}

impl Hdf5Sink {
    /// Creates (or truncates) `path`, creating its parent directories, so that an
    /// unwritable destination fails before the run starts.
    pub fn create(path: &Path) -> Result<Self, OutputError> {
        if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
            std::fs::create_dir_all(dir).map_err(|e| io_err(path, e))?;
        }
        let space = DiskSpace::new(path).map_err(|e| {
            io_err(
                path,
                format!("write error: cannot reserve room beside the file: {e}"),
            )
        })?;
        Self::create_with_space(path, Box::new(space))
    }

    /// [`Hdf5Sink::create`] with the room claimed from `space` (e.g. a
    /// [`space::LimitedDisk`] to test the full-disk path); the parent directory must
    /// exist.
    pub fn create_with_space(path: &Path, space: Box<dyn Space>) -> Result<Self, OutputError> {
        let sink = Hdf5Sink {
            path: path.to_path_buf(),
            shape: None,
            pending: Vec::new(),
            gauges: None,
            pending_gauges: GaugeRows::default(),
            finished: false,
            times: Vec::new(),
            has_maps: false,
            map_names: None,
            space,
            steps_written: 0,
            gauge_rows_written: 0,
            damaged: false,
            full: false,
        };
        let file = sink.create_file()?;
        sink.close(file, false)?;
        Ok(sink)
    }

    /// The file being written.
    pub fn path(&self) -> &Path {
        &self.path
    }

    fn err(&self, e: impl std::fmt::Display) -> OutputError {
        io_err(&self.path, e)
    }

    fn create_file(&self) -> Result<H5File, OutputError> {
        let opts = H5File::options().no_locking();
        opts.create(&self.path).map_err(|e| self.err(e))
    }

    fn open_file(&self) -> Result<H5File, OutputError> {
        let opts = H5File::options().no_locking();
        opts.open_rw(&self.path).map_err(|e| self.err(e))
    }

    fn close(&self, file: H5File, sync: bool) -> Result<(), OutputError> {
        let closed = if sync {
            file.close()
        } else {
            file.close_no_sync()
        };
        closed.map_err(|e| self.err(e))
    }

    /// Appends the buffered step records on their own (reopen, append, close), when
    /// many steps pass between two snapshots.
    fn flush_steps(&mut self) -> Result<(), OutputError> {
        self.claim(self.batch_bytes(0, false))?;
        let written = self.open_file().and_then(|file| {
            layout::append_steps(&file, &self.pending).map_err(|e| self.err(e))?;
            self.close(file, false)
        });
        self.after_batch(written, true, false)
    }

    /// Bytes the next batch can add to the file: the pending step records (and their
    /// new chunks), with `gauges` the pending gauge rows, a snapshot of `snapshot_values`
    /// numbers, and [`HEADER_BYTES`].
    fn batch_bytes(&self, snapshot_values: usize, gauges: bool) -> u64 {
        let new_chunks = |written: u64, more: u64, chunk: u64| {
            (written + more).div_ceil(chunk) - written.div_ceil(chunk)
        };
        let series = layout::STEP_DATASETS.len() as u64;
        let p = self.pending.len() as u64;
        let chunk = layout::STEP_CHUNK as u64;
        let mut bytes = series * 8 * (p + chunk * new_chunks(self.steps_written, p, chunk));
        if gauges {
            let n = self.gauges.unwrap_or(0) as u64;
            let rows = (layout::GAUGE_CHUNK_VALUES as u64 / n.max(1)).max(1);
            let g = self.pending_gauges.t.len() as u64;
            let chunks = new_chunks(self.gauge_rows_written, g, rows);
            bytes += 8 * (1 + 2 * n) * (g + rows * chunks);
        }
        if snapshot_values > 0 {
            bytes += 8 * (snapshot_values as u64 + layout::SNAP_T_CHUNK as u64);
            // A deflated raster chunk that does not compress is stored a little
            // larger than raw (zlib's stored blocks: 5 bytes per 64 KiB, and a header).
            bytes += 8 * snapshot_values as u64 / 1024 + 4096;
        }
        bytes + HEADER_BYTES
    }

    /// Claims room for a batch of `bytes` before it touches the file.
    fn claim(&mut self, bytes: u64) -> Result<(), OutputError> {
        if self.damaged {
            return Err(self.err("write error: an earlier write failed half-way"));
        }
        let len = std::fs::metadata(&self.path).map_or(0, |m| m.len());
        self.space.claim(len, bytes).map_err(|e| {
            self.full = true;
            self.err(format!(
                "write error: {e} (the file keeps what was written before)"
            ))
        })
    }

    /// Records a batch's outcome: on success its records are on disk; on failure the
    /// file is left alone from now on.
    fn after_batch(
        &mut self,
        written: Result<(), OutputError>,
        steps: bool,
        gauges: bool,
    ) -> Result<(), OutputError> {
        match written {
            Ok(()) => {
                if steps {
                    self.steps_written += self.pending.len() as u64;
                    self.pending.clear();
                }
                if gauges {
                    self.gauge_rows_written += self.pending_gauges.t.len() as u64;
                    self.pending_gauges.clear();
                }
                Ok(())
            }
            Err(OutputError::Io { path, message }) => {
                self.damaged = true;
                Err(OutputError::Io {
                    path,
                    message: format!("write error: {message}"),
                })
            }
        }
    }

    /// The XDMF file beside a raster run's HDF5 file ([`super::xdmf`]), rewritten
    /// with every snapshot so that it lists exactly the frames on disk.
    fn write_xdmf(&self) -> Result<(), OutputError> {
        let Some(shape) = &self.shape else {
            return Ok(());
        };
        let Some((nx, ny)) = shape.raster else {
            return Ok(());
        };
        let mut fields = vec!["h", "u", "v"];
        fields.extend(shape.extra.iter().flatten().copied());
        let desc = super::xdmf::XdmfRun {
            h5_name: &self
                .path
                .file_name()
                .map(|n| n.to_string_lossy().into_owned())
                .unwrap_or_default(),
            nx,
            ny,
            origin: shape.origin,
            spacing: shape.spacing,
            times: &self.times,
            fields: &fields,
            maps: if self.has_maps {
                &super::xdmf::MAP_NAMES
            } else {
                &[]
            },
        };
        super::xdmf::write(&super::xdmf::xdmf_path(&self.path), &desc)
    }

    /// Checks a call that writes maps: a raster run, before the final maps, every map
    /// one value per cell, and the same names as the maps already on disk. Returns the
    /// raster's (nx, ny).
    fn check_maps(&self, call: &str, maps: &[CellField]) -> Result<(usize, usize), OutputError> {
        let shape = self.check_open(call)?;
        let Some(raster) = shape.raster else {
            return Err(self.err("maps of a run that is not on a raster"));
        };
        if self.has_maps {
            return Err(self.err(format!("{call} after the final maps")));
        }
        let cells = raster.0 * raster.1;
        if let Some(bad) = maps.iter().find(|f| f.data.len() != cells) {
            return Err(self.err(format!(
                "map {} has {} values, expected {cells}",
                bad.name,
                bad.data.len()
            )));
        }
        let names: Vec<&str> = maps.iter().map(|f| f.name).collect();
        if let Some(old) = self.map_names.as_ref().filter(|old| **old != names) {
            return Err(self.err(format!(
                "{call}: maps {names:?} differ from those on disk {old:?}"
            )));
        }
        Ok(raster)
    }

    fn check_open(&self, call: &str) -> Result<Shape, OutputError> {
        if self.finished {
            return Err(self.err(format!("{call} after finish")));
        }
        self.shape
            .clone()
            .ok_or_else(|| self.err(format!("{call} before begin")))
    }
}

impl OutputSink for Hdf5Sink {
    fn begin(&mut self, info: &RunInfo, grid: &GridData) -> Result<(), OutputError> {
        if self.finished || self.shape.is_some() {
            return Err(self.err("begin called twice"));
        }
        let nx = grid.x.len();
        if nx == 0 || grid.b.len() != nx || grid.h_bed.len() != nx || info.layers == 0 {
            return Err(self.err(format!(
                "bad grid: x, b, h_bed have {}, {}, {} values and layers = {}",
                nx,
                grid.b.len(),
                grid.h_bed.len(),
                info.layers
            )));
        }
        let raster = match &info.raster {
            Some(_) => Some(raster_geometry(grid).map_err(|e| self.err(e))?),
            None => None,
        };
        let file = self.create_file()?;
        layout::write_layout(&file, info, grid).map_err(|e| self.err(e))?;
        self.close(file, false)?;
        self.shape = Some(Shape {
            nx,
            nl: info.layers,
            has_w: None,
            has_p_nh: None,
            extra: None,
            raster: raster.map(|g| g.0),
            origin: raster.map_or((0.0, 0.0), |g| g.1),
            spacing: raster.map_or((0.0, 0.0), |g| g.2),
        });
        Ok(())
    }

    fn snapshot(&mut self, snap: &SnapshotView) -> Result<(), OutputError> {
        let mut shape = self.check_open("snapshot")?;
        let (create, create_extra) = shape
            .check_lengths(snap)
            .and_then(|()| shape.fix_optional(snap))
            .and_then(|create| Ok((create, shape.fix_extra(snap)?)))
            .map_err(|e| self.err(format!("snapshot at t = {}: {e}", snap.t)))?;
        let (nx, nl, raster) = (shape.nx, shape.nl, shape.raster);
        let values = snap.h.len()
            + snap.u.len()
            + snap.v.map_or(0, <[f64]>::len)
            + snap.w.map_or(0, <[f64]>::len)
            + snap.p_nh.map_or(0, <[f64]>::len)
            + snap.layer_uv.map_or(0, |uv| uv.0.len() + uv.1.len())
            + snap.extra.iter().map(|f| f.data.len()).sum::<usize>();
        self.claim(self.batch_bytes(values, true))?;
        // Fixed only once the batch may go ahead: a refused snapshot leaves no trace.
        self.shape = Some(shape);
        let written = self.open_file().and_then(|file| {
            layout::create_optional(&file, (nx, nl), create)
                .and_then(|()| layout::create_cell_fields(&file, nx, raster, &create_extra))
                .and_then(|()| layout::append_steps(&file, &self.pending))
                .and_then(|()| layout::append_gauges(&file, &self.pending_gauges))
                .and_then(|()| layout::append_snapshot(&file, snap))
                .map_err(|e| self.err(e))?;
            self.close(file, false)
        });
        self.after_batch(written, true, true)?;
        self.times.push(snap.t);
        self.write_xdmf()
    }

    fn step(&mut self, rec: &StepRecord) -> Result<(), OutputError> {
        self.check_open("step")?;
        self.pending.push(*rec);
        if self.pending.len() >= MAX_PENDING_STEPS {
            self.flush_steps()?;
        }
        Ok(())
    }

    fn finish(&mut self, summary: &RunSummary) -> Result<(), OutputError> {
        if self.finished {
            return Err(self.err("finish called twice"));
        }
        self.finished = true;
        if self.damaged {
            self.space.release();
            return Err(self.err(
                "write error: an earlier write failed half-way; the file was left as it was",
            ));
        }
        // A full disk: the reserve makes room for the last records and the status; if
        // even that is not enough, the status alone, saying so.
        let mut summary = summary.clone();
        let mut lost = None;
        if self.full {
            self.space.release();
        }
        if let Err(e) = self.claim(self.batch_bytes(0, true)) {
            self.space.release();
            if self.claim(self.batch_bytes(0, true)).is_err() {
                lost = Some(e);
                self.pending.clear();
                self.pending_gauges.clear();
                if !summary.status.starts_with("failed") {
                    summary.status = format!("failed: {}", lost.as_ref().expect("set above"));
                }
            }
        }
        let written = self.open_file().and_then(|file| {
            layout::append_steps(&file, &self.pending)
                .and_then(|()| layout::append_gauges(&file, &self.pending_gauges))
                .and_then(|()| layout::write_summary(&file, &summary, self.shape.is_some()))
                .map_err(|e| self.err(e))?;
            self.close(file, true)
        });
        let written = self.after_batch(written, true, true);
        self.space.release();
        match lost {
            Some(e) => Err(e),
            None => written.and_then(|()| self.write_xdmf()),
        }
    }

    fn maps(&mut self, maps: &RunMaps) -> Result<(), OutputError> {
        let raster = self.check_maps("maps", maps.maps)?;
        let create = self.map_names.is_none();
        let values: usize = maps.maps.iter().map(|f| f.data.len()).sum();
        // Deflated maps take new room when rewritten: claimed as on the first write.
        self.claim(self.batch_bytes(values, false))?;
        let written = self.open_file().and_then(|file| {
            layout::append_steps(&file, &self.pending)
                .and_then(|()| layout::write_maps(&file, raster, maps, create))
                .map_err(|e| self.err(e))?;
            self.close(file, false)
        });
        self.after_batch(written, true, false)?;
        self.map_names = Some(maps.maps.iter().map(|f| f.name).collect());
        self.has_maps = true;
        Ok(())
    }

    fn maps_so_far(&mut self, maps: &[CellField]) -> Result<(), OutputError> {
        let raster = self.check_maps("maps_so_far", maps)?;
        let create = self.map_names.is_none();
        let values: usize = maps.iter().map(|f| f.data.len()).sum();
        self.claim(self.batch_bytes(values, false))?;
        let written = self.open_file().and_then(|file| {
            layout::write_map_fields(&file, raster, maps, create).map_err(|e| self.err(e))?;
            self.close(file, false)
        });
        self.after_batch(written, false, false)?;
        self.map_names = Some(maps.iter().map(|f| f.name).collect());
        Ok(())
    }

    fn begin_gauges(&mut self, x: &[f64]) -> Result<(), OutputError> {
        self.check_open("begin_gauges")?;
        if self.gauges.is_some() {
            return Err(self.err("begin_gauges called twice"));
        }
        if x.is_empty() {
            return Err(self.err("begin_gauges without gauges"));
        }
        let file = self.open_file()?;
        layout::create_gauges(&file, x).map_err(|e| self.err(e))?;
        self.close(file, false)?;
        self.gauges = Some(x.len());
        Ok(())
    }

    fn gauges_y(&mut self, y: &[f64]) -> Result<(), OutputError> {
        self.check_open("gauges_y")?;
        if self.gauges != Some(y.len()) {
            return Err(self.err("gauges_y without as many gauges from begin_gauges"));
        }
        let file = self.open_file()?;
        layout::gauge_y(&file, y).map_err(|e| self.err(e))?;
        self.close(file, false)
    }

    fn gauges(&mut self, rec: &GaugeRecord) -> Result<(), OutputError> {
        self.check_open("gauges")?;
        let Some(n) = self.gauges else {
            return Err(self.err("gauges before begin_gauges"));
        };
        if rec.eta.len() != n || rec.h_grains.len() != n {
            return Err(self.err(format!(
                "gauge record at t = {} has {} and {} values, expected {n}",
                rec.t,
                rec.eta.len(),
                rec.h_grains.len()
            )));
        }
        self.pending_gauges.push(rec);
        if self.pending_gauges.values() >= GAUGE_BUFFER_VALUES {
            self.claim(self.batch_bytes(0, true))?;
            let written = self.open_file().and_then(|file| {
                layout::append_steps(&file, &self.pending)
                    .and_then(|()| layout::append_gauges(&file, &self.pending_gauges))
                    .map_err(|e| self.err(e))?;
                self.close(file, false)
            });
            self.after_batch(written, true, true)?;
        }
        Ok(())
    }
}

impl Drop for Hdf5Sink {
    /// A run that unwinds without calling `finish` still gets the step records it
    /// produced since its last snapshot, when the file can take them.
    fn drop(&mut self) {
        let nothing = self.pending.is_empty() && self.pending_gauges.t.is_empty();
        if self.finished || nothing || self.shape.is_none() || self.damaged {
            return;
        }
        let saved = self
            .claim(self.batch_bytes(0, true))
            .and_then(|()| self.open_file())
            .and_then(|file| {
                let appended = layout::append_steps(&file, &self.pending)
                    .and_then(|()| layout::append_gauges(&file, &self.pending_gauges))
                    .map_err(|e| self.err(e));
                appended.and(self.close(file, false))
            });
        if let Err(e) = saved {
            crate::terminal::print_err(&format!(
                "granflow: the last step records were not saved: {e}\n"
            ));
        }
    }
}

/// The raster of a run: (nx, ny), the lower-left corner and the spacing, from the
/// grid's spec, checked against the cell centres handed to `begin` (row-major x and y
/// of every cell).
#[allow(clippy::type_complexity)]
fn raster_geometry(grid: &GridData) -> Result<((usize, usize), (f64, f64), (f64, f64)), String> {
    let Some(g) = grid.spec.raster() else {
        return Err("a raster run on a grid that is not a raster".into());
    };
    let (nx, ny, cells) = (g.nx, g.ny, grid.x.len());
    let Some(y) = grid.y else {
        return Err("a raster run without y coordinates".into());
    };
    if nx == 0 || ny == 0 || nx * ny != cells || y.len() != cells || grid.shape != Some((ny, nx)) {
        return Err(format!(
            "bad raster: {nx} × {ny} cells but x, y have {} and {} values of shape {:?}",
            cells,
            y.len(),
            grid.shape
        ));
    }
    Ok(((nx, ny), (g.x_min, g.y_min), (g.dx, g.dy)))
}

fn present(yes: bool) -> &'static str {
    if yes {
        "present"
    } else {
        "absent"
    }
}

fn io_err(path: &Path, e: impl std::fmt::Display) -> OutputError {
    OutputError::Io {
        path: path.display().to_string(),
        message: e.to_string(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::{GridSpec, LineGeometry, RasterGeometry};

    fn info(layers: usize) -> RunInfo {
        RunInfo {
            granflow_version: "test".into(),
            model: "granular".into(),
            pressure: "hydrostatic".into(),
            layers,
            coordinates: "local".into(),
            slope_deg: 0.0,
            scenario_toml: String::new(),
            front_threshold: 1e-3,
            raster: None,
        }
    }

    /// The run information of a raster run.
    fn raster_info() -> RunInfo {
        let mut raster = info(1);
        raster.raster = Some(crate::output::RasterInfo {
            release: None,
            wall_cells: 0,
        });
        raster
    }

    /// A raster of `nx` × `ny` cells of 1 m from (0, 0), without CRS.
    fn raster_spec(nx: usize, ny: usize) -> GridSpec {
        let (w, h) = (nx as f64, ny as f64);
        GridSpec::Raster(RasterGeometry::of_extent(nx, ny, [0.0, w], [0.0, h]))
    }

    /// A line of `nx` cells of 1 m from 0.
    fn line_spec(nx: usize) -> GridSpec {
        GridSpec::Line(LineGeometry {
            nx,
            x_min: 0.0,
            x_max: nx as f64,
            dx: 1.0,
        })
    }

    fn begin(path: &Path) -> Hdf5Sink {
        let mut sink = Hdf5Sink::create(path).unwrap();
        let x = [0.5, 1.5, 2.5];
        sink.begin(
            &info(2),
            &GridData {
                spec: &line_spec(3),
                x: &x,
                y: None,
                shape: None,
                b: &[0.0; 3],
                h_bed: &[0.0; 3],
            },
        )
        .unwrap();
        sink
    }

    /// The grid's spec is written as `/grid` attributes: its kind, and on a raster the
    /// text that reads back to the same geometry and the CRS; a raster spec whose cells
    /// are not the grid's is refused.
    #[test]
    fn the_grid_spec_is_written_as_attributes_of_grid() {
        let dir = tempfile::tempdir().unwrap();
        let line = dir.path().join("line.h5");
        drop(begin(&line));
        let file = H5File::open(&line).unwrap();
        let grid = file.root_group().group("grid").unwrap();
        assert_eq!(grid.attr_string("kind").unwrap(), "line");
        assert!(grid.attr_string("spec").is_err());

        let path = dir.path().join("raster.h5");
        let mut geometry = RasterGeometry::of_extent(3, 2, [600_000.1, 600_000.4], [-0.3, -0.1]);
        geometry.crs = crate::gis::Crs::from_epsg(32632);
        let spec = GridSpec::Raster(geometry.clone());
        let x = [0.5, 1.5, 2.5, 0.5, 1.5, 2.5];
        let y = [0.5, 0.5, 0.5, 1.5, 1.5, 1.5];
        let mut grid = GridData {
            spec: &spec,
            x: &x,
            y: Some(&y),
            shape: Some((2, 3)),
            b: &[0.0; 6],
            h_bed: &[0.0; 6],
        };
        Hdf5Sink::create(&path)
            .unwrap()
            .begin(&raster_info(), &grid)
            .unwrap();
        let file = H5File::open(&path).unwrap();
        let g = file.root_group().group("grid").unwrap();
        assert_eq!(g.attr_string("kind").unwrap(), "raster");
        assert_eq!(g.attr_string("crs").unwrap(), "EPSG:32632");
        let text = g.attr_string("spec").unwrap();
        let back = RasterGeometry::from_text(&text, geometry.crs.clone());
        assert_eq!(back, Some(geometry));

        let wrong = raster_spec(2, 3);
        grid.spec = &wrong;
        let e = Hdf5Sink::create(&dir.path().join("wrong.h5"))
            .unwrap()
            .begin(&raster_info(), &grid)
            .unwrap_err();
        assert!(e.to_string().contains("bad raster"), "{e}");
    }

    fn view<'a>(t: f64, data: &'a [f64], extra: &'a [CellField<'a>]) -> SnapshotView<'a> {
        SnapshotView {
            t,
            h: &data[..3],
            u: data,
            v: None,
            shape: None,
            w: None,
            p_nh: None,
            layers: 2,
            extra,
            layer_uv: None,
        }
    }

    #[test]
    fn per_cell_fields_are_written_as_frames() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("extra.h5");
        let mut sink = begin(&path);
        let data = [1.0, 2.0, 3.0, 4.0, 5.0, 6.0];
        for t in [0.0, 1.0] {
            let s = [t, t + 0.5, t + 0.25];
            let extra = [CellField {
                name: "static_interface",
                units: "m",
                description: "",
                data: &s,
            }];
            sink.snapshot(&view(t, &data, &extra)).unwrap();
        }
        let file = H5File::open(&path).unwrap();
        let ds = file.dataset("snapshots/static_interface").unwrap();
        assert_eq!(ds.shape(), [2, 3]);
        assert_eq!(
            ds.read_raw::<f64>().unwrap(),
            [0.0, 0.5, 0.25, 1.0, 1.5, 1.25]
        );
    }

    #[test]
    fn per_cell_fields_are_checked() {
        let dir = tempfile::tempdir().unwrap();
        let data = [1.0; 6];
        let field = |name: &'static str, data: &'static [f64]| CellField {
            name,
            units: "m",
            description: "",
            data,
        };
        let cases: [(&[CellField], &str); 4] = [
            (&[field("h", &[0.0; 3])], "not allowed"),
            (&[field("bad name", &[0.0; 3])], "not allowed"),
            (&[field("phi", &[0.0; 2])], "phi has 2 values"),
            (&[field("phi", &[0.0; 3]), field("phi", &[0.0; 3])], "twice"),
        ];
        for (k, (extra, message)) in cases.into_iter().enumerate() {
            let mut sink = begin(&dir.path().join(format!("bad{k}.h5")));
            let e = sink.snapshot(&view(0.0, &data, extra)).unwrap_err();
            assert!(e.to_string().contains(message), "{e}");
        }
        // The names are fixed by the first snapshot.
        let mut sink = begin(&dir.path().join("change.h5"));
        sink.snapshot(&view(0.0, &data, &[field("phi", &[0.0; 3])]))
            .unwrap();
        let e = sink.snapshot(&view(1.0, &data, &[])).unwrap_err();
        assert!(e.to_string().contains("earlier snapshots"), "{e}");
    }

    #[test]
    fn gauge_rows_are_written_when_the_buffer_fills_and_on_drop() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("gauges.h5");
        let mut sink = begin(&path);
        assert!(sink
            .gauges(&GaugeRecord {
                t: 0.0,
                eta: &[1.0],
                h_grains: &[1.0]
            })
            .is_err());
        sink.begin_gauges(&[0.5, 2.5]).unwrap();
        assert!(sink.begin_gauges(&[0.5]).is_err());
        let row = |k: usize| GaugeRecord {
            t: k as f64,
            eta: &[0.0, 1.0],
            h_grains: &[2.0, 3.0],
        };
        let bad = GaugeRecord {
            t: 0.0,
            eta: &[1.0],
            h_grains: &[1.0, 2.0],
        };
        assert!(sink
            .gauges(&bad)
            .unwrap_err()
            .to_string()
            .contains("expected 2"));
        // 5 values a row (t and two per quantity): the bound is reached at this row.
        let rows = GAUGE_BUFFER_VALUES.div_ceil(5);
        for k in 0..rows {
            sink.gauges(&row(k)).unwrap();
        }
        {
            let file = H5File::open(&path).unwrap();
            let t = file.dataset("gauges/t").unwrap().read_raw::<f64>().unwrap();
            assert_eq!(t.len(), rows);
            assert_eq!(t[rows - 1], (rows - 1) as f64);
            let eta = file.dataset("gauges/eta").unwrap();
            assert_eq!(eta.shape(), [rows, 2]);
            assert_eq!(
                file.dataset("gauges/x").unwrap().read_raw::<f64>().unwrap(),
                [0.5, 2.5]
            );
        }
        // A sink dropped without finish still saves the rows it holds.
        sink.gauges(&row(rows)).unwrap();
        drop(sink);
        let file = H5File::open(&path).unwrap();
        let h = file.dataset("gauges/h_grains").unwrap();
        assert_eq!(h.shape(), [rows + 1, 2]);
        assert_eq!(h.read_raw::<f64>().unwrap()[2 * rows..], [2.0, 3.0]);
    }
    /// A raster run's snapshot fields are stored in bands of rows, shuffled and
    /// deflated: a mostly dry raster (a wet disc on 2 % of 150 000 cells, NaN walls
    /// in one corner) takes a small fraction of its raw size and reads back exactly.
    #[test]
    fn raster_snapshots_are_chunked_deflated_and_read_back_exactly() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("raster.h5");
        let (nx, ny) = (500, 300);
        let mut sink = Hdf5Sink::create(&path).unwrap();
        let raster = raster_info();
        let spec = raster_spec(nx, ny);
        let x: Vec<f64> = (0..nx * ny).map(|k| (k % nx) as f64 + 0.5).collect();
        let y: Vec<f64> = (0..nx * ny).map(|k| (k / nx) as f64 + 0.5).collect();
        let zeros = vec![0.0; nx * ny];
        let grid = GridData {
            spec: &spec,
            x: &x,
            y: Some(&y),
            shape: Some((ny, nx)),
            b: &zeros,
            h_bed: &zeros,
        };
        sink.begin(&raster, &grid).unwrap();
        let frames = 4;
        let field = |t: f64, scale: f64| -> Vec<f64> {
            (0..nx * ny)
                .map(|k| {
                    let (i, j) = ((k % nx) as f64, (k / nx) as f64);
                    let r2 = (i - 100.0 - 50.0 * t).powi(2) + (j - 150.0).powi(2);
                    if i < 10.0 && j < 10.0 {
                        f64::NAN
                    } else if r2 < 1200.0 {
                        scale * (1.0 - r2 / 1200.0) + 1e-3 * (i * j).sin()
                    } else {
                        0.0
                    }
                })
                .collect()
        };
        for k in 0..frames {
            let t = k as f64;
            let (h, u, v) = (field(t, 2.0), field(t, 30.0), field(t, -5.0));
            sink.snapshot(&SnapshotView {
                t,
                h: &h,
                u: &u,
                v: Some(&v),
                shape: Some((ny, nx)),
                w: None,
                p_nh: None,
                layers: 1,
                extra: &[],
                layer_uv: None,
            })
            .unwrap();
        }
        sink.finish(&RunSummary::not_run("completed".into(), 0.0))
            .unwrap();
        let file = H5File::open(&path).unwrap();
        for (name, scale) in [("h", 2.0), ("u", 30.0), ("v", -5.0)] {
            let ds = file.dataset(&format!("snapshots/{name}")).unwrap();
            assert_eq!(ds.shape(), [frames, ny, nx]);
            // 262 rows of 500 values: 1 MiB per chunk.
            assert_eq!(ds.chunk_dims(), Some(vec![1, 262, nx]));
            let ids: Vec<u16> = ds.filters().unwrap().iter().map(|f| f.id).collect();
            // HDF5's filter ids: 2 shuffle, then 1 deflate.
            assert_eq!(ids, [2, 1]);
            let data = ds.read_raw::<f64>().unwrap();
            for k in 0..frames {
                let want = field(k as f64, scale);
                let got = &data[k * nx * ny..(k + 1) * nx * ny];
                assert!(
                    got.iter()
                        .zip(&want)
                        .all(|(a, b)| a.to_bits() == b.to_bits()),
                    "{name} frame {k}"
                );
            }
        }
        // The file against the raw size of its snapshots (its flat bed and erodible
        // bed, zeros, are deflated too).
        let raw = 3 * frames * nx * ny * 8;
        let size = std::fs::metadata(&path).unwrap().len() as usize;
        assert!(size < raw / 10, "{size} bytes against {raw} raw");
    }

    #[test]
    fn maps_are_written_with_snapshots_and_rewritten_in_place() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("maps.h5");
        let mut sink = Hdf5Sink::create(&path).unwrap();
        let raster = raster_info();
        let x = [0.5, 1.5, 2.5, 0.5, 1.5, 2.5];
        let y = [0.5, 0.5, 0.5, 1.5, 1.5, 1.5];
        sink.begin(
            &raster,
            &GridData {
                spec: &raster_spec(3, 2),
                x: &x,
                y: Some(&y),
                shape: Some((2, 3)),
                b: &[0.0; 6],
                h_bed: &[0.0; 6],
            },
        )
        .unwrap();
        let map = |name: &'static str, data: &'static [f64]| CellField {
            name,
            units: "m",
            description: "",
            data,
        };
        let read = |name: &str| {
            let file = H5File::open(&path).unwrap();
            let ds = file.dataset(name).unwrap();
            assert_eq!(ds.shape(), [2, 3]);
            ds.read_raw::<f64>().unwrap()
        };
        sink.maps_so_far(&[map("h_max", &[1.0; 6]), map("deposit", &[2.0; 6])])
            .unwrap();
        // A file read now (a run killed after this snapshot) holds the maps.
        assert_eq!(read("maps/h_max"), [1.0; 6]);
        sink.maps_so_far(&[map("h_max", &[3.0; 6]), map("deposit", &[4.0; 6])])
            .unwrap();
        assert_eq!(read("maps/deposit"), [4.0; 6]);
        let e = sink
            .maps_so_far(&[map("h_max", &[3.0; 6])])
            .unwrap_err()
            .to_string();
        assert!(e.contains("differ from those on disk"), "{e}");
        let last = [map("h_max", &[5.0; 6]), map("deposit", &[6.0; 6])];
        sink.maps(&RunMaps {
            maps: &last,
            series: &[],
            scalars: &[],
            profile: &[],
        })
        .unwrap();
        assert_eq!(read("maps/h_max"), [5.0; 6]);
        assert_eq!(read("maps/deposit"), [6.0; 6]);
        let e = sink.maps_so_far(&last).unwrap_err().to_string();
        assert!(e.contains("after the final maps"), "{e}");
    }
}
