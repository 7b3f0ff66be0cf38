//! Scenario files: the TOML a user writes, validated into plain data.
//!
//! Two layers, as in ripgrep's LowArgs → HiArgs: `raw` is a serde mirror of the TOML
//! (`deny_unknown_fields`, no logic); `validate` turns it into the [`Scenario`] below,
//! checking every key and naming it (with its line) in the error. Profiles (`bed.b`,
//! `initial.h`, `initial.u`, `initial.v`, `initial.w`) are expressions in `x` (and `y`
//! on a raster domain), CSV tables or raster files (`profile`).
//! `--set key=value` overrides are applied to the document before deserialising
//! (`overrides`), so a sweep is a list of override sets over one base file.

mod compiled;
mod document;
mod error;
mod overrides;
mod profile;
mod raw;
mod validate;

pub use error::ScenarioError;
pub(crate) use profile::read_bounded;
pub use profile::Profile;
pub(crate) use validate::MAX_SCENARIO_BYTES;
pub use validate::{load_file, load_file_within, load_str, load_str_within};

use std::path::PathBuf;

pub use crate::gis::path::{PathField, PathSpec};
pub use crate::gis::release::CoverageRule;
pub use crate::gis::Crs;
pub use crate::grid::{BoundaryKind, Coordinates};
pub use crate::model::dilatant::DilatantSpec;
pub use crate::model::granular::config::{MultilayerSpec, Pressure};
pub use crate::model::granular_2d::FrictionZones;
pub use crate::model::submarine::SubmarineSpec;
pub use crate::model::ModelKind;
pub use crate::numerics::muscl::Limiter;
pub use crate::numerics::viscous::{
    BasalCondition, Regularization, Sidewall, SidewallForm, ViscosityTime,
};
pub use crate::physics::rheology::{FrictionLaw, MonolayerShear};
pub use crate::physics::Material;

#[derive(Debug, Clone, PartialEq)]
pub struct Domain {
    pub x_min: f64,
    pub x_max: f64,
    pub cells: usize,
    /// Inclination θ of the reference plane, degrees (0 for Cartesian runs).
    pub slope_deg: f64,
    pub coordinates: Coordinates,
    /// `domain.curvature`: the centrifugal term uᵀ∇²b u in the basal normal stress of
    /// the bed-normal frame (default true; no effect in the other frames).
    pub curvature: bool,
    /// The y axis of a raster domain (`cells` is then nx); `None` on a line.
    pub plane: Option<Plane>,
}

/// The y extent of a raster domain of nx × ny cells, with the coordinate reference
/// system of its raster files (carried into the output, never used).
#[derive(Debug, Clone, PartialEq)]
pub struct Plane {
    pub y_min: f64,
    pub y_max: f64,
    pub ny: usize,
    pub crs: crate::gis::Crs,
    /// (x of the west edge, y of the north edge, cell size) of the raster bed whose
    /// grid the domain is, exactly as read (after `domain.crop` and `domain.coarsen`),
    /// so that the outputs sit on the DEM's very grid; `None` for a domain given by
    /// its keys.
    pub geotransform: Option<[f64; 3]>,
}

impl Domain {
    /// Number of cells: nx on a line, nx · ny on a raster.
    pub fn cell_count(&self) -> usize {
        self.cells * self.plane.as_ref().map_or(1, |p| p.ny)
    }
}

/// How the thickness of a release polygon is measured.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ThicknessIs {
    /// Along the vertical of the domain's frame: used as it is.
    Vertical,
    /// Normal to the bed: divided by cos θ of the bed's local slope (docs/gis.md).
    Normal,
}

/// A release polygon (`initial.h = { polygon = … }`) as it was rasterised onto the
/// domain: printed when a run starts and stored in `/summary`.
#[derive(Debug, Clone, PartialEq)]
pub struct ReleaseSummary {
    /// The polygon file as written in the scenario.
    pub file: PathBuf,
    /// Features (polygons with a thickness) read from it.
    pub features: usize,
    /// Area of the polygons (m²).
    pub area: f64,
    pub rule: CoverageRule,
    pub thickness_is: ThicknessIs,
    /// Σ h × cell area of the vertical thickness on the cells of flow (m³): the
    /// initial volume of the run.
    pub volume: f64,
    /// Volume that fell on wall (nodata) cells and was dropped (m³, the thickness as
    /// given).
    pub volume_on_walls: f64,
}

