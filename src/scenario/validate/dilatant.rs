//! The keys of the dilatant model (Bouchut et al. 2021): `[dilatancy]`, `initial.phi`, and the
//! μ(I) law and wall keys of `[rheology]` read as μ_1, μ_2, I_0 (eq. 2.14) and
//! μ_w, W (eq. 4.1).

use super::super::profile::Profile;
use super::super::raw::{RawDilatancy, RawRheology};
use super::super::{
    DilatantSpec, Domain, FrictionLaw, Initial, Material, ModelKind, ModelSpec, MonolayerShear,
    TimeSpec,
};
use super::check::*;
use super::granular::coefficient;
use crate::grid::line::cell_centre;
use crate::numerics::dilatant::flux::FluxOptions;
use crate::numerics::dilatant::source::DilatancyUpdate;
use crate::numerics::dilatant::stabilisation::Viscosity;
use crate::numerics::dilatant::step::{DilatantOptions, SchemeKind, DEFAULT_THIN_LAYER_GRAINS};
use crate::physics::dilatancy::{DilatantLaw, PhiEq};

/// The dilatant model's keys (`[dilatancy]`, `initial.phi`, the μ(I) law of
/// `[rheology]` as μ_1, μ_2, I_0 of Bouchut et al. 2021, eq. 2.14, its optional walls eq. 4.1), or
/// None for the other models, which refuse them.
pub(super) fn dilatancy(
    raw_dilatancy: Option<&RawDilatancy>,
    r: &RawRheology,
    friction: &FrictionLaw,
    material: &Material,
    model: &ModelSpec,
    initial: &Initial,
    time: &TimeSpec,
) -> Res<Option<DilatantSpec>> {
    let Some(d) = raw_dilatancy.filter(|_| model.kind == ModelKind::Dilatant) else {
        if model.kind == ModelKind::Dilatant {
            return err(
                "dilatancy",
                "missing table [dilatancy] (model.kind = \"dilatant\")",
            );
        }
        if raw_dilatancy.is_some() {
            return err("dilatancy", "only used by model.kind = \"dilatant\"");
        }
        if initial.phi.is_some() {
            return err("initial.phi", "only used by model.kind = \"dilatant\"");
        }
        return Ok(None);
    };
    let FrictionLaw::MuI {
        mu_s,
        mu_2,
        i0,
        shear,
    } = *friction
    else {
        return err(
            "rheology.law",
            "the dilatant model needs law = \"mu_i\" (Bouchut et al. 2021, eq. 2.14)",
        );
    };
    if shear != MonolayerShear::Bagnold {
        return err(
            "rheology.monolayer_shear",
            "the dilatant model takes the Bagnold shear rate (Bouchut et al. 2021, eq. 2.15)",
        );
    }
    if initial.phi.is_none() {
        return err("initial.phi", "required by model.kind = \"dilatant\"");
    }
    if initial.has_erodible_bed() {
        return err(
            "initial.erodible_bed",
            "not available in the dilatant model",
        );
    }
    if r.basal.is_some()
        || r.regularization.is_some()
        || r.delta.is_some()
        || r.c_msm.is_some()
        || r.sidewall.is_some()
        || r.viscosity.is_some()
        || r.viscosity_tolerance.is_some()
        || r.viscosity_iterations.is_some()
    {
        let key = [
            ("rheology.basal", r.basal.is_some()),
            ("rheology.regularization", r.regularization.is_some()),
            ("rheology.delta", r.delta.is_some()),
            ("rheology.c_msm", r.c_msm.is_some()),
            ("rheology.sidewall", r.sidewall.is_some()),
            ("rheology.viscosity", r.viscosity.is_some()),
            (
                "rheology.viscosity_tolerance",
                r.viscosity_tolerance.is_some(),
            ),
            (
                "rheology.viscosity_iterations",
                r.viscosity_iterations.is_some(),
            ),
        ]
        .iter()
        .find(|(_, given)| *given)
        .map(|(k, _)| *k)
        .unwrap_or("rheology");
        return err(key, "only used by the multilayer model");
    }
    let k = non_negative("dilatancy.k", required("dilatancy.k", d.k)?)?;
    let k_tilde = non_negative(
        "dilatancy.k_tilde",
        required("dilatancy.k_tilde", d.k_tilde)?,
    )?;
    let phi_stat = finite(
        "dilatancy.phi_stat",
        required("dilatancy.phi_stat", d.phi_stat)?,
    )?;
    if !(MIN_PHI..1.0).contains(&phi_stat) {
        return err(
            "dilatancy.phi_stat",
            format!(
                "must be in [{MIN_PHI}, 1) (a solid volume fraction of a dense granular mass), got {}",
                num(phi_stat)
            ),
        );
    }
    #[derive(Clone, Copy, PartialEq)]
    enum Reg {
        F0,
        F1,
        F2,
    }
    let reg = choice(
        "dilatancy.phi_eq",
        d.phi_eq.as_deref(),
        Reg::F2,
        &[("f0", Reg::F0), ("f1", Reg::F1), ("f2", Reg::F2)],
    )?;
    if d.n.is_some() && reg != Reg::F2 {
        return err("dilatancy.n", "only used by phi_eq = \"f2\"");
    }
    let n = positive("dilatancy.n", d.n.unwrap_or(1.0))?;
    let phi_eq = match reg {
        Reg::F0 => PhiEq::F0,
        Reg::F1 => PhiEq::F1,
        Reg::F2 => PhiEq::F2 { n },
    };
    let update = choice(
        "dilatancy.update",
        d.update.as_deref(),
        DilatancyUpdate::Implicit,
        &[
            ("implicit", DilatancyUpdate::Implicit),
            ("exponential", DilatancyUpdate::Exponential),
        ],
    )?;
    let alpha = finite("dilatancy.alpha", d.alpha.unwrap_or(2.0))?;
    if alpha <= 1.0 || alpha > MAX_ALPHA {
        return err(
            "dilatancy.alpha",
            format!(
                "must be in (1, {MAX_ALPHA}] (Bouchut et al. 2021, eq. B.19; the scheme carries φ^α h, and φ^(α−1) must not underflow for φ ≥ 0.01), got {}",
                num(alpha)
            ),
        );
    }
    let lambda = non_negative("dilatancy.lambda", d.lambda.unwrap_or(0.0))?;
    let scheme = choice(
        "dilatancy.scheme",
        d.scheme.as_deref(),
        SchemeKind::Split,
        &[
            ("split", SchemeKind::Split),
            ("appendix_b", SchemeKind::AppendixB),
        ],
    )?;
    let xi = match &d.xi {
        // The split scheme needs no stabilisation (docs/numerics.md); Appendix B does.
        None if scheme == SchemeKind::Split => [0.0; 3],
        None => Viscosity::default().xi,
        Some(v) if v.len() == 3 => {
            for x in v {
                non_negative("dilatancy.xi", *x)?;
                if *x > MAX_XI {
                    return err(
                        "dilatancy.xi",
                        format!(
                            "{} is beyond the largest stabilisation coefficient {MAX_XI:e} (Bouchut et al. 2021, §3.3 uses ξ = (2, 2, 5); the explicit sub-steps of a time step grow as ξ)",
                            num(*x)
                        ),
                    );
                }
            }
            [v[0], v[1], v[2]]
        }
        Some(v) => {
            return err(
                "dilatancy.xi",
                format!("needs 3 values ξ_1, ξ_2, ξ_3, got {}", v.len()),
            )
        }
    };
    // Bouchut et al. 2021, §3.3: no dilatancy in layers thinner than "about tens of
    // particles"; 10 grain diameters, the smallest such number, by default.
    if d.thin_layer_grains.is_some() && scheme != SchemeKind::Split {
        return err(
            "dilatancy.thin_layer_grains",
            "only used by scheme = \"split\"",
        );
    }
    let thin_layer_grains = non_negative(
        "dilatancy.thin_layer_grains",
        d.thin_layer_grains.unwrap_or(DEFAULT_THIN_LAYER_GRAINS),
    )?;
    let mu_w = coefficient("mu_w", r.mu_w, r.mu_w_deg)?;
    let (mu_w, width) = match (mu_w, r.channel_width) {
        (None, None) => (0.0, 1.0),
        (Some((mu_w, _)), Some(w)) => (mu_w, positive("rheology.channel_width", w)?),
        (Some((_, key)), None) => {
            return err(
                &key,
                "wall friction needs the channel width rheology.channel_width too",
            )
        }
        (None, Some(_)) => {
            return err(
                "rheology.channel_width",
                "needs the wall friction rheology.mu_w (or mu_w_deg)",
            )
        }
    };
    let law = DilatantLaw {
        mu_1: mu_s,
        mu_2,
        i0,
        d: material.d_s,
        k,
        k_tilde,
        phi_stat,
        phi_eq,
        mu_w,
        width,
    };
    let options = DilatantOptions {
        scheme,
        flux: FluxOptions { alpha, lambda },
        viscosity: Viscosity { xi },
        update,
        cfl: time.cfl,
        h_thin: thin_layer_grains * material.d_s,
    };
    Ok(Some(DilatantSpec { law, options }))
}

/// `initial.phi` at every cell centre (`values`, at the bed `b`): finite, at least
/// [`MIN_PHI`] and below 1.
pub(super) fn check_fraction(domain: &Domain, b: &[f64], phi: &Profile, values: &[f64]) -> Res<()> {
    let n = domain.cells;
    let dx = (domain.x_max - domain.x_min) / n as f64;
    let Some(i) = values.iter().position(|&v| !(MIN_PHI..1.0).contains(&v)) else {
        return Ok(());
    };
    let x = cell_centre(domain.x_min, dx, i);
    match phi.try_eval(x, b[i]) {
        Ok(v) => err(
            "initial.phi",
            format!(
                "must be in [{MIN_PHI}, 1) (a solid volume fraction of a dense granular mass), got {} at x = {x}",
                num(v)
            ),
        ),
        Err(m) => err("initial.phi", format!("{m} at x = {x}")),
    }
}
