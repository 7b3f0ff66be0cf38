//! Reading a raster (2-D) run's HDF5 file back (`docs/output-format.md`, "Raster (2-D)
//! runs"): its grid as a north-up [`Raster`], its CRS, the `/maps` and the snapshot
//! frames.
//!
//! The file stores fields (ny, nx) with row j = 0 at the south edge (y increasing);
//! a [`Raster`] has row 0 at the top (north). [`north_up`] flips the rows, so cell
//! (i, j) of the file is cell (col i, row ny − 1 − j) of the raster. The raster's
//! top-left corner is (x₀ − Δ/2, y_{ny−1} + Δ/2) from the cell centres `/grid/x`,
//! `/grid/y`; the cells must be square (Δx = Δy within 10⁻⁹), as GeoTIFF and ESRI
//! ASCII grids have them.
//!
//! The CRS is the root attribute `crs` (`EPSG:n`) and/or `crs_wkt`, both strings (the
//! HDF5 library granflow uses reads string attributes back, not numeric ones).

use std::path::{Path, PathBuf};

use rust_hdf5::H5File;

use super::ResultsError;
use crate::gis::{Crs, Raster};

/// An open raster run file.
pub struct RunFile {
    path: PathBuf,
    file: H5File,
    nx: usize,
    ny: usize,
    grid: Raster,
    times: Vec<f64>,
    coordinates: String,
}

impl std::fmt::Debug for RunFile {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("RunFile")
            .field("path", &self.path)
            .field("nx", &self.nx)
            .field("ny", &self.ny)
            .finish()
    }
}

fn spacing(axis: &[f64]) -> Option<f64> {
    (axis.len() > 1).then(|| (axis[axis.len() - 1] - axis[0]) / (axis.len() - 1) as f64)
}

impl RunFile {
    /// Opens `path`, refusing (as bad input) a missing file, a file that is not a
    /// granflow HDF5 file, a 1-D run and a raster whose cells are not square.
    pub fn open(path: &Path) -> Result<RunFile, ResultsError> {
        let bad = |reason: String| ResultsError::input(format!("{}: {reason}", path.display()));
        if !path.is_file() {
            return Err(bad("no such file".into()));
        }
        let file = H5File::options()
            .no_locking()
            .open(path)
            .map_err(|e| bad(format!("not a readable HDF5 file ({e})")))?;
        let root = file.root_group();
        if root.attr_string("granflow_version").is_err() {
            return Err(bad(
                "not a granflow output file (no granflow_version)".into()
            ));
        }
        if root.attr_string("grid").ok().as_deref() != Some("raster") {
            return Err(bad(
                "a 1-D run: only raster (2-D) runs have maps to export (docs/output-format.md)"
                    .into(),
            ));
        }
        let read = |name: &str| -> Result<Vec<f64>, ResultsError> {
            file.dataset(name)
                .and_then(|d| d.read_raw::<f64>())
                .map_err(|e| bad(format!("cannot read /{name}: {e}")))
        };
        let x = read("grid/x")?;
        let y = read("grid/y")?;
        let (nx, ny) = (x.len(), y.len());
        if nx == 0 || ny == 0 {
            return Err(bad("an empty grid".into()));
        }
        let (dx, dy) = match (spacing(&x), spacing(&y)) {
            (Some(dx), Some(dy)) => (dx, dy),
            (Some(d), None) | (None, Some(d)) => (d, d),
            (None, None) => return Err(bad("a grid of one cell has no cell size".into())),
        };
        if !(dx > 0.0 && dy > 0.0) || (dx - dy).abs() > 1e-9 * dx.max(dy) {
            return Err(bad(format!(
                "cells are not square (dx = {dx}, dy = {dy}): GeoTIFF and ESRI ASCII grids need \
                 square cells; run with domain.cells = [nx, ny] in the ratio of the extents"
            )));
        }
        let mut crs = match root.attr_string("crs_wkt") {
            Ok(wkt) => Crs::from_wkt(&wkt),
            Err(_) => Crs::unknown(),
        };
        if let Some(code) = root
            .attr_string("crs")
            .ok()
            .and_then(|s| s.strip_prefix("EPSG:").and_then(|c| c.parse::<u32>().ok()))
        {
            crs.epsg = Some(code);
        }
        let mut grid = Raster::filled(nx, ny, x[0] - 0.5 * dx, y[ny - 1] + 0.5 * dx, dx, 0.0);
        grid.crs = crs;
        let times = read("snapshots/t")?;
        let coordinates = root.attr_string("coordinates").unwrap_or_default();
        Ok(RunFile {
            path: path.to_path_buf(),
            file,
            nx,
            ny,
            grid,
            times,
            coordinates,
        })
    }

    /// The file's path.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// The grid (values 0, no nodata) with the run's georeferencing and CRS.
    pub fn grid(&self) -> &Raster {
        &self.grid
    }

    /// The times of the snapshots on disk (s).
    pub fn times(&self) -> &[f64] {
        &self.times
    }

    /// The run's `/summary` `status` (`unfinished` while it runs or when its writer was
    /// killed; `None` in a file without one).
    pub fn status(&self) -> Option<String> {
        self.file
            .root_group()
            .group("summary")
            .ok()?
            .attr_string("status")
            .ok()
    }

    /// The `coordinates` attribute (`cartesian` or `local`).
    pub fn coordinates(&self) -> &str {
        &self.coordinates
    }

    fn bad(&self, reason: String) -> ResultsError {
        ResultsError::input(format!("{}: {reason}", self.path.display()))
    }

    /// `/maps/<name>` in the file's order (row 0 south).
    pub fn map(&self, name: &str) -> Result<Vec<f64>, ResultsError> {
        let ds = self.file.dataset(&format!("maps/{name}")).map_err(|_| {
            self.bad(format!(
                "no /maps/{name} (a run killed before its first snapshot, or written by an \
                 older granflow)"
            ))
        })?;
        if ds.shape() != [self.ny, self.nx] {
            return Err(self.bad(format!(
                "/maps/{name} has shape {:?}, expected [{}, {}]",
                ds.shape(),
                self.ny,
                self.nx
            )));
        }
        ds.read_raw::<f64>()
            .map_err(|e| self.bad(format!("cannot read /maps/{name}: {e}")))
    }

    /// Frame `k` of `/snapshots/<name>` in the file's order (row 0 south).
    pub fn frame(&self, name: &str, k: usize) -> Result<Vec<f64>, ResultsError> {
        let ds = self
            .file
            .dataset(&format!("snapshots/{name}"))
            .map_err(|e| self.bad(format!("cannot open /snapshots/{name}: {e}")))?;
        let shape = ds.shape();
        if shape.len() != 3 || shape[1..] != [self.ny, self.nx] || k >= shape[0] {
            return Err(self.bad(format!(
                "/snapshots/{name} has shape {shape:?}, no frame {k} of ({}, {})",
                self.ny, self.nx
            )));
        }
        ds.read_slice::<f64>(&[k, 0, 0], &[1, self.ny, self.nx])
            .map_err(|e| self.bad(format!("cannot read /snapshots/{name}[{k}]: {e}")))
    }
}

/// The values of a (ny, nx) field stored south row first, reordered north row first
/// (the order of a [`Raster`]); the same flip takes a raster's values back to the
/// file's order.
pub fn north_up<T: Copy>(values: &[T], nx: usize, ny: usize) -> Vec<T> {
    debug_assert_eq!(values.len(), nx * ny);
    let mut out = Vec::with_capacity(nx * ny);
    for row in values.chunks(nx).rev() {
        out.extend_from_slice(row);
    }
    out
}
