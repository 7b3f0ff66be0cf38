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
