//! Builds the submarine model (seed 004) from a validated scenario: the bed angle from
//! b(x), the grains' vertical thickness `initial.h` = H₂cos²θ and velocity `initial.u`,
//! the water up to the surface `initial.eta` (H₁cos²θ = max(0, η − b − H₂cos²θ)), at rest.

use crate::model::submarine::Submarine;
use crate::numerics::two_layer::{TwoLayerGeometry, TwoLayerSolver, TwoLayerStage, TwoLayerState};
use crate::numerics::Stage;
use crate::physics::rheology::FrictionLaw;
use crate::pipeline::Pipeline;
use crate::scenario::Scenario;
use crate::setup::{mesh_of, run_config, run_info};
use crate::simulation::Simulation;

pub fn build(scn: &Scenario) -> Simulation<Submarine> {
    let mesh = mesh_of(scn);
    let spec = scn
        .submarine
        .expect("validated: a submarine scenario has its spec");
    let mu = match scn.friction {
        FrictionLaw::Coulomb { mu } => mu,
        FrictionLaw::MuI { .. } => unreachable!("validated: Coulomb friction"),
    };
    let params = spec.params(mu);
    let geometry = TwoLayerGeometry::new(mesh.x_min, mesh.dx, &mesh.b, mesh.left, mesh.right);
    let mut state = TwoLayerState::zeros(mesh.nx);
    for i in 1..=mesh.nx {
        let (x, b, c2) = (mesh.x[i - 1], geometry.b[i], geometry.cos2[i]);
        let d2 = scn.initial.h.eval(x, b);
        state.h2[i] = d2 / c2;
        state.q2[i] = state.h2[i] * scn.initial.u.eval(x, b);
        if let Some(eta) = &scn.initial.eta {
            state.h1[i] = (eta.eval(x, b) - b - d2).max(0.0) / c2;
        }
    }
    state.fill_ghosts(&geometry);
    let stage = TwoLayerStage {
        solver: TwoLayerSolver::new(params, scn.time.cfl, mesh.nx),
        geometry: geometry.clone(),
    };
    let stages: Vec<Box<dyn Stage<TwoLayerState>>> = vec![Box::new(stage)];
    let eta0 = Submarine::initial_surface(&geometry, &state, scn.output.front_threshold);
    let model = Submarine {
        params,
        geometry,
        front_threshold: scn.output.front_threshold,
        h_bed: vec![0.0; mesh.nx],
        eta0,
    };
    // Snapshots carry the grain layer in h, u (one layer) and the water in extra fields.
    let info = run_info(scn, "hydrostatic", 1);
    let rules = crate::stop::default_rules(&scn.time);
    Simulation::new(
        mesh,
        model,
        state,
        Pipeline::new(stages),
        rules,
        run_config(scn),
        info,
    )
}
