//! Output sinks. The run loop talks to an [`OutputSink`] and never knows about HDF5.
//!
//! The on-disk layout is the contract of `docs/output-format.md` (format_version 1):
//! root attributes, `/grid`, `/snapshots`, `/front`, `/diagnostics`, `/summary`.
//! Sinks write progressively: a snapshot handed to [`OutputSink::snapshot`] is on disk
//! when the call returns, so a run that dies later keeps it.

pub mod budget;
pub mod csv;
pub mod gauges;
pub mod hdf5;
pub mod maps;
pub mod memory;
pub mod stop_reason;
pub mod tee;
pub mod xdmf;

use std::path::{Path, PathBuf};

use thiserror::Error;

use crate::grid::GridSpec;

pub use csv::{front_csv_path, FrontCsvSink};
pub use gauges::{gauge_csv_path, GaugeCsvSink};
pub use hdf5::Hdf5Sink;
pub use tee::Tee;

/// The name of a run's files: the HDF5 file's name without an HDF5 extension (`.h5`,
/// `.hdf5`, `.hdf`, any case). Only that extension is taken off, so `out/mu_0.0046`
/// is `mu_0.0046` and two runs whose names differ after a dot keep their own
/// companion files.
pub fn run_stem(h5: &Path) -> String {
    let name = h5.file_name().map_or_else(
        || "granflow".to_string(),
        |s| s.to_string_lossy().into_owned(),
    );
    match name.rsplit_once('.') {
        Some((stem, ext))
            if !stem.is_empty()
                && ["h5", "hdf5", "hdf"]
                    .iter()
                    .any(|e| ext.eq_ignore_ascii_case(e)) =>
        {
            stem.to_string()
        }
        _ => name,
    }
}

/// The file beside the HDF5 file `h5` named by its [`run_stem`] and `suffix`:
/// `out/run.h5` and `_front.csv` give `out/run_front.csv`.
pub fn companion_path(h5: &Path, suffix: &str) -> PathBuf {
    h5.with_file_name(format!("{}{suffix}", run_stem(h5)))
}

/// Version of the HDF5 layout; bump on any rename.
pub const FORMAT_VERSION: i64 = 1;

#[derive(Debug, Error)]
pub enum OutputError {
    #[error("cannot write output file {path}: {message}")]
    Io { path: String, message: String },
}

/// Run-level metadata, written as root attributes.
#[derive(Debug, Clone)]
pub struct RunInfo {
    pub granflow_version: String,
    /// `model.kind`, e.g. "granular".
    pub model: String,
    /// "hydrostatic" | "nonhydrostatic".
    pub pressure: String,
    pub layers: usize,
    /// "local" | "cartesian".
    pub coordinates: String,
    pub slope_deg: f64,
    /// The scenario TOML exactly as read, after overrides.
    pub scenario_toml: String,
    /// Front threshold (m), stored as `/front` attribute `threshold`.
    pub front_threshold: f64,
    /// The raster of a 2-D run (cells row-major, index j·nx + i); `None` on a line.
    pub raster: Option<RasterInfo>,
}

/// What a raster run's output records besides its grid (whose geometry and CRS are
/// [`GridData::spec`]).
#[derive(Debug, Clone, PartialEq)]
pub struct RasterInfo {
    /// The volumes of a release polygon, when the initial thickness is one.
    pub release: Option<ReleaseVolumes>,
    /// Number of wall cells (nodata cells of the DEM).
    pub wall_cells: usize,
}

/// The volumes of a rasterised release polygon (m³), `/summary` attributes
/// `release_volume` and `release_volume_on_walls`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ReleaseVolumes {
    pub volume: f64,
    pub volume_on_walls: f64,
}

/// Static grid data, `/grid`.
#[derive(Debug, Clone, Copy)]
pub struct GridData<'a> {
    /// The grid's extent, cell sizes and CRS, as the scenario gave them: the `/grid`
    /// attributes (and, on a raster, the root attributes `nx`, `dx`, `crs`, …).
    pub spec: &'a GridSpec,
    /// Cell centres (nx), every cell's x on a raster (nx·ny, row-major).
    pub x: &'a [f64],
    /// Every cell's y on a raster (nx·ny, row-major); `None` on a line.
    pub y: Option<&'a [f64]>,
    /// (ny, nx) of a raster, whose per-cell arrays are row-major (cell = j·nx + i);
    /// `None` on a line.
    pub shape: Option<(usize, usize)>,
    /// Bed elevation over the reference plane (nx).
    pub b: &'a [f64],
    /// Initial erodible-bed thickness (nx).
    pub h_bed: &'a [f64],
}

