//! Friction zones of a raster domain: `rheology.mu` (or `mu_deg`) of the Coulomb and
//! Voellmy laws and Voellmy's `rheology.xi` given as a field, an expression in x, y
//! (and b) or a raster file `{ raster = "mu.asc" }` read like every raster profile
//! (`profile.rs`, the checks of `plane::profiles_fit`), sampled once at the cell
//! centres into [`FrictionZones`]. A line takes numbers only (its steps have one law).

use std::path::Path;

use super::super::error::ScenarioError;
use super::super::raw::RawRheology;
use super::super::{raster_centres, Domain, FrictionLaw, FrictionZones, Profile, Sampled};
use super::check::*;

/// A coefficient given as a field: its key (`mu`, `mu_deg` or `xi`) and its profile.
pub(super) type Field = (&'static str, Profile);

/// Takes the keys of `r` given as fields out, leaving in their place a number that
/// passes the law's checks (the law's value is set from the field by [`sample`]).
/// A key of another type than a number, a string or a table is refused.
pub(super) fn take(r: &mut RawRheology, base_dir: &Path) -> Res<Vec<Field>> {
    let mut fields = Vec::new();
    for (name, slot, stand_in) in [
        ("mu", &mut r.mu, 0.0),
        ("mu_deg", &mut r.mu_deg, 0.0),
        ("xi", &mut r.xi, 1.0),
    ] {
        let key = format!("rheology.{name}");
        match slot {
            None | Some(toml::Value::Integer(_) | toml::Value::Float(_)) => {}
            Some(v @ (toml::Value::String(_) | toml::Value::Table(_))) => {
                fields.push((name, Profile::from_toml(&key, v, base_dir, true)?));
                *slot = Some(toml::Value::Float(stand_in));
            }
            Some(other) => {
                return err(
                    &key,
                    format!(
                        "wrong type: expected a number (or on a raster domain an expression in x, y or {{ raster = \"file\" }}), found {}",
                        other.type_str()
                    ),
                )
            }
        }
    }
    Ok(fields)
}

/// The number of a coefficient key (after [`take`]).
pub(super) fn number(v: &Option<toml::Value>) -> Option<f64> {
    match v {
        Some(toml::Value::Integer(i)) => Some(*i as f64),
        Some(toml::Value::Float(f)) => Some(*f),
        _ => None,
    }
}

/// Keeps the fields that `law` uses (a key of another law was refused, or ignored
/// after `rheology.law` was overridden) and refuses them on a line.
pub(super) fn used(fields: Vec<Field>, law: &FrictionLaw, domain: &Domain) -> Res<Vec<Field>> {
    let fields: Vec<Field> = fields
        .into_iter()
        .filter(|(name, _)| match law {
            FrictionLaw::Coulomb { .. } => *name != "xi",
            FrictionLaw::Voellmy { .. } => true,
            FrictionLaw::MuI { .. } => false,
        })
        .collect();
    if let (Some((name, _)), None) = (fields.first(), &domain.plane) {
        return err(
            &format!("rheology.{name}"),
            "a friction field (an expression or a raster file) needs a raster domain; give a number on a line",
        );
    }
    Ok(fields)
}

/// Samples the fields at the cell centres (a wall cell takes the law's stand-in),
/// checks every value (μ ≥ 0, an angle in [0, 90) degrees, ξ > 0, all finite, naming
/// the key, the field and the point) and sets the law's coefficient to the field's
/// smallest value.
pub(super) fn sample(
    fields: &[Field],
    law: &mut FrictionLaw,
    domain: &Domain,
    sampled: &Sampled,
) -> Res<Option<FrictionZones>> {
    let Some(plane) = &domain.plane else {
        return Ok(None);
    };
    if fields.is_empty() {
        return Ok(None);
    }
    let centres = raster_centres(domain, plane);
    let wall = |k: usize| !sampled.wall.is_empty() && sampled.wall[k];
    let mut zones = FrictionZones::default();
    for (name, profile) in fields {
        let key = format!("rheology.{name}");
        let mut values = Vec::with_capacity(centres.len());
        let mut smallest = f64::INFINITY;
        for (k, &(x, y)) in centres.iter().enumerate() {
            if wall(k) {
                values.push(f64::NAN);
                continue;
            }
            let v = profile
                .try_eval_xy(x, y, sampled.b[k])
                .map_err(|m| ScenarioError::at(&key, format!("{m} at (x, y) = ({x}, {y})")))?;
            let (ok, what) = match *name {
                "mu" => (v.is_finite() && v >= 0.0, "a finite coefficient ≥ 0"),
                "mu_deg" => ((0.0..90.0).contains(&v), "an angle in [0, 90) degrees"),
                _ => (v.is_finite() && v > 0.0, "a finite coefficient > 0 (m/s²)"),
            };
            if !ok {
                let v = if v.is_nan() {
                    "no value (NaN, or nodata in a raster)".to_string()
                } else {
                    num(v)
                };
                return err(
                    &key,
                    format!(
                        "{} gives {v} at (x, y) = ({x}, {y}); must be {what}",
                        profile.describe()
                    ),
                );
            }
            let v = if *name == "mu_deg" {
                v.to_radians().tan()
            } else {
                v
            };
            smallest = smallest.min(v);
            values.push(v);
        }
        // Wall cells carry no mass; they take the smallest value (never read).
        for v in values.iter_mut().filter(|v| v.is_nan()) {
            *v = smallest;
        }
        match (*name, &mut *law) {
            ("xi", FrictionLaw::Voellmy { xi, .. }) => {
                *xi = smallest;
                zones.xi = Some(values);
            }
            (_, FrictionLaw::Coulomb { mu } | FrictionLaw::Voellmy { mu, .. }) => {
                *mu = smallest;
                zones.mu = Some(values);
            }
            _ => unreachable!("`used` keeps the fields of the law"),
        }
    }
    Ok(Some(zones))
}
