//! The keys of the granular model and of its friction laws: `[rheology]` (the basal
//! law, Garres-Díaz et al. 2021, eq. 6, and the multilayer model's viscous options, Fernández-Nieto et al. 2016, eq. 6,
//! 25–32, Escalante et al. 2023, eq. 10 and 36), `[model]` and `output.static_threshold`. A new model
//! adds its own file beside this one (docs/architecture.md, "How to add a model").

use super::super::error::ScenarioError;
use super::super::raw::{RawModel, RawRheology};
use super::super::{
    BasalCondition, FrictionLaw, ModelKind, ModelSpec, MonolayerShear, MultilayerSpec, Pressure,
    Regularization, Sidewall, SidewallForm, ViscosityTime,
};
use super::check::*;
use super::zones::number;
use super::MAX_LAYERS;

/// A friction coefficient given either plainly (`mu`) or as an angle (`mu_deg`).
/// Returns the coefficient and the key it came from.
pub(super) fn coefficient(
    name: &str,
    plain: Option<f64>,
    degrees: Option<f64>,
) -> Res<Option<(f64, String)>> {
    let key = format!("rheology.{name}");
    let key_deg = format!("rheology.{name}_deg");
    match (plain, degrees) {
        (Some(_), Some(_)) => err(
            &key_deg,
            format!("give either {key} or {key_deg}, not both"),
        ),
        (Some(v), None) => Ok(Some((non_negative(&key, v)?, key))),
        (None, Some(a)) => {
            finite(&key_deg, a)?;
            if !(0.0..90.0).contains(&a) {
                return err(
                    &key_deg,
                    format!("must be an angle in [0, 90) degrees, got {}", num(a)),
                );
            }
            Ok(Some((a.to_radians().tan(), key_deg)))
        }
        (None, None) => Ok(None),
    }
}

