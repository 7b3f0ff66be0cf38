//! A release polygon as the initial thickness of a raster run, and in the same way
//! polygons of an erodible bed (AvaFrame's entrainment areas):
//!
//! ```toml
//! [initial]
//! h = { polygon = "release.geojson", thickness = 1.5, thickness_is = "normal" }
//! erodible_bed = { polygon = "ENT/ent.shp", thickness = 0.3, thickness_is = "normal" }
//! ```
//!
//! Keys: `polygon` (a `.shp` or a GeoJSON file, relative to the scenario), the
//! thickness as a number (`thickness`, m) or a numeric attribute of each feature
//! (`thickness_attribute`), `thickness_is` (`"vertical"` or `"normal"` to the slope;
//! required: the two differ by cos θ), and `rule` (`"area_fraction"`, the default, or
//! `"cell_centre"`). The polygons are rasterised onto the domain's cells
//! (`gis::release::rasterise`: area fraction or cell centre), a slope-normal thickness
//! is divided by cos θ of the bed's local slope (`gis::release::vertical_thickness`,
//! `h_v = h_n / cos θ`), and the released volume Σ h ΔxΔy is recorded with the volume
//! that fell on wall (nodata) cells. The CRS of the polygons and of the scenario's
//! rasters are compared (both files named on a mismatch); a polygon outside the
//! domain, or partly outside, is refused.

use std::path::{Path, PathBuf};

use super::super::error::ScenarioError;
use super::super::profile::Profile;
use super::super::{CoverageRule, Domain, ReleaseSummary, Sampled, ThicknessIs};
use super::check::*;
use crate::gis::release::{self as polygons, ReleaseAreas, ThicknessSource};
use crate::gis::Raster;
use crate::grid::spec::north_up;

/// Largest accepted polygon file (bytes): a bound, so that a wrong path is refused at
/// once instead of read until memory runs out.
const MAX_POLYGON_BYTES: u64 = 256 << 20;

/// The keys of a release polygon, with its features read.
#[derive(Debug)]
pub(super) struct ReleaseKeys {
    /// The scenario key: `initial.h` or `initial.erodible_bed`.
    key: &'static str,
    /// As written in the scenario.
    file: PathBuf,
    areas: ReleaseAreas,
    thickness_is: ThicknessIs,
    rule: CoverageRule,
}

/// Whether a key is given as polygons (`{ polygon = … }`).
fn is_polygon(v: Option<&toml::Value>) -> bool {
    matches!(v, Some(toml::Value::Table(t)) if t.contains_key("polygon"))
}