impl ReleaseSummary {
    /// One line for the terminal.
    pub fn describe(&self) -> String {
        let rule = match self.rule {
            CoverageRule::AreaFraction => "area fraction",
            CoverageRule::CellCentre => "cell centre",
        };
        let thickness = match self.thickness_is {
            ThicknessIs::Vertical => "vertical thickness",
            ThicknessIs::Normal => "thickness normal to the slope, divided by cos θ",
        };
        format!(
            "{}: {} polygon feature{} of {:.6e} m², released volume {:.6e} m³ ({rule} rule, {thickness}); {:.6e} m³ on wall (nodata) cells dropped",
            self.file.display(),
            self.features,
            if self.features == 1 { "" } else { "s" },
            self.area,
            self.volume,
            self.volume_on_walls
        )
    }
}

#[derive(Debug, Clone, PartialEq)]
pub struct ModelSpec {
    pub kind: ModelKind,
    pub pressure: Pressure,
    pub layers: usize,
}

#[derive(Debug, Clone)]
pub struct Initial {
    /// Flow thickness above the erodible bed, h(x) ≥ 0 (the bed layer is added on top).
    pub h: Profile,
    /// Depth-averaged downslope velocity u(x).
    pub u: Profile,
    /// Depth-averaged velocity along y, v(x, y) (raster domains; 0 on a line).
    pub v: Profile,
    /// Normal velocity w(x) (non-hydrostatic model only; Garres-Díaz et al. 2021, eq. 30).
    pub w: Profile,
    /// Erodible-bed thickness h_i ≥ 0 (Fernández-Nieto et al. 2016, §4.2): a layer of
    /// the same grains at rest added on top of the bed (a number, or a profile in x,
    /// and y on a raster domain).
    pub erodible_bed: Profile,
    /// Water free-surface elevation η(x) of the submarine model (no water if absent);
    /// its `initial.h` is then the grains' vertical thickness H₂cos²θ.
    pub eta: Option<Profile>,
    /// Solid volume fraction φ(x) of the dilatant model (Bouchut et al. 2021), in (0, 1).
    pub phi: Option<Profile>,
}

