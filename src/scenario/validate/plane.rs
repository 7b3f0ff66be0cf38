//! The keys of a raster (2-D) domain: `domain.y_min`, `domain.y_max`,
//! `domain.cells = [nx, ny]` (or the grid of a raster bed), the four sides of
//! `[boundary]`, `initial.v`, gauges at points `[x, y]`, raster profiles, and the keys
//! a raster domain cannot take (the multilayer, non-hydrostatic, submarine and dilatant
//! models are 1-D). A line domain is the one of `validate/mod.rs`, untouched by any of
//! this except that it refuses these keys with a message naming them.

use super::super::error::ScenarioError;
use super::super::raw::{RawBoundary, RawDomain, RawInitial};
use super::super::{
    raster_centres, Boundaries, BoundaryKind, Domain, Initial, ModelKind, ModelSpec, OutputSpec,
    Plane, Pressure, Profile, Sampled,
};
use super::check::*;
use super::zones::Field;
use super::{frame, line_boundary, line_gauges, MAX_CELLS, MIN_RELATIVE_DX};
use crate::gis::Crs;
use crate::grid::Coordinates;

const RASTER_HINT: &str =
    "give domain.y_min, domain.y_max and cells = [nx, ny] for a raster domain";

/// Whether the `[domain]` table describes a raster: it has `y_min` or `y_max`, or
/// `cells` is an array.
pub(super) fn is_raster(d: &RawDomain) -> bool {
    d.y_min.is_some() || d.y_max.is_some() || matches!(d.cells, Some(toml::Value::Array(_)))
}

/// Whether the domain takes the grid of the raster bed: `bed.b = { raster = … }` and
/// none of the grid keys x_min, x_max, y_min, y_max, cells is given.
pub(super) fn grid_from_bed(d: &RawDomain, bed: Option<&toml::Value>) -> bool {
    let no_grid = d.x_min.is_none()
        && d.x_max.is_none()
        && d.y_min.is_none()
        && d.y_max.is_none()
        && d.cells.is_none();
    let raster_bed = matches!(bed, Some(toml::Value::Table(t)) if t.contains_key("raster"));
    no_grid && raster_bed
}

/// `domain.cells` of a line: an integer (the range is checked by the caller).
pub(super) fn line_cells(v: Option<&toml::Value>) -> Res<Option<i64>> {
    match v {
        None => Ok(None),
        Some(toml::Value::Integer(n)) => Ok(Some(*n)),
        Some(other) => err(
            "domain.cells",
            format!(
                "wrong type: expected an integer (or [nx, ny] on a raster domain), found {}",
                describe(other)
            ),
        ),
    }
}

fn describe(v: &toml::Value) -> String {
    match v {
        toml::Value::String(s) => format!("string \"{s}\""),
        toml::Value::Float(f) => format!("floating point `{f}`"),
        toml::Value::Array(_) => "an array".into(),
        toml::Value::Table(_) => "a table".into(),
        other => other.type_str().to_owned(),
    }
}

/// `domain.cells = [nx, ny]`.
fn raster_cells(v: Option<&toml::Value>) -> Res<(usize, usize)> {
    const KEY: &str = "domain.cells";
    let v = required(KEY, v)?;
    let toml::Value::Array(a) = v else {
        return err(
            KEY,
            format!(
                "a raster domain (domain.y_min, domain.y_max) needs cells = [nx, ny], found {}",
                describe(v)
            ),
        );
    };
    if a.len() != 2 {
        return err(
            KEY,
            format!(
                "must be [nx, ny] (two integers) on a raster domain, got {} value{}",
                a.len(),
                if a.len() == 1 { "" } else { "s" }
            ),
        );
    }
    let mut n = [0usize; 2];
    for (k, (axis, value)) in ["nx", "ny"].iter().zip(a).enumerate() {
        let toml::Value::Integer(c) = value else {
            return err(
                KEY,
                format!("{axis} must be an integer, found {}", describe(value)),
            );
        };
        if *c < 1 {
            return err(KEY, format!("{axis} must be at least 1, got {c}"));
        }
        n[k] = *c as usize;
    }
    let total = n[0].saturating_mul(n[1]);
    if total > MAX_CELLS as usize {
        return err(
            KEY,
            format!(
                "{} × {} = {total} cells is more than {MAX_CELLS} (the state would not fit in memory)",
                n[0], n[1]
            ),
        );
    }
    Ok((n[0], n[1]))
}

