//! Loading: text → (overrides) → raw serde mirror → checked [`Scenario`].
//!
//! Every check names its dotted key; the line is added afterwards by the
//! [`Locator`](super::document::Locator) from the key, so this file never deals with spans.

use crate::grid::line::cell_centre;
use std::path::{Path, PathBuf};

use rayon::prelude::*;

mod check;
mod dilatant;
mod granular;
mod path;
mod plane;
mod release;
mod resample;
mod submarine;
mod zones;

use crate::output::budget::{size, OUTPUT_LIMIT};

use super::document::{line_of, serde_error, syntax_error, KeyIndex, Locator};
use super::error::ScenarioError;
use super::overrides::Override;
use super::profile::{read_bounded, Profile};
use super::raw::{
    RawBoundary, RawDomain, RawInitial, RawMaterial, RawNumerics, RawOutput, RawScenario, RawTime,
};
use super::{
    Boundaries, BoundaryKind, Coordinates, Domain, Initial, Limiter, Material, ModelSpec, Numerics,
    OutputSpec, Pressure, Sampled, Scenario, TimeSpec,
};
use check::*;
use dilatant::{check_fraction, dilatancy};
use granular::{model, multilayer, rheology, ViscousKeys};

/// The tables of a scenario file.
const SECTIONS: [&str; 12] = [
    "domain",
    "bed",
    "material",
    "rheology",
    "model",
    "initial",
    "boundary",
    "time",
    "output",
    "submarine",
    "dilatancy",
    "numerics",
];

/// Largest accepted `domain.cells`.
pub(crate) const MAX_CELLS: i64 = 10_000_000;
/// Largest accepted scenario file (bytes), so that `granflow check /dev/zero` ends.
pub(crate) const MAX_SCENARIO_BYTES: u64 = 64 << 20;
/// Smallest Δx relative to the largest |x| of the domain: Δx is then known to about
/// 2e-7 of itself (f64 round-off 2.2e-16 |x|).
pub(crate) const MIN_RELATIVE_DX: f64 = 1e-9;
/// Largest number of snapshots a run may write (t_end / output.every).
pub(crate) const MAX_SNAPSHOTS: f64 = 100_000.0;
/// Largest accepted `model.layers`.
pub(crate) const MAX_LAYERS: i64 = 1000;
/// Largest memory (GiB) of the exact pressure solver of the multilayer non-hydrostatic
/// model: the band of its Cholesky factor, (cells + 1) N (N + 2) values.
const MAX_NH_SOLVER_GIB: f64 = 4.0;

/// Reads and validates a scenario file. Tables are resolved against the file's directory
/// and the default output file is `<file stem>.h5`.
pub fn load_file(path: &Path, overrides: &[String]) -> Result<Scenario, ScenarioError> {
    load_file_within(path, overrides, Some(OUTPUT_LIMIT))
}

/// [`load_file`] refusing a run that would write more than `output_limit` bytes
/// (`None`: any size; `--force`), naming the output key responsible.
pub fn load_file_within(
    path: &Path,
    overrides: &[String],
    output_limit: Option<u64>,
) -> Result<Scenario, ScenarioError> {
    let text = read_bounded(path, MAX_SCENARIO_BYTES).map_err(|e| {
        ScenarioError::new(format!(
            "cannot read scenario file '{}': {e}",
            path.display()
        ))
    })?;
    let base_dir = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    };
    let stem = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .filter(|s| !s.is_empty())
        .unwrap_or_else(|| "granflow".to_owned());
    load(
        &text,
        &base_dir,
        overrides,
        &format!("{stem}.h5"),
        output_limit,
    )
}

/// Validates scenario text; tables are resolved against `base_dir` and the default output
/// file is `granflow.h5`.
pub fn load_str(
    text: &str,
    base_dir: &Path,
    overrides: &[String],
) -> Result<Scenario, ScenarioError> {
    load(text, base_dir, overrides, "granflow.h5", Some(OUTPUT_LIMIT))
}

/// [`load_str`] with the output limit `output_limit` (see [`load_file_within`]).
pub fn load_str_within(
    text: &str,
    base_dir: &Path,
    overrides: &[String],
    output_limit: Option<u64>,
) -> Result<Scenario, ScenarioError> {
    load(text, base_dir, overrides, "granflow.h5", output_limit)
}

fn load(
    text: &str,
    base_dir: &Path,
    overrides: &[String],
    default_output: &str,
    output_limit: Option<u64>,
) -> Result<Scenario, ScenarioError> {
    let doc = toml_edit::Document::parse(text).map_err(|e| syntax_error(text, &e))?;
    let sets = overrides
        .iter()
        .map(|s| Override::parse(s))
        .collect::<Result<Vec<_>, _>>()?;
    let locator = Locator {
        file: KeyIndex::build(text, &doc),
        overridden: sets.iter().map(|s| s.key.clone()).collect(),
    };
    // `[[domain]]` would reach serde as a sequence read field by field ("expected a
    // number, found a table"): name the mistake instead.
    if let Some((name, _)) = doc
        .as_table()
        .iter()
        .find(|(name, item)| item.is_array_of_tables() && SECTIONS.contains(name))
    {
        let e = ScenarioError::at(
            name,
            format!("must be a table [{name}], not an array of tables [[{name}]]"),
        );
        return Err(locator.locate(e));
    }
    // The document parsed above is deserialised as it is: the text is parsed once
    // (again only to locate an error in a document edited by overrides).
    let (parsed, source) = if sets.is_empty() {
        (
            <RawScenario as serde::Deserialize>::deserialize(toml_edit::de::Deserializer::from(
                doc,
            )),
            text.to_owned(),
        )
    } else {
        let mut edited = doc.into_mut();
        for s in &sets {
            s.apply(&mut edited)?;
        }
        let source = edited.to_string();
        (toml_edit::de::from_document::<RawScenario>(edited), source)
    };
    let raw = match parsed {
        Ok(raw) => raw,
        Err(e) => {
            let err = if sets.is_empty() {
                let err = serde_error(&e, &locator.file);
                match (err.key(), e.span()) {
                    (None, Some(span)) => {
                        let line = line_of(text, span.start);
                        err.with_line(Some(line))
                    }
                    _ => err,
                }
            } else {
                // The edited document has no spans: deserialise its text for them.
                match (
                    toml_edit::Document::parse(source.as_str()),
                    toml_edit::de::from_str::<RawScenario>(&source),
                ) {
                    (Ok(edited), Err(e)) => serde_error(&e, &KeyIndex::build(&source, &edited)),
                    _ => ScenarioError::new(e.message().trim().to_owned()),
                }
            };
            return Err(locator.locate(err));
        }
    };
    // Switching the law on the command line (or as a sweep axis) leaves the keys of the
    // file's law behind; they are ignored with a note instead of refused.
    let law_overridden = sets.iter().any(|s| s.key == "rheology.law");
    validate(raw, source, base_dir, default_output, law_overridden)
        .and_then(|scn| within_output_limit(scn, output_limit))
        .map_err(|e| locator.locate(e))
}

// ---------------------------------------------------------------------------------------
// Sections