impl Initial {
    /// Whether an erodible bed is given (anything but the number 0).
    pub fn has_erodible_bed(&self) -> bool {
        self.erodible_bed.as_constant() != Some(0.0)
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Boundaries {
    /// x = x_min (`boundary.left`, or `boundary.west` on a raster).
    pub left: BoundaryKind,
    /// x = x_max (`boundary.right`, or `boundary.east` on a raster).
    pub right: BoundaryKind,
    /// y = y_min (`boundary.south`; raster domains only).
    pub south: BoundaryKind,
    /// y = y_max (`boundary.north`; raster domains only).
    pub north: BoundaryKind,
}

#[derive(Debug, Clone, PartialEq)]
pub struct TimeSpec {
    pub t_end: f64,
    pub cfl: f64,
    /// End the run early once the whole mass is at rest.
    pub stop_at_rest: bool,
    /// Kinetic energy, as a fraction of its peak, below which the mass counts as
    /// settled (`settled_time`, `stop_when_settled`), in (0, 1).
    pub settle_fraction: f64,
    /// End the run (status `settled`) once the kinetic energy is at or below
    /// `settle_fraction` × its peak.
    pub stop_when_settled: bool,
    /// Raster runs: a cell whose normal thickness is below this (m) does not count for
    /// the kinetic energy (nor so for `settle_fraction`); 0 (the default): every cell.
    pub film_thickness: f64,
}

#[derive(Debug, Clone, PartialEq)]
pub struct OutputSpec {
    /// HDF5 file, relative to the current directory unless absolute.
    pub file: PathBuf,
    /// Snapshot interval (s); the time step is shortened to land on it.
    pub every: f64,
    /// Thickness above which a cell counts as flowing mass for the front position (m).
    pub front_threshold: f64,
    /// Gauge positions (m), inside the domain; empty: no gauges.
    pub gauges: Vec<f64>,
    /// The gauges' y on a raster domain (one per gauge), empty on a line.
    pub gauges_y: Vec<f64>,
    /// Gauge interval (s); `None`: every time step.
    pub gauge_every: Option<f64>,
    /// The path along which a raster run's runout is measured (`output.path`).
    pub path: Option<PathSpec>,
}

/// The profiles at the cell centres x_i = x_min + (i + ½)Δx (on a raster domain at
/// (x_i, y_j), y_j = y_min + (j + ½)Δy, row-major: index j·nx + i), sampled once by
/// validation (which checks these very values) and used by setup to build the mesh and
/// the initial state.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Sampled {
    /// `bed.b`.
    pub b: Vec<f64>,
    /// `initial.h` (without `initial.erodible_bed`).
    pub h: Vec<f64>,
    /// `initial.erodible_bed` (0 on the wall cells of a raster domain).
    pub h_bed: Vec<f64>,
    /// `initial.u`.
    pub u: Vec<f64>,
    /// `initial.v` (raster domains; empty on a line).
    pub v: Vec<f64>,
    /// `initial.w`.
    pub w: Vec<f64>,
    /// `initial.eta`, when given.
    pub eta: Option<Vec<f64>>,
    /// `initial.phi`, when given.
    pub phi: Option<Vec<f64>>,
    /// Wall cells of a raster domain (where a raster bed has no data), row-major;
    /// empty when there is none. Initial profiles are 0 there.
    pub wall: Vec<bool>,
}

impl Sampled {
    /// Evaluates the bed, then each initial profile at the bed, at every cell centre of
    /// `domain` (NaN where an expression fails). Validation does this once; a scenario
    /// assembled by hand (tests) calls it to fill [`Scenario::sampled`].
    pub fn of(domain: &Domain, bed: &Profile, initial: &Initial) -> Sampled {
        use rayon::prelude::*;
        if let Some(plane) = &domain.plane {
            return Sampled::of_plane(domain, plane, bed, initial);
        }
        let n = domain.cells;
        let dx = (domain.x_max - domain.x_min) / n as f64;
        let x_min = domain.x_min;
        let centre = move |i: usize| crate::grid::line::cell_centre(x_min, dx, i);
        let b: Vec<f64> = match bed.as_constant() {
            Some(c) => vec![c; n],
            None => (0..n)
                .into_par_iter()
                .map(|i| bed.eval(centre(i), 0.0))
                .collect(),
        };
        let at = |p: &Profile| -> Vec<f64> {
            match p.as_constant() {
                Some(c) => vec![c; n],
                None => (0..n)
                    .into_par_iter()
                    .map(|i| p.eval(centre(i), b[i]))
                    .collect(),
            }
        };
        Sampled {
            h: at(&initial.h),
            h_bed: at(&initial.erodible_bed),
            u: at(&initial.u),
            w: at(&initial.w),
            eta: initial.eta.as_ref().map(&at),
            phi: initial.phi.as_ref().map(&at),
            v: Vec::new(),
            wall: Vec::new(),
            b,
        }
    }

