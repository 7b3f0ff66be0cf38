//! Friction zones of a raster domain: `rheology.mu` (or `mu_deg`) of the Coulomb and
//! Voellmy laws and Voellmy's `rheology.xi` given as a field, an expression in x, y
//! (and b) or a raster file `{ raster = "mu.asc" }` read like every raster profile
//! (`profile.rs`, the checks of `plane::profiles_fit`), sampled once at the cell
//! centres into [`FrictionZones`]. A line takes numbers only (its steps have one law).
//!
//! Polygons (a shapefile or GeoJSON, as AvaFrame's resistance areas) give a field too:
//! `{ polygon = "RES/res.shp", value = 0.5, outside = 0.25 }` (or `value_attribute =
//! "mu"`, a numeric attribute of each feature), rasterised onto the domain's cells as
//! a release is (`rule = "area_fraction"`, the default, or `"cell_centre"`): a cell
//! takes the values of the features over it weighted by the fractions they cover, and
//! `outside` for the rest (where features overlap, their mean).

use std::path::{Path, PathBuf};

use super::super::error::ScenarioError;
use super::super::raw::RawRheology;
use super::super::{raster_centres, Domain, FrictionLaw, FrictionZones, Profile, Sampled};
use super::check::*;
use crate::gis::release::{self as polygons, CoverageRule, ThicknessSource};
use crate::gis::Raster;

/// A coefficient given as a field: its key (`mu`, `mu_deg` or `xi`) and its profile.
pub(super) type Field = (&'static str, Profile);

/// Takes the keys of `r` given as fields out, leaving in their place a number that
/// passes the law's checks (the law's value is set from the field by [`sample`]).
/// A key of another type than a number, a string or a table is refused.
pub(super) fn take(r: &mut RawRheology, base_dir: &Path, domain: &Domain) -> Res<Vec<Field>> {
    let mut fields = Vec::new();
    for (name, slot, stand_in) in [
        ("mu", &mut r.mu, 0.0),
        ("mu_deg", &mut r.mu_deg, 0.0),
        ("xi", &mut r.xi, 1.0),
    ] {
        let key = format!("rheology.{name}");
        match slot {
            None | Some(toml::Value::Integer(_) | toml::Value::Float(_)) => {}
            Some(toml::Value::Table(t)) if t.contains_key("polygon") => {
                fields.push((name, polygon_field(&key, t, base_dir, domain)?));
                *slot = Some(toml::Value::Float(stand_in));
            }
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

/// A coefficient given by polygons (see the module docs), as a raster profile on the
/// domain's grid in the polygons' CRS (compared with the other rasters' by
/// `plane::profiles_fit`).
fn polygon_field(key: &str, t: &toml::Table, base_dir: &Path, domain: &Domain) -> Res<Profile> {
    const ALLOWED: &str = "polygon, value, value_attribute, outside, rule";
    if let Some(other) = t
        .keys()
        .find(|k| !ALLOWED.split(", ").any(|a| a == k.as_str()))
    {
        return err(
            &format!("{key}.{other}"),
            format!("unknown key '{other}' in a zone polygon (allowed: {ALLOWED})"),
        );
    }
    let Some(plane) = &domain.plane else {
        return err(
            &format!("{key}.polygon"),
            "zone polygons need a raster (2-D) domain; give a number on a line",
        );
    };
    let number = |name: &str| -> Res<Option<f64>> {
        match t.get(name) {
            None => Ok(None),
            Some(toml::Value::Integer(i)) => Ok(Some(*i as f64)),
            Some(toml::Value::Float(f)) => Ok(Some(*f)),
            Some(other) => err(
                &format!("{key}.{name}"),
                format!("must be a number, found {}", other.type_str()),
            ),
        }
    };
    let string = |name: &str| -> Res<Option<&str>> {
        match t.get(name) {
            None => Ok(None),
            Some(toml::Value::String(s)) => Ok(Some(s.as_str())),
            Some(other) => err(
                &format!("{key}.{name}"),
                format!("must be a string, found {}", other.type_str()),
            ),
        }
    };
    let file = string("polygon")?.unwrap_or_default();
    if file.trim().is_empty() {
        return err(&format!("{key}.polygon"), "must be a file name, got \"\"");
    }
    let source = match (number("value")?, string("value_attribute")?) {
        (Some(v), None) => ThicknessSource::Uniform(v),
        (None, Some(a)) => ThicknessSource::Attribute(a),
        _ => {
            return err(
                &format!("{key}.value"),
                "zone polygons need value = <number> (the same in every feature) or value_attribute = \"<field>\" (one of each feature), not both",
            )
        }
    };
    let Some(outside) = number("outside")? else {
        return err(
            &format!("{key}.outside"),
            "zone polygons need outside = <number>, the value where no polygon is",
        );
    };
    let rule = match string("rule")? {
        None | Some("area_fraction") => CoverageRule::AreaFraction,
        Some("cell_centre") => CoverageRule::CellCentre,
        Some(other) => {
            return err(
                &format!("{key}.rule"),
                format!("must be \"area_fraction\" or \"cell_centre\", got \"{other}\""),
            )
        }
    };
    let path = PathBuf::from(file);
    let areas = polygons::read(&base_dir.join(&path), source).map_err(|e| {
        ScenarioError::at(
            format!("{key}.polygon"),
            format!("cannot read the zone polygons: {e}"),
        )
    })?;
    let (nx, ny) = (domain.cells, plane.ny);
    let d = (domain.x_max - domain.x_min) / nx as f64;
    let mut grid = Raster::filled(nx, ny, domain.x_min, plane.y_max, d, 0.0);
    let mut covered = vec![0.0; nx * ny];
    let mut sum = vec![0.0; nx * ny];
    for feature in &areas.features {
        let fractions = polygons::coverage(&feature.polygons, &grid, rule);
        for (k, f) in fractions.into_iter().enumerate() {
            covered[k] += f;
            sum[k] += f * feature.thickness;
        }
    }
    for (k, v) in grid.values.iter_mut().enumerate() {
        *v = if covered[k] > 1.0 {
            sum[k] / covered[k]
        } else {
            sum[k] + (1.0 - covered[k]) * outside
        };
    }
    grid.crs = areas.crs;
    Ok(Profile::from_raster(&path, grid))
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