/// A model-specific field with one value per cell, written as `/snapshots/<name>`
/// of shape (nt, nx), e.g. the multilayer model's `static_interface`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CellField<'a> {
    /// Dataset name: ASCII letters, digits and `_`, not one of the fixed names.
    pub name: &'static str,
    /// The `units` attribute.
    pub units: &'static str,
    /// The `description` attribute: what the values are, in words (none when empty).
    pub description: &'a str,
    /// nx values.
    pub data: &'a [f64],
}

/// One snapshot, `/snapshots/*[k]`. Layered arrays are layer-major: index α·nx + i.
#[derive(Debug, Clone, Copy)]
pub struct SnapshotView<'a> {
    pub t: f64,
    /// Flow thickness (nx).
    pub h: &'a [f64],
    /// Downslope velocity of each layer (nl·nx); on a raster the x-velocity of every
    /// cell (nx·ny, row-major).
    pub u: &'a [f64],
    /// The y-velocity of every cell of a raster (nx·ny, row-major); `None` on a line.
    pub v: Option<&'a [f64]>,
    /// (ny, nx) of a raster's per-cell fields (`h`, `u`, `v`, `extra`); `None` on a line.
    pub shape: Option<(usize, usize)>,
    /// Normal velocity of each layer (nl·nx), when the model has it.
    pub w: Option<&'a [f64]>,
    /// Non-hydrostatic pressure at the interfaces ((nl+1)·(nx+1)), non-hydrostatic runs only.
    pub p_nh: Option<&'a [f64]>,
    pub layers: usize,
    /// Model-specific per-cell fields; the same names in every snapshot of a run.
    pub extra: &'a [CellField<'a>],
    /// The velocities (u_α, v_α) of every layer of a layered raster run (nl > 1),
    /// layer-major (α·nx·ny + cell): `/snapshots/u_layers`, `v_layers`. `None`
    /// elsewhere (a line's layers are in `u`).
    pub layer_uv: Option<(&'a [f64], &'a [f64])>,
}

/// What a raster run gathers over the whole run, handed to the sink once before
/// `finish`: maps (`/maps/*`, one value per cell), per-step series that extend
/// `/diagnostics` (one value per step record) and summary numbers (`/summary`).
#[derive(Debug, Clone, Copy)]
pub struct RunMaps<'a> {
    pub maps: &'a [CellField<'a>],
    /// (name, units, one value per step record).
    pub series: &'a [(&'static str, &'static str, &'a [f64])],
    /// (name, value), written as `/summary` attributes.
    pub scalars: &'a [(&'static str, f64)],
    /// (name, units, one value per station) of the profiles along `output.path`,
    /// written as `/path/<name>`; empty without a path.
    pub profile: &'a [(&'static str, &'static str, &'a [f64])],
}

/// One row per time step: `/diagnostics/*` and `/front/*`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StepRecord {
    pub t: f64,
    pub dt: f64,
    /// ∫ h dx (m²).
    pub mass: f64,
    /// ∫ ½ h |u|² dx per unit density (m⁴/s²).
    pub kinetic_energy: f64,
    pub max_speed: f64,
    /// Front position (largest x with h − h_bed > threshold); NaN if no such cell.
    pub front_x: f64,
}

/// The gauge values at one time, `/gauges/*[k]`: one value per gauge, in the order
/// of the positions handed to [`OutputSink::begin_gauges`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GaugeRecord<'a> {
    pub t: f64,
    /// Free-surface elevation: the water surface η of the submarine model, the top of
    /// the flow b + h of the granular model (m).
    pub eta: &'a [f64],
    /// Grain depth: the submarine model's H₂, the granular flow thickness h (m).
    pub h_grains: &'a [f64],
}