/// The friction law. Keys of the other law are an error (a mix-up in the file), unless
/// `rheology.law` was overridden (`--set`, a sweep axis): then they are left over from
/// the file's own law and are ignored, with a note naming them.
pub(super) fn rheology(
    r: &RawRheology,
    law_overridden: bool,
    notes: &mut Vec<String>,
) -> Res<FrictionLaw> {
    let law = required("rheology.law", r.law.as_deref())?;
    #[derive(Clone, Copy, PartialEq)]
    enum Law {
        Coulomb,
        MuI,
        Voellmy,
    }
    let law = choice(
        "rheology.law",
        Some(law),
        Law::Coulomb,
        &[
            ("coulomb", Law::Coulomb),
            ("mu_i", Law::MuI),
            ("voellmy", Law::Voellmy),
        ],
    )?;
    let name = |l: Law| match l {
        Law::Coulomb => "coulomb",
        Law::MuI => "mu_i",
        Law::Voellmy => "voellmy",
    };
    // Each law's keys, and the laws that use them.
    const COULOMB_LIKE: &[Law] = &[Law::Coulomb, Law::Voellmy];
    let keys: [(&str, bool, &[Law]); 9] = [
        ("mu", r.mu.is_some(), COULOMB_LIKE),
        ("mu_deg", r.mu_deg.is_some(), COULOMB_LIKE),
        ("mu_s", r.mu_s.is_some(), &[Law::MuI]),
        ("mu_s_deg", r.mu_s_deg.is_some(), &[Law::MuI]),
        ("mu_2", r.mu_2.is_some(), &[Law::MuI]),
        ("mu_2_deg", r.mu_2_deg.is_some(), &[Law::MuI]),
        ("i0", r.i0.is_some(), &[Law::MuI]),
        ("monolayer_shear", r.monolayer_shear.is_some(), &[Law::MuI]),
        ("xi", r.xi.is_some(), &[Law::Voellmy]),
    ];
    let foreign: Vec<(&str, &[Law])> = keys
        .iter()
        .filter(|(_, given, laws)| *given && !laws.contains(&law))
        .map(|&(key, _, laws)| (key, laws))
        .collect();
    let this = name(law);
    if law_overridden && !foreign.is_empty() {
        let keys: Vec<String> = foreign
            .iter()
            .map(|(n, _)| format!("rheology.{n}"))
            .collect();
        let others: Vec<String> = foreign
            .iter()
            .flat_map(|(_, laws)| laws.iter().map(|&l| format!("\"{}\"", name(l))))
            .fold(Vec::new(), |mut all, l| {
                if !all.contains(&l) {
                    all.push(l);
                }
                all
            });
        notes.push(format!(
            "{} ignored: only used by law = {} and rheology.law was set to \"{this}\"",
            keys.join(", "),
            others.join(" or ")
        ));
    } else if let Some((key, laws)) = foreign.first() {
        let others: Vec<String> = laws.iter().map(|&l| format!("\"{}\"", name(l))).collect();
        return err(
            &format!("rheology.{key}"),
            format!(
                "only used by law = {} (rheology.law is \"{this}\"); remove it",
                others.join(" or ")
            ),
        );
    }
    // The Coulomb coefficient of the laws that have one (`name` as in rheology.law).
    let mu = |name: &str| -> Result<f64, ScenarioError> {
        let (mu, _) = coefficient("mu", number(&r.mu), number(&r.mu_deg))?.ok_or_else(|| {
            ScenarioError::at(
                "rheology.mu",
                format!("missing required key (law = \"{name}\" needs mu or mu_deg)"),
            )
        })?;
        Ok(mu)
    };
    match law {
        Law::Coulomb => Ok(FrictionLaw::Coulomb { mu: mu("coulomb")? }),
        Law::MuI => {
            let need = |name: &str| {
                ScenarioError::at(
                    format!("rheology.{name}"),
                    format!("missing required key (law = \"mu_i\" needs {name} or {name}_deg)"),
                )
            };
            let (mu_s, _) = coefficient("mu_s", r.mu_s, r.mu_s_deg)?.ok_or_else(|| need("mu_s"))?;
            let (mu_2, key_2) =
                coefficient("mu_2", r.mu_2, r.mu_2_deg)?.ok_or_else(|| need("mu_2"))?;
            if mu_2 < mu_s {
                return err(
                    &key_2,
                    format!("mu_2 = {mu_2} must be at least mu_s = {mu_s}"),
                );
            }
            let i0 = positive("rheology.i0", required("rheology.i0", r.i0)?)?;
            let shear = choice(
                "rheology.monolayer_shear",
                r.monolayer_shear.as_deref(),
                MonolayerShear::Bagnold,
                &[
                    ("bagnold", MonolayerShear::Bagnold),
                    ("layer", MonolayerShear::Layer),
                ],
            )?;
            Ok(FrictionLaw::MuI {
                mu_s,
                mu_2,
                i0,
                shear,
            })
        }
        Law::Voellmy => {
            let mu = mu("voellmy")?;
            let xi = positive("rheology.xi", required("rheology.xi", number(&r.xi))?)?;
            Ok(FrictionLaw::Voellmy { mu, xi })
        }
    }
}

pub(super) fn model(m: &RawModel) -> Res<ModelSpec> {
    let kind = choice(
        "model.kind",
        m.kind.as_deref(),
        ModelKind::Granular,
        &[
            ("granular", ModelKind::Granular),
            ("submarine", ModelKind::Submarine),
            ("dilatant", ModelKind::Dilatant),
        ],
    )?;
    let pressure = choice(
        "model.pressure",
        m.pressure.as_deref(),
        Pressure::Hydrostatic,
        &[
            ("hydrostatic", Pressure::Hydrostatic),
            ("nonhydrostatic", Pressure::NonHydrostatic),
        ],
    )?;
    let layers = int_in("model.layers", m.layers.unwrap_or(1), 1, MAX_LAYERS)?;
    if kind == ModelKind::Dilatant {
        if pressure != Pressure::Hydrostatic {
            return err("model.pressure", "the dilatant model is hydrostatic");
        }
        if layers != 1 {
            return err("model.layers", "the dilatant model has one layer");
        }
    }
    Ok(ModelSpec {
        kind,
        pressure,
        layers,
    })
}

