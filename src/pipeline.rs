//! Builds the sub-step pipeline of a run from the model choice (architecture note:
//! "the pipeline is built from the scenario"). Each stage is monomorphised over the
//! friction law, so a constant-Coulomb run contains no μ(I) code at all, and a
//! hydrostatic run has no projection stage.

use crate::numerics::friction::CoulombFrictionStep;
use crate::numerics::hydrostatic::HydrostaticStep;
use crate::numerics::Stage;
use crate::physics::rheology::{BasalFriction, Coulomb, MuI};
use crate::scenario::{FrictionLaw, Material};
// Non-hydrostatic pipeline (issue 3).
use crate::mesh::Mesh;
use crate::numerics::nonhydrostatic::{NhFrictionStep, NhHyperbolicStep};
use crate::numerics::projection::monolayer::MonolayerOperator;
use crate::numerics::projection::{ProjectionStage, ThomasSolver};

fn monolayer<L: BasalFriction + 'static>(law: L, nx: usize) -> Vec<Box<dyn Stage>> {
    vec![
        Box::new(HydrostaticStep::new(law, nx)),
        Box::new(CoulombFrictionStep::new(law)),
    ]
}

/// The hydrostatic monolayer pipeline: hyperbolic → friction.
pub fn hydrostatic_monolayer(
    law: &FrictionLaw,
    material: &Material,
    nx: usize,
) -> Vec<Box<dyn Stage>> {
    match *law {
        FrictionLaw::Coulomb { mu } => monolayer(Coulomb { mu }, nx),
        FrictionLaw::MuI { mu_s, mu_2, i0 } => monolayer(
            MuI {
                mu_s,
                mu_2,
                i0,
                d_s: material.d_s,
                phi: material.phi,
            },
            nx,
        ),
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
        FrictionLaw::MuI { mu_s, mu_2, i0 } => nh_monolayer(
            MuI {
                mu_s,
                mu_2,
                i0,
                d_s: material.d_s,
                phi: material.phi,
            },
            mesh,
        ),
    }
}