/// An axis [lo, hi] of `n` cells whose centres are distinct (as on a line).
fn axis(lo_key: &str, hi_key: &str, lo: Option<f64>, hi: Option<f64>, n: usize) -> Res<(f64, f64)> {
    let lo = finite(lo_key, required(lo_key, lo)?)?;
    let hi = finite(hi_key, required(hi_key, hi)?)?;
    if hi <= lo {
        return err(
            hi_key,
            format!("must be greater than {lo_key} = {lo}, got {}", num(hi)),
        );
    }
    if !(hi - lo).is_finite() {
        return err(hi_key, format!("the extent {hi_key} - {lo_key} overflows"));
    }
    let d = (hi - lo) / n as f64;
    let scale = lo.abs().max(hi.abs());
    if d < MIN_RELATIVE_DX * scale {
        return err(
            "domain.cells",
            format!(
                "cells of {d:e} m are at the round-off of the coordinates (up to {scale:e} m): cell centres would not be distinct; use fewer cells or shift the domain towards 0"
            ),
        );
    }
    Ok((lo, hi))
}

/// `domain.curvature`, which only the bed-normal frame takes.
pub(super) fn curvature(d: &RawDomain, coordinates: Coordinates) -> Res<bool> {
    match d.curvature {
        Some(_) if coordinates != Coordinates::BedNormal => err(
            "domain.curvature",
            "the centrifugal term belongs to domain.coordinates = \"bed_normal\" (the frame of DEM runs); the other frames have no curvature in the friction",
        ),
        c => Ok(c.unwrap_or(true)),
    }
}

/// A raster domain given by its keys.
pub(super) fn domain(d: RawDomain) -> Res<Domain> {
    let (nx, ny) = raster_cells(d.cells.as_ref())?;
    let (x_min, x_max) = axis("domain.x_min", "domain.x_max", d.x_min, d.x_max, nx)?;
    let (y_min, y_max) = axis("domain.y_min", "domain.y_max", d.y_min, d.y_max, ny)?;
    let (coordinates, slope_deg) = frame(&d, Coordinates::Local)?;
    Ok(Domain {
        x_min,
        x_max,
        cells: nx,
        slope_deg,
        coordinates,
        curvature: curvature(&d, coordinates)?,
        plane: Some(Plane {
            y_min,
            y_max,
            ny,
            crs: Crs::unknown(),
            geotransform: None,
        }),
    })
}

/// The raster domain of the raster bed's own grid (`bed.b = { raster = … }` and no
/// grid key in `[domain]`).
pub(super) fn domain_of_raster(d: RawDomain, bed: &Profile) -> Res<Domain> {
    let r = bed.raster().expect("grid_from_bed saw a raster bed");
    let b = r.bbox();
    if r.nx.saturating_mul(r.ny) > MAX_CELLS as usize {
        return err(
            "bed.b",
            format!(
                "the raster has {} × {} cells, more than {MAX_CELLS}: coarsen it or give the domain's keys",
                r.nx, r.ny
            ),
        );
    }
    // A DEM's own grid: the terrain-following frame unless the scenario names another.
    let (coordinates, slope_deg) = frame(&d, Coordinates::BedNormal)?;
    Ok(Domain {
        x_min: b.x_min,
        x_max: b.x_max,
        cells: r.nx,
        slope_deg,
        coordinates,
        curvature: curvature(&d, coordinates)?,
        plane: Some(Plane {
            y_min: b.y_min,
            y_max: b.y_max,
            ny: r.ny,
            crs: r.crs.clone(),
            geotransform: Some([r.x_left, r.y_top, r.cell_size]),
        }),
    })
}

