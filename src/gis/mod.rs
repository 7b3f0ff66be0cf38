//! GIS input and output: rasters (DEMs, release thickness, hazard maps) and release
//! polygons, in the formats users bring from r.avaflow, AvaFrame or RAMMS. Everything
//! here is pure Rust: no GDAL, libnetcdf or libhdf5 is linked. `docs/gis.md` is the
//! user reference; this is the summary.
//!
//! # The raster convention
//!
//! A [`Raster`] is a north-up grid of square cells: `nx` columns, `ny` rows, cell size
//! `cell_size`, the **left edge** at `x_left` and the **top edge** at `y_top` (the
//! corner GeoTIFF tiepoints name). Values are row-major with **row 0 at the top**
//! (northernmost) and column 0 at the left: `values[row * nx + col]`, which is the order
//! of both the ESRI ASCII grid and the GeoTIFF strips, so reading and writing copy no
//! rows. The centre of cell `(col, row)` is
//! `(x_left + (col + ½)·d, y_top − (row + ½)·d)`.
//!
//! Cells equal to `nodata` (or NaN, when `nodata` is NaN) have no value. The rule
//! proposed for the 2-D solver is that **nodata cells are walls**: no mass enters them.
//! The CRS ([`Crs`]: an EPSG code and/or WKT text) is carried through, never used for
//! reprojection: inputs in different CRS are refused ([`Crs::check_same`]).
//!
//! # Modules
//!
//! * [`asc`]: ESRI ASCII grid (`.asc` + optional `.prj`), read and write;
//! * [`geotiff`]: single-band GeoTIFF, read (any compression the `tiff` crate decodes)
//!   and write (uncompressed, LZW or Deflate);
//! * [`release`]: release polygons from shapefiles and GeoJSON, rasterised by the
//!   cell-centre or the area-fraction rule, released volume, slope-normal → vertical
//!   thickness;
//! * [`netcdf`]: a CF-1.8 NetCDF writer for time series of 2-D fields;
//! * [`path`]: an avalanche path (thalweg) and the runout along it; [`profile`]: the
//!   largest pft, pfv and ppr across its band at each station (AvaFrame's AIMEC);
//! * `validity`: the checks that refuse release polygons which are not simple areas
//!   (self-crossing rings, holes outside their ring, rings without area).
//!
//! [`Raster::crop`] and [`Raster::coarsen`] cut and coarsen grids.

pub mod asc;
mod crs;
pub mod geotiff;
pub mod netcdf;
pub mod path;
pub mod profile;
mod raster;
pub mod release;
mod validity;

use std::path::PathBuf;

pub use crs::Crs;
pub use raster::{Bbox, Raster};

/// Relative tolerance under which the x and y pixel sizes count as equal.
pub const SQUARE_TOLERANCE: f64 = 1e-9;