fn validate(
    raw: RawScenario,
    source_toml: String,
    base_dir: &Path,
    default_output: &str,
    law_overridden: bool,
) -> Res<Scenario> {
    let mut notes = Vec::new();
    let raw_domain = section("domain", raw.domain)?;
    let raw_bed = raw.bed.and_then(|b| b.b);
    let read_bed = |v: &Option<toml::Value>| match v {
        Some(v) => Profile::from_toml("bed.b", v, base_dir, false),
        None => Ok(Profile::constant(0.0)),
    };
    // A domain without its grid keys takes the grid of a raster bed (read first then).
    let from_bed = plane::grid_from_bed(&raw_domain, raw_bed.as_ref());
    let resample = resample::keys(&raw_domain, from_bed)?;
    let mut original_grid = None;
    let (mut domain, bed) = if from_bed {
        let mut bed = read_bed(&raw_bed)?;
        if let Some(r) = &resample {
            let (resampled, original) = r.bed(&bed, &mut notes)?;
            bed = resampled;
            original_grid = Some(original);
        }
        (plane::domain_of_raster(raw_domain, &bed)?, bed)
    } else {
        let domain = domain(raw_domain)?;
        (domain, read_bed(&raw_bed)?)
    };
    let material = material(raw.material.unwrap_or_default())?;
    let mut raw_rheology = section("rheology", raw.rheology)?;
    let fields = zones::take(&mut raw_rheology, base_dir, &domain)?;
    let mut friction = rheology(&raw_rheology, law_overridden, &mut notes)?;
    let mut fields = zones::used(fields, &friction, &domain)?;
    let raw_model = raw.model.unwrap_or_default();
    let model = model(&raw_model)?;
    if domain.cells.saturating_mul(model.layers) > MAX_CELLS as usize {
        return err(
            "model.layers",
            format!(
                "{} layers × {} cells = {} unknowns per field is more than {MAX_CELLS} (the state would not fit in memory); use fewer layers or domain.cells",
                model.layers,
                domain.cells,
                domain.cells.saturating_mul(model.layers)
            ),
        );
    }
    nonhydrostatic_solver_fits(&domain, &model)?;
    bed_normal_line_fits(&domain, &model)?;
    if matches!(friction, super::FrictionLaw::Voellmy { .. }) && model.layers > 1 {
        // Its drag g|u|²/ξ is a basal law of the depth-averaged flow; inside a column
        // of layers it has no local form.
        return err(
            "rheology.law",
            format!(
                "\"voellmy\" is a basal law of the depth-averaged (monolayer) flow; \
                 model.layers is {}: use model.layers = 1, or law = \"coulomb\" or \"mu_i\"",
                model.layers
            ),
        );
    }
    let mut raw_initial = section("initial", raw.initial)?;
    let raw_w = raw_initial.w.is_some();
    plane::raster_keys(&domain, &model, &raw_initial, raw.submarine.is_some())?;
    let raster = domain.plane.is_some();
    let release_keys = release::take(("initial.h", &mut raw_initial.h), raster, base_dir)?;
    let erodible_keys = release::take(
        ("initial.erodible_bed", &mut raw_initial.erodible_bed),
        raster,
        base_dir,
    )?;
    let mut initial = initial(raw_initial, base_dir)?;
    if let (Some(r), Some(original)) = (&resample, &original_grid) {
        r.profile("initial.h", &mut initial.h, original)?;
        r.profile("initial.u", &mut initial.u, original)?;
        r.profile("initial.v", &mut initial.v, original)?;
        r.profile("initial.erodible_bed", &mut initial.erodible_bed, original)?;
        for (name, p) in &mut fields {
            r.profile(&format!("rheology.{name}"), p, original)?;
        }
    }
    plane::profiles_fit(&mut domain, &bed, &initial, &fields, from_bed)?;
    // Sampled once here; the checks below look at these values and setup uses them.
    let mut sampled = Sampled::of(&domain, &bed, &initial);
    if domain.plane.is_some() {
        plane::some_cell_has_bed(&domain, &sampled, &bed)?;
    }
    let friction_zones = zones::sample(&fields, &mut friction, &domain, &sampled)?;
    if let Some(keys) = &release_keys {
        release::adopt_crs(keys, &mut domain, &bed, &mut notes);
    }
    let release = match release_keys {
        Some(keys) => Some(release::rasterise(
            keys,
            &domain,
            &bed,
            &mut sampled,
            &mut initial.h,
        )?),
        None => None,
    };
    if let Some(keys) = erodible_keys {
        let bed_polygons =
            release::rasterise(keys, &domain, &bed, &mut sampled, &mut initial.erodible_bed)?;
        notes.push(format!(
            "initial.erodible_bed: {}",
            bed_polygons.describe().replace("released", "erodible")
        ));
    }
    let submarine = submarine::submarine(
        raw.submarine,
        &model,
        &domain,
        &friction,
        &initial,
        raw_w,
        &sampled,
    )?;
    let boundary = plane::boundary(raw.boundary.unwrap_or_default(), &domain)?;
    let time = time(section("time", raw.time)?)?;
    if time.film_thickness > 0.0 && domain.plane.is_none() {
        return err(
            "time.film_thickness",
            "applies to raster (2-D) runs only: a line counts every cell for its kinetic energy",
        );
    }
    let numerics = numerics(raw.numerics.unwrap_or_default(), &model, &domain)?;
    let raw_output = raw.output.unwrap_or_default();
    let mut output = output(&raw_output, &time, &domain, default_output)?;
    output.path = path::spec(raw_output.path.as_ref(), &domain, base_dir)?;
    plane::gauges_off_walls(&output, &domain, &sampled)?;
    let dilatancy = dilatancy(
        raw.dilatancy.as_ref(),
        &raw_rheology,
        &friction,
        &material,
        &model,
        &initial,
        &time,
    )?;
    if numerics.order == 2
        && dilatancy
            .is_some_and(|d| d.options.scheme != crate::numerics::dilatant::step::SchemeKind::Split)
    {
        return err(
            "numerics.order",
            "order 2 of the dilatant model is written for dilatancy.scheme = \"split\" (the default); the Appendix B scheme has order 1 only: use numerics.order = 1",
        );
    }
    let mut viscous_keys = ViscousKeys::of(&raw_rheology);
    if dilatancy.is_some() {
        // The wall keys belong to the dilatant law (Bouchut et al. 2021, eq. 4.1).
        viscous_keys.mu_w = None;
        viscous_keys.mu_w_deg = None;
        viscous_keys.channel_width = None;
    }
    let multilayer = multilayer(
        viscous_keys,
        raw_model.layer_fractions.clone(),
        raw_output.static_threshold,
        model.layers,
    )?;
    plane::layered_raster_fits(
        &domain,
        &model,
        &multilayer,
        friction_zones.is_some(),
        &sampled,
    )?;
    if domain.plane.is_some() {
        plane::check_profiles(&domain, &sampled, &bed, &initial)?;
    } else {
        check_profiles(&domain, &sampled, &bed, &initial, model.pressure)?;
    }
    if let (Some(phi), Some(values)) = (&initial.phi, &sampled.phi) {
        check_fraction(&domain, &sampled.b, phi, values)?;
    }
    Ok(Scenario {
        notes,
        source_toml,
        base_dir: base_dir.to_path_buf(),
        domain,
        bed,
        material,
        friction,
        friction_zones,
        model,
        multilayer,
        dilatancy,
        initial,
        boundary,
        time,
        output,
        submarine,
        sampled,
        release,
        numerics,
    })
}

/// Refuses a scenario whose output keys make its run write more than `limit` bytes.
fn within_output_limit(scn: Scenario, limit: Option<u64>) -> Res<Scenario> {
    let estimate = scn.output_estimate();
    match limit {
        Some(limit) if estimate.bytes() > limit as f64 => err(
            estimate.key(),
            format!(
                "the run would write {}, more than the limit of {}: use a larger interval (or fewer cells), or pass --force to lift the limit",
                estimate.describe(),
                size(limit as f64)
            ),
        ),
        _ => Ok(scn),
    }
}

/// The multilayer non-hydrostatic model stores the band of its pressure matrix's
/// Cholesky factor; refuse sizes that cannot fit rather than fail allocating.
fn nonhydrostatic_solver_fits(domain: &Domain, model: &ModelSpec) -> Res<()> {
    if model.pressure != Pressure::NonHydrostatic || model.layers == 1 {
        return Ok(());
    }
    let n = model.layers as f64;
    let gib = (domain.cells as f64 + 1.0) * n * (n + 2.0) * 8.0 / (1u64 << 30) as f64;
    if gib > MAX_NH_SOLVER_GIB {
        return err(
            "model.layers",
            format!(
                "{} layers on {} cells need {gib:.1} GiB for the non-hydrostatic pressure solver (at most {MAX_NH_SOLVER_GIB} GiB); use fewer layers or cells",
                model.layers, domain.cells
            ),
        );
    }
    Ok(())
}

fn domain(d: RawDomain) -> Res<Domain> {
    if plane::is_raster(&d) {
        return plane::domain(d);
    }
    let cells = plane::line_cells(d.cells.as_ref())?;
    let x_min = finite("domain.x_min", required("domain.x_min", d.x_min)?)?;
    let x_max = finite("domain.x_max", required("domain.x_max", d.x_max)?)?;
    if x_max <= x_min {
        return err(
            "domain.x_max",
            format!(
                "must be greater than domain.x_min = {x_min}, got {}",
                num(x_max)
            ),
        );
    }
    if !(x_max - x_min).is_finite() {
        return err("domain.x_max", "domain length x_max - x_min overflows");
    }
    let cells = int_in(
        "domain.cells",
        required("domain.cells", cells)?,
        1,
        MAX_CELLS,
    )?;
    // Cell centres x_min + (i + ½)Δx must be distinct and their spacing accurate: a Δx
    // at the round-off of |x| makes neighbouring centres equal (or Δx wrong by whole
    // ulps), and every flux difference over them meaningless.
    let dx = (x_max - x_min) / cells as f64;
    let scale = x_min.abs().max(x_max.abs());
    if dx < MIN_RELATIVE_DX * scale {
        return err(
            "domain.cells",
            format!(
                "cells of Δx = {dx:e} m are at the round-off of the coordinates (|x| up to {scale:e} m): cell centres would not be distinct; need Δx ≥ {MIN_RELATIVE_DX:e}·max(|x_min|, |x_max|), so use fewer cells or shift the domain towards 0"
            ),
        );
    }
    let (coordinates, slope_deg) = frame(&d, Coordinates::Local)?;
    Ok(Domain {
        x_min,
        x_max,
        cells,
        slope_deg,
        coordinates,
        curvature: plane::curvature(&d, coordinates)?,
        plane: None,
    })
}

