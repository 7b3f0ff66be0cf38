//! Builds the submarine model (Fernández-Nieto et al. 2008) from a validated scenario: the bed angle from
//! b(x), the grains' vertical thickness `initial.h` = H₂cos²θ and velocity `initial.u`,
//! the water up to the surface `initial.eta` (H₁cos²θ = max(0, η − b − H₂cos²θ)), at rest;
//! with `submarine.water_pressure = "nonhydrostatic"` the water's layers (at rest) and
//! its projection stage ([`crate::numerics::water_nh`]).

use crate::grid::CurvedLine;
use crate::model::submarine::{Submarine, WaterPressure};
use crate::numerics::two_layer::{TwoLayerSolver, TwoLayerStage};
use crate::numerics::water_nh::{WaterProjection, WaterProjectionStage};
use crate::numerics::Stage;
use crate::physics::rheology::FrictionLaw;
use crate::pipeline::Pipeline;
use crate::scenario::Scenario;
use crate::setup::{run_config, run_info, scenario_line};
use crate::simulation::Simulation;
use crate::state::TwoLayerState;

pub fn build(scn: &Scenario) -> Simulation<Submarine> {
    let grid = CurvedLine::new(scenario_line(scn));
    let spec = scn
        .submarine
        .expect("validated: a submarine scenario has its spec");
    let mu = match scn.friction {
        FrictionLaw::Coulomb { mu } => mu,
        FrictionLaw::MuI { .. } | FrictionLaw::Voellmy { .. } => {
            unreachable!("validated: Coulomb friction")
        }
    };
    let params = spec.params(mu);
    let nx = grid.line.nx;
    let mut state = TwoLayerState::zeros(nx);
    let sampled = &scn.sampled;
    for i in 1..=nx {
        let (b, c2) = (grid.line.b_ghost[i], grid.cos2[i]);
        let d2 = sampled.h[i - 1];
        state.h2[i] = d2 / c2;
        state.q2[i] = state.h2[i] * sampled.u[i - 1];
        if let Some(eta) = &sampled.eta {
            state.h1[i] = (eta[i - 1] - b - d2).max(0.0) / c2;
        }
    }
    state.fill_ghosts(&grid);
    let stage = TwoLayerStage {
        solver: TwoLayerSolver::new(params, scn.time.cfl, nx),
    };
    let mut stages: Vec<Box<dyn Stage<CurvedLine, TwoLayerState>>> = vec![Box::new(stage)];
    // Non-hydrostatic water: its layers at rest, and the projection after the
    // two-layer step. Hydrostatic water builds none of it.
    if let WaterPressure::NonHydrostatic { layers } = spec.water {
        let projection = WaterProjection::new(&grid, layers, params.r * params.a1);
        state.water = Some(projection.water_at_rest(nx));
        stages.push(Box::new(WaterProjectionStage::new(projection)));
    }
    let eta0 = Submarine::initial_surface(&grid, &state, scn.output.front_threshold);
    let model = Submarine {
        params,
        front_threshold: scn.output.front_threshold,
        h_bed: vec![0.0; nx],
        eta0,
    };
    // Snapshots carry the grain layer in h, u (one layer) and the water in extra fields.
    let info = run_info(scn, "hydrostatic", 1);
    let rules = crate::stop::default_rules(super::stop_options(
        scn,
        grid.line.z[1..=grid.line.nx].iter().copied(),
    ));
    Simulation::new(
        grid,
        model,
        state,
        Pipeline::new(stages),
        rules,
        run_config(scn),
        info,
    )
}