/// Every error of the GIS readers and writers. Errors about a file name it.
#[derive(Debug, thiserror::Error)]
pub enum GisError {
    #[error("{path}: {source}")]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{path}: no such file: {reason}")]
    MissingSidecar { path: PathBuf, reason: String },
    #[error("{path}: not a regular file (a FIFO, a device or a directory)")]
    NotRegular { path: PathBuf },
    #[error("{path}: the file is empty (0 bytes)")]
    EmptyFile { path: PathBuf },
    #[error("{path}: the header has no `{key}` (an ESRI ASCII grid needs ncols, nrows, xllcorner or xllcenter, yllcorner or yllcenter, cellsize)")]
    MissingKey { path: PathBuf, key: &'static str },
    #[error("{path}, line {line}: bad header: {reason}")]
    BadHeader {
        path: PathBuf,
        line: usize,
        reason: String,
    },
    #[error("{path}, line {line}: `{token}` is not a number")]
    NonNumeric {
        path: PathBuf,
        line: usize,
        token: String,
    },
    #[error("{path}: the header promises {expected} values (ncols × nrows) but the file has only {found}")]
    TooFewValues {
        path: PathBuf,
        expected: usize,
        found: usize,
    },
    #[error("{path}: the header promises {expected} values (ncols × nrows) but the file has more (line {line} holds value {found})")]
    TooManyValues {
        path: PathBuf,
        expected: usize,
        found: usize,
        line: usize,
    },
    #[error("{path}: the cell size must be positive, got {}", short(.value))]
    NonPositiveCellSize { path: PathBuf, value: f64 },
    #[error("{path}: cells are not square (dx = {}, dy = {}); granflow needs square cells: resample first (e.g. gdalwarp -tr D D)", short(.dx), short(.dy))]
    NonSquareCells { path: PathBuf, dx: f64, dy: f64 },
    #[error("{path}: {reason}")]
    BadGrid { path: PathBuf, reason: String },
    #[error("{path}: {source}")]
    Tiff {
        path: PathBuf,
        source: tiff::TiffError,
    },
    #[error("{path}: unsupported GeoTIFF: {reason}")]
    UnsupportedTiff { path: PathBuf, reason: String },
    #[error("{path}: the raster is rotated or sheared ({what}); granflow needs a north-up grid: warp it first (e.g. gdalwarp)")]
    Rotated { path: PathBuf, what: String },
    #[error("{path}: no georeferencing: {reason}")]
    NotGeoreferenced { path: PathBuf, reason: String },
    #[error(
        "{path}: NaN values cannot be written without a finite nodata value (set Raster::nodata)"
    )]
    NanWithoutNodata { path: PathBuf },
    #[error("{path}: {source}")]
    Shapefile {
        path: PathBuf,
        source: shapefile::Error,
    },
    #[error("{path}: invalid JSON: {source}")]
    Json {
        path: PathBuf,
        source: serde_json::Error,
    },
    #[error("{path}: invalid GeoJSON: {reason}")]
    GeoJson { path: PathBuf, reason: String },
    #[error("{path}: feature {feature} has no attribute `{field}` (attributes: {available})")]
    MissingAttribute {
        path: PathBuf,
        feature: usize,
        field: String,
        available: String,
    },
    #[error("{path}: feature {feature}: thickness {value} is not a finite non-negative number")]
    BadThickness {
        path: PathBuf,
        feature: usize,
        value: String,
    },
    #[error("{path}: feature {feature} is a {kind}, not a polygon")]
    NotPolygon {
        path: PathBuf,
        feature: usize,
        kind: String,
    },
    #[error("{path}: feature {feature} is not a valid polygon: {reason}")]
    InvalidPolygon {
        path: PathBuf,
        feature: usize,
        reason: String,
    },
    #[error("{path}: no polygon (only Polygon and MultiPolygon geometries are release areas)")]
    NoPolygons { path: PathBuf },
    #[error("release feature {feature} lies outside the raster: polygon x {} .. {}, y {} .. {}; raster x {} .. {}, y {} .. {} (wrong CRS or wrong file?)", short(.px0), short(.px1), short(.py0), short(.py1), short(.rx0), short(.rx1), short(.ry0), short(.ry1))]
    PolygonOutsideRaster {
        feature: usize,
        px0: f64,
        px1: f64,
        py0: f64,
        py1: f64,
        rx0: f64,
        rx1: f64,
        ry0: f64,
        ry1: f64,
    },
    #[error("release feature {feature}: {percent:.3} % of its area lies outside the raster; that mass would be lost (extend the DEM or trim the polygon)")]
    PolygonPartlyOutside { feature: usize, percent: f64 },
    #[error("CRS mismatch: EPSG:{a} ({what_a}) against EPSG:{b} ({what_b}); granflow does not reproject: convert one of them first")]
    CrsMismatch {
        what_a: String,
        a: u32,
        what_b: String,
        b: u32,
    },
    #[error("the rasters differ in grid ({reason}); they must share nx, ny, origin and cell size")]
    GridMismatch { reason: String },
    #[error("crop box x {} .. {}, y {} .. {} contains no cell centre of the raster", short(.x0), short(.x1), short(.y0), short(.y1))]
    EmptyCrop { x0: f64, x1: f64, y0: f64, y1: f64 },
    #[error("{path}: {reason}")]
    BadLine { path: PathBuf, reason: String },
    #[error("cannot cut the raster: {0}")]
    BadWindow(String),
    #[error("cannot coarsen by {factor}: {reason}")]
    BadCoarsen { factor: usize, reason: String },
    #[error("{path}: {reason}")]
    NetCdf { path: PathBuf, reason: String },
}

/// Result of the GIS functions.
pub type Result<T> = std::result::Result<T, GisError>;

pub(crate) fn io_err(path: &std::path::Path) -> impl FnOnce(std::io::Error) -> GisError + '_ {
    move |source| GisError::Io {
        path: path.to_path_buf(),
        source,
    }
}

/// `v` for a message: in exponent form when very large or small (`1e300`, not the 301
/// digits of `{}`), as written otherwise.
pub fn short_number(v: f64) -> String {
    let a = v.abs();
    if a != 0.0 && a.is_finite() && !(1e-5..1e16).contains(&a) {
        format!("{v:e}")
    } else {
        format!("{v}")
    }
}

/// [`short_number`] of a field, for the error texts.
fn short(v: &f64) -> String {
    short_number(*v)
}

/// Largest side-car file (`.prj`) read: a WKT is a few kB.
const MAX_SIDECAR_BYTES: u64 = 1 << 20;

/// Refuses `path` when it exists but is not a regular file (a FIFO would block the
/// read for ever, a device would be read without end); `Ok(false)` when it does not
/// exist.
pub(crate) fn regular_if_present(path: &std::path::Path) -> Result<bool> {
    match std::fs::metadata(path) {
        Ok(meta) if meta.is_file() => Ok(true),
        Ok(_) => Err(GisError::NotRegular {
            path: path.to_path_buf(),
        }),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(false),
        Err(e) => Err(io_err(path)(e)),
    }
}

/// The text of the side-car file `path` (a `.prj`), `None` when there is none; one that
/// is not a regular file or is larger than 1 MiB is refused.
pub(crate) fn read_sidecar(path: &std::path::Path) -> Result<Option<String>> {
    if !regular_if_present(path)? {
        return Ok(None);
    }
    let len = std::fs::metadata(path).map_err(io_err(path))?.len();
    if len > MAX_SIDECAR_BYTES {
        return Err(GisError::BadGrid {
            path: path.to_path_buf(),
            reason: format!(
                "{len} bytes is more than a side-car file may be ({MAX_SIDECAR_BYTES})"
            ),
        });
    }
    match std::fs::read_to_string(path) {
        Ok(text) => Ok(Some(text)),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(None),
        Err(e) => Err(io_err(path)(e)),
    }
}

/// `a` and `b` (positive) equal within [`SQUARE_TOLERANCE`].
pub(crate) fn nearly_equal(a: f64, b: f64) -> bool {
    (a - b).abs() <= SQUARE_TOLERANCE * a.abs().max(b.abs())
}