/// The bed-normal frame on a line exists for the monolayer hydrostatic granular model
/// (the 1-D reduction of the raster's system, docs/numerics.md); the other models
/// and layer counts are written in the local or Cartesian frame and refuse it by name.
fn bed_normal_line_fits(domain: &Domain, model: &ModelSpec) -> Res<()> {
    if domain.plane.is_some() || domain.coordinates != Coordinates::BedNormal {
        return Ok(());
    }
    let refuse = |what: String| {
        err(
            "domain.coordinates",
            format!(
                "\"bed_normal\" on a line is the frame of the monolayer hydrostatic granular model; {what}: use \"local\" or \"cartesian\""
            ),
        )
    };
    if model.kind != crate::model::ModelKind::Granular {
        return refuse(format!("model.kind is \"{}\"", model.kind.name()));
    }
    if model.layers != 1 {
        return refuse(format!("model.layers is {}", model.layers));
    }
    if model.pressure != Pressure::Hydrostatic {
        return refuse("model.pressure is \"nonhydrostatic\"".to_string());
    }
    Ok(())
}

/// `domain.coordinates` (`default` where it is not given) and `domain.slope_deg`.
fn frame(d: &RawDomain, default: Coordinates) -> Res<(Coordinates, f64)> {
    let coordinates = choice(
        "domain.coordinates",
        d.coordinates.as_deref(),
        default,
        &[
            ("local", Coordinates::Local),
            ("cartesian", Coordinates::Cartesian),
            ("bed_normal", Coordinates::BedNormal),
        ],
    )?;
    let slope_deg = finite("domain.slope_deg", d.slope_deg.unwrap_or(0.0))?;
    if slope_deg <= -90.0 || slope_deg >= 90.0 {
        return err(
            "domain.slope_deg",
            format!(
                "must be strictly between -90 and 90 degrees, got {}",
                num(slope_deg)
            ),
        );
    }
    if coordinates != Coordinates::Local && slope_deg != 0.0 {
        let name = if coordinates == Coordinates::Cartesian {
            "cartesian"
        } else {
            "bed_normal"
        };
        return err(
            "domain.slope_deg",
            format!(
                "must be 0 with domain.coordinates = \"{name}\" (put the slope in bed.b), got {}",
                num(slope_deg)
            ),
        );
    }
    Ok((coordinates, slope_deg))
}

fn material(m: RawMaterial) -> Res<Material> {
    let rho_s = positive("material.rho_s", m.rho_s.unwrap_or(2500.0))?;
    let phi = positive("material.phi", m.phi.unwrap_or(0.62))?;
    if phi > 1.0 {
        return err(
            "material.phi",
            format!("must be in (0, 1], got {}", num(phi)),
        );
    }
    let d_s = positive("material.d_s", m.d_s.unwrap_or(0.7e-3))?;
    Ok(Material { rho_s, phi, d_s })
}

fn initial(i: RawInitial, base_dir: &Path) -> Res<Initial> {
    let h = Profile::from_toml("initial.h", &required("initial.h", i.h)?, base_dir, true)?;
    let u = match i.u {
        Some(v) => Profile::from_toml("initial.u", &v, base_dir, true)?,
        None => Profile::constant(0.0),
    };
    let v = match i.v {
        Some(v) => Profile::from_toml("initial.v", &v, base_dir, true)?,
        None => Profile::constant(0.0),
    };
    let w = match i.w {
        Some(v) => Profile::from_toml("initial.w", &v, base_dir, true)?,
        None => Profile::constant(0.0),
    };
    let erodible_bed = match i.erodible_bed {
        Some(v) => Profile::from_toml("initial.erodible_bed", &v, base_dir, true)?,
        None => Profile::constant(0.0),
    };
    if let Some(h_i) = erodible_bed.as_constant() {
        non_negative("initial.erodible_bed", h_i)?;
        magnitude_at_most(
            "initial.erodible_bed",
            h_i,
            MAX_THICKNESS,
            "m",
            THICKNESS_WHY,
        )?;
    }
    let eta = match i.eta {
        Some(v) => Some(Profile::from_toml("initial.eta", &v, base_dir, true)?),
        None => None,
    };
    let phi = match i.phi {
        Some(v) => Some(Profile::from_toml("initial.phi", &v, base_dir, true)?),
        None => None,
    };
    Ok(Initial {
        h,
        u,
        v,
        w,
        erodible_bed,
        eta,
        phi,
    })
}

fn line_boundary(b: RawBoundary) -> Res<Boundaries> {
    let kinds = [
        ("wall", BoundaryKind::Wall),
        ("outflow", BoundaryKind::Outflow),
    ];
    Ok(Boundaries {
        left: choice(
            "boundary.left",
            b.left.as_deref(),
            BoundaryKind::Wall,
            &kinds,
        )?,
        right: choice(
            "boundary.right",
            b.right.as_deref(),
            BoundaryKind::Wall,
            &kinds,
        )?,
        south: BoundaryKind::Wall,
        north: BoundaryKind::Wall,
    })
}

/// `[numerics]`: order 2 exists for the hydrostatic granular model: on a line with any
/// number of layers (local and Cartesian frames), on a raster with one layer in all
/// three frames (docs/numerics.md, "Second order"); any other model refuses it by name.
fn numerics(n: RawNumerics, model: &ModelSpec, domain: &Domain) -> Res<Numerics> {
    let order = int_in("numerics.order", n.order.unwrap_or(1), 1, 2)? as u8;
    let limiters = [
        ("minmod", Limiter::Minmod),
        ("van_leer", Limiter::VanLeer),
        ("mc", Limiter::Mc),
    ];
    let limiter = choice(
        "numerics.limiter",
        n.limiter.as_deref(),
        Numerics::default().limiter,
        &limiters,
    )?;
    if order == 2 {
        let refuse = |what: &str| {
            err(
                "numerics.order",
                format!(
                    "order 2 is implemented for the granular model (hydrostatic: any model.layers on a line, one layer on a raster; non-hydrostatic: one layer on a line) and the dilatant model's split scheme; {what}: use numerics.order = 1"
                ),
            )
        };
        if model.kind == crate::model::ModelKind::Submarine {
            return err(
                "numerics.order",
                "order 2 is not available for model.kind = \"submarine\": its two-layer face kernel carries the layers' non-conservative coupling and the curved line's cos θ terms, which a reconstruction would also have to integrate inside every cell, and its Coulomb rule holds a deposit because τ_crit cancels each face's static part between cell means exactly; use numerics.order = 1",
            );
        }
        if model.pressure == Pressure::NonHydrostatic && domain.plane.is_some() {
            return refuse("model.pressure is \"nonhydrostatic\" on a raster");
        }
        if model.pressure == Pressure::NonHydrostatic && model.layers > 1 {
            return refuse(&format!(
                "model.pressure is \"nonhydrostatic\" with model.layers = {} (order 2 is written for the non-hydrostatic monolayer)",
                model.layers
            ));
        }
        if model.layers > 1 && domain.plane.is_some() {
            return refuse(&format!("model.layers is {} on a raster", model.layers));
        }
        if domain.plane.is_none() && domain.coordinates == Coordinates::BedNormal {
            return refuse("domain.coordinates is \"bed_normal\" on a line (order 2 is written for the local and Cartesian frames of a line, and for every frame of a raster)");
        }
    } else if n.limiter.is_some() {
        return err(
            "numerics.limiter",
            "the limiter belongs to the second-order reconstruction: set numerics.order = 2",
        );
    }
    Ok(Numerics { order, limiter })
}

fn time(t: RawTime) -> Res<TimeSpec> {
    let t_end = positive("time.t_end", required("time.t_end", t.t_end)?)?;
    let cfl = positive("time.cfl", t.cfl.unwrap_or(0.5))?;
    if cfl > 1.0 {
        return err("time.cfl", format!("must be in (0, 1], got {}", num(cfl)));
    }
    let settle_fraction = positive("time.settle_fraction", t.settle_fraction.unwrap_or(1e-6))?;
    if settle_fraction >= 1.0 {
        return err(
            "time.settle_fraction",
            format!(
                "must be in (0, 1) (a fraction of the peak kinetic energy), got {}",
                num(settle_fraction)
            ),
        );
    }
    Ok(TimeSpec {
        t_end,
        cfl,
        stop_at_rest: t.stop_at_rest.unwrap_or(false),
        settle_fraction,
        stop_when_settled: t.stop_when_settled.unwrap_or(false),
        film_thickness: non_negative("time.film_thickness", t.film_thickness.unwrap_or(0.0))?,
    })
}

