//! Builds the sub-step pipeline of a run from the model choice (architecture note:
//! "the pipeline is built from the scenario"). Each stage is monomorphised over the
//! friction law, so a constant-Coulomb run contains no μ(I) code at all, and a
//! hydrostatic run has no projection stage.

use crate::numerics::friction::CoulombFrictionStep;
use crate::numerics::hydrostatic::HydrostaticStep;
use crate::numerics::Stage;
use crate::physics::rheology::{BasalFriction, Coulomb, MuI};
use crate::scenario::{FrictionLaw, Material};

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
