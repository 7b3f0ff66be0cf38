//! Scenario files: the TOML a user writes, validated into plain data.
//!
//! Two layers, as in ripgrep's LowArgs → HiArgs: `raw` is a serde mirror of the TOML
//! (`deny_unknown_fields`, no logic); `validate` turns it into the [`Scenario`] below,
//! checking every key and naming it (with its line) in the error. Profiles (`bed.b`,
//! `initial.h`, `initial.u`, `initial.w`) are expressions in `x` or CSV tables (`profile`).
//! `--set key=value` overrides are applied to the document before deserialising
//! (`overrides`), so a sweep is a list of override sets over one base file.

mod document;
mod error;
mod overrides;
mod profile;
mod raw;
mod validate;

pub use error::ScenarioError;
pub use profile::Profile;
pub use validate::{load_file, load_str};

use std::path::PathBuf;

/// Frame in which the shallow model is written (seed 000 §4.1).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Coordinates {
    /// Along and normal to a reference plane of slope θ; gravity g cos θ normal to it.
    Local,
    /// Horizontal x, vertical z; the slope lives inside b(x) and gravity is g.
    Cartesian,
}

#[derive(Debug, Clone, PartialEq)]
pub struct Domain {
    pub x_min: f64,
    pub x_max: f64,
    pub cells: usize,
    /// Inclination θ of the reference plane, degrees (0 for Cartesian runs).
    pub slope_deg: f64,
    pub coordinates: Coordinates,
}

#[derive(Debug, Clone, PartialEq)]
pub struct Material {
    /// Grain density ρ_s (kg/m³).
    pub rho_s: f64,
    /// Solid volume fraction φ_s (flow density ρ = φ_s ρ_s).
    pub phi: f64,
    /// Grain diameter d_s (m).
    pub d_s: f64,
}

/// Basal friction law (seed 000 eq. 6).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum FrictionLaw {
    /// Constant Coulomb coefficient μ (classical Savage–Hutter).
    Coulomb { mu: f64 },
    /// μ(I) = μ_s + (μ_2 − μ_s) I / (I_0 + I).
    MuI { mu_s: f64, mu_2: f64, i0: f64 },
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ModelKind {
    /// The layered family: Savage–Hutter, multilayer, non-hydrostatic.
    Granular,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Pressure {
    Hydrostatic,
    NonHydrostatic,
}

#[derive(Debug, Clone, PartialEq)]
pub struct ModelSpec {
    pub kind: ModelKind,
    pub pressure: Pressure,
    pub layers: usize,
}

/// Condition at the bed of the multilayer model (seed 001 eq. 28 and end of §3.3).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BasalCondition {
    /// Coulomb friction μ(I_{1/2}) p_b u_1/|u_1| (`rheology.basal = "coulomb"`).
    Coulomb,
    /// u = 0 at the bed, stress from the rheology with ∂_z u ≈ 2u_1/h_1 (`"no_slip"`).
    NoSlip,
}

/// How the μ(I) viscosity η = μ(I) p / |∂_z u| is kept finite where the shear vanishes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Regularization {
    /// η = μ p / √(‖D‖² + δ²) (seed 003 eq. 10), `rheology.delta` = δ in 1/s.
    Delta { delta: f64 },
    /// η = μ p / max(‖D‖, μ p/η_M), η_M = 250 ρ √(g h³) (seed 001 eq. 6 and 25).
    Bound,
}

/// Where the sidewall friction of a channel of width W enters the multilayer model.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SidewallForm {
    /// Jop's term μ_w (H − z)/W added to μ(I) (seed 001 eq. 30).
    Jop,
    /// A friction force −l_α h (2/W) μ_w p_α u_α/|u_α| on each layer (seed 003 eq. 36).
    Layer,
}

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sidewall {
    /// Wall friction coefficient μ_w.
    pub mu_w: f64,
    /// Channel width W (m).
    pub width: f64,
    pub form: SidewallForm,
}

/// Options of the multilayer model (`model.layers > 1`); the monolayer model ignores
/// `regularization`, `c_msm` and `static_threshold` and rejects the others.
#[derive(Debug, Clone, PartialEq)]
pub struct MultilayerSpec {
    /// Layer fractions l_α, bottom first (`model.layer_fractions`, uniform by default).
    pub layer_fractions: Vec<f64>,
    pub basal: BasalCondition,
    pub regularization: Regularization,
    pub sidewall: Option<Sidewall>,
    /// Second-order strain-rate correction of seed 001 eq. (32) ("C-MSM").
    pub c_msm: bool,
    /// Speed (m/s) above which a layer flows, for `/snapshots/static_interface`.
    pub static_threshold: f64,
}

#[derive(Debug, Clone)]
pub struct Initial {
    /// Flow thickness above the erodible bed, h(x) ≥ 0 (the bed layer is added on top).
    pub h: Profile,
    /// Depth-averaged downslope velocity u(x).
    pub u: Profile,
    /// Normal velocity w(x) (non-hydrostatic model only; seed 000 eq. 30).
    pub w: Profile,
    /// Uniform erodible-bed thickness h_i ≥ 0 (seed 001 §4.2).
    pub erodible_bed: f64,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BoundaryKind {
    /// Reflecting wall: ghost discharge opposite, thickness mirrored (seed 003 Remark 6).
    Wall,
    /// Free outflow: ghost state copied (homogeneous Neumann).
    Outflow,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Boundaries {
    pub left: BoundaryKind,
    pub right: BoundaryKind,
}

#[derive(Debug, Clone, PartialEq)]
pub struct TimeSpec {
    pub t_end: f64,
    pub cfl: f64,
    /// End the run early once the whole mass is at rest.
    pub stop_at_rest: bool,
}

#[derive(Debug, Clone, PartialEq)]
pub struct OutputSpec {
    /// HDF5 file, relative to the current directory unless absolute.
    pub file: PathBuf,
    /// Snapshot interval (s); the time step is shortened to land on it.
    pub every: f64,
    /// Thickness above which a cell counts as flowing mass for the front position (m).
    pub front_threshold: f64,
}

/// A validated scenario: every value checked, nothing left to interpret.
#[derive(Debug, Clone)]
pub struct Scenario {
    /// The TOML text as read, after `--set` overrides (stored in the output file).
    pub source_toml: String,
    /// Directory of the scenario file (tables are resolved against it).
    pub base_dir: PathBuf,
    pub domain: Domain,
    /// Bed elevation b(x) over the reference plane.
    pub bed: Profile,
    pub material: Material,
    pub friction: FrictionLaw,
    pub model: ModelSpec,
    /// Layer fractions and viscous options of the multilayer model.
    pub multilayer: MultilayerSpec,
    pub initial: Initial,
    pub boundary: Boundaries,
    pub time: TimeSpec,
    pub output: OutputSpec,
}