fn output(o: &RawOutput, time: &TimeSpec, domain: &Domain, default_file: &str) -> Res<OutputSpec> {
    let file = o.file.clone().unwrap_or_else(|| default_file.to_owned());
    if file.trim().is_empty() {
        return err("output.file", "must not be empty");
    }
    let every = positive("output.every", o.every.unwrap_or(time.t_end / 20.0))?;
    let snapshots = time.t_end / every;
    if snapshots > MAX_SNAPSHOTS {
        return err(
            "output.every",
            format!(
                "{every:e} s gives {snapshots:.3e} snapshots over time.t_end = {} s (at most {MAX_SNAPSHOTS}): each snapshot is a full frame on disk and the time step is shortened to land on it; use a larger interval",
                time.t_end
            ),
        );
    }
    let front_threshold = positive("output.front_threshold", o.front_threshold.unwrap_or(1e-3))?;
    let (gauges, gauges_y) = plane::gauges(o.gauges.as_ref(), domain)?;
    let gauge_every = match o.gauge_every {
        Some(_) if gauges.is_empty() => {
            return err(
                "output.gauge_every",
                "needs output.gauges (no gauge is set)",
            )
        }
        Some(v) => Some(positive("output.gauge_every", v)?),
        None => None,
    };
    Ok(OutputSpec {
        file: PathBuf::from(file),
        every,
        front_threshold,
        gauges,
        gauges_y,
        gauge_every,
        path: None,
    })
}

/// `output.gauges`: finite positions inside [x_min, x_max], each at most once.
fn line_gauges(xs: &[f64], domain: &Domain) -> Res<Vec<f64>> {
    const KEY: &str = "output.gauges";
    for (k, &x) in xs.iter().enumerate() {
        if !x.is_finite() {
            return err(
                KEY,
                format!("gauge {} must be a finite number, got {}", num(x), k + 1),
            );
        }
        if x < domain.x_min || x > domain.x_max {
            return err(
                KEY,
                format!(
                    "gauge {} at x = {x} lies outside the domain [{}, {}]",
                    k + 1,
                    domain.x_min,
                    domain.x_max
                ),
            );
        }
        if xs[..k].contains(&x) {
            return err(KEY, format!("gauge {} at x = {x} is given twice", k + 1));
        }
    }
    Ok(xs.to_vec())
}

