//! Small checks shared by the key validators, each naming its dotted key.

use super::super::error::ScenarioError;

pub(super) type Res<T> = Result<T, ScenarioError>;

pub(super) fn err<T>(key: &str, message: impl Into<String>) -> Res<T> {
    Err(ScenarioError::at(key, message))
}

pub(super) fn section<T>(name: &str, s: Option<T>) -> Res<T> {
    s.ok_or_else(|| ScenarioError::at(name, format!("missing required table [{name}]")))
}

pub(super) fn required<T>(key: &str, v: Option<T>) -> Res<T> {
    v.ok_or_else(|| ScenarioError::at(key, "missing required key"))
}

/// A number for a message: as Rust prints it between 1e-5 and 1e16, in exponent form
/// outside (so 1e300 is not 301 digits long).
pub(crate) fn num(v: f64) -> String {
    let a = v.abs();
    if a != 0.0 && a.is_finite() && !(1e-5..1e16).contains(&a) {
        format!("{v:e}")
    } else {
        format!("{v}")
    }
}

pub(super) fn finite(key: &str, v: f64) -> Res<f64> {
    if v.is_finite() {
        Ok(v)
    } else {
        err(key, format!("must be a finite number, got {v}"))
    }
}

pub(super) fn positive(key: &str, v: f64) -> Res<f64> {
    finite(key, v)?;
    if v > 0.0 {
        Ok(v)
    } else {
        err(key, format!("must be greater than 0, got {}", num(v)))
    }
}

pub(super) fn non_negative(key: &str, v: f64) -> Res<f64> {
    finite(key, v)?;
    if v >= 0.0 {
        Ok(v)
    } else {
        err(key, format!("must be at least 0, got {}", num(v)))
    }
}

pub(super) fn int_in(key: &str, v: i64, min: i64, max: i64) -> Res<usize> {
    if v < min {
        err(key, format!("must be at least {min}, got {v}"))
    } else if v > max {
        err(key, format!("must be at most {max}, got {v}"))
    } else {
        Ok(v as usize)
    }
}

/// One of a fixed set of names.
pub(super) fn choice<T: Copy>(
    key: &str,
    v: Option<&str>,
    default: T,
    options: &[(&str, T)],
) -> Res<T> {
    let Some(v) = v else { return Ok(default) };
    match options.iter().find(|(name, _)| *name == v) {
        Some(&(_, t)) => Ok(t),
        None => {
            let names: Vec<String> = options.iter().map(|(n, _)| format!("\"{n}\"")).collect();
            err(
                key,
                format!("unknown value \"{v}\" (expected {})", names.join(" or ")),
            )
        }
    }
}

/// Largest speed (m/s) an initial profile may give (`initial.u`, `initial.w`): the
/// fastest rock avalanches reach about 100 m/s, and free fall from the height of
/// Everest (8.8 km) ends at √(2 g · 8848 m) ≈ 417 m/s. A larger value is a typo or a
/// unit mistake, and one of 1e100 m/s only sends the CFL step to zero.
pub(crate) const MAX_SPEED: f64 = 1e3;

/// Largest thickness (m) of the granular layer (`initial.h`, `initial.erodible_bed`):
/// the largest known landslides are under 2 km thick; 10 km is the height of the
/// highest mountains.
pub(crate) const MAX_THICKNESS: f64 = 1e4;

/// Largest water depth (m) over the bed (`initial.eta` − `bed.b`): the deepest ocean
/// trench is 11 km deep.
pub(crate) const MAX_DEPTH: f64 = 2e4;

/// Largest bed elevation |b| (m) over the reference plane: ten times the height of
/// Everest.
pub(crate) const MAX_ELEVATION: f64 = 1e5;

/// Smallest solid volume fraction (`initial.phi`, `dilatancy.phi_stat`): below 1 %
/// solid the mixture is a dilute suspension, not the dense granular mass of the model,
/// whose terms scale with 1/φ.
pub(crate) const MIN_PHI: f64 = 0.01;

/// Largest exponent α of the dilatant scheme's variable φ^α h (Bouchut et al. 2021,
/// eq. B.19): the scheme divides by φ^(α−1), which for φ ≥ [`MIN_PHI`] stays above
/// 1e-198 up to α = 100 and underflows to 0 beyond α ≈ 155.
pub(crate) const MAX_ALPHA: f64 = 100.0;

/// Smallest layer fraction (`model.layer_fractions`): a layer thinner than 1e-4 of the
/// column makes the viscous system's conditioning (l_max / l_min)² worse than 1e8.
pub(crate) const MIN_LAYER_FRACTION: f64 = 1e-4;

/// `v` with |v| ≤ `max`, else an error naming `key` and the bound's `why`.
pub(super) fn magnitude_at_most(key: &str, v: f64, max: f64, unit: &str, why: &str) -> Res<f64> {
    finite(key, v)?;
    if v.abs() <= max {
        Ok(v)
    } else {
        err(
            key,
            format!(
                "{} {unit} is beyond the physical bound |{}| ≤ {} {unit} ({why})",
                num(v),
                key.rsplit('.').next().unwrap_or(key),
                num(max)
            ),
        )
    }
}

pub(super) const SPEED_WHY: &str =
    "the fastest rock avalanches reach about 100 m/s; free fall from 8.8 km ends at 417 m/s";
pub(super) const THICKNESS_WHY: &str =
    "the largest landslides are under 2 km thick; 10 km is the height of the highest mountains";
pub(super) const DEPTH_WHY: &str = "the water depth η − b; the deepest ocean trench is 11 km deep";
pub(super) const ELEVATION_WHY: &str = "ten times the height of Everest";

/// Largest stabilisation coefficient ξ of the dilatant scheme (`dilatancy.xi`): the
/// paper's values are ξ = (2, 2, 5) (Bouchut et al. 2021, §3.3), and the explicit
/// sub-steps a time step takes grow as ξ (a run asking for more than 10 000 of them in
/// one step fails).
pub(crate) const MAX_XI: f64 = 1e3;
