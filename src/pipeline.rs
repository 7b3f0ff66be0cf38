//! Builds the sub-step pipeline of a run from the model choice (architecture note:
//! "the pipeline is built from the scenario"). Each stage is monomorphised over the
//! friction law, so a constant-Coulomb run contains no μ(I) code at all, and a
//! hydrostatic run has no projection stage. A monolayer has the friction stage, a
//! multilayer run (N > 1) the viscous stage instead: the hyperbolic stage and the
//! state are the same code for every N.

use crate::mesh::Mesh;
use crate::numerics::friction::CoulombFrictionStep;
use crate::numerics::hydrostatic::HydrostaticStep;
use crate::numerics::nonhydrostatic::{NhFrictionStep, NhHyperbolicStep};
use crate::numerics::projection::monolayer::MonolayerOperator;
use crate::numerics::projection::{ProjectionStage, ThomasSolver};
use crate::numerics::viscous::{MultilayerViscousStep, ViscousOptions};
use crate::numerics::Stage;
use crate::physics::rheology::{BasalFriction, Coulomb, LocalFriction, MuI};
use crate::scenario::{FrictionLaw, Material, MultilayerSpec};

fn monolayer<L: BasalFriction + 'static>(law: L, nx: usize) -> Vec<Box<dyn Stage>> {
    vec![
        Box::new(HydrostaticStep::new(law, nx)),
        Box::new(CoulombFrictionStep::new(law)),
    ]
}

fn multilayer<L: BasalFriction + LocalFriction + 'static>(
    law: L,
    nx: usize,
    l: &[f64],
    opts: ViscousOptions,
) -> Vec<Box<dyn Stage>> {
    vec![
        Box::new(HydrostaticStep::with_layers(law, nx, l.len())),
        Box::new(MultilayerViscousStep::new(law, nx, l, opts)),
    ]
}

fn mu_i(mu_s: f64, mu_2: f64, i0: f64, material: &Material) -> MuI {
    MuI {
        mu_s,
        mu_2,
        i0,
        d_s: material.d_s,
        phi: material.phi,
    }
}

/// The hydrostatic monolayer pipeline: hyperbolic → friction.
pub fn hydrostatic_monolayer(
    law: &FrictionLaw,
    material: &Material,
    nx: usize,
) -> Vec<Box<dyn Stage>> {
    match *law {
        FrictionLaw::Coulomb { mu } => monolayer(Coulomb { mu }, nx),
        FrictionLaw::MuI { mu_s, mu_2, i0 } => monolayer(mu_i(mu_s, mu_2, i0, material), nx),
    }
}

// Non-hydrostatic monolayer (issue 3, seed 000 §3): only these scenarios build the
// projection stage.

fn nh_monolayer<L: BasalFriction + 'static>(law: L, mesh: &Mesh) -> Vec<Box<dyn Stage>> {
    vec![
        Box::new(NhHyperbolicStep::new(law, mesh.nx)),
        Box::new(NhFrictionStep::new(law, mesh)),
        Box::new(ProjectionStage::new(
            MonolayerOperator::new(mesh),
            ThomasSolver::default(),
            mesh.nx,
        )),
    ]
}

/// The non-hydrostatic monolayer pipeline: hyperbolic (with hw transport) → friction
/// (with the total pressure) → projection.
pub fn nonhydrostatic_monolayer(
    law: &FrictionLaw,
    material: &Material,
    mesh: &Mesh,
) -> Vec<Box<dyn Stage>> {
    match *law {
        FrictionLaw::Coulomb { mu } => nh_monolayer(Coulomb { mu }, mesh),
        FrictionLaw::MuI { mu_s, mu_2, i0 } => nh_monolayer(mu_i(mu_s, mu_2, i0, material), mesh),
    }
}
/// The hydrostatic multilayer pipeline with layer fractions `l` (N = `l.len()` > 1):
/// hyperbolic → viscous. With `law` Coulomb the rheology is μ(I) ≡ μ (seed 001's
/// "μ_s-MSM").
pub fn hydrostatic_multilayer(
    law: &FrictionLaw,
    material: &Material,
    nx: usize,
    l: &[f64],
    opts: ViscousOptions,
) -> Vec<Box<dyn Stage>> {
    match *law {
        FrictionLaw::Coulomb { mu } => multilayer(Coulomb { mu }, nx, l, opts),
        FrictionLaw::MuI { mu_s, mu_2, i0 } => {
            multilayer(mu_i(mu_s, mu_2, i0, material), nx, l, opts)
        }
    }
}

/// The hydrostatic pipeline of a scenario: monolayer for one layer, multilayer with the
/// scenario's viscous options otherwise.
pub fn hydrostatic(
    law: &FrictionLaw,
    material: &Material,
    nx: usize,
    spec: &MultilayerSpec,
) -> Vec<Box<dyn Stage>> {
    if spec.layer_fractions.len() == 1 {
        return hydrostatic_monolayer(law, material, nx);
    }
    let opts = ViscousOptions {
        basal: spec.basal,
        regularization: spec.regularization,
        sidewall: spec.sidewall,
        c_msm: spec.c_msm,
    };
    hydrostatic_multilayer(law, material, nx, &spec.layer_fractions, opts)
}