/// The `[rheology]` keys of the multilayer model's viscous step (the friction law's keys
/// are read by `rheology`).
pub(super) struct ViscousKeys {
    basal: Option<String>,
    regularization: Option<String>,
    delta: Option<f64>,
    pub(super) mu_w: Option<f64>,
    pub(super) mu_w_deg: Option<f64>,
    pub(super) channel_width: Option<f64>,
    sidewall: Option<String>,
    c_msm: Option<bool>,
    viscosity: Option<String>,
    viscosity_tolerance: Option<f64>,
    viscosity_iterations: Option<i64>,
}

impl ViscousKeys {
    pub(super) fn of(r: &RawRheology) -> ViscousKeys {
        ViscousKeys {
            basal: r.basal.clone(),
            regularization: r.regularization.clone(),
            delta: r.delta,
            mu_w: r.mu_w,
            mu_w_deg: r.mu_w_deg,
            channel_width: r.channel_width,
            sidewall: r.sidewall.clone(),
            c_msm: r.c_msm,
            viscosity: r.viscosity.clone(),
            viscosity_tolerance: r.viscosity_tolerance,
            viscosity_iterations: r.viscosity_iterations,
        }
    }
}

/// Default regularisation parameter δ (1/s) of Escalante et al. 2023, §5.
pub(crate) const DEFAULT_DELTA: f64 = 1e-5;

/// Default residual tolerance (m/s) of `rheology.viscosity = "implicit"`.
pub(crate) const DEFAULT_VISCOSITY_TOLERANCE: f64 = 1e-10;

/// Default most column solves per step of `rheology.viscosity = "implicit"`.
pub(crate) const DEFAULT_VISCOSITY_ITERATIONS: i64 = 1000;