/// End-of-run summary, `/summary` attributes (and, without the stage times, the
/// outcome part of a sweep's result file).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct RunSummary {
    pub runout: f64,
    /// First time the mass is at rest, NaN if never.
    pub stop_time: f64,
    /// Time after which the kinetic energy stays at or below `time.settle_fraction` ×
    /// its peak (the time of the first step of that final period), NaN if it does not
    /// end the run there. Unlike `stop_time` it converges under refinement for μ(I),
    /// whose mass creeps long after it has practically stopped.
    #[serde(default = "nan")]
    pub settled_time: f64,
    /// `time.settle_fraction` of the run (what `settled_time` and the status `settled`
    /// count from), NaN for a run that never got going.
    #[serde(default = "nan")]
    pub settle_fraction: f64,
    pub h_max_final: f64,
    pub t_end: f64,
    pub steps: u64,
    pub wall_time_s: f64,
    /// "completed" | "stopped_at_rest" | "settled" | "failed: …" | … (docs/output-format.md).
    pub status: String,
    /// Models with a water surface (submarine): max over time and wet cells of
    /// |η − η₀| (m), η₀ the initial surface. `None` for the others.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_wave_amplitude: Option<f64>,
    /// Fraction of the initial mass that left through outflow boundaries by the end
    /// (0 for a domain closed by walls; NaN without mass or without a run).
    #[serde(default = "nan")]
    pub outflowed_fraction: f64,
    /// First time the front stood in the domain's last cell (the runout is then the
    /// domain's, not the flow's), NaN if never.
    #[serde(default = "nan")]
    pub front_at_end_time: f64,
    /// Largest speed of the material at the end (m/s).
    #[serde(default = "nan")]
    pub max_speed_final: f64,
    /// Raster runs: the runout along the flow, the travel angle and the area reached
    /// (the `/summary` numbers of the maps, written there with them). `None` for
    /// 1-D runs, whose `runout` is the front's advance.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub spread: Option<Spread>,
    /// (stage name, wall seconds), written as `time_<stage>_s`.
    #[serde(skip)]
    pub stage_times: Vec<(String, f64)>,
    /// Raster runs: the wet fraction and the cell updates per second (where the run's
    /// time went). `None` for 1-D runs.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub wet: Option<WetCells>,
}

/// Where a raster run's work went: how much of the raster held material, and the cell
/// updates per second of the run's wall time counted on the wet cells and on the cells
/// the steps visited (`/summary` `flow_cells`, `wet_fraction_mean`, `wet_fraction_peak`,
/// `wet_cell_updates_per_s`, `cell_updates_per_s`). A cell is wet when h > H_DRY
/// (10⁻¹⁰ m): a film left behind by the flow counts.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct WetCells {
    /// Cells material can occupy (the raster's cells but its walls).
    pub flow_cells: usize,
    /// Mean over the steps of the fraction of `flow_cells` wet at a step's start.
    pub mean_fraction: f64,
    /// Largest fraction of `flow_cells` wet at once.
    pub peak_fraction: f64,
    /// Wet-cell updates (the cells wet at each step's start, summed over the steps)
    /// per second of wall time.
    pub wet_updates_per_s: f64,
    /// Cell updates per second of wall time: the cells each step visited (those of its
    /// active tiles, `state::tiles`; dry cells next to the flow included), summed over
    /// the steps.
    pub cell_updates_per_s: f64,
}

/// How far a raster run went, as a practitioner reports it (`/summary`
/// `runout_length`, `travel_angle_deg`, `area_reached`).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Spread {
    /// Horizontal distance from the top of the release to the runout point, along the
    /// main flow direction (m).
    pub runout_length: f64,
    /// Heim's travel angle, atan(drop / runout_length) (degrees).
    pub travel_angle_deg: f64,
    /// Area of the cells the flow reached (m²).
    pub area_reached: f64,
    /// With `output.path`: the runout along the path, from the top of the release (m).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub path_runout_length: Option<f64>,
    /// With `output.path`: the runout angle along the path (degrees).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub path_runout_angle_deg: Option<f64>,
    /// With `output.path`: the largest pft (m), pfv (m/s) and ppr (Pa) of the band
    /// around the path (the maxima of its profiles, `gis::profile`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub path_max: Option<[f64; 3]>,
}