    /// [`Sampled::of`] on a raster domain: every profile at the nx · ny centres,
    /// row-major (no w, η or φ there).
    fn of_plane(domain: &Domain, plane: &Plane, bed: &Profile, initial: &Initial) -> Sampled {
        use rayon::prelude::*;
        let centres = raster_centres(domain, plane);
        let b: Vec<f64> = centres
            .par_iter()
            .map(|&(x, y)| bed.eval_xy(x, y, 0.0))
            .collect();
        // A raster bed without a value at a centre (a nodata cell there or among the
        // four the interpolation reads; the raster covers the domain) makes it a wall.
        let wall: Vec<bool> = match bed.raster() {
            Some(_) if b.iter().any(|b| b.is_nan()) => b.iter().map(|b| b.is_nan()).collect(),
            _ => Vec::new(),
        };
        let at = |p: &Profile| -> Vec<f64> {
            centres
                .par_iter()
                .zip(&b)
                .enumerate()
                .map(|(k, (&(x, y), &b))| {
                    if !wall.is_empty() && wall[k] {
                        0.0
                    } else {
                        p.eval_xy(x, y, b)
                    }
                })
                .collect()
        };
        Sampled {
            h: at(&initial.h),
            h_bed: at(&initial.erodible_bed),
            u: at(&initial.u),
            v: at(&initial.v),
            w: Vec::new(),
            eta: None,
            phi: None,
            b,
            wall,
        }
    }
}

/// The centres (x_i, y_j) of a raster domain, row-major (index j·nx + i), with the
/// line's centre formula on each axis.
pub fn raster_centres(domain: &Domain, plane: &Plane) -> Vec<(f64, f64)> {
    let (nx, ny) = (domain.cells, plane.ny);
    let dx = (domain.x_max - domain.x_min) / nx as f64;
    let dy = (plane.y_max - plane.y_min) / ny as f64;
    let mut centres = Vec::with_capacity(nx * ny);
    for j in 0..ny {
        let y = crate::grid::line::cell_centre(plane.y_min, dy, j);
        for i in 0..nx {
            centres.push((crate::grid::line::cell_centre(domain.x_min, dx, i), y));
        }
    }
    centres
}

impl Scenario {
    /// What its run will write at least, from its output keys
    /// (`crate::output::budget`).
    pub fn output_estimate(&self) -> crate::output::budget::OutputEstimate {
        let nl = self.model.layers;
        let nx = self.domain.cell_count();
        let nh = self.model.pressure == Pressure::NonHydrostatic;
        // h, u per layer, w per layer (non-hydrostatic), up to three model fields;
        // p_nh at the (nl + 1) interfaces of the nx + 1 faces.
        // A layered raster: h, ū, v̄, u_α, v_α and the static interface.
        let per_cell = if self.domain.plane.is_some() && nl > 1 {
            4 + 2 * nl
        } else {
            1 + nl + if nh { nl } else { 0 } + 3
        };
        let p_nh = if nh { (nl + 1) * (nx + 1) } else { 0 };
        crate::output::budget::OutputEstimate::new(
            nx,
            per_cell,
            p_nh,
            self.time.t_end,
            self.output.every,
            self.output.gauges.len(),
            self.output.gauge_every,
        )
    }
}

/// A validated scenario: every value checked, nothing left to interpret.
#[derive(Debug, Clone)]
pub struct Scenario {
    /// Things the user should know that are not errors (keys ignored after a law
    /// switch, …), one sentence each; printed as `note: …`.
    pub notes: Vec<String>,
    /// The TOML text as read, after `--set` overrides (stored in the output file).
    pub source_toml: String,
    /// Directory of the scenario file (tables are resolved against it).
    pub base_dir: PathBuf,
    pub domain: Domain,
    /// Bed elevation b(x) over the reference plane.
    pub bed: Profile,
    pub material: Material,
    /// The friction law; where a coefficient is a field (`friction_zones`), its
    /// smallest value over the domain's cells.
    pub friction: FrictionLaw,
    /// The per-cell friction coefficients of a raster domain whose `rheology.mu`
    /// (`mu_deg`) or `rheology.xi` is a field; `None` where every coefficient is a number.
    pub friction_zones: Option<FrictionZones>,
    pub model: ModelSpec,
    /// Layer fractions and viscous options of the multilayer model.
    pub multilayer: MultilayerSpec,
    /// Law and numerics of the dilatant model (`model.kind = "dilatant"` only).
    pub dilatancy: Option<DilatantSpec>,
    pub initial: Initial,
    pub boundary: Boundaries,
    pub time: TimeSpec,
    pub output: OutputSpec,
    /// The two-layer model's keys (`model.kind = "submarine"` only).
    pub submarine: Option<SubmarineSpec>,
    /// `bed` and `initial` at the cell centres of `domain`.
    pub sampled: Sampled,
    /// The release polygon of `initial.h`, when it is one.
    pub release: Option<ReleaseSummary>,
    /// `[numerics]`: the order of the scheme and its limiter.
    pub numerics: Numerics,
}

/// `[numerics]`: first-order scheme (the default) or the second-order one
/// (`order = 2`: MUSCL reconstruction and Heun's method; the models that have it are
/// listed in docs/scenario-format.md, `numerics.order`; docs/numerics.md).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Numerics {
    /// 1 or 2.
    pub order: u8,
    /// The slope limiter of the reconstruction (order 2).
    pub limiter: Limiter,
}

impl Default for Numerics {
    fn default() -> Self {
        Numerics {
            order: 1,
            limiter: Limiter::Mc,
        }
    }
}
