//! Serde mirror of the scenario TOML: one struct per table, one field per key.
//!
//! No logic and no defaults here: every key is optional so that `validate` can tell
//! "absent" from "given", fill in defaults and name the key in its errors. Names, enums
//! and profiles stay loosely typed (`String`, `toml::Value`) for the same reason.
//! Adding a key is adding a field here and its check in `validate`.

use serde::Deserialize;

/// A profile as written: a number, an expression string or `{ table = "file.csv" }`.
pub(crate) type RawProfile = toml::Value;

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawScenario {
    pub domain: Option<RawDomain>,
    pub bed: Option<RawBed>,
    pub material: Option<RawMaterial>,
    pub rheology: Option<RawRheology>,
    pub model: Option<RawModel>,
    pub initial: Option<RawInitial>,
    pub boundary: Option<RawBoundary>,
    pub time: Option<RawTime>,
    pub output: Option<RawOutput>,
    pub submarine: Option<RawSubmarine>,
    pub dilatancy: Option<RawDilatancy>,
    pub numerics: Option<RawNumerics>,
}

/// `[numerics]`: the scheme's order and limiter.
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawNumerics {
    pub order: Option<i64>,
    pub limiter: Option<String>,
}

/// `[dilatancy]`: the dilatant model's law and numerics (Bouchut et al. 2021).
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawDilatancy {
    pub k: Option<f64>,
    pub k_tilde: Option<f64>,
    pub phi_stat: Option<f64>,
    pub phi_eq: Option<String>,
    pub n: Option<f64>,
    pub update: Option<String>,
    pub alpha: Option<f64>,
    pub lambda: Option<f64>,
    pub xi: Option<Vec<f64>>,
    pub scheme: Option<String>,
    pub thin_layer_grains: Option<f64>,
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawSubmarine {
    pub r: Option<f64>,
    pub k: Option<f64>,
    pub lambda1: Option<f64>,
    pub lambda2: Option<f64>,
    pub k_in: Option<f64>,
    pub buoyancy: Option<String>,
    pub water_pressure: Option<String>,
    pub water_layers: Option<i64>,
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawDomain {
    pub x_min: Option<f64>,
    pub x_max: Option<f64>,
    pub y_min: Option<f64>,
    pub y_max: Option<f64>,
    /// `n` (a line) or `[nx, ny]` (a raster).
    pub cells: Option<toml::Value>,
    pub slope_deg: Option<f64>,
    pub coordinates: Option<String>,
    /// The centrifugal term in the friction's normal stress (bed-normal rasters).
    pub curvature: Option<bool>,
    /// `[x_min, x_max, y_min, y_max]`: crop the raster bed's grid (raster domains).
    pub crop: Option<Vec<f64>>,
    /// Coarsen the raster bed's grid by this integer factor (raster domains).
    pub coarsen: Option<i64>,
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawBed {
    pub b: Option<RawProfile>,
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawMaterial {
    pub rho_s: Option<f64>,
    pub phi: Option<f64>,
    pub d_s: Option<f64>,
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawRheology {
    pub law: Option<String>,
    /// A number, or on a raster domain a field (expression in x, y or raster file).
    pub mu: Option<RawProfile>,
    pub mu_deg: Option<RawProfile>,
    pub mu_s: Option<f64>,
    pub mu_s_deg: Option<f64>,
    pub mu_2: Option<f64>,
    pub mu_2_deg: Option<f64>,
    pub i0: Option<f64>,
    pub monolayer_shear: Option<String>,
    pub basal: Option<String>,
    pub regularization: Option<String>,
    pub delta: Option<f64>,
    pub mu_w: Option<f64>,
    pub mu_w_deg: Option<f64>,
    pub channel_width: Option<f64>,
    pub xi: Option<RawProfile>,
    pub sidewall: Option<String>,
    pub c_msm: Option<bool>,
    pub viscosity: Option<String>,
    pub viscosity_tolerance: Option<f64>,
    pub viscosity_iterations: Option<i64>,
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawModel {
    pub kind: Option<String>,
    pub pressure: Option<String>,
    pub layers: Option<i64>,
    pub layer_fractions: Option<Vec<f64>>,
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawInitial {
    pub h: Option<RawProfile>,
    pub u: Option<RawProfile>,
    pub v: Option<RawProfile>,
    pub w: Option<RawProfile>,
    pub phi: Option<RawProfile>,
    pub erodible_bed: Option<RawProfile>,
    pub eta: Option<RawProfile>,
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawBoundary {
    pub left: Option<String>,
    pub right: Option<String>,
    pub west: Option<String>,
    pub east: Option<String>,
    pub south: Option<String>,
    pub north: Option<String>,
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawTime {
    pub t_end: Option<f64>,
    pub cfl: Option<f64>,
    pub stop_at_rest: Option<bool>,
    pub settle_fraction: Option<f64>,
    pub stop_when_settled: Option<bool>,
    pub film_thickness: Option<f64>,
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawOutput {
    pub file: Option<String>,
    pub every: Option<f64>,
    pub front_threshold: Option<f64>,
    pub static_threshold: Option<f64>,
    /// Positions `[x, …]` on a line, points `[[x, y], …]` on a raster.
    pub gauges: Option<toml::Value>,
    pub gauge_every: Option<f64>,
    /// `{ line = "path.shp", field = "pft" | "ppr", threshold = … }` (raster runs).
    pub path: Option<toml::Value>,
}
