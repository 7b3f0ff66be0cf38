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
//! * [`netcdf`]: a CF-1.8 NetCDF writer for time series of 2-D fields.
//!
//! [`Raster::crop`] and [`Raster::coarsen`] cut and coarsen grids.

pub mod asc;
mod crs;
pub mod geotiff;
pub mod netcdf;
pub mod path;
mod raster;
pub mod release;

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
    #[error("{path}: the cell size must be positive, got {value}")]
    NonPositiveCellSize { path: PathBuf, value: f64 },
    #[error("{path}: cells are not square (dx = {dx}, dy = {dy}); granflow needs square cells: resample first (e.g. gdalwarp -tr D D)")]
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
    #[error("{path}: no polygon (only Polygon and MultiPolygon geometries are release areas)")]
    NoPolygons { path: PathBuf },
    #[error("release feature {feature} lies outside the raster: polygon x {px0} .. {px1}, y {py0} .. {py1}; raster x {rx0} .. {rx1}, y {ry0} .. {ry1} (wrong CRS or wrong file?)")]
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
    #[error("CRS mismatch: {what_a} is EPSG:{a} but {what_b} is EPSG:{b}; granflow does not reproject: convert one of them first")]
    CrsMismatch {
        what_a: String,
        a: u32,
        what_b: String,
        b: u32,
    },
    #[error("the rasters differ in grid ({reason}); they must share nx, ny, origin and cell size")]
    GridMismatch { reason: String },
    #[error("crop box x {x0} .. {x1}, y {y0} .. {y1} contains no cell centre of the raster")]
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

/// `a` and `b` (positive) equal within [`SQUARE_TOLERANCE`].
pub(crate) fn nearly_equal(a: f64, b: f64) -> bool {
    (a - b).abs() <= SQUARE_TOLERANCE * a.abs().max(b.abs())
}
