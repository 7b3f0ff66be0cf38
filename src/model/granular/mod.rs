//! The granular family of Garres-Díaz et al. 2021, Fernández-Nieto et al. 2016 and Escalante et al. 2023: one material in N layers of fixed
//! fractions ([`LayeredState`]).
//!
//! - `layers = 1`, hydrostatic: the Savage–Hutter model with Coulomb or μ(I) friction
//!   (Garres-Díaz et al. 2021, Remark 1): hyperbolic → friction.
//! - `layers = N > 1`, hydrostatic: the multilayer μ(I) model (Fernández-Nieto et al. 2016, eq. 27–28,
//!   Escalante et al. 2023, eq. 9 with p_nh = 0): hyperbolic → viscous.
//! - `layers = 1`, non-hydrostatic: the weakly non-hydrostatic model (Garres-Díaz et al. 2021,
//!   eq. 15): hyperbolic (hw as a tracer) → friction with the total pressure →
//!   projection.
//!
//! The pipelines are in [`pipeline`], the set-up from a scenario in
//! `setup/granular.rs`, the diagnostics in [`diagnostics`], the extra output of the multilayer model (normal
//! velocities, the static/flowing interface) in [`profiles`].

pub mod config;
pub mod diagnostics;
pub mod pipeline;
pub mod profiles;

use crate::grid::Line;
use crate::model::{Diagnostics, Model};
use crate::output::{CellField, OutputError, OutputSink, SnapshotView};
use crate::physics::shallow::velocity;
use crate::state::LayeredState;
use profiles::{normal_velocities, static_interface};

/// The granular model's run-time parameters (the physics of its stages is in the
/// pipeline).
#[derive(Debug, Clone)]
pub struct Granular {
    /// Initial erodible-bed thickness per cell (Fernández-Nieto et al. 2016, §4.2), zeros without one.
    pub h_bed: Vec<f64>,
    /// Thickness above the erodible bed from which a cell counts for the front (m).
    pub front_threshold: f64,
    /// Layer speed (m/s) above which a layer counts as flowing, for the multilayer
    /// output `/snapshots/static_interface` (default 1e-3 m/s, Fernández-Nieto et al. 2016, §4.2.5).
    pub static_threshold: f64,
    /// Largest speed (m/s) of a mass at rest, for the stop time and `stop_at_rest`: 0
    /// for the monolayer, which stops exactly; the multilayer model keeps regularised
    /// creep velocities (Escalante et al. 2023, Remark 2) and uses its static threshold.
    pub rest_speed: f64,
}

impl Model for Granular {
    type Grid = Line;
    type State = LayeredState;

    fn kind(&self) -> &'static str {
        "granular"
    }

    fn diagnose(&self, mesh: &Line, state: &LayeredState) -> Diagnostics {
        diagnostics::diagnose(mesh, state, &self.h_bed, self.front_threshold)
    }

    fn rest_speed(&self) -> f64 {
        self.rest_speed
    }

    fn fastest_cell(&self, _mesh: &Line, state: &LayeredState) -> Option<usize> {
        diagnostics::fastest_cell(state)
    }

    fn bed_layer(&self) -> &[f64] {
        &self.h_bed
    }

    /// The top of the flow b + h and the flow thickness h.
    fn gauge_cell(&self, mesh: &Line, state: &LayeredState, i: usize) -> Option<(f64, f64)> {
        let h = state.h[i + 1];
        Some((mesh.b[i] + h, h))
    }

    fn snapshot(
        &self,
        mesh: &Line,
        state: &LayeredState,
        t: f64,
        sink: &mut dyn OutputSink,
    ) -> Result<(), OutputError> {
        let (nx, n) = (mesh.nx, state.layers);
        let mut u = vec![0.0; n * nx];
        for i in 0..nx {
            let h = state.h[i + 1];
            for a in 0..n {
                u[a * nx + i] = velocity(h, state.hu[(i + 1) * n + a]);
            }
        }
        let nh = state.nh.as_ref().map(|nh| nh.snapshot_fields(state));
        // The multilayer model also reports its normal velocities (Fernández-Nieto et al. 2016, eq. 20)
        // and the flow/no-flow interface.
        let (w_ml, interface) = if n > 1 {
            let mut w = vec![0.0; n * nx];
            normal_velocities(mesh, state, &mut w);
            let mut interface = vec![0.0; nx];
            static_interface(state, self.static_threshold, &mut interface);
            (Some(w), interface)
        } else {
            (None, Vec::new())
        };
        let extra = [CellField {
            name: "static_interface",
            units: "m",
            description: "elevation of the interface between the static and the flowing grains",
            data: &interface,
        }];
        sink.snapshot(&SnapshotView {
            t,
            h: state.h_interior(),
            u: &u,
            v: None,
            shape: None,
            w: nh.as_ref().map(|(w, _)| w.as_slice()).or(w_ml.as_deref()),
            p_nh: nh.as_ref().map(|(_, p)| p.as_slice()),
            layers: n,
            extra: if n > 1 { &extra } else { &[] },
            layer_uv: None,
        })
    }
}
