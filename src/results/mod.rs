//! What is done with a run's results after it ran: `granflow export` (a raster run's
//! maps and snapshots as GeoTIFF, ESRI ASCII grids or CF NetCDF, with the run's
//! georeferencing) and `granflow maps` (the maps of a sweep's ensemble: the
//! probability that the peak flow thickness exceeds a threshold, means and maxima,
//! and, against an observed footprint, each run's skill). User documentation:
//! `docs/gis.md` ("Result rasters") and `docs/sweeps.md`.
//!
//! - [`run_file`]: reads a raster run's HDF5 file back (grid, CRS, maps, frames);
//! - [`export`]: `granflow export`;
//! - [`ensemble`]: the per-cell statistics of an ensemble of runs;
//! - [`skill`]: a run's footprint against an observed one (areas, ROC point);
//! - [`maps`]: `granflow maps`;
//! - [`publish`]: how both put their files in place (never a user's file, never half).

pub mod args;
pub mod avaframe;
pub mod ensemble;
pub mod export;
pub mod maps;
pub mod publish;
pub mod run_file;
pub mod skill;

pub use args::{ExportArgs, Layout, MapsArgs, RasterFormat};

use crate::terminal::{EXIT_BAD_INPUT, EXIT_FAILURE};

/// The value written for cells without a value (NaN in the run file, e.g. the arrival
/// time of a cell the flow never reached) in GeoTIFF and ESRI ASCII grids; NetCDF
/// files keep NaN (their `_FillValue`).
pub const NODATA: f64 = -9999.0;

/// An error of `export` or `maps`: bad input (exit code 2) or a failure to write
/// (exit code 1).
#[derive(Debug, Clone, PartialEq)]
pub enum ResultsError {
    Input(String),
    Failure(String),
}

impl ResultsError {
    pub fn input(message: impl Into<String>) -> ResultsError {
        ResultsError::Input(message.into())
    }

    pub fn failure(message: impl Into<String>) -> ResultsError {
        ResultsError::Failure(message.into())
    }

    /// The process exit code.
    pub fn exit_code(&self) -> u8 {
        match self {
            ResultsError::Input(_) => EXIT_BAD_INPUT,
            ResultsError::Failure(_) => EXIT_FAILURE,
        }
    }
}

impl std::fmt::Display for ResultsError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            ResultsError::Input(m) | ResultsError::Failure(m) => f.write_str(m),
        }
    }
}

impl std::error::Error for ResultsError {}

/// Writes `values` (north row first, NaN for no value) on `grid`'s cells as a GeoTIFF
/// (Float32, or Float64 when `float64`; Deflate) or an ESRI ASCII grid (with its `.prj`,
/// see [`publish`]), NaN becoming [`NODATA`], through `publish`.
pub fn write_raster(
    publish: &mut publish::Publish,
    grid: &crate::gis::Raster,
    values: Vec<f64>,
    format: RasterFormat,
    float64: bool,
    path: &std::path::Path,
) -> Result<(), ResultsError> {
    write_raster_band(publish, grid, values, (format, float64), path, None)
}

/// [`write_raster`], a GeoTIFF's band described by `band` (an ESRI ASCII grid has no
/// place for it). The `.prj` of a grid is the CRS's WKT, or one made from its EPSG
/// code ([`crate::gis::Crs::wkt_text`]).
pub fn write_raster_band(
    publish: &mut publish::Publish,
    grid: &crate::gis::Raster,
    values: Vec<f64>,
    (format, float64): (RasterFormat, bool),
    path: &std::path::Path,
    band: Option<crate::gis::geotiff::Band>,
) -> Result<(), ResultsError> {
    use crate::gis::geotiff::{self, Compression, SampleType, WriteOptions};
    use publish::Owner;
    let mut raster = crate::gis::Raster {
        values,
        nodata: Some(NODATA),
        crs: grid.crs.clone(),
        ..*grid
    };
    for v in &mut raster.values {
        if v.is_nan() {
            *v = NODATA;
        }
    }
    let failure = |e: crate::gis::GisError| ResultsError::failure(e.to_string());
    match format {
        RasterFormat::Geotiff => publish.write(path, &Owner::Geotiff, |tmp| {
            let options = WriteOptions {
                sample: if float64 {
                    SampleType::F64
                } else {
                    SampleType::F32
                },
                compression: Compression::Deflate,
            };
            geotiff::write_band(&raster, tmp, options, band).map_err(failure)
        }),
        RasterFormat::Asc => {
            use crate::gis::asc;
            let grid_owner = Owner::Asc;
            publish.write(path, &grid_owner, |tmp| {
                asc::write_grid(&raster, tmp).map_err(failure)
            })?;
            let prj = asc::prj_path(path);
            let text = raster.crs.wkt_text().map(|w| format!("{w}\n"));
            let owner = Owner::Prj {
                text: text.clone(),
                grid: path.to_path_buf(),
                grid_owner: Box::new(grid_owner),
            };
            match text {
                Some(text) => publish.write(&prj, &owner, |tmp| {
                    std::fs::write(tmp, text).map_err(|e| {
                        ResultsError::failure(format!("cannot write {}: {e}", tmp.display()))
                    })
                }),
                None => publish.remove(&prj, &owner),
            }
        }
    }
}
