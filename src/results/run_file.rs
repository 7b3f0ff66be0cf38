//! Reading a raster (2-D) run's HDF5 file back (`docs/output-format.md`, "Raster (2-D)
//! runs"): its grid as a north-up [`Raster`], its CRS, the `/maps` and the snapshot
//! frames.
//!
//! The file stores fields (ny, nx) with row j = 0 at the south edge (y increasing);
//! a [`Raster`] has row 0 at the top (north). [`north_up`] flips the rows, so cell
//! (i, j) of the file is cell (col i, row ny − 1 − j) of the raster.
//!
//! The grid is the run's [`RasterGeometry`] as the `/grid` attributes record it (the
//! text attribute `spec` and the CRS attributes `crs`, `crs_wkt`: the HDF5 library
//! granflow uses reads a group's string attributes back, not its numeric ones): the
//! raster's top-left corner is (x_min, y_max), its cell size Δx. A file written before
//! those attributes gives the grid by its cell centres `/grid/x`, `/grid/y` (corner
//! (x₀ − Δ/2, y_{ny−1} + Δ/2), or the root attribute `geotransform` when it is the same
//! grid) and the CRS by the root attributes `crs`, `crs_wkt`. Either way the cells
//! must be square (Δx = Δy within 10⁻⁹), as GeoTIFF and ESRI ASCII grids have them.

use std::path::{Path, PathBuf};

use rust_hdf5::H5File;

use super::ResultsError;
use crate::gis::{Crs, Raster};
pub use crate::grid::spec::north_up;
use crate::grid::RasterGeometry;

/// Most cells (and values of one axis) a run file may declare: the largest raster
/// domain of a run (`domain.cells`, 10⁷). A larger size is a damaged or crafted file,
/// refused before it is read.
pub const MAX_RUN_CELLS: usize = 10_000_000;