/// Keys that a raster domain cannot take, and `initial.v`, which a line cannot.
pub(super) fn raster_keys(
    domain: &Domain,
    model: &ModelSpec,
    initial: &RawInitial,
    submarine: bool,
) -> Res<()> {
    if domain.plane.is_none() {
        if initial.v.is_some() {
            return err(
                "initial.v",
                format!("a velocity along y needs a raster domain: {RASTER_HINT}"),
            );
        }
        return Ok(());
    }
    let why = "is not available on a raster domain (the 2-D models are the hydrostatic Savage–Hutter monolayer and the hydrostatic multilayer μ(I) model)";
    if model.kind != ModelKind::Granular {
        return err(
            "model.kind",
            format!("\"{}\" {why}; use \"granular\"", model.kind.name()),
        );
    }
    if model.layers > 1 && domain.coordinates == Coordinates::BedNormal {
        return err(
            "domain.coordinates",
            format!(
                "\"bed_normal\" (the default on a raster) is the frame of the monolayer; the multilayer model (model.layers = {}) is written in the local and Cartesian frames: use domain.coordinates = \"local\" or \"cartesian\", or model.layers = 1",
                model.layers
            ),
        );
    }
    if model.pressure != Pressure::Hydrostatic {
        return err("model.pressure", format!("non-hydrostatic pressure {why}"));
    }
    if submarine {
        return err("submarine", format!("the submarine model {why}"));
    }
    for (key, given) in [
        ("initial.w", initial.w.is_some()),
        ("initial.eta", initial.eta.is_some()),
        ("initial.phi", initial.phi.is_some()),
    ] {
        if given {
            return err(key, why);
        }
    }
    Ok(())
}

/// The multilayer model on a raster (`model.layers` > 1) takes the line's keys but
/// not those its raster stages do not implement: wall cells (nodata in the bed), the
/// sidewall friction and the C-MSM correction of a channel, the implicit viscosity,
/// friction zones; and its state must fit in memory. Each is refused by its key.
pub(super) fn layered_raster_fits(
    domain: &Domain,
    model: &ModelSpec,
    multilayer: &crate::model::granular::config::MultilayerSpec,
    zoned: bool,
    sampled: &Sampled,
) -> Res<()> {
    let n = model.layers;
    if domain.plane.is_none() || n == 1 {
        return Ok(());
    }
    let not_yet = |what: &str| {
        format!("{what} is not available for the multilayer model on a raster (model.layers = {n})")
    };
    let cells = domain.cell_count();
    if cells.saturating_mul(n) > MAX_CELLS as usize {
        return err(
            "model.layers",
            format!(
                "{n} layers × {cells} cells = {} unknowns per field is more than {MAX_CELLS} (the state would not fit in memory); use fewer layers or a coarser raster",
                cells.saturating_mul(n)
            ),
        );
    }
    let walls = sampled.wall.iter().filter(|&&w| w).count();
    if walls > 0 {
        return err(
            "bed.b",
            format!(
                "{}: the bed has {walls} cells without data (wall cells); fill them, crop the domain to the data, or use model.layers = 1",
                not_yet("a bed with nodata cells")
            ),
        );
    }
    if zoned {
        return err(
            "rheology.mu",
            format!(
                "{}; give one number, or use model.layers = 1",
                not_yet("a friction field (zones)")
            ),
        );
    }
    if multilayer.sidewall.is_some() {
        return err(
            "rheology.channel_width",
            format!(
                "{}; remove rheology.mu_w and rheology.channel_width",
                not_yet("sidewall friction (a channel's walls)")
            ),
        );
    }
    if multilayer.c_msm {
        return err(
            "rheology.c_msm",
            format!("{}; remove it", not_yet("the C-MSM correction")),
        );
    }
    if matches!(
        multilayer.viscosity,
        crate::numerics::viscous::ViscosityTime::Implicit { .. }
    ) {
        return err(
            "rheology.viscosity",
            format!(
                "{}; use \"lagged\" (the default) or \"frozen\"",
                not_yet("\"implicit\"")
            ),
        );
    }
    Ok(())
}

