//! The sub-step pipeline of a granular run, built from the model choice (architecture
//! note: "the pipeline is built from the scenario"). Every stage is monomorphised over
//! the friction law, chosen once in [`with_law`]: a constant-Coulomb run contains no
//! μ(I) code at all, a hydrostatic run has no projection stage, a monolayer run no
//! viscous solve. The hyperbolic stage is the same code for every N and every
//! pressure; the non-hydrostatic normal discharge rides it as a tracer.

use crate::grid::Line;
use crate::model::granular::config::{MultilayerSpec, Pressure};
use crate::numerics::friction::{BedNormalFrictionStep, CoulombFrictionStep};
use crate::numerics::hydrostatic::HydrostaticStep;
use crate::numerics::line_bed_normal::BedNormalLineStep;
use crate::numerics::muscl::Limiter;
use crate::numerics::nh_heun::NhHeun;
use crate::numerics::nh_multilayer::NhViscousProjection;
use crate::numerics::nonhydrostatic::NhFrictionStep;
use crate::numerics::projection::monolayer::MonolayerOperator;
use crate::numerics::projection::{ProjectionStage, ThomasSolver};
use crate::numerics::ssp_rk2::{HeunLayers, HeunSplitting};
use crate::numerics::viscous::{MultilayerViscousStep, ViscosityTime};
use crate::numerics::Stage;
use crate::physics::rheology::{BasalFriction, Coulomb, FrictionLaw, LocalFriction, MuI, Voellmy};
use crate::physics::Material;
use crate::pipeline::Pipeline;
use crate::state::layered::LayeredState;

/// Something built for a concrete friction law type.
pub trait WithLaw {
    type Out;
    fn with<L: BasalFriction + LocalFriction + 'static>(self, law: L) -> Self::Out;
}

/// Calls `w` with the law of `law` as a concrete type: the one place where the
/// scenario's friction law becomes code.
pub fn with_law<W: WithLaw>(law: &FrictionLaw, material: &Material, w: W) -> W::Out {
    match *law {
        FrictionLaw::Coulomb { mu } => w.with(Coulomb { mu }),
        FrictionLaw::MuI {
            mu_s,
            mu_2,
            i0,
            shear,
        } => w.with(MuI {
            mu_s,
            mu_2,
            i0,
            d_s: material.d_s,
            phi: material.phi,
            shear,
        }),
        FrictionLaw::Voellmy { mu, xi } => w.with(Voellmy { mu, xi }),
    }
}

/// The stages of a granular run: hyperbolic, then friction (N = 1) or viscous
/// (N > 1), then the projection of a non-hydrostatic run.
pub struct Stages<'a> {
    pub mesh: &'a Line,
    pub pressure: Pressure,
    pub multilayer: &'a MultilayerSpec,
    /// `Some(limiter)`: the second-order step (`numerics.order = 2`; the validation
    /// allows it on local and Cartesian lines for the hydrostatic model, N ≥ 1 layers,
    /// and the non-hydrostatic monolayer; the N-layer non-hydrostatic step is built
    /// here too, for the tests, see `nh_heun`).
    pub second_order: Option<Limiter>,
}

impl WithLaw for Stages<'_> {
    type Out = Vec<Box<dyn Stage<Line, LayeredState>>>;

    fn with<L: BasalFriction + LocalFriction + 'static>(self, law: L) -> Self::Out {
        let (mesh, spec) = (self.mesh, self.multilayer);
        let (nx, l) = (mesh.nx, &spec.layer_fractions);
        if mesh.metric().is_some() {
            // The bed-normal frame (the validation allows it for the monolayer
            // hydrostatic model at order 1 only).
            assert!(self.pressure == Pressure::Hydrostatic && l.len() == 1);
            assert!(self.second_order.is_none());
            return vec![
                Box::new(BedNormalLineStep::new(law, nx)),
                Box::new(BedNormalFrictionStep::new(law)),
            ];
        }
        if let Some(limiter) = self.second_order {
            if self.pressure == Pressure::NonHydrostatic {
                // Heun's method around the whole split step (`nh_heun`): the first-order
                // step 2 and projection below, after the order-2 hyperbolic step.
                let rest = non_hydrostatic_rest(law, mesh, spec);
                return vec![Box::new(NhHeun::new(law, nx, l.len(), limiter, rest))];
            }
            if l.len() == 1 {
                return vec![Box::new(HeunSplitting::new(law, nx, limiter))];
            }
            let opts = spec.viscous_options();
            return vec![Box::new(HeunLayers::new(law, nx, l, opts, limiter))];
        }
        let mut stages: Self::Out = vec![Box::new(HydrostaticStep::with_layers(law, nx, l.len()))];
        match (self.pressure, l.len()) {
            (Pressure::Hydrostatic, 1) => stages.push(Box::new(CoulombFrictionStep::new(law))),
            (Pressure::Hydrostatic, _) => {
                let opts = spec.viscous_options();
                stages.push(Box::new(MultilayerViscousStep::new(law, nx, l, opts)));
            }
            (Pressure::NonHydrostatic, _) => stages.extend(non_hydrostatic_rest(law, mesh, spec)),
        }
        stages
    }
}

/// Steps 2 and 3 of a non-hydrostatic run, after the hyperbolic step: the explicit pⁿ
/// terms with the friction (N = 1) or the μ(I) viscous step (N > 1), then the
/// projection (for N > 1 one stage, which owns the projection's operator).
fn non_hydrostatic_rest<L: BasalFriction + LocalFriction + 'static>(
    law: L,
    mesh: &Line,
    spec: &MultilayerSpec,
) -> Vec<Box<dyn Stage<Line, LayeredState>>> {
    let (nx, l) = (mesh.nx, &spec.layer_fractions);
    if l.len() == 1 {
        return vec![
            Box::new(NhFrictionStep::new(law, mesh)),
            Box::new(ProjectionStage::new(
                MonolayerOperator::new(mesh),
                ThomasSolver::default(),
                nx,
            )),
        ];
    }
    // Escalante et al. 2023, §4: explicit p^n and the μ(I) viscous step with the total
    // pressures, then the exact N-layer projection, one stage with one operator.
    let viscous = MultilayerViscousStep::new(law, nx, l, spec.viscous_options());
    let lagged = spec.viscosity == ViscosityTime::Lagged;
    vec![Box::new(
        NhViscousProjection::new(mesh, l, viscous).lagged(lagged),
    )]
}

/// The pipeline of a granular run with friction law `law`.
pub fn granular(
    law: &FrictionLaw,
    material: &Material,
    mesh: &Line,
    pressure: Pressure,
    multilayer: &MultilayerSpec,
    second_order: Option<Limiter>,
) -> Pipeline<Line, LayeredState> {
    let stages = Stages {
        mesh,
        pressure,
        multilayer,
        second_order,
    };
    Pipeline::new(with_law(law, material, stages))
}
