//! From a validated [`Scenario`] to a ready granular [`Simulation`]: samples the
//! profiles on the mesh, adds the erodible bed (Fernández-Nieto et al. 2016, §4.2, Escalante et al. 2023, eq. 34: the
//! column sits on a layer h_i of the same material, so h = initial.h + h_i),
//! and builds the pipeline of the chosen model (every layer starts with the velocity
//! `initial.u`; a non-hydrostatic run also with the normal velocity `initial.w`).
//! In the bed-normal frame the state holds H = h/c per horizontal length (as a raster
//! does): `initial.h` and the erodible bed are thicknesses normal to the bed, and
//! `initial.u` is the horizontal velocity.
//! Everything that can be wrong with the scenario was refused by its validation.

use crate::model::granular::config::Pressure;
use crate::model::granular::pipeline;
use crate::model::granular::Granular;
use crate::scenario::Scenario;
use crate::setup::{run_config, run_info, scenario_line};
use crate::simulation::Simulation;
use crate::state::layered::LayeredState;

pub fn build(scn: &Scenario) -> Simulation<Granular> {
    let mesh = scenario_line(scn);
    let mesh = if scn.domain.curvature {
        mesh
    } else {
        mesh.without_friction_curvature()
    };
    let per_length = |values: &[f64]| -> Vec<f64> {
        match mesh.metric() {
            Some(m) => values.iter().zip(&m.cos).map(|(h, c)| h / c).collect(),
            None => values.to_vec(),
        }
    };
    let h_bed = &per_length(&scn.sampled.h_bed);
    let h: Vec<f64> = per_length(&scn.sampled.h)
        .iter()
        .zip(h_bed)
        .map(|(&h, &h_i)| h + h_i)
        .collect();
    let u = &scn.sampled.u;
    let mut state = LayeredState::from_profiles(&mesh, &scn.multilayer.layer_fractions, &h, u);
    if scn.model.pressure == Pressure::NonHydrostatic {
        // An imposed normal velocity (the gate, Garres-Díaz et al. 2021, eq. 30) enters the first step
        // as it is, as in the paper (docs/numerics.md, "Initial normal velocity").
        state.add_nonhydrostatic(&scn.sampled.w);
    }
    let stages = pipeline::granular(
        &scn.friction,
        &scn.material,
        &mesh,
        scn.model.pressure,
        &scn.multilayer,
        (scn.numerics.order == 2).then_some(scn.numerics.limiter),
    );
    let layers = scn.model.layers;
    let model = Granular {
        h_bed: h_bed.clone(),
        front_threshold: scn.output.front_threshold,
        static_threshold: scn.multilayer.static_threshold,
        rest_speed: if layers > 1 {
            scn.multilayer.static_threshold
        } else {
            0.0
        },
    };
    let pressure = match scn.model.pressure {
        Pressure::Hydrostatic => "hydrostatic",
        Pressure::NonHydrostatic => "nonhydrostatic",
    };
    let info = run_info(scn, pressure, layers);
    let rules = crate::stop::default_rules(super::stop_options(
        scn,
        mesh.z[1..=mesh.nx].iter().copied(),
    ));
    Simulation::new(mesh, model, state, stages, rules, run_config(scn), info)
}