/// An open raster run file.
pub struct RunFile {
    path: PathBuf,
    file: H5File,
    nx: usize,
    ny: usize,
    geometry: RasterGeometry,
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
        // Every size is checked against what a run can write before anything is read:
        // a crafted file of 2 MB may declare a grid of 10¹⁰ cells.
        let read = |name: &str| -> Result<Vec<f64>, ResultsError> {
            let ds = file
                .dataset(name)
                .map_err(|e| bad(format!("cannot read /{name}: {e}")))?;
            let shape = ds.shape();
            if shape.len() != 1 || shape[0] > MAX_RUN_CELLS {
                return Err(bad(format!(
                    "/{name} has shape {shape:?}; a run writes one axis of at most \
                     {MAX_RUN_CELLS} values"
                )));
            }
            ds.read_raw::<f64>()
                .map_err(|e| bad(format!("cannot read /{name}: {e}")))
        };
        let x = read("grid/x")?;
        let y = read("grid/y")?;
        let (nx, ny) = (x.len(), y.len());
        if nx == 0 || ny == 0 {
            return Err(bad("an empty grid".into()));
        }
        if nx.saturating_mul(ny) > MAX_RUN_CELLS {
            return Err(bad(format!(
                "a grid of {nx} x {ny} cells; a run has at most {MAX_RUN_CELLS}"
            )));
        }
        if !x.iter().chain(&y).all(|v| v.is_finite()) {
            return Err(bad(
                "the cell centres /grid/x, /grid/y are not all finite".into()
            ));
        }
        let on_grid = |name: &str| root.group("grid").ok()?.attr_string(name).ok();
        let geometry = match on_grid("spec") {
            Some(text) => {
                let crs = crs_of(|name| on_grid(name));
                let g = RasterGeometry::from_text(&text, crs).ok_or_else(|| {
                    bad(format!(
                        "the /grid attribute spec = {text:?} is not a raster's"
                    ))
                })?;
                if (g.nx, g.ny) != (nx, ny) {
                    return Err(bad(format!(
                        "/grid says {} x {} cells, /grid/x and /grid/y have {nx} and {ny}",
                        g.nx, g.ny
                    )));
                }
                g
            }
            None => geometry_of_centres(&file, &x, &y).map_err(bad)?,
        };
        let (dx, dy) = (geometry.dx, geometry.dy);
        if !(dx > 0.0 && dy > 0.0) || (dx - dy).abs() > 1e-9 * dx.max(dy) {
            return Err(bad(format!(
                "cells are not square (dx = {dx}, dy = {dy}): GeoTIFF and ESRI ASCII grids need \
                 square cells; run with domain.cells = [nx, ny] in the ratio of the extents"
            )));
        }
        let mut grid = Raster::filled(nx, ny, geometry.x_min, geometry.y_max, dx, 0.0);
        grid.crs = geometry.crs.clone();
        let times = read("snapshots/t")?;
        let coordinates = root.attr_string("coordinates").unwrap_or_default();
        Ok(RunFile {
            path: path.to_path_buf(),
            file,
            nx,
            ny,
            geometry,
            grid,
            times,
            coordinates,
        })
    }

    /// The file's path.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// The run's grid as the file records it: the `/grid` attributes, or in a file
    /// written before them, what the cell centres and root attributes give.
    pub fn geometry(&self) -> &RasterGeometry {
        &self.geometry
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

    /// The `description` attribute of `/maps/<name>`, when the file has one (files of
    /// granflow before it had none).
    pub fn map_description(&self, name: &str) -> Option<String> {
        let ds = self.file.dataset(&format!("maps/{name}")).ok()?;
        ds.attr("description").ok()?.read_string().ok()
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

/// The CRS of the attributes `crs_wkt` and `crs` (`EPSG:n`) that `attr` reads.
fn crs_of(attr: impl Fn(&str) -> Option<String>) -> Crs {
    let mut crs = attr("crs_wkt").map_or_else(Crs::unknown, |wkt| Crs::from_wkt(&wkt));
    if let Some(code) =
        attr("crs").and_then(|s| s.strip_prefix("EPSG:").and_then(|c| c.parse::<u32>().ok()))
    {
        crs.epsg = Some(code);
    }
    crs
}

/// The grid of a file written before the `/grid` attributes: the cell size from the
/// centres `x`, `y` (or an axis' `spacing` attribute when it has one cell), the edges
/// half a cell beyond the outer centres, unless the root attribute `geotransform`
/// gives the same grid exactly; the CRS of the root attributes.
fn geometry_of_centres(file: &H5File, x: &[f64], y: &[f64]) -> Result<RasterGeometry, String> {
    let (nx, ny) = (x.len(), y.len());
    // An axis of one cell has no spacing between centres: the cell size is the
    // axis' `spacing` attribute (files without it cannot be placed).
    let stored = |name: &str| -> Option<f64> {
        let ds = file.dataset(name).ok()?;
        let attr = ds.attr("spacing").ok()?;
        attr.read_numeric::<f64>().ok()
    };
    let axis_step = |axis: &[f64], name: &str, what: &str| {
        spacing(axis).or_else(|| stored(name)).ok_or_else(|| {
            format!(
                "one {what} and no `spacing` attribute on /{name}: the cell size along \
                 it is unknown (a file of an older granflow)"
            )
        })
    };
    let dx = axis_step(x, "grid/x", "column")?;
    let dy = axis_step(y, "grid/y", "row")?;
    let root = file.root_group();
    let mut g = RasterGeometry {
        nx,
        ny,
        x_min: x[0] - 0.5 * dx,
        x_max: x[nx - 1] + 0.5 * dx,
        y_min: y[0] - 0.5 * dy,
        y_max: y[ny - 1] + 0.5 * dy,
        dx,
        dy,
        crs: crs_of(|name| root.attr_string(name).ok()),
    };
    if let Some([x_left, d, y_top]) = root
        .attr_string("geotransform")
        .ok()
        .and_then(|t| exact_grid(&t, &g))
    {
        (g.x_min, g.y_max, g.dx, g.dy) = (x_left, y_top, d, d);
        (g.x_max, g.y_min) = (x_left + nx as f64 * d, y_top - ny as f64 * d);
    }
    Ok(g)
}

/// The DEM's grid from the `geotransform` attribute (`x₀ Δ 0 y₀ 0 −Δ`, exact doubles)
/// as (x₀, Δ, y₀), when it is that of `grid` (from the cell centres) to 10⁻⁶ of a cell:
/// the centres give the grid only to rounding.
fn exact_grid(text: &str, grid: &RasterGeometry) -> Option<[f64; 3]> {
    let v: Vec<f64> = text
        .split_whitespace()
        .map(str::parse)
        .collect::<Result<_, _>>()
        .ok()?;
    let &[x0, d, rx, y0, ry, minus_d] = v.as_slice() else {
        return None;
    };
    let close = |a: f64, b: f64| (a - b).abs() <= 1e-6 * grid.dx;
    (rx == 0.0
        && ry == 0.0
        && minus_d == -d
        && close(d, grid.dx)
        && close(x0, grid.x_min)
        && close(y0, grid.y_max))
    .then_some([x0, d, y0])
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A raster run file of `geometry` with only what [`RunFile::open`] reads: the
    /// cell centres, one snapshot time, the root attributes `old` (a file written
    /// before the `/grid` attributes) and, when `spec`, the `/grid` attributes.
    fn write(path: &Path, geometry: &RasterGeometry, old: &[(&str, String)], spec: bool) {
        let file = H5File::options().no_locking().create(path).unwrap();
        file.set_attr_string("granflow_version", "test").unwrap();
        file.set_attr_string("grid", "raster").unwrap();
        for (name, value) in old {
            file.set_attr_string(name, value).unwrap();
        }
        let g = file.create_group("grid").unwrap();
        let centre = |min: f64, d: f64, k: usize| min + (k as f64 + 0.5) * d;
        let x: Vec<f64> = (0..geometry.nx)
            .map(|i| centre(geometry.x_min, geometry.dx, i))
            .collect();
        let y: Vec<f64> = (0..geometry.ny)
            .map(|j| centre(geometry.y_min, geometry.dy, j))
            .collect();
        for (name, data) in [("x", &x), ("y", &y)] {
            let ds = g
                .new_dataset::<f64>()
                .shape([data.len()])
                .create(name)
                .unwrap();
            ds.write_raw(data).unwrap();
        }
        if spec {
            g.set_attr_string("spec", &geometry.to_text()).unwrap();
            g.set_attr_string("crs", "EPSG:2056").unwrap();
        }
        let s = file.create_group("snapshots").unwrap();
        let t = s.new_dataset::<f64>().shape([1]).create("t").unwrap();
        t.write_raw(&[0.0]).unwrap();
        file.close().unwrap();
    }

    /// A DEM's grid whose edges the cell centres give only to rounding.
    fn dem() -> RasterGeometry {
        let (x_left, y_top, d, nx, ny) = (2_600_123.37, 1_200_456.91, 0.3, 13, 9);
        RasterGeometry {
            nx,
            ny,
            x_min: x_left,
            x_max: x_left + nx as f64 * d,
            y_min: y_top - ny as f64 * d,
            y_max: y_top,
            dx: d,
            dy: d,
            crs: Crs::from_epsg(2056),
        }
    }

    fn header(r: &Raster) -> (usize, usize, f64, f64, f64, Option<u32>) {
        (r.nx, r.ny, r.x_left, r.y_top, r.cell_size, r.crs.epsg)
    }

    #[test]
    fn the_grid_of_the_grid_attributes_is_the_runs_exactly() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("new.h5");
        let g = dem();
        write(&path, &g, &[], true);
        let run = RunFile::open(&path).unwrap();
        assert_eq!(run.geometry(), &g);
        let want = (13, 9, g.x_min, g.y_max, g.dx, Some(2056));
        assert_eq!(header(run.grid()), want);
    }

    #[test]
    fn a_file_without_the_grid_attributes_gives_the_grid_as_before() {
        let dir = tempfile::tempdir().unwrap();
        let g = dem();
        // With the DEM's geotransform: the DEM's grid exactly.
        let path = dir.path().join("dem.h5");
        let transform = format!("{} {} 0 {} 0 {}", g.x_min, g.dx, g.y_max, -g.dx);
        let old = [
            ("crs", "EPSG:2056".to_string()),
            ("geotransform", transform),
        ];
        write(&path, &g, &old, false);
        let run = RunFile::open(&path).unwrap();
        assert_eq!(
            header(run.grid()),
            (13, 9, g.x_min, g.y_max, g.dx, Some(2056))
        );
        // Without: half a cell beyond the outer centres, the cell size from their spacing.
        let path = dir.path().join("keys.h5");
        write(&path, &g, &[], false);
        let run = RunFile::open(&path).unwrap();
        let x = |i: usize| g.x_min + (i as f64 + 0.5) * g.dx;
        let y = |j: usize| g.y_min + (j as f64 + 0.5) * g.dy;
        let dx = (x(12) - x(0)) / 12.0;
        let dy = (y(8) - y(0)) / 8.0;
        assert_eq!(
            header(run.grid()),
            (13, 9, x(0) - 0.5 * dx, y(8) + 0.5 * dy, dx, None)
        );
    }
}