/// The profiles fit the domain: on a line none depends on y; on a raster every raster
/// profile covers the domain (and has its very grid when the domain is the bed's
/// grid), all rasters are in one CRS, which the domain records.
pub(super) fn profiles_fit(
    domain: &mut Domain,
    bed: &Profile,
    initial: &Initial,
    fields: &[Field],
    grid_from_bed: bool,
) -> Res<()> {
    let mut profiles: Vec<(String, Option<&Profile>)> = [
        ("bed.b", Some(bed)),
        ("initial.h", Some(&initial.h)),
        ("initial.u", Some(&initial.u)),
        ("initial.v", Some(&initial.v)),
        ("initial.w", Some(&initial.w)),
        ("initial.erodible_bed", Some(&initial.erodible_bed)),
        ("initial.eta", initial.eta.as_ref()),
        ("initial.phi", initial.phi.as_ref()),
    ]
    .into_iter()
    .map(|(key, p)| (key.to_string(), p))
    .collect();
    for (name, p) in fields {
        profiles.push((format!("rheology.{name}"), Some(p)));
    }
    let x_span = (domain.x_min, domain.x_max);
    let nx = domain.cells;
    let Some(plane) = domain.plane.as_mut() else {
        for (key, p) in &profiles {
            if p.is_some_and(Profile::uses_y) {
                return err(
                    key,
                    format!("depends on y (an expression in y or a raster file): {RASTER_HINT}"),
                );
            }
        }
        return Ok(());
    };
    let mut crs: Option<(&str, Crs)> = None;
    for (key, p) in &profiles {
        let key = key.as_str();
        let Some(r) = p.and_then(Profile::raster) else {
            continue;
        };
        let file = p
            .and_then(Profile::raster_path)
            .map_or_else(String::new, |f| format!(" '{}'", f.display()));
        let b = r.bbox();
        if grid_from_bed && (r.nx, r.ny) != (nx, plane.ny) {
            return err(
                key,
                format!(
                    "the raster{file} has {} × {} cells (ncols × nrows) but the domain, the grid of bed.b, has {} × {}",
                    r.nx, r.ny, nx, plane.ny
                ),
            );
        }
        let tol = 1e-9 * r.cell_size;
        let covers = b.x_min <= x_span.0 + tol
            && b.x_max >= x_span.1 - tol
            && b.y_min <= plane.y_min + tol
            && b.y_max >= plane.y_max - tol;
        if !covers {
            return err(
                key,
                format!(
                    "the raster{file} covers x in [{}, {}], y in [{}, {}] but the domain is x in [{}, {}], y in [{}, {}]",
                    num(b.x_min), num(b.x_max), num(b.y_min), num(b.y_max), num(x_span.0), num(x_span.1), num(plane.y_min), num(plane.y_max)
                ),
            );
        }
        if r.crs.is_geographic() {
            return err(key, geographic(&file, &r.crs));
        }
        match &crs {
            Some((first, c)) => c
                .check_same(first, &r.crs, key)
                .map_err(|e| ScenarioError::at(key, e.to_string()))?,
            None => crs = Some((key, r.crs.clone())),
        }
    }
    if let Some((_, c)) = crs {
        plane.crs = c;
    }
    Ok(())
}

/// The refusal of an input in a geographic CRS: its coordinates are degrees, which the
/// model would take as metres (cells of 10⁻⁴ "m" on a DEM of 10 m spacing).
pub(super) fn geographic(file: &str, crs: &Crs) -> String {
    format!(
        "the file{file} is in a geographic CRS ({crs}): its coordinates are degrees of longitude and latitude, not metres; reproject it to a projected CRS in metres first (e.g. gdalwarp -t_srs EPSG:<UTM zone>)"
    )
}

/// `[boundary]`: `left`/`right` on a line; on a raster `west` (or `left`), `east` (or
/// `right`), `south`, `north`, each `"wall"` (the default) or `"outflow"`.
pub(super) fn boundary(b: RawBoundary, domain: &Domain) -> Res<Boundaries> {
    if domain.plane.is_none() {
        for (key, given) in [
            ("boundary.west", b.west.is_some()),
            ("boundary.east", b.east.is_some()),
            ("boundary.south", b.south.is_some()),
            ("boundary.north", b.north.is_some()),
        ] {
            if given {
                return err(
                    key,
                    format!("a side of a raster domain; a line has boundary.left and boundary.right ({RASTER_HINT})"),
                );
            }
        }
        return line_boundary(b);
    }
    let kinds = [
        ("wall", BoundaryKind::Wall),
        ("outflow", BoundaryKind::Outflow),
    ];
    let side = |key: &str, alias: Option<(&str, &Option<String>)>, v: &Option<String>| {
        let (key, v) = match (alias, v) {
            (Some((alias, Some(_))), Some(_)) => {
                return err(
                    key,
                    format!("give either {key} or {alias} (the same side), not both"),
                )
            }
            (Some((alias, a @ Some(_))), None) => (alias, a),
            _ => (key, v),
        };
        choice(key, v.as_deref(), BoundaryKind::Wall, &kinds)
    };
    Ok(Boundaries {
        left: side("boundary.west", Some(("boundary.left", &b.left)), &b.west)?,
        right: side("boundary.east", Some(("boundary.right", &b.right)), &b.east)?,
        south: side("boundary.south", None, &b.south)?,
        north: side("boundary.north", None, &b.north)?,
    })
}

