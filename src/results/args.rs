//! Command lines of `granflow export` and `granflow maps` (clap), kept here so that
//! `cli.rs` only names them.

use std::path::PathBuf;

use clap::{Args, ValueEnum};

/// The raster formats of `export` and `maps`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum RasterFormat {
    /// GeoTIFF (`.tif`), Float32 (or Float64 with --float64), Deflate.
    Geotiff,
    /// ESRI ASCII grid (`.asc`, with a `.prj` when the CRS has WKT text).
    Asc,
}

impl RasterFormat {
    /// The file extension.
    pub fn extension(self) -> &'static str {
        match self {
            RasterFormat::Geotiff => "tif",
            RasterFormat::Asc => "asc",
        }
    }
}

/// The formats of `granflow export`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum ExportFormat {
    /// GeoTIFF (`.tif`), one file per field.
    Geotiff,
    /// ESRI ASCII grid (`.asc`), one file per field.
    Asc,
    /// CF-1.8 NetCDF (`.nc`): the snapshots as a time series and the maps.
    Netcdf,
}

/// The file layouts of `granflow export`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum Layout {
    /// `DIR/RUN_<field>.<ext>`, ppr in Pa.
    Granflow,
    /// AvaFrame's: `DIR/Outputs/com1DFA/peakFiles/<name>_<hash>_C_null_dfa_<pft|pfv|ppr>.<ext>`,
    /// ppr in kPa, as AIMEC reads com1DFA's peak files.
    Avaframe,
}

/// `granflow export RUN.h5 [options]`.
#[derive(Debug, Args)]
pub struct ExportArgs {
    /// The HDF5 file of a raster (2-D) run.
    #[arg(value_name = "RUN.h5")]
    pub run: PathBuf,
    /// Output format.
    #[arg(long, value_enum, default_value_t = ExportFormat::Geotiff)]
    pub format: ExportFormat,
    /// Export the snapshot nearest this time (s; the earlier one on a tie) instead
    /// of the maps; an error outside the snapshots' times.
    #[arg(long, value_name = "T", allow_negative_numbers = true)]
    pub time: Option<f64>,
    /// Fields, comma-separated: maps pft, pfv, ppr, deposit, arrival_time (default:
    /// all); with --time, or in NetCDF, snapshot fields h, u, v, speed (default: h,
    /// speed with --time; all in NetCDF).
    #[arg(long, value_delimiter = ',', value_name = "NAMES")]
    pub fields: Vec<String>,
    /// Output directory (default: the run file's directory); files are named
    /// `RUN_<field>.<ext>`.
    #[arg(long, short, value_name = "DIR")]
    pub output: Option<PathBuf>,
    /// File names and units: granflow's, or AvaFrame's peak files (DIR is then the
    /// avalanche directory; pft, pfv, ppr only, ppr in kPa; docs/gis.md).
    #[arg(long, value_enum, default_value_t = Layout::Granflow)]
    pub layout: Layout,
    /// GeoTIFF samples as Float64 (the file's values exactly) instead of Float32.
    #[arg(long)]
    pub float64: bool,
    /// Replace files of the same names that granflow did not write (without it, only
    /// granflow's own earlier exports are replaced).
    #[arg(long)]
    pub force: bool,
    /// Do not list the files written.
    #[arg(long, short)]
    pub quiet: bool,
}

/// `granflow maps SWEEP_DIR [options]`.
#[derive(Debug, Args)]
pub struct MapsArgs {
    /// Output directory of a sweep of raster runs (holding sweep-plan.toml).
    #[arg(value_name = "SWEEP_DIR")]
    pub dir: PathBuf,
    /// Peak flow thickness (m) above which a cell counts as reached.
    #[arg(
        long,
        default_value_t = 0.1,
        value_name = "METRES",
        allow_negative_numbers = true
    )]
    pub threshold: f64,
    /// Observed footprint: polygons (.geojson, .json, .shp) or a raster (.tif, .asc;
    /// cells > 0 observed) on the runs' grid. Adds each run's skill and ranks the runs.
    #[arg(long, value_name = "FILE")]
    pub observed: Option<PathBuf>,
    /// Raster format of the maps.
    #[arg(long, value_enum, default_value_t = RasterFormat::Geotiff)]
    pub format: RasterFormat,
    /// Output directory (default: SWEEP_DIR/maps).
    #[arg(long, short, value_name = "DIR")]
    pub output: Option<PathBuf>,
    /// Use the runs that are done when some are not (failed, missing or running);
    /// without it such a sweep is refused.
    #[arg(long)]
    pub partial: bool,
    /// GeoTIFF samples as Float64 instead of Float32.
    #[arg(long)]
    pub float64: bool,
    /// Replace files of the same names that granflow did not write (without it, only
    /// granflow's own earlier maps are replaced).
    #[arg(long)]
    pub force: bool,
    /// No table.
    #[arg(long, short)]
    pub quiet: bool,
}
