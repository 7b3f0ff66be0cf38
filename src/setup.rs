//! From a validated [`Scenario`] to a ready [`Simulation`]: samples the profiles on
//! the mesh, adds the erodible bed (seed 001 §4.2, seed 003 eq. 34: the column sits
//! on a uniform layer h_i of the same material, so h = initial.h + h_i), and builds
//! the pipeline of the chosen model (monolayer or multilayer with `model.layers`
//! layers; every layer starts with the velocity `initial.u`).

use crate::mesh::{Mesh, MeshSpec};
use crate::output::RunInfo;
use crate::pipeline;
use crate::scenario::{Coordinates, Pressure, Scenario};
use crate::simulation::{RunConfig, Simulation};
use crate::state::{NonHydrostatic, State};

/// A scenario that is valid TOML but asks for something this build cannot run.
#[derive(Debug, thiserror::Error)]
#[error("scenario error, key '{key}': {message}")]
pub struct SetupError {
    pub key: String,
    pub message: String,
}

fn setup_error(key: &str, message: &str) -> SetupError {
    SetupError {
        key: key.to_string(),
        message: message.to_string(),
    }
}

pub fn build_simulation(scn: &Scenario) -> Result<Simulation, SetupError> {
    if scn.model.layers > 1 && scn.model.pressure == Pressure::NonHydrostatic {
        return Err(setup_error(
            "model.pressure",
            "the multilayer non-hydrostatic model (layers > 1 with \"nonhydrostatic\") is not available yet",
        ));
    }
    if scn.domain.coordinates == Coordinates::Cartesian && scn.domain.slope_deg != 0.0 {
        return Err(setup_error(
            "domain.slope_deg",
            "must be 0 with coordinates = \"cartesian\": the slope belongs in bed.b",
        ));
    }
    let d = &scn.domain;
    let spec = MeshSpec {
        x_min: d.x_min,
        x_max: d.x_max,
        cells: d.cells,
        slope_deg: d.slope_deg,
        coordinates: d.coordinates,
        left: scn.boundary.left,
        right: scn.boundary.right,
    };
    let x = spec.centres();
    let b: Vec<f64> = x.iter().map(|&x| scn.bed.eval(x, 0.0)).collect();
    let h_i = scn.initial.erodible_bed;
    let h: Vec<f64> = x
        .iter()
        .zip(&b)
        .map(|(&x, &b)| scn.initial.h.eval(x, b) + h_i)
        .collect();
    let u: Vec<f64> = x
        .iter()
        .zip(&b)
        .map(|(&x, &b)| scn.initial.u.eval(x, b))
        .collect();
    let w = sample_normal_velocity(scn, &x, &b);
    let mesh = Mesh::new(&spec, b);
    let mut state = State::from_profiles(&mesh, &scn.multilayer.layer_fractions, &h, &u);
    let stages = match scn.model.pressure {
        Pressure::Hydrostatic => {
            if w.is_some() {
                return Err(setup_error(
                    "initial.w",
                    "a normal velocity needs model.pressure = \"nonhydrostatic\"",
                ));
            }
            pipeline::hydrostatic(&scn.friction, &scn.material, d.cells, &scn.multilayer)
        }
        Pressure::NonHydrostatic => nonhydrostatic(scn, &mesh, &mut state, w),
    };
    let config = RunConfig {
        t_end: scn.time.t_end,
        cfl: scn.time.cfl,
        stop_at_rest: scn.time.stop_at_rest,
        output_every: scn.output.every,
        front_threshold: scn.output.front_threshold,
    };
    let info = RunInfo {
        granflow_version: env!("CARGO_PKG_VERSION").to_string(),
        model: "granular".to_string(),
        pressure: match scn.model.pressure {
            Pressure::Hydrostatic => "hydrostatic",
            Pressure::NonHydrostatic => "nonhydrostatic",
        }
        .to_string(),
        layers: scn.model.layers,
        coordinates: match d.coordinates {
            Coordinates::Local => "local",
            Coordinates::Cartesian => "cartesian",
        }
        .to_string(),
        slope_deg: d.slope_deg,
        scenario_toml: scn.source_toml.clone(),
        front_threshold: scn.output.front_threshold,
    };
    let mut sim = Simulation::new(mesh, state, vec![h_i; d.cells], stages, config, info);
    sim.static_threshold = scn.multilayer.static_threshold;
    if scn.model.layers > 1 {
        sim.rest_speed = scn.multilayer.static_threshold;
    }
    Ok(sim)
}

// Non-hydrostatic set-up (issue 3, seed 000).

/// `initial.w` at the cell centres, or `None` when it is zero everywhere.
fn sample_normal_velocity(scn: &Scenario, x: &[f64], b: &[f64]) -> Option<Vec<f64>> {
    if scn.initial.w.as_constant() == Some(0.0) {
        return None;
    }
    let w: Vec<f64> = x
        .iter()
        .zip(b)
        .map(|(&x, &b)| scn.initial.w.eval(x, b))
        .collect();
    w.iter().any(|&w| w != 0.0).then_some(w)
}

/// Adds the non-hydrostatic unknowns (hw = h w, p = 0) to the state and builds the
/// pipeline. An imposed normal velocity (the gate, seed 000 eq. 30) enters the first
/// step as it is, as in the paper (docs/numerics.md, "Initial normal velocity").
fn nonhydrostatic(
    scn: &Scenario,
    mesh: &Mesh,
    state: &mut State,
    w: Option<Vec<f64>>,
) -> Vec<Box<dyn crate::numerics::Stage>> {
    let w = w.unwrap_or_else(|| vec![0.0; mesh.nx]);
    state.nh = Some(NonHydrostatic::from_profile(state, &w));
    pipeline::nonhydrostatic_monolayer(&scn.friction, &scn.material, mesh)
}