/// `output.gauges`: positions `[x, …]` on a line, points `[[x, y], …]` inside a
/// raster domain, each at most once. Returns the x and (raster only) the y.
pub(super) fn gauges(v: Option<&toml::Value>, domain: &Domain) -> Res<(Vec<f64>, Vec<f64>)> {
    const KEY: &str = "output.gauges";
    let Some(v) = v else {
        return Ok((Vec::new(), Vec::new()));
    };
    let number = |v: &toml::Value| match v {
        toml::Value::Integer(i) => Some(*i as f64),
        toml::Value::Float(f) => Some(*f),
        _ => None,
    };
    let toml::Value::Array(items) = v else {
        return err(
            KEY,
            format!(
                "wrong type: expected an array of positions, found {}",
                describe(v)
            ),
        );
    };
    let Some(plane) = &domain.plane else {
        let xs: Option<Vec<f64>> = items.iter().map(number).collect();
        let Some(xs) = xs else {
            return err(
                KEY,
                "wrong type: expected an array of numbers (positions x in m)",
            );
        };
        return Ok((line_gauges(&xs, domain)?, Vec::new()));
    };
    let (mut xs, mut ys) = (Vec::new(), Vec::new());
    for (k, item) in items.iter().enumerate() {
        let point = match item {
            toml::Value::Array(p) if p.len() == 2 => number(&p[0]).zip(number(&p[1])),
            _ => None,
        };
        let Some((x, y)) = point else {
            return err(
                KEY,
                format!(
                    "gauge {} must be a point [x, y] (two numbers) on a raster domain",
                    k + 1
                ),
            );
        };
        if !(x.is_finite() && y.is_finite()) {
            return err(
                KEY,
                format!("gauge {} must be finite, got [{x}, {y}]", k + 1),
            );
        }
        let inside =
            (domain.x_min..=domain.x_max).contains(&x) && (plane.y_min..=plane.y_max).contains(&y);
        if !inside {
            return err(
                KEY,
                format!(
                    "gauge {} at [{x}, {y}] lies outside the domain [{}, {}] × [{}, {}]",
                    k + 1,
                    domain.x_min,
                    domain.x_max,
                    plane.y_min,
                    plane.y_max
                ),
            );
        }
        if xs.iter().zip(&ys).any(|(&a, &b)| a == x && b == y) {
            return err(KEY, format!("gauge {} at [{x}, {y}] is given twice", k + 1));
        }
        xs.push(x);
        ys.push(y);
    }
    Ok((xs, ys))
}

/// Refuses a gauge of a raster domain that reads a wall cell (nodata of the bed): its
/// value is interpolated bilinearly between the four centres around it
/// (`Raster2d::locate`), and a wall cell has no surface to record.
pub(super) fn gauges_off_walls(output: &OutputSpec, domain: &Domain, sampled: &Sampled) -> Res<()> {
    let Some(plane) = &domain.plane else {
        return Ok(());
    };
    if sampled.wall.is_empty() {
        return Ok(());
    }
    let (nx, ny) = (domain.cells, plane.ny);
    let dx = (domain.x_max - domain.x_min) / nx as f64;
    let dy = (plane.y_max - plane.y_min) / ny as f64;
    let centre = crate::grid::line::cell_centre;
    let xs: Vec<f64> = (0..nx).map(|i| centre(domain.x_min, dx, i)).collect();
    let ys: Vec<f64> = (0..ny).map(|j| centre(plane.y_min, dy, j)).collect();
    for (k, (&x, &y)) in output.gauges.iter().zip(&output.gauges_y).enumerate() {
        let (i, wx) = crate::grid::line::interpolate(&xs, dx, x);
        let (j, wy) = crate::grid::line::interpolate(&ys, dy, y);
        for (dj, fy) in [(0, 1.0 - wy), (1, wy)] {
            for (di, fx) in [(0, 1.0 - wx), (1, wx)] {
                let cell = (j + dj) * nx + i + di;
                if fx * fy != 0.0 && sampled.wall[cell] {
                    return err(
                        "output.gauges",
                        format!(
                            "gauge {} at [{x}, {y}] reads the wall (nodata) cell centred at ({}, {}) of bed.b; move it onto cells with data",
                            k + 1,
                            xs[i + di],
                            ys[j + dj]
                        ),
                    );
                }
            }
        }
    }
    Ok(())
}