pub(super) fn multilayer(
    v: ViscousKeys,
    fractions: Option<Vec<f64>>,
    static_threshold: Option<f64>,
    layers: usize,
) -> Res<MultilayerSpec> {
    let multilayer_only = |key: &str| -> ScenarioError {
        ScenarioError::at(
            key,
            "only used by the multilayer model; set model.layers > 1 or remove it",
        )
    };
    let layer_fractions = match fractions {
        None => vec![1.0 / layers as f64; layers],
        Some(l) => layer_fractions(l, layers)?,
    };
    let basal = choice(
        "rheology.basal",
        v.basal.as_deref(),
        BasalCondition::Coulomb,
        &[
            ("coulomb", BasalCondition::Coulomb),
            ("no_slip", BasalCondition::NoSlip),
        ],
    )?;
    if basal == BasalCondition::NoSlip && layers == 1 {
        return Err(multilayer_only("rheology.basal"));
    }
    #[derive(Clone, Copy, PartialEq)]
    enum Reg {
        Delta,
        Bound,
    }
    let reg = choice(
        "rheology.regularization",
        v.regularization.as_deref(),
        Reg::Delta,
        &[("delta", Reg::Delta), ("bound", Reg::Bound)],
    )?;
    let regularization = match (reg, v.delta) {
        (Reg::Bound, Some(_)) => {
            return err(
                "rheology.delta",
                "only used by regularization = \"delta\" (rheology.regularization is \"bound\"); remove it",
            )
        }
        (Reg::Bound, None) => Regularization::Bound,
        (Reg::Delta, d) => Regularization::Delta {
            delta: positive("rheology.delta", d.unwrap_or(DEFAULT_DELTA))?,
        },
    };
    let mu_w = coefficient("mu_w", v.mu_w, v.mu_w_deg)?;
    let sidewall = match (mu_w, v.channel_width) {
        (None, None) => {
            if v.sidewall.is_some() {
                return err(
                    "rheology.sidewall",
                    "needs the wall friction rheology.mu_w (or mu_w_deg) and rheology.channel_width",
                );
            }
            None
        }
        (Some((_, key)), None) => {
            return err(
                &key,
                "sidewall friction needs the channel width rheology.channel_width too",
            )
        }
        (None, Some(_)) => {
            return err(
                "rheology.channel_width",
                "sidewall friction needs the wall friction rheology.mu_w (or mu_w_deg) too",
            )
        }
        (Some((mu_w, key)), Some(w)) => {
            if layers == 1 {
                return Err(multilayer_only(&key));
            }
            let width = positive("rheology.channel_width", w)?;
            let form = choice(
                "rheology.sidewall",
                v.sidewall.as_deref(),
                SidewallForm::Jop,
                &[("jop", SidewallForm::Jop), ("layer", SidewallForm::Layer)],
            )?;
            Some(Sidewall { mu_w, width, form })
        }
    };
    let static_threshold = positive("output.static_threshold", static_threshold.unwrap_or(1e-3))?;
    #[derive(Clone, Copy, PartialEq)]
    enum Visc {
        Frozen,
        Lagged,
        Implicit,
    }
    let visc = choice(
        "rheology.viscosity",
        v.viscosity.as_deref(),
        Visc::Lagged,
        &[
            ("lagged", Visc::Lagged),
            ("frozen", Visc::Frozen),
            ("implicit", Visc::Implicit),
        ],
    )?;
    let implicit_only = "only used by viscosity = \"implicit\"; remove it";
    let viscosity = match (visc, v.viscosity_tolerance, v.viscosity_iterations) {
        (Visc::Implicit, tolerance, iterations) => ViscosityTime::Implicit {
            tolerance: positive(
                "rheology.viscosity_tolerance",
                tolerance.unwrap_or(DEFAULT_VISCOSITY_TOLERANCE),
            )?,
            max_iterations: int_in(
                "rheology.viscosity_iterations",
                iterations.unwrap_or(DEFAULT_VISCOSITY_ITERATIONS),
                1,
                100_000,
            )?,
        },
        (_, Some(_), _) => return err("rheology.viscosity_tolerance", implicit_only),
        (_, _, Some(_)) => return err("rheology.viscosity_iterations", implicit_only),
        (Visc::Frozen, None, None) => ViscosityTime::Frozen,
        (Visc::Lagged, None, None) => ViscosityTime::Lagged,
    };
    Ok(MultilayerSpec {
        layer_fractions,
        basal,
        regularization,
        sidewall,
        c_msm: v.c_msm.unwrap_or(false),
        viscosity,
        static_threshold,
    })
}

/// `model.layer_fractions`: one positive number per layer, bottom first, summing to 1
/// (to 1e-9; the fractions are then rescaled to sum to 1 to round-off).
pub(super) fn layer_fractions(l: Vec<f64>, layers: usize) -> Res<Vec<f64>> {
    let key = "model.layer_fractions";
    if l.len() != layers {
        return err(
            key,
            format!(
                "has {} values but model.layers = {layers}; give one fraction per layer",
                l.len()
            ),
        );
    }
    for &v in &l {
        positive(key, v)?;
        if v < MIN_LAYER_FRACTION {
            return err(
                key,
                format!(
                    "{} is below the smallest layer fraction {MIN_LAYER_FRACTION:e} (the viscous system's conditioning grows as (l_max / l_min)²)",
                    num(v)
                ),
            );
        }
    }
    let sum: f64 = l.iter().sum();
    if (sum - 1.0).abs() > 1e-9 {
        return err(key, format!("must sum to 1, sums to {sum}"));
    }
    Ok(l.iter().map(|v| v / sum).collect())
}
