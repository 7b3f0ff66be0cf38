//! From a validated [`Scenario`] with `model.kind = "dilatant"` to a ready
//! [`Simulation`] of the dilatant model (Bouchut et al. 2021): samples h, u and φ at the cell
//! centres and builds the one-stage pipeline. Everything that can be wrong with the
//! scenario was refused by its validation.

use crate::grid::Line;
use crate::model::dilatant::{Dilatant, DilatantScheme, REST_SPEED};
use crate::numerics::dilatant::heun::HeunSplit;
use crate::numerics::dilatant::split::SplitScheme;
use crate::numerics::dilatant::step::SchemeKind;
use crate::numerics::Stage;
use crate::pipeline::Pipeline;
use crate::scenario::Scenario;
use crate::setup::{run_config, run_info, scenario_line};
use crate::simulation::Simulation;
use crate::state::dilatant::DilatantState;

pub fn build(scn: &Scenario) -> Simulation<Dilatant> {
    let spec = scn
        .dilatancy
        .expect("validation requires [dilatancy] for model.kind = \"dilatant\"");
    let phi = scn
        .sampled
        .phi
        .as_ref()
        .expect("validation requires initial.phi for model.kind = \"dilatant\"");
    let mesh = scenario_line(scn);
    let (h, u) = (&scn.sampled.h, &scn.sampled.u);
    let state = DilatantState::from_profiles(&mesh, spec.options.flux.alpha, h, u, phi);
    let (stage, rest_depth, rest_speed): (Box<dyn Stage<Line, DilatantState>>, f64, f64) =
        match spec.options.scheme {
            SchemeKind::Split => {
                let (law, opt, nx, phi) = (spec.law, spec.options, mesh.nx, scn.material.phi);
                // Order 2: Heun's method around the split step with the second-order
                // reconstruction (validation allows it for the split scheme only).
                let scheme: Box<dyn Stage<Line, DilatantState>> = if scn.numerics.order == 2 {
                    Box::new(HeunSplit::new(law, opt, nx, phi, scn.numerics.limiter))
                } else {
                    Box::new(SplitScheme::new(law, opt, nx, phi))
                };
                // K = 0: the Savage–Hutter run's exact rest (bit for bit). K > 0: a mass
                // near its static threshold μ_1 + K(φ − φ_stat) compacts as it creeps and
                // comes to rest only asymptotically (backward-Euler friction, split.rs),
                // so rest is as for the Appendix B scheme.
                let (depth, speed) = if spec.law.k == 0.0 {
                    (0.0, 0.0)
                } else {
                    (spec.law.d, REST_SPEED)
                };
                (scheme, depth, speed)
            }
            SchemeKind::AppendixB => (
                Box::new(DilatantScheme::new(spec.law, spec.options, mesh.nx)),
                spec.law.d,
                REST_SPEED,
            ),
        };
    let model = Dilatant {
        h_bed: vec![0.0; mesh.nx],
        front_threshold: scn.output.front_threshold,
        rest_depth,
        rest_speed,
    };
    let info = run_info(scn, "hydrostatic", 1);
    let rules = crate::stop::default_rules(super::stop_options(
        scn,
        mesh.z[1..=mesh.nx].iter().copied(),
    ));
    let pipeline = Pipeline::new(vec![stage]);
    Simulation::new(mesh, model, state, pipeline, rules, run_config(scn), info)
}