/// Refuses a raster domain on which every cell is a wall (the raster bed has no data
/// under the domain).
pub(super) fn some_cell_has_bed(domain: &Domain, sampled: &Sampled, bed: &Profile) -> Res<()> {
    if !sampled.wall.is_empty() && sampled.wall.iter().all(|&w| w) {
        let file = bed
            .raster_path()
            .map_or_else(String::new, |p| format!(" '{}'", p.display()));
        return err(
            "bed.b",
            format!(
                "the raster{file} has no data (nodata) under any of the domain's {} cells",
                domain.cell_count()
            ),
        );
    }
    Ok(())
}

/// Checks the sampled profiles of a raster domain: finite bed (but on wall cells,
/// where a raster bed has no data), finite non-negative
/// thickness, finite velocities; the first offending centre is reported.
pub(super) fn check_profiles(
    domain: &Domain,
    sampled: &Sampled,
    bed: &Profile,
    initial: &Initial,
) -> Res<()> {
    let plane = domain.plane.as_ref().expect("a raster domain");
    let centres = raster_centres(domain, plane);
    let not_finite = |key: &str, p: &Profile, i: usize, b: f64| -> ScenarioError {
        let (x, y) = centres[i];
        let message = match p.try_eval_xy(x, y, b) {
            Err(m) => format!("{m} at (x, y) = ({x}, {y})"),
            Ok(v) => format!("evaluates to {v} at (x, y) = ({x}, {y})"),
        };
        ScenarioError::at(key, message)
    };
    let b = &sampled.b;
    let wall = |i: usize| !sampled.wall.is_empty() && sampled.wall[i];
    if let Some(i) = (0..b.len()).position(|i| !b[i].is_finite() && !wall(i)) {
        return Err(not_finite("bed.b", bed, i, 0.0));
    }
    if let Some(i) = sampled.h.iter().position(|h| !(h.is_finite() && *h >= 0.0)) {
        let (x, y) = centres[i];
        return match initial.h.try_eval_xy(x, y, b[i]) {
            Ok(h) if h.is_finite() => err(
                "initial.h",
                format!("negative thickness {h} at (x, y) = ({x}, {y})"),
            ),
            _ => Err(not_finite("initial.h", &initial.h, i, b[i])),
        };
    }
    if let Some(i) = sampled
        .h_bed
        .iter()
        .position(|h| !(h.is_finite() && *h >= 0.0))
    {
        let (x, y) = centres[i];
        return match initial.erodible_bed.try_eval_xy(x, y, b[i]) {
            Ok(h) if h.is_finite() => err(
                "initial.erodible_bed",
                format!(
                    "{} gives a negative thickness {h} at (x, y) = ({x}, {y})",
                    initial.erodible_bed.describe()
                ),
            ),
            _ => Err(not_finite(
                "initial.erodible_bed",
                &initial.erodible_bed,
                i,
                b[i],
            )),
        };
    }
    for (key, p, values) in [
        ("initial.u", &initial.u, &sampled.u),
        ("initial.v", &initial.v, &sampled.v),
    ] {
        if let Some(i) = values.iter().position(|v| !v.is_finite()) {
            return Err(not_finite(key, p, i, b[i]));
        }
    }
    // Physical magnitudes, as on a line (the bounds and their reasons: `check.rs`).
    for (key, values, max, unit, why) in [
        ("bed.b", b, MAX_ELEVATION, "m", ELEVATION_WHY),
        ("initial.h", &sampled.h, MAX_THICKNESS, "m", THICKNESS_WHY),
        (
            "initial.erodible_bed",
            &sampled.h_bed,
            MAX_THICKNESS,
            "m",
            THICKNESS_WHY,
        ),
        ("initial.u", &sampled.u, MAX_SPEED, "m/s", SPEED_WHY),
        ("initial.v", &sampled.v, MAX_SPEED, "m/s", SPEED_WHY),
    ] {
        if let Some(i) = values.iter().position(|v| v.abs() > max) {
            let (x, y) = centres[i];
            magnitude_at_most(key, values[i], max, unit, why).map_err(|e| {
                ScenarioError::at(key, format!("{} at (x, y) = ({x}, {y})", e.message()))
            })?;
        }
    }
    Ok(())
}
