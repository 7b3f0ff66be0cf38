//! `output.path`: the avalanche path along which a raster run's runout is measured,
//! as AvaFrame's AIMEC does:
//!
//! ```toml
//! [output]
//! path = { line = "LINES/pathAB.shp", field = "ppr", threshold = 1000.0 }
//! ```
//!
//! `line` is a polyline file (shapefile or GeoJSON, top of the path first), `field` the
//! map whose threshold defines the cells reached (`"pft"`, m, the default, or `"ppr"`,
//! Pa), `threshold` (required) the value they must exceed, `width` (m, optional) the
//! width of the band centred on the line whose cells count (AIMEC's `domainWidth`;
//! every cell without it). The line's CRS is compared with the domain's, as a
//! release's is.

use std::path::{Path, PathBuf};

use super::super::error::ScenarioError;
use super::super::{Domain, PathField, PathSpec};
use super::check::*;

const KEY: &str = "output.path";

pub(super) fn spec(
    v: Option<&toml::Value>,
    domain: &Domain,
    base_dir: &Path,
) -> Res<Option<PathSpec>> {
    let Some(v) = v else {
        return Ok(None);
    };
    let toml::Value::Table(t) = v else {
        return err(
            KEY,
            format!(
                "must be a table {{ line = \"path.shp\", field = \"pft\", threshold = 1.0 }}, found {}",
                v.type_str()
            ),
        );
    };
    let Some(plane) = &domain.plane else {
        return err(KEY, "a runout path needs a raster (2-D) domain");
    };
    const ALLOWED: &str = "line, field, threshold, width";
    if let Some(other) = t
        .keys()
        .find(|k| !ALLOWED.split(", ").any(|a| a == k.as_str()))
    {
        return err(
            &format!("{KEY}.{other}"),
            format!("unknown key '{other}' (allowed: {ALLOWED})"),
        );
    }
    let file = match t.get("line") {
        Some(toml::Value::String(s)) if !s.trim().is_empty() => PathBuf::from(s),
        Some(other) => {
            return err(
                &format!("{KEY}.line"),
                format!("must be a file name, found {other}"),
            )
        }
        None => return err(&format!("{KEY}.line"), "the path needs line = \"path.shp\""),
    };
    let field = match t.get("field") {
        None => PathField::Pft,
        Some(toml::Value::String(s)) if s == "pft" => PathField::Pft,
        Some(toml::Value::String(s)) if s == "ppr" => PathField::Ppr,
        Some(other) => {
            return err(
                &format!("{KEY}.field"),
                format!("must be \"pft\" (m) or \"ppr\" (Pa), found {other}"),
            )
        }
    };
    let threshold = match t.get("threshold") {
        Some(toml::Value::Integer(i)) => *i as f64,
        Some(toml::Value::Float(f)) => *f,
        Some(other) => {
            return err(
                &format!("{KEY}.threshold"),
                format!("must be a number, found {}", other.type_str()),
            )
        }
        None => {
            return err(
                &format!("{KEY}.threshold"),
                "the path needs threshold = <m for pft, Pa for ppr>, the value a cell must exceed to count as reached (AIMEC often uses ppr > 1000 Pa)",
            )
        }
    };
    if !(threshold.is_finite() && threshold >= 0.0) {
        return err(
            &format!("{KEY}.threshold"),
            format!("must be a finite number ≥ 0, got {threshold}"),
        );
    }
    let width = match t.get("width") {
        None => None,
        Some(toml::Value::Integer(i)) if *i > 0 => Some(*i as f64),
        Some(toml::Value::Float(f)) if f.is_finite() && *f > 0.0 => Some(*f),
        Some(other) => {
            return err(
                &format!("{KEY}.width"),
                format!("must be a width in m > 0 (AIMEC's default is 600), found {other}"),
            )
        }
    };
    let line = crate::gis::path::read(&base_dir.join(&file))
        .map_err(|e| ScenarioError::at(format!("{KEY}.line"), e.to_string()))?;
    plane
        .crs
        .check_same(
            "the domain's rasters",
            &line.crs,
            &format!("the path ({})", file.display()),
        )
        .map_err(|e| ScenarioError::at(format!("{KEY}.line"), e.to_string()))?;
    Ok(Some(PathSpec {
        file,
        line,
        field,
        threshold,
        width,
    }))
}
