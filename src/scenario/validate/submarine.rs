//! The submarine model's keys (`model.kind = "submarine"`, Fernández-Nieto et al. 2008): `[submarine]`,
//! `initial.eta`, and the shared keys it constrains (Cartesian domain, Coulomb
//! friction, one hydrostatic layer, no erodible bed, no w).

use super::check::*;
use crate::grid::line::cell_centre;
use crate::model::submarine::{SubmarineSpec, WaterPressure, MAX_WATER_LAYERS};
use crate::physics::two_layer::Buoyancy;
use crate::scenario::raw::RawSubmarine;
use crate::scenario::{Coordinates, Domain, FrictionLaw, Initial, ModelSpec, Pressure, Sampled};

/// Fewest cells of the two-layer scheme: the bed angle of a cell is a centred difference
/// of the bed, one-sided at the ends.
const MIN_CELLS: usize = 2;

/// Validates the `[submarine]` table and the consistency of the other keys with it.
/// `raw_w` tells whether `initial.w` was given.
pub(super) fn submarine(
    s: Option<RawSubmarine>,
    model: &ModelSpec,
    domain: &Domain,
    friction: &FrictionLaw,
    initial: &Initial,
    raw_w: bool,
    sampled: &Sampled,
) -> Res<Option<SubmarineSpec>> {
    if model.kind != crate::model::ModelKind::Submarine {
        if s.is_some() {
            return err(
                "submarine",
                "the [submarine] table needs model.kind = \"submarine\"",
            );
        }
        if initial.eta.is_some() {
            return err(
                "initial.eta",
                "the water surface needs model.kind = \"submarine\"",
            );
        }
        return Ok(None);
    }
    let s = s.unwrap_or_default();
    if domain.cells < MIN_CELLS {
        return err(
            "domain.cells",
            format!(
                "the submarine model needs at least {MIN_CELLS} cells (its bed angle is a difference between cells), got {}",
                domain.cells
            ),
        );
    }
    if domain.coordinates != Coordinates::Cartesian {
        return err(
            "domain.coordinates",
            "the submarine model is written in Cartesian coordinates (Fernández-Nieto et al. 2008, eq. 62): set domain.coordinates = \"cartesian\" and the slope in bed.b",
        );
    }
    if !matches!(friction, FrictionLaw::Coulomb { .. }) {
        return err(
            "rheology.law",
            "the submarine model uses Coulomb friction (law = \"coulomb\", mu_deg = δ0)",
        );
    }
    if model.layers != 1 || model.pressure != Pressure::Hydrostatic {
        return err(
            "model.layers",
            "the submarine model has one hydrostatic granular layer under the water",
        );
    }
    if raw_w {
        return err(
            "initial.w",
            "the submarine model is hydrostatic: no normal velocity",
        );
    }
    if initial.has_erodible_bed() {
        return err(
            "initial.erodible_bed",
            "the submarine model has no erodible bed",
        );
    }
    let r = finite("submarine.r", required("submarine.r", s.r)?)?;
    if !(0.0..1.0).contains(&r) {
        return err(
            "submarine.r",
            format!(
                "the density ratio ρ_water/ρ_grains must be in [0, 1), got {}",
                num(r)
            ),
        );
    }
    let k = positive("submarine.k", s.k.unwrap_or(1.0))?;
    let unit = |key: &str, v: Option<f64>| -> Res<f64> {
        let v = finite(key, v.unwrap_or(0.0))?;
        if (0.0..=1.0).contains(&v) {
            Ok(v)
        } else {
            err(key, format!("must be in [0, 1], got {}", num(v)))
        }
    };
    let lambda1 = unit("submarine.lambda1", s.lambda1)?;
    let lambda2 = unit("submarine.lambda2", s.lambda2)?;
    if non_negative("submarine.k_in", s.k_in.unwrap_or(0.0))? != 0.0 {
        return err(
            "submarine.k_in",
            "friction between the layers (K_in > 0) is not implemented; Fernández-Nieto et al. 2008, §5 uses K_in = 0",
        );
    }
    let buoyancy = choice(
        "submarine.buoyancy",
        s.buoyancy.as_deref(),
        Buoyancy::Everywhere,
        &[
            ("everywhere", Buoyancy::Everywhere),
            ("submerged", Buoyancy::Submerged),
        ],
    )?;
    let water = water_pressure(s.water_pressure.as_deref(), s.water_layers)?;
    let spec = SubmarineSpec {
        r,
        k,
        lambda1,
        lambda2,
        buoyancy,
        water,
    };
    if !spec.params(0.0).bound_is_proven() {
        return err(
            "submarine.k",
            "A2 = rλ2 + K(1 − rλ2) must be at least r A1 = r(λ1 + K(1 − λ1)) (hyperbolicity bound of the scheme)",
        );
    }
    if let Some(eta) = &sampled.eta {
        if let Some(i) = eta.iter().position(|v| !v.is_finite()) {
            let dx = (domain.x_max - domain.x_min) / domain.cells as f64;
            let x = cell_centre(domain.x_min, dx, i);
            let v = eta[i];
            return err("initial.eta", format!("evaluates to {v} at x = {x}"));
        }
    }
    Ok(Some(spec))
}

/// `submarine.water_pressure` ("hydrostatic", the default, or "nonhydrostatic") and
/// `submarine.water_layers` (M ≥ 1, default 1, only with the non-hydrostatic water).
fn water_pressure(pressure: Option<&str>, layers: Option<i64>) -> Res<WaterPressure> {
    let nonhydrostatic = choice(
        "submarine.water_pressure",
        pressure,
        false,
        &[("hydrostatic", false), ("nonhydrostatic", true)],
    )?;
    if !nonhydrostatic {
        if layers.is_some() {
            return err(
                "submarine.water_layers",
                "water layers need submarine.water_pressure = \"nonhydrostatic\" (hydrostatic water is one layer)",
            );
        }
        return Ok(WaterPressure::Hydrostatic);
    }
    let layers = int_in(
        "submarine.water_layers",
        layers.unwrap_or(1),
        1,
        MAX_WATER_LAYERS as i64,
    )?;
    Ok(WaterPressure::NonHydrostatic { layers })
}