impl Spread {
    /// From the `/summary` scalars of a raster run's maps; `None` when they are absent.
    pub fn from_scalars(scalars: &[(&str, f64)]) -> Option<Spread> {
        let get = |name: &str| scalars.iter().find(|(n, _)| *n == name).map(|&(_, v)| v);
        Some(Spread {
            runout_length: get("runout_length")?,
            travel_angle_deg: get("travel_angle_deg")?,
            area_reached: get("area_reached")?,
            path_runout_length: get("path_runout_length"),
            path_runout_angle_deg: get("path_runout_angle_deg"),
            path_max: (|| {
                Some([
                    get("path_max_pft")?,
                    get("path_max_pfv")?,
                    get("path_max_ppr")?,
                ])
            })(),
        })
    }
}

fn nan() -> f64 {
    f64::NAN
}

impl RunSummary {
    /// The summary of a run that never got going: `status`, unknown numbers (NaN).
    pub fn not_run(status: String, wall_time_s: f64) -> RunSummary {
        RunSummary {
            runout: f64::NAN,
            stop_time: f64::NAN,
            settled_time: f64::NAN,
            settle_fraction: f64::NAN,
            h_max_final: f64::NAN,
            t_end: f64::NAN,
            steps: 0,
            wall_time_s,
            status,
            max_wave_amplitude: None,
            wet: None,
            outflowed_fraction: f64::NAN,
            front_at_end_time: f64::NAN,
            max_speed_final: f64::NAN,
            spread: None,
            stage_times: Vec::new(),
        }
    }
}

/// Where a run's results go. `Send`: a raster run's loop runs on its own threads
/// ([`crate::numerics::workers::Workers::install`]), and writes from there.
pub trait OutputSink: Send {
    fn begin(&mut self, info: &RunInfo, grid: &GridData) -> Result<(), OutputError>;
    fn snapshot(&mut self, snap: &SnapshotView) -> Result<(), OutputError>;
    /// Called after every time step (and once for t = 0).
    fn step(&mut self, rec: &StepRecord) -> Result<(), OutputError>;
    /// Called once, also after a failure, so what is valid stays readable.
    fn finish(&mut self, summary: &RunSummary) -> Result<(), OutputError>;
    /// Called once after `begin` when the run has gauges, with their positions (m).
    /// Sinks that do not record gauges keep this default.
    fn begin_gauges(&mut self, _x: &[f64]) -> Result<(), OutputError> {
        Ok(())
    }
    /// Called right after `begin_gauges` by raster runs, with the gauges' y (m).
    fn gauges_y(&mut self, _y: &[f64]) -> Result<(), OutputError> {
        Ok(())
    }
    /// Called at every gauge time (after `begin_gauges`), in increasing t.
    fn gauges(&mut self, _rec: &GaugeRecord) -> Result<(), OutputError> {
        Ok(())
    }
    /// Called once before `finish` by runs that gather maps over the run (raster
    /// runs). Sinks that do not record them keep this default.
    fn maps(&mut self, _maps: &RunMaps) -> Result<(), OutputError> {
        Ok(())
    }
    /// Called with every snapshot by runs that gather maps, with the maps as they
    /// stand (the same names and lengths every time, and as `maps` later), so that a
    /// run that is killed keeps them. Sinks that do not record them keep this default.
    fn maps_so_far(&mut self, _maps: &[CellField]) -> Result<(), OutputError> {
        Ok(())
    }
}

/// The outputs of one `granflow run`: the HDF5 file at `h5`, the front series next to
/// it ([`front_csv_path`]) and, when the run has gauges, their series
/// ([`gauge_csv_path`], created at [`OutputSink::begin_gauges`]).
pub type RunSinks = Tee<Hdf5Sink, Tee<FrontCsvSink, GaugeCsvSink>>;

/// The sinks of [`RunSinks`] for the HDF5 file `h5`.
pub fn create_run_sinks(h5: &Path) -> Result<RunSinks, OutputError> {
    Ok(Tee::new(
        Hdf5Sink::create(h5)?,
        Tee::new(
            FrontCsvSink::create(&front_csv_path(h5))?,
            GaugeCsvSink::new(&gauge_csv_path(h5)),
        ),
    ))
}