/// Checks `bed.b`, then `initial.h`, `initial.u` and `initial.w` at every cell centre
/// (`sampled`): all must be finite, the thickness non-negative, and w zero unless the
/// pressure is non-hydrostatic. The first offending centre is reported.
fn check_profiles(
    domain: &Domain,
    sampled: &Sampled,
    bed: &Profile,
    initial: &Initial,
    pressure: Pressure,
) -> Res<()> {
    let n = domain.cells;
    let dx = (domain.x_max - domain.x_min) / n as f64;
    let x_min = domain.x_min;
    let centre = move |i: usize| cell_centre(x_min, dx, i);
    let first_bad = |values: &[f64], bad: &(dyn Fn(f64) -> bool + Sync)| -> Option<usize> {
        values.par_iter().position_first(|&v| bad(v))
    };
    let not_finite = |key: &str, p: &Profile, x: f64, b: f64| -> ScenarioError {
        let message = match p.try_eval(x, b) {
            Err(m) => format!("{m} at x = {x}"),
            Ok(v) => format!("evaluates to {v} at x = {x}"),
        };
        ScenarioError::at(key, message)
    };
    let b = &sampled.b;
    if let Some(i) = first_bad(b, &|b| !b.is_finite()) {
        return Err(not_finite("bed.b", bed, centre(i), 0.0));
    }
    if let Some(i) = first_bad(&sampled.h, &|h| !(h.is_finite() && h >= 0.0)) {
        let (x, b) = (centre(i), b[i]);
        return match initial.h.try_eval(x, b) {
            Ok(h) if h.is_finite() => {
                err("initial.h", format!("negative thickness {h} at x = {x}"))
            }
            _ => Err(not_finite("initial.h", &initial.h, x, b)),
        };
    }
    if let Some(i) = first_bad(&sampled.h_bed, &|h| !(h.is_finite() && h >= 0.0)) {
        let (x, b) = (centre(i), b[i]);
        return match initial.erodible_bed.try_eval(x, b) {
            Ok(h) if h.is_finite() => err(
                "initial.erodible_bed",
                format!("negative thickness {h} at x = {x}"),
            ),
            _ => Err(not_finite(
                "initial.erodible_bed",
                &initial.erodible_bed,
                x,
                b,
            )),
        };
    }
    if let Some(i) = first_bad(&sampled.u, &|u| !u.is_finite()) {
        return Err(not_finite("initial.u", &initial.u, centre(i), b[i]));
    }
    if let Some(i) = first_bad(&sampled.w, &|w| !w.is_finite()) {
        return Err(not_finite("initial.w", &initial.w, centre(i), b[i]));
    }
    // Physical magnitudes (the bounds and their reasons: `check.rs`).
    let beyond = |key: &str, values: &[f64], max: f64, unit: &str, why: &str| -> Res<()> {
        match first_bad(values, &|v| v.abs() > max) {
            None => Ok(()),
            Some(i) => magnitude_at_most(key, values[i], max, unit, why)
                .map(|_| ())
                .map_err(|e| {
                    ScenarioError::at(key, format!("{} at x = {}", e.message(), centre(i)))
                }),
        }
    };
    beyond("bed.b", b, MAX_ELEVATION, "m", ELEVATION_WHY)?;
    beyond("initial.h", &sampled.h, MAX_THICKNESS, "m", THICKNESS_WHY)?;
    beyond(
        "initial.erodible_bed",
        &sampled.h_bed,
        MAX_THICKNESS,
        "m",
        THICKNESS_WHY,
    )?;
    beyond("initial.u", &sampled.u, MAX_SPEED, "m/s", SPEED_WHY)?;
    beyond("initial.w", &sampled.w, MAX_SPEED, "m/s", SPEED_WHY)?;
    if let Some(eta) = &sampled.eta {
        let depth: Vec<f64> = eta.iter().zip(b).map(|(e, b)| e - b).collect();
        beyond("initial.eta", &depth, MAX_DEPTH, "m", DEPTH_WHY)?;
    }
    if pressure == Pressure::Hydrostatic && first_bad(&sampled.w, &|w| w != 0.0).is_some() {
        return err(
            "initial.w",
            "a normal velocity needs model.pressure = \"nonhydrostatic\"",
        );
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scenario::{
        BasalCondition, FrictionLaw, ModelKind, ModelSpec, MonolayerShear, Regularization,
        SidewallForm, ViscosityTime,
    };
    use std::fs;

    const MINIMAL: &str = r#"[domain]
x_min = 0.0
x_max = 1.0
cells = 10

[rheology]
law = "coulomb"
mu = 0.5

[initial]
h = 0.1

[time]
t_end = 2.0
"#;

    fn load(text: &str) -> Res<Scenario> {
        load_str(text, Path::new("."), &[])
    }

    fn load_set(text: &str, sets: &[&str]) -> Res<Scenario> {
        let sets: Vec<String> = sets.iter().map(|s| s.to_string()).collect();
        load_str(text, Path::new("."), &sets)
    }

    #[test]
    fn second_order_is_refused_by_name_where_it_is_not_implemented_and_rasters_take_it() {
        let s = load_set(MINIMAL, &["numerics.order=2", "numerics.limiter=van_leer"]).unwrap();
        assert_eq!(
            (s.numerics.order, s.numerics.limiter),
            (2, Limiter::VanLeer)
        );
        let s = load(MINIMAL).unwrap();
        assert_eq!(s.numerics, Numerics::default());
        assert_eq!(s.numerics.order, 1);
        let s = load_set(MINIMAL, &["numerics.order=2", "model.layers=3"]).unwrap();
        assert_eq!((s.numerics.order, s.model.layers), (2, 3));
        // The non-hydrostatic monolayer runs order 2 (docs/numerics.md, "Non-hydrostatic
        // monolayer"); the multilayer is refused.
        let nh = load_set(
            MINIMAL,
            &["numerics.order=2", "model.pressure=nonhydrostatic"],
        );
        assert_eq!(nh.unwrap().numerics.order, 2);
        let sets = [
            "model.layers=3",
            "model.pressure=nonhydrostatic",
            "numerics.order=2",
        ];
        let e = load_set(MINIMAL, &sets).unwrap_err();
        assert!(e.to_string().contains("numerics.order"), "{e}");
        assert!(e.message().contains("nonhydrostatic"), "{e}");
        let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios");
        // The dilatant model takes it with its split scheme (the default), not with
        // the Appendix B scheme.
        let dilatant = load_file(
            &root.join("dilatancy_dense.toml"),
            &["numerics.order=2".to_owned()],
        );
        assert_eq!(dilatant.unwrap().numerics.order, 2);
        for (file, extra, what) in [
            (
                "dilatancy_dense.toml",
                "dilatancy.scheme=\"appendix_b\"",
                "split",
            ),
            ("submarine_landslide.toml", "numerics.order=2", "submarine"),
        ] {
            let sets = ["numerics.order=2".to_owned(), extra.to_owned()];
            let e = load_file(&root.join(file), &sets).unwrap_err();
            assert!(e.to_string().contains("numerics.order"), "{file}: {e}");
            assert!(e.message().contains(what), "{file}: {e}");
            assert!(load_file(&root.join(file), &[]).is_ok(), "{file}");
        }
        // Rasters run order 2 (docs/numerics.md, "Second order on a raster").
        let order_2 = ["numerics.order=2".to_owned()];
        let raster = load_file(&root.join("radial_collapse.toml"), &order_2).unwrap();
        assert_eq!(raster.numerics.order, 2);
        let e = load_set(MINIMAL, &["numerics.order=3"]).unwrap_err();
        assert!(e.to_string().contains("numerics.order"), "{e}");
        let e = load_set(MINIMAL, &["numerics.limiter=superbee", "numerics.order=2"]).unwrap_err();
        assert!(e.to_string().contains("numerics.limiter"), "{e}");
        let e = load_set(MINIMAL, &["numerics.limiter=mc"]).unwrap_err();
        assert!(e.to_string().contains("numerics.limiter"), "{e}");
    }

    #[test]
    fn multilayer_nonhydrostatic_size_is_bounded_by_the_solver_memory() {
        let nh = ["model.pressure=nonhydrostatic", "model.layers=100"];
        assert!(load_set(MINIMAL, &nh).is_ok());
        let e = load_set(MINIMAL, &[&nh[..], &["domain.cells=100000"]].concat()).unwrap_err();
        assert!(
            e.message().contains("GiB") && e.to_string().contains("model.layers"),
            "{e}"
        );
        // The hydrostatic model stores no such band (its 1.7 GB of snapshots are above
        // the output limit, lifted here).
        let sets = [
            "model.layers=100".to_owned(),
            "domain.cells=100000".to_owned(),
        ];
        assert!(load_str_within(MINIMAL, Path::new("."), &sets, None).is_ok());
    }

    /// Loads `text`, expects an error at `key` on `line`, returns it.
    #[track_caller]
    fn fails_at(text: &str, key: &str, line: Option<usize>) -> ScenarioError {
        match load(text) {
            Ok(_) => panic!("expected an error at {key}, scenario loaded"),
            Err(e) => {
                assert_eq!(e.key(), Some(key), "{e}");
                assert_eq!(e.line(), line, "{e}");
                e
            }
        }
    }

    fn replace(text: &str, from: &str, to: &str) -> String {
        assert!(text.contains(from), "{from}");
        text.replacen(from, to, 1)
    }

    #[test]
    fn minimal_scenario_gets_defaults() {
        let s = load(MINIMAL).unwrap();
        assert_eq!(s.source_toml, MINIMAL);
        assert_eq!(
            s.domain,
            Domain {
                x_min: 0.0,
                x_max: 1.0,
                cells: 10,
                slope_deg: 0.0,
                coordinates: Coordinates::Local,
                curvature: true,
                plane: None,
            }
        );
        assert_eq!(s.bed.as_constant(), Some(0.0));
        assert_eq!(
            s.material,
            Material {
                rho_s: 2500.0,
                phi: 0.62,
                d_s: 0.7e-3
            }
        );
        assert_eq!(s.friction, FrictionLaw::Coulomb { mu: 0.5 });
        assert_eq!(
            s.model,
            ModelSpec {
                kind: ModelKind::Granular,
                pressure: Pressure::Hydrostatic,
                layers: 1
            }
        );
        assert_eq!(s.initial.h.as_constant(), Some(0.1));
        assert_eq!(s.initial.u.as_constant(), Some(0.0));
        assert_eq!(s.initial.erodible_bed.as_constant(), Some(0.0));
        assert_eq!(
            s.boundary,
            Boundaries {
                left: BoundaryKind::Wall,
                right: BoundaryKind::Wall,
                south: BoundaryKind::Wall,
                north: BoundaryKind::Wall,
            }
        );
        assert_eq!(
            s.time,
            TimeSpec {
                t_end: 2.0,
                cfl: 0.5,
                stop_at_rest: false,
                settle_fraction: 1e-6,
                stop_when_settled: false,
                film_thickness: 0.0,
            }
        );
        assert_eq!(
            s.output,
            OutputSpec {
                file: PathBuf::from("granflow.h5"),
                every: 0.1,
                front_threshold: 1e-3,
                gauges: Vec::new(),
                gauges_y: Vec::new(),
                gauge_every: None,
                path: None,
            }
        );
        assert_eq!(s.base_dir, PathBuf::from("."));
    }

    #[test]
    fn full_scenario_reads_every_key() {
        let text = r#"
[domain]
x_min = -1
x_max = 3
cells = 400
slope_deg = 25.5
coordinates = "local"

[bed]
b = "0.01*noise(x, 3)"

[material]
rho_s = 2600
phi = 0.6
d_s = 1e-3

[rheology]
law = "mu_i"
mu_s_deg = 20.9
mu_2 = 0.64
i0 = 0.279

[model]
kind = "granular"
pressure = "hydrostatic"
layers = 4

[initial]
h = "if(x <= 0, 0.14, 0)"
u = -0.5
erodible_bed = 0.01

[boundary]
left = "wall"
right = "outflow"

[time]
t_end = 1.5
cfl = 0.45
stop_at_rest = true
settle_fraction = 1e-4
stop_when_settled = true

[output]
file = "out/run.h5"
every = 0.05
front_threshold = 2e-3
"#;
        let s = load(text).unwrap();
        assert_eq!(s.domain.cells, 400);
        assert_eq!(s.domain.slope_deg, 25.5);
        let FrictionLaw::MuI { mu_s, mu_2, i0, .. } = s.friction else {
            panic!("{:?}", s.friction)
        };
        assert!((mu_s - 20.9f64.to_radians().tan()).abs() < 1e-15);
        assert_eq!((mu_2, i0), (0.64, 0.279));
        assert_eq!(s.model.pressure, Pressure::Hydrostatic);
        assert_eq!(s.model.layers, 4);
        assert_eq!(s.initial.h.eval(-0.5, 0.0), 0.14);
        assert_eq!(s.initial.h.eval(0.5, 0.0), 0.0);
        assert_eq!(s.initial.u.as_constant(), Some(-0.5));
        assert_eq!(s.initial.erodible_bed.as_constant(), Some(0.01));
        assert_eq!(s.boundary.right, BoundaryKind::Outflow);
        assert!(s.time.stop_at_rest);
        assert_eq!(s.time.settle_fraction, 1e-4);
        assert!(s.time.stop_when_settled);
        assert_eq!(s.time.cfl, 0.45);
        assert_eq!(s.output.file, PathBuf::from("out/run.h5"));
        assert_eq!(s.output.every, 0.05);
        assert_eq!(s.output.front_threshold, 2e-3);
        let b = s.bed.eval(0.3, 0.0);
        assert!((0.0..0.01).contains(&b));
    }

    #[test]
    fn unknown_key_names_the_dotted_key_and_line() {
        let text = replace(MINIMAL, "cells = 10", "cels = 10");
        let e = fails_at(&text, "domain.cels", Some(4));
        assert!(e.message().contains("unknown key 'cels'"), "{e}");
        assert!(e.message().contains("cells"), "{e}");
        let e = fails_at(
            &format!("{MINIMAL}\n[outptu]\nfile = \"a\"\n"),
            "outptu",
            Some(16),
        );
        assert!(e.to_string().contains("unknown key 'outptu'"), "{e}");
    }

    #[test]
    fn wrong_type_names_key_and_line() {
        let text = replace(MINIMAL, "cells = 10", "cells = \"ten\"");
        let e = fails_at(&text, "domain.cells", Some(4));
        assert!(e.message().contains("expected an integer"), "{e}");
        let text = replace(MINIMAL, "t_end = 2.0", "t_end = true");
        let e = fails_at(&text, "time.t_end", Some(14));
        assert!(e.message().contains("expected a number"), "{e}");
    }

    #[test]
    fn zero_cells() {
        let text = replace(MINIMAL, "cells = 10", "cells = 0");
        let e = fails_at(&text, "domain.cells", Some(4));
        assert_eq!(
            e.to_string(),
            "scenario error at line 4, key 'domain.cells': must be at least 1, got 0"
        );
        let text = replace(MINIMAL, "cells = 10", "cells = 20_000_000");
        fails_at(&text, "domain.cells", Some(4));
    }

    #[test]
    fn x_max_not_above_x_min() {
        let text = replace(MINIMAL, "x_max = 1.0", "x_max = 0.0");
        fails_at(&text, "domain.x_max", Some(3));
        let text = replace(MINIMAL, "x_max = 1.0", "x_max = -1");
        fails_at(&text, "domain.x_max", Some(3));
    }

    #[test]
    fn missing_keys_point_at_their_table() {
        let text = replace(MINIMAL, "x_max = 1.0\n", "");
        let e = fails_at(&text, "domain.x_max", Some(1));
        assert!(e.message().contains("missing"), "{e}");
        let text = replace(MINIMAL, "[time]\nt_end = 2.0\n", "");
        let e = fails_at(&text, "time", None);
        assert!(e.message().contains("[time]"), "{e}");
    }

    #[test]
    fn missing_table_file() {
        let text = replace(
            MINIMAL,
            "h = 0.1",
            "h = { table = \"no-such-file-91.csv\" }",
        );
        let e = fails_at(&text, "initial.h", Some(11));
        assert!(e.message().contains("no-such-file-91.csv"), "{e}");
    }

    #[test]
    fn csv_table_profiles_resolve_against_base_dir() {
        let dir = tempfile::tempdir().unwrap();
        fs::write(dir.path().join("h.csv"), "x,value\n0,0.2\n1,0.0\n").unwrap();
        fs::write(dir.path().join("bad.csv"), "x,value\n0,0.2\n0.5,zz\n").unwrap();
        let text = replace(MINIMAL, "h = 0.1", "h = { table = \"h.csv\" }");
        let s = load_str(&text, dir.path(), &[]).unwrap();
        assert!((s.initial.h.eval(0.25, 0.0) - 0.15).abs() < 1e-15);
        assert_eq!(s.initial.h.eval(-3.0, 0.0), 0.2);
        assert_eq!(s.initial.h.eval(3.0, 0.0), 0.0);
        let text = replace(MINIMAL, "h = 0.1", "h = { table = \"bad.csv\" }");
        let e = load_str(&text, dir.path(), &[]).unwrap_err();
        assert_eq!(e.key(), Some("initial.h"));
        assert_eq!(e.line(), Some(11));
        assert!(
            e.message().contains("bad.csv") && e.message().contains("line 3"),
            "{e}"
        );
    }

    #[test]
    fn load_file_uses_parent_dir_and_stem() {
        let dir = tempfile::tempdir().unwrap();
        fs::write(dir.path().join("bed.csv"), "x,value\n0,0.0\n1,0.5\n").unwrap();
        let text = format!("{MINIMAL}\n[bed]\nb = {{ table = \"bed.csv\" }}\n");
        let path = dir.path().join("slide.toml");
        fs::write(&path, &text).unwrap();
        let s = load_file(&path, &[]).unwrap();
        assert_eq!(s.source_toml, text);
        assert_eq!(s.base_dir, dir.path());
        assert_eq!(s.output.file, PathBuf::from("slide.h5"));
        assert_eq!(s.bed.eval(0.5, 0.0), 0.25);

        let missing = dir.path().join("nope.toml");
        let e = load_file(&missing, &[]).unwrap_err();
        assert!(e.to_string().contains("nope.toml"), "{e}");
        assert_eq!(e.key(), None);
    }

    #[test]
    fn mu_2_below_mu_s() {
        let text = replace(
            MINIMAL,
            "law = \"coulomb\"\nmu = 0.5",
            "law = \"mu_i\"\nmu_s = 0.4\nmu_2 = 0.3\ni0 = 0.3",
        );
        let e = fails_at(&text, "rheology.mu_2", Some(9));
        assert!(e.message().contains("mu_s"), "{e}");
    }

    #[test]
    fn rheology_key_combinations() {
        // Coulomb with a μ(I) key.
        let text = replace(MINIMAL, "mu = 0.5", "mu = 0.5\ni0 = 0.3");
        let e = fails_at(&text, "rheology.i0", Some(9));
        assert!(e.message().contains("only used by law = \"mu_i\""), "{e}");
        // μ(I) with mu.
        let text = replace(
            MINIMAL,
            "law = \"coulomb\"\nmu = 0.5",
            "law = \"mu_i\"\nmu = 0.5\nmu_s = 0.4\nmu_2 = 0.6\ni0 = 0.3",
        );
        let e = fails_at(&text, "rheology.mu", Some(8));
        assert!(
            e.message().contains("only used by law = \"coulomb\""),
            "{e}"
        );
        // Both forms.
        let text = replace(MINIMAL, "mu = 0.5", "mu = 0.5\nmu_deg = 20");
        let e = fails_at(&text, "rheology.mu_deg", Some(9));
        assert!(e.message().contains("not both"), "{e}");
        // Degrees.
        let text = replace(MINIMAL, "mu = 0.5", "mu_deg = 45");
        let s = load(&text).unwrap();
        let FrictionLaw::Coulomb { mu } = s.friction else {
            panic!()
        };
        assert!((mu - 1.0).abs() < 1e-12);
        // Missing μ, unknown law, negative μ, μ_2 below μ_s in degrees.
        let text = replace(MINIMAL, "mu = 0.5\n", "");
        fails_at(&text, "rheology.mu", Some(6));
        let text = replace(MINIMAL, "law = \"coulomb\"", "law = \"colomb\"");
        let e = fails_at(&text, "rheology.law", Some(7));
        assert!(e.message().contains("\"coulomb\" or \"mu_i\""), "{e}");
        let text = replace(MINIMAL, "mu = 0.5", "mu = -0.1");
        fails_at(&text, "rheology.mu", Some(8));
        let text = replace(
            MINIMAL,
            "law = \"coulomb\"\nmu = 0.5",
            "law = \"mu_i\"\nmu_s = 0.4\nmu_2_deg = 10\ni0 = 0.3",
        );
        fails_at(&text, "rheology.mu_2_deg", Some(9));
        let text = replace(
            MINIMAL,
            "law = \"coulomb\"\nmu = 0.5",
            "law = \"mu_i\"\nmu_s = 0.4\nmu_2 = 0.5\ni0 = 0",
        );
        fails_at(&text, "rheology.i0", Some(10));
    }

    #[test]
    fn monolayer_shear_key() {
        let mu_i = replace(
            MINIMAL,
            "law = \"coulomb\"\nmu = 0.5",
            "law = \"mu_i\"\nmu_s = 0.4\nmu_2 = 0.6\ni0 = 0.3",
        );
        let shear = |s: &Scenario| match s.friction {
            FrictionLaw::MuI { shear, .. } => shear,
            other => panic!("{other:?}"),
        };
        assert_eq!(shear(&load(&mu_i).unwrap()), MonolayerShear::Bagnold);
        let layer = mu_i.replace("i0 = 0.3", "i0 = 0.3\nmonolayer_shear = \"layer\"");
        assert_eq!(shear(&load(&layer).unwrap()), MonolayerShear::Layer);
        let set = load_set(&mu_i, &["rheology.monolayer_shear=layer"]).unwrap();
        assert_eq!(shear(&set), MonolayerShear::Layer);
        let e = fails_at(
            &mu_i.replace("i0 = 0.3", "i0 = 0.3\nmonolayer_shear = \"bagnld\""),
            "rheology.monolayer_shear",
            Some(11),
        );
        assert!(e.message().contains("\"bagnold\" or \"layer\""), "{e}");
        // Coulomb has no inertial number.
        let text = replace(MINIMAL, "mu = 0.5", "mu = 0.5\nmonolayer_shear = \"layer\"");
        fails_at(&text, "rheology.monolayer_shear", Some(9));
    }

    #[test]
    fn negative_thickness() {
        let text = replace(MINIMAL, "h = 0.1", "h = \"-0.1\"");
        let e = fails_at(&text, "initial.h", Some(11));
        assert!(e.message().contains("negative thickness"), "{e}");
        // Negative only beyond x = 0.5: the first bad centre is 0.55.
        let text = replace(MINIMAL, "h = 0.1", "h = \"0.5 - x\"");
        let e = fails_at(&text, "initial.h", Some(11));
        assert!(e.message().contains("at x = 0.55"), "{e}");
        let text = replace(MINIMAL, "h = 0.1", "h = -1");
        fails_at(&text, "initial.h", Some(11));
    }

    #[test]
    fn non_finite_values() {
        let text = replace(MINIMAL, "x_min = 0.0", "x_min = nan");
        let e = fails_at(&text, "domain.x_min", Some(2));
        assert!(e.message().contains("finite"), "{e}");
        let text = replace(MINIMAL, "t_end = 2.0", "t_end = inf");
        fails_at(&text, "time.t_end", Some(14));
        let text = replace(MINIMAL, "h = 0.1", "h = nan");
        fails_at(&text, "initial.h", Some(11));
        let text = replace(MINIMAL, "mu = 0.5", "mu = -inf");
        fails_at(&text, "rheology.mu", Some(8));
        // An expression that is infinite at a cell centre.
        let text = replace(MINIMAL, "h = 0.1", "h = 0.1\nu = \"1/(x - 0.05)\"");
        let e = fails_at(&text, "initial.u", Some(12));
        assert!(e.message().contains("x = 0.05"), "{e}");
    }

    #[test]
    fn normal_velocity_defaults_to_zero_and_is_checked() {
        assert_eq!(load(MINIMAL).unwrap().initial.w.as_constant(), Some(0.0));
        let text = replace(MINIMAL, "h = 0.1", "h = 0.1\nw = \"if(x < 0.5, 2.3, b)\"");
        let e = fails_at(&text, "initial.w", Some(12));
        assert!(e.message().contains("nonhydrostatic"), "{e}");
        let text = format!("{text}\n[model]\npressure = \"nonhydrostatic\"\n");
        let s = load(&text).unwrap();
        assert_eq!(s.initial.w.eval(0.25, 0.0), 2.3);
        assert_eq!(s.initial.w.eval(0.75, 0.1), 0.1);
        let text = replace(MINIMAL, "h = 0.1", "h = 0.1\nw = \"1/(x - 0.05)\"");
        let e = fails_at(&text, "initial.w", Some(12));
        assert!(e.message().contains("x = 0.05"), "{e}");
    }

    #[test]
    fn expression_errors_name_key_and_line() {
        let text = format!("{MINIMAL}[bed]\nb = \"0.1*x +\"\n");
        fails_at(&text, "bed.b", Some(16));
        let text = format!("{MINIMAL}[bed]\nb = \"b + x\"\n");
        let e = fails_at(&text, "bed.b", Some(16));
        assert!(e.message().contains("bed elevation b"), "{e}");
        let text = format!("{MINIMAL}[bed]\nb = \"sin(x, 2)\"\n");
        let e = fails_at(&text, "bed.b", Some(16));
        assert!(e.message().contains("sin takes 1 argument"), "{e}");
        // An evaluation error at one cell centre only.
        let text = format!("{MINIMAL}[bed]\nb = \"if(x < 0.5, 0, x < 2)\"\n");
        let e = fails_at(&text, "bed.b", Some(16));
        assert!(e.message().contains("at x = 0.55"), "{e}");
    }

    #[test]
    fn bed_variable_in_initial_thickness() {
        let text = format!(
            "{}[bed]\nb = \"0.2*x\"\n",
            replace(MINIMAL, "h = 0.1", "h = \"max(0, 0.1 - b)\"")
        );
        let s = load(&text).unwrap();
        let b = s.bed.eval(0.25, 0.0);
        assert!((b - 0.05).abs() < 1e-15);
        assert!((s.initial.h.eval(0.25, b) - 0.05).abs() < 1e-15);
    }

    #[test]
    fn other_ranges() {
        let cases = [
            (
                "cells = 10",
                "cells = 10\nslope_deg = 90",
                "domain.slope_deg",
                5,
            ),
            (
                "cells = 10",
                "cells = 10\nslope_deg = 10\ncoordinates = \"cartesian\"",
                "domain.slope_deg",
                5,
            ),
            (
                "cells = 10",
                "cells = 10\ncoordinates = \"polar\"",
                "domain.coordinates",
                5,
            ),
            ("t_end = 2.0", "t_end = 2.0\ncfl = 1.5", "time.cfl", 15),
            (
                "t_end = 2.0",
                "t_end = 2.0\nsettle_fraction = 1.0",
                "time.settle_fraction",
                15,
            ),
            (
                "t_end = 2.0",
                "t_end = 2.0\nsettle_fraction = -1e-6",
                "time.settle_fraction",
                15,
            ),
            (
                "t_end = 2.0",
                "t_end = 2.0\nstop_when_settled = 1",
                "time.stop_when_settled",
                15,
            ),
            ("t_end = 2.0", "t_end = 0", "time.t_end", 14),
            (
                "h = 0.1",
                "h = 0.1\nerodible_bed = -1",
                "initial.erodible_bed",
                12,
            ),
        ];
        for (from, to, key, line) in cases {
            fails_at(&replace(MINIMAL, from, to), key, Some(line));
        }
        let tail = [
            ("[material]\nphi = 1.2\n", "material.phi"),
            ("[material]\nrho_s = 0\n", "material.rho_s"),
            ("[material]\nd_s = -1e-3\n", "material.d_s"),
            ("[model]\nlayers = 0\n", "model.layers"),
            ("[model]\nlayers = 1001\n", "model.layers"),
            ("[model]\npressure = \"nh\"\n", "model.pressure"),
            ("[model]\nkind = \"fluid\"\n", "model.kind"),
            ("[boundary]\nleft = \"periodic\"\n", "boundary.left"),
            ("[output]\nevery = 0\n", "output.every"),
            ("[output]\nfront_threshold = -1\n", "output.front_threshold"),
            ("[output]\nfile = \"\"\n", "output.file"),
        ];
        for (extra, key) in tail {
            fails_at(&format!("{MINIMAL}{extra}"), key, Some(16));
        }
    }

    #[test]
    fn every_larger_than_t_end_is_allowed() {
        let s = load(&format!("{MINIMAL}[output]\nevery = 10\n")).unwrap();
        assert_eq!(s.output.every, 10.0);
    }

    #[test]
    fn syntax_error_has_line() {
        let text = replace(MINIMAL, "cells = 10", "cells = ");
        let e = load(&text).unwrap_err();
        assert_eq!(e.line(), Some(4), "{e}");
        assert!(e.message().contains("invalid TOML"), "{e}");
        // A table defined twice: the parser points at the second header.
        let e = load(&format!("{MINIMAL}[domain]\ncells = 3\n")).unwrap_err();
        assert_eq!(e.line(), Some(15), "{e}");
    }

    #[test]
    fn override_changes_value_and_source() {
        let s = load_set(MINIMAL, &["domain.slope_deg=16"]).unwrap();
        assert_eq!(s.domain.slope_deg, 16.0);
        assert!(
            s.source_toml.contains("slope_deg = 16"),
            "{}",
            s.source_toml
        );
        assert!(s.source_toml.starts_with("[domain]\nx_min = 0.0\n"));
        let s = load_set(MINIMAL, &["initial.erodible_bed=0.02", "time.t_end=4"]).unwrap();
        assert_eq!(s.initial.erodible_bed.as_constant(), Some(0.02));
        assert_eq!(s.time.t_end, 4.0);
        assert_eq!(s.output.every, 0.2);
        let s = load_set(MINIMAL, &["initial.h=\"max(0, 0.14 - x)\""]).unwrap();
        assert!((s.initial.h.eval(0.04, 0.0) - 0.1).abs() < 1e-15);
        let s = load_set(MINIMAL, &["output.file=sweep/run1.h5"]).unwrap();
        assert_eq!(s.output.file, PathBuf::from("sweep/run1.h5"));
    }

    #[test]
    fn override_switching_law() {
        let mu_i = replace(
            MINIMAL,
            "law = \"coulomb\"\nmu = 0.5",
            "law = \"mu_i\"\nmu_s = 0.4\nmu_2 = 0.6\ni0 = 0.3",
        );
        // Leftover μ(I) keys in the file are ignored, with a note naming them.
        let s = load_set(&mu_i, &["rheology.law=coulomb", "rheology.mu=0.5"]).unwrap();
        assert_eq!(s.friction, FrictionLaw::Coulomb { mu: 0.5 });
        assert_eq!(s.notes.len(), 1);
        assert!(
            s.notes[0].contains("rheology.mu_s, rheology.mu_2, rheology.i0 ignored"),
            "{:?}",
            s.notes
        );
        // Without an override of the law, they are still an error, with its line.
        let e = load_set(&mu_i.replace("i0 = 0.3", "i0 = 0.3\nmu = 0.5"), &[]).unwrap_err();
        assert_eq!(e.key(), Some("rheology.mu"));
        assert!(
            e.message().contains("only used by law = \"coulomb\""),
            "{e}"
        );
        // From a Coulomb file the switch works (mu set from the file).
        let s = load_set(MINIMAL, &["rheology.law=coulomb", "rheology.mu=0.25"]).unwrap();
        assert_eq!(s.friction, FrictionLaw::Coulomb { mu: 0.25 });
    }

    /// `time.film_thickness` applies to rasters only (a line refuses it) and is at
    /// least 0, its default.
    #[test]
    fn film_thickness_is_for_rasters_and_not_negative() {
        let e = load_set(MINIMAL, &["time.film_thickness=1e-4"]).unwrap_err();
        assert_eq!(e.key(), Some("time.film_thickness"));
        assert!(e.message().contains("raster (2-D) runs only"), "{e}");
        let e = load_set(MINIMAL, &["time.film_thickness=-1"]).unwrap_err();
        assert_eq!(e.key(), Some("time.film_thickness"));
        let s = load_set(MINIMAL, &["time.film_thickness=0"]).unwrap();
        assert_eq!(s.time.film_thickness, 0.0);
    }

    #[test]
    fn override_errors_are_marked() {
        let e = load_set(MINIMAL, &["domain.slope_dg=16"]).unwrap_err();
        assert_eq!(e.key(), Some("domain.slope_dg"));
        assert!(e.is_from_set());
        assert_eq!(e.line(), None);
        assert!(e.to_string().contains("(from --set)"), "{e}");
        assert!(e.message().contains("unknown key 'slope_dg'"), "{e}");

        let e = load_set(MINIMAL, &["physics.g=9.81"]).unwrap_err();
        assert_eq!(e.key(), Some("physics.g"));
        assert!(e.is_from_set());

        let e = load_set(MINIMAL, &["domain.cells=0"]).unwrap_err();
        assert_eq!(e.key(), Some("domain.cells"));
        assert!(e.is_from_set());

        let e = load_set(MINIMAL, &["domain.cells=ten"]).unwrap_err();
        assert_eq!(e.key(), Some("domain.cells"));
        assert!(e.is_from_set());
        assert!(e.message().contains("expected an integer"), "{e}");

        let e = load_set(MINIMAL, &["initial.h.table=missing-77.csv"]).unwrap_err();
        assert_eq!(e.key(), Some("initial.h"));
        assert!(e.is_from_set());
        assert!(e.message().contains("missing-77.csv"), "{e}");

        let e = load_set(MINIMAL, &["domain.cells.n=3"]).unwrap_err();
        assert_eq!(e.key(), Some("domain.cells"));
        assert!(e.is_from_set());

        // An error elsewhere in the file keeps its line despite the override shifting text.
        let text = replace(MINIMAL, "t_end = 2.0", "t_end = -2.0");
        let e = load_set(&text, &["domain.slope_deg=16", "model.layers=2"]).unwrap_err();
        assert_eq!(e.key(), Some("time.t_end"));
        assert_eq!(e.line(), Some(14));

        let e = load_set(MINIMAL, &["no_equals_sign"]).unwrap_err();
        assert!(e.message().contains("key=value"), "{e}");
    }

    #[test]
    fn no_overrides_keeps_text_verbatim() {
        let text = format!("# a comment\n{MINIMAL}\n\n# trailing\n");
        assert_eq!(load(&text).unwrap().source_toml, text);
    }

    #[test]
    fn documented_example_loads() {
        let doc = include_str!("../../../docs/scenario-format.md");
        let start = doc.find("```toml\n").expect("an example") + "```toml\n".len();
        let example = &doc[start..start + doc[start..].find("```").unwrap()];
        let s = load(example).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(s.domain.cells, 600);
        assert_eq!(s.boundary.right, BoundaryKind::Outflow);
        assert!(matches!(s.friction, FrictionLaw::MuI { .. }));
    }

    #[test]
    fn multilayer_keys() {
        let text = format!(
            "{MINIMAL}[model]\nlayers = 3\nlayer_fractions = [0.2, 0.3, 0.5]\n[output]\nstatic_threshold = 2e-3\n"
        );
        let text = replace(
            &text,
            "mu = 0.5",
            "mu = 0.5\nbasal = \"no_slip\"\nregularization = \"bound\"\nmu_w_deg = 10.4\nchannel_width = 0.1\nsidewall = \"layer\"\nc_msm = true",
        );
        let s = load(&text).unwrap();
        let m = &s.multilayer;
        assert_eq!(m.layer_fractions, vec![0.2, 0.3, 0.5]);
        assert_eq!(m.basal, BasalCondition::NoSlip);
        assert_eq!(m.regularization, Regularization::Bound);
        let w = m.sidewall.unwrap();
        assert!((w.mu_w - 10.4f64.to_radians().tan()).abs() < 1e-15);
        assert_eq!((w.width, w.form), (0.1, SidewallForm::Layer));
        assert!(m.c_msm);
        assert_eq!(m.static_threshold, 2e-3);

        // Defaults: uniform layers, Coulomb bed, δ = 1e-5, no sidewalls.
        let s = load_set(MINIMAL, &["model.layers=4"]).unwrap();
        assert_eq!(s.multilayer.layer_fractions, vec![0.25; 4]);
        assert_eq!(s.multilayer.basal, BasalCondition::Coulomb);
        assert_eq!(
            s.multilayer.regularization,
            Regularization::Delta { delta: 1e-5 }
        );
        assert_eq!(s.multilayer.sidewall, None);
        assert!(!s.multilayer.c_msm);
        assert_eq!(s.multilayer.viscosity, ViscosityTime::Lagged);
        assert_eq!(s.multilayer.static_threshold, 1e-3);
        let s = load_set(MINIMAL, &["model.layers=4", "rheology.viscosity=frozen"]).unwrap();
        assert_eq!(s.multilayer.viscosity, ViscosityTime::Frozen);
        let s = load_set(MINIMAL, &["model.layers=4", "rheology.viscosity=implicit"]).unwrap();
        assert_eq!(
            s.multilayer.viscosity,
            ViscosityTime::Implicit {
                tolerance: 1e-10,
                max_iterations: 1000
            }
        );
        let s = load_set(
            MINIMAL,
            &[
                "model.layers=4",
                "rheology.viscosity=implicit",
                "rheology.viscosity_tolerance=1e-8",
                "rheology.viscosity_iterations=30",
            ],
        )
        .unwrap();
        assert_eq!(
            s.multilayer.viscosity,
            ViscosityTime::Implicit {
                tolerance: 1e-8,
                max_iterations: 30
            }
        );
        assert_eq!(load(MINIMAL).unwrap().multilayer.layer_fractions, vec![1.0]);

        let bad = [
            (
                &["model.layers=2", "model.layer_fractions=[0.5]"][..],
                "model.layer_fractions",
                "one fraction per layer",
            ),
            (
                &["model.layers=2", "model.layer_fractions=[0.5, 0.6]"],
                "model.layer_fractions",
                "sum to 1",
            ),
            (
                &["model.layers=2", "model.layer_fractions=[1.5, -0.5]"],
                "model.layer_fractions",
                "greater than 0",
            ),
            (&["rheology.basal=no_slip"], "rheology.basal", "multilayer"),
            (
                &["model.layers=2", "rheology.basal=slip"],
                "rheology.basal",
                "unknown value",
            ),
            (
                &[
                    "model.layers=2",
                    "rheology.regularization=bound",
                    "rheology.delta=1e-3",
                ],
                "rheology.delta",
                "only used by",
            ),
            (
                &["model.layers=2", "rheology.delta=0"],
                "rheology.delta",
                "greater than 0",
            ),
            (
                &["model.layers=2", "rheology.viscosity=explicit"],
                "rheology.viscosity",
                "unknown value \"explicit\" (expected \"lagged\" or \"frozen\" or \"implicit\")",
            ),
            (
                &["model.layers=2", "rheology.viscosity_tolerance=1e-8"],
                "rheology.viscosity_tolerance",
                "only used by viscosity = \"implicit\"",
            ),
            (
                &["model.layers=2", "rheology.viscosity_iterations=10"],
                "rheology.viscosity_iterations",
                "only used by viscosity = \"implicit\"",
            ),
            (
                &[
                    "model.layers=2",
                    "rheology.viscosity=implicit",
                    "rheology.viscosity_tolerance=0",
                ],
                "rheology.viscosity_tolerance",
                "greater than 0",
            ),
            (
                &[
                    "model.layers=2",
                    "rheology.viscosity=implicit",
                    "rheology.viscosity_iterations=0",
                ],
                "rheology.viscosity_iterations",
                "at least 1",
            ),
            (
                &["model.layers=2", "rheology.mu_w=0.2"],
                "rheology.mu_w",
                "channel_width",
            ),
            (
                &["model.layers=2", "rheology.channel_width=0.1"],
                "rheology.channel_width",
                "mu_w",
            ),
            (
                &["model.layers=2", "rheology.sidewall=jop"],
                "rheology.sidewall",
                "mu_w",
            ),
            (
                &["rheology.mu_w=0.2", "rheology.channel_width=0.1"],
                "rheology.mu_w",
                "multilayer",
            ),
            (
                &[
                    "model.layers=2",
                    "rheology.mu_w=0.2",
                    "rheology.channel_width=0",
                ],
                "rheology.channel_width",
                "greater than 0",
            ),
            (
                &["model.layers=2", "output.static_threshold=0"],
                "output.static_threshold",
                "greater than 0",
            ),
        ];
        for (sets, key, message) in bad {
            let e = load_set(MINIMAL, sets).unwrap_err();
            assert_eq!(e.key(), Some(key), "{sets:?}: {e}");
            assert!(e.message().contains(message), "{sets:?}: {e}");
        }
    }

    #[test]
    fn scenario_is_send_sync() {
        fn check<T: Send + Sync + Clone>() {}
        check::<Scenario>();
    }
}