/// When the thickness `KEY` (`initial.h` or `initial.erodible_bed`, held in `slot`)
/// is given as polygons: its keys checked and its file read, and the key replaced by
/// 0 (the rasterised thickness takes its place after sampling, [`rasterise`]).
pub(super) fn take(
    (key, slot): (&'static str, &mut Option<toml::Value>),
    raster_domain: bool,
    base_dir: &Path,
) -> Res<Option<ReleaseKeys>> {
    let what = what(key);
    if !is_polygon(slot.as_ref()) {
        return Ok(None);
    }
    let Some(toml::Value::Table(t)) = slot.replace(toml::Value::Float(0.0)) else {
        unreachable!("is_polygon saw a table")
    };
    if !raster_domain {
        return err(
            &format!("{key}.polygon"),
            format!("{what} needs a raster (2-D) domain (domain.y_min, domain.y_max, or the grid of a raster bed)"),
        );
    }
    const ALLOWED: &str = "polygon, thickness, thickness_attribute, thickness_is, rule";
    if let Some(other) = t
        .keys()
        .find(|k| !ALLOWED.split(", ").any(|a| a == k.as_str()))
    {
        return err(
            &format!("{key}.{other}"),
            format!("unknown key '{other}' in {what} (allowed: {ALLOWED})"),
        );
    }
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
    let file = string("polygon")?.expect("is_polygon saw the key");
    if file.trim().is_empty() {
        return err(&format!("{key}.polygon"), "must be a file name, got \"\"");
    }
    let thickness = match t.get("thickness") {
        None => None,
        Some(toml::Value::Integer(i)) => Some(*i as f64),
        Some(toml::Value::Float(f)) => Some(*f),
        Some(other) => {
            return err(
                &format!("{key}.thickness"),
                format!("must be a number (m), found {}", other.type_str()),
            )
        }
    };
    let attribute = string("thickness_attribute")?;
    let source = match (thickness, attribute) {
        (Some(_), Some(_)) => {
            return err(
                &format!("{key}.thickness_attribute"),
                "give either thickness (the same for every feature) or thickness_attribute (a field of each feature), not both",
            )
        }
        (None, None) => {
            return err(
                &format!("{key}.thickness"),
                format!("{what} needs thickness = <m> or thickness_attribute = \"<field>\""),
            )
        }
        (Some(h), None) => {
            let key = format!("{key}.thickness");
            non_negative(&key, h)?;
            magnitude_at_most(&key, h, MAX_THICKNESS, "m", THICKNESS_WHY)?;
            ThicknessSource::Uniform(h)
        }
        (None, Some(a)) => ThicknessSource::Attribute(a),
    };
    let thickness_is = match string("thickness_is")? {
        Some("vertical") => ThicknessIs::Vertical,
        Some("normal") => ThicknessIs::Normal,
        Some(other) => {
            return err(
                &format!("{key}.thickness_is"),
                format!("must be \"vertical\" or \"normal\" (to the slope), got \"{other}\""),
            )
        }
        None => {
            return err(
                &format!("{key}.thickness_is"),
                "say how the thickness is measured: \"vertical\", or \"normal\" to the slope (divided by cos θ of the bed's slope; the released volumes differ by that factor)",
            )
        }
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
    let full = base_dir.join(file);
    let polygon_key = format!("{key}.polygon");
    match std::fs::metadata(&full) {
        Ok(meta) if !meta.is_file() => {
            return err(
                &polygon_key,
                format!("'{}' is not a regular file", full.display()),
            )
        }
        Ok(meta) if meta.len() > MAX_POLYGON_BYTES => {
            return err(
                &polygon_key,
                format!(
                    "'{}' is {} MiB, more than the {} MiB a release file may be",
                    full.display(),
                    meta.len() >> 20,
                    MAX_POLYGON_BYTES >> 20
                ),
            )
        }
        _ => {}
    }
    let areas = polygons::read(&full, source).map_err(|e| {
        ScenarioError::at(
            &polygon_key,
            format!("cannot read the release polygons: {e}"),
        )
    })?;
    Ok(Some(ReleaseKeys {
        key,
        file: PathBuf::from(file),
        areas,
        thickness_is,
        rule,
    }))
}

/// A DEM that states no CRS (an ESRI ASCII grid without its `.prj`) under a release
/// that states one: the run takes the release's CRS for its outputs, with a note that
/// says so, rather than writing rasters a GIS cannot place.
pub(super) fn adopt_crs(
    keys: &ReleaseKeys,
    domain: &mut Domain,
    bed: &Profile,
    notes: &mut Vec<String>,
) {
    let Some(plane) = domain.plane.as_mut() else {
        return;
    };
    let none = |c: &crate::gis::Crs| c.is_unknown() || c.is_local();
    if !none(&plane.crs) || none(&keys.areas.crs) {
        return;
    }
    let dem = bed.raster_path().map_or_else(
        || "the domain".to_owned(),
        |p| format!("the DEM '{}'", p.display()),
    );
    notes.push(format!(
        "{dem} states no CRS (no .prj beside an ESRI ASCII grid, or a LOCAL_CS); the outputs take the CRS of the release '{}', {}: check that the DEM is in it",
        keys.file.display(),
        keys.areas.crs
    ));
    plane.crs = keys.areas.crs.clone();
}

/// "a release polygon" or "an erodible-bed polygon", for messages.
fn what(key: &str) -> &'static str {
    if key == "initial.h" {
        "a release polygon"
    } else {
        "an erodible-bed polygon"
    }
}

/// Rasterises the polygons onto the domain's cells: sets the thickness they give
/// (`sampled.h` for the release, `sampled.h_bed` for an erodible bed) and `profile`
/// (a raster profile of the same values, so that sampling it again gives them) and
/// returns the summary.
pub(super) fn rasterise(
    keys: ReleaseKeys,
    domain: &Domain,
    bed: &Profile,
    sampled: &mut Sampled,
    profile: &mut Profile,
) -> Res<ReleaseSummary> {
    let plane = domain.plane.as_ref().expect("checked by take");
    let polygon_key = format!("{}.polygon", keys.key);
    let what = what(keys.key);
    let (nx, ny) = (domain.cells, plane.ny);
    let dx = (domain.x_max - domain.x_min) / nx as f64;
    let dy = (plane.y_max - plane.y_min) / ny as f64;
    if (dx - dy).abs() > 1e-9 * dx.max(dy) {
        return err(
            &polygon_key,
            format!("{what} is rasterised on square cells; the domain's are Δx = {dx} m by Δy = {dy} m (choose domain.cells so that they are equal)"),
        );
    }
    let file = keys.file.display().to_string();
    let rasters = match bed.raster_path() {
        Some(p) => format!("the DEM ({})", p.display()),
        None => "the scenario's raster files".to_owned(),
    };
    if keys.areas.crs.is_geographic() {
        return err(
            &polygon_key,
            super::plane::geographic(&format!(" '{file}'"), &keys.areas.crs),
        );
    }
    plane
        .crs
        .check_same(&rasters, &keys.areas.crs, &format!("the polygons ({file})"))
        .map_err(|e| ScenarioError::at(&polygon_key, e.to_string()))?;
    // The domain as a GIS raster: row 0 at the top (north), the bed as its values,
    // NaN (nodata) on the wall cells.
    let mut grid = Raster::filled(nx, ny, domain.x_min, plane.y_max, dx, 0.0);
    grid.nodata = Some(f64::NAN);
    grid.crs = plane.crs.clone();
    let wall = |k: usize| !sampled.wall.is_empty() && sampled.wall[k];
    let bed: Vec<f64> = (0..nx * ny)
        .map(|k| if wall(k) { f64::NAN } else { sampled.b[k] })
        .collect();
    grid.values = north_up(&bed, nx, ny);
    let release = polygons::rasterise(&keys.areas, &grid, keys.rule)
        .map_err(|e| ScenarioError::at(&polygon_key, format!("{file}: {e}")))?;
    let mut thickness = match keys.thickness_is {
        ThicknessIs::Vertical => release.thickness,
        ThicknessIs::Normal => polygons::vertical_thickness(&release.thickness, &grid)
            .map_err(|e| ScenarioError::at(&polygon_key, format!("{file}: {e}")))?,
    };
    // Wall cells hold nothing.
    for v in thickness.values.iter_mut() {
        if v.is_nan() {
            *v = 0.0;
        }
    }
    thickness.nodata = None;
    let target = if keys.key == "initial.h" {
        &mut sampled.h
    } else {
        &mut sampled.h_bed
    };
    *target = north_up(&thickness.values, nx, ny);
    let volume = target.iter().sum::<f64>() * dx * dy;
    if volume <= 0.0 && release.volume_on_nodata > 0.0 {
        return err(
            &polygon_key,
            format!("{file}: the whole of {what} lies on wall (nodata) cells of the DEM"),
        );
    }
    let area = keys
        .areas
        .features
        .iter()
        .flat_map(|f| &f.polygons)
        .map(polygons::Polygon::area)
        .sum();
    *profile = Profile::from_raster(&keys.file, thickness);
    Ok(ReleaseSummary {
        file: keys.file,
        features: keys.areas.features.len(),
        area,
        rule: keys.rule,
        thickness_is: keys.thickness_is,
        volume,
        volume_on_walls: release.volume_on_nodata,
    })
}
