//! The dilatant μ(I)–φ model of Bouchut et al. 2021 (`model.kind = "dilatant"`): one granular
//! layer whose solid volume fraction φ evolves with the dilatancy law (eq. 2.2–2.15).
//! Its state is [`DilatantState`] ((h, hv, φ), and (φh, φhv, φ^α h) for the Appendix B
//! scheme), its time step a single stage: `numerics/dilatant/split.rs` by default (the
//! Savage–Hutter μ(I) step with φ carried by its mass fluxes, then the dilatant terms),
//! or [`DilatantScheme`] (Bouchut et al. 2021, §3: Appendix B fluxes → stabilisation → dilatancy)
//! with `dilatancy.scheme = "appendix_b"`; its set-up `setup/dilatant.rs`.
//!
//! Diagnostics: `mass` is the grain volume ∫φh dx (conserved), the kinetic energy
//! ∫½ φh v² dx, the others the monolayer's (same operations); the largest speed counts
//! cells at least `rest_depth` thick; snapshots carry φ per cell as the extra field
//! `phi`.

use crate::grid::Line;
use crate::model::{Diagnostics, Model};
use crate::output::{CellField, OutputError, OutputSink, SnapshotView};
use crate::physics::shallow::{celerity, velocity};
use crate::state::dilatant::DilatantState;

pub use crate::numerics::dilatant::step::{DilatantOptions, DilatantScheme};
pub use crate::physics::dilatancy::DilatantLaw;

/// The validated `[dilatancy]` table with the μ(I) and wall keys of `[rheology]`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DilatantSpec {
    pub law: DilatantLaw,
    pub options: DilatantOptions,
}

/// Largest speed (m/s) of a mass that counts as at rest.
pub const REST_SPEED: f64 = 1e-6;

/// Run-time parameters of the dilatant model.
#[derive(Debug, Clone)]
pub struct Dilatant {
    /// Zeros: the model has no erodible bed.
    pub h_bed: Vec<f64>,
    /// Thickness from which a cell counts for the front (m).
    pub front_threshold: f64,
    /// Thickness (m) below which a cell's speed does not count for the rest test: 0 for
    /// the split scheme with K = 0 (every cell counts, as in the monolayer), the grain
    /// diameter d for the Appendix B scheme, whose stabilisation viscosity (Bouchut et al. 2021,
    /// eq. 3.20) spreads films of ~1e-10 m ahead of a deposit that keep a speed of
    /// order 0.1 m/s (Bouchut et al. 2021, §3.3 calls layers thinner than a few grains physically
    /// meaningless), and for the split scheme with K > 0, whose front films (tens of µm,
    /// φ ≈ 0.5) compact while they creep and slow down only exponentially.
    pub rest_depth: f64,
    /// Largest speed of a mass at rest (m/s).
    pub rest_speed: f64,
}

impl Model for Dilatant {
    type Grid = Line;
    type State = DilatantState;

    fn kind(&self) -> &'static str {
        "dilatant"
    }

    /// The monolayer's diagnostics (`model/granular/diagnostics.rs`, N = 1) with the
    /// same operations, so that a K = 0 run takes the Savage–Hutter run's time steps,
    /// plus the grain volume ∫φh as `mass`. Cells thinner than `rest_depth` do not count
    /// for the largest speed.
    fn diagnose(&self, mesh: &Line, s: &DilatantState) -> Diagnostics {
        let nx = s.nx;
        let (mut mass, mut ke, mut q_sum, mut max_speed, mut h_max) =
            (0.0, 0.0, 0.0, 0.0f64, 0.0f64);
        let mut cell_max = 0.0f64;
        let mut front = None;
        let cells = s.h[1..=nx].iter().zip(&s.hu[1..=nx]).zip(&s.phi[1..=nx]);
        for (i, ((&h, &q), &phi)) in cells.enumerate() {
            mass += phi * h;
            h_max = h_max.max(h);
            q_sum += q;
            let u = velocity(h, q);
            ke += phi * h * u * u;
            if h >= self.rest_depth {
                max_speed = max_speed.max(u.abs());
            }
            cell_max = cell_max.max(u.abs() + celerity(mesh.g_n, h));
            if h > self.front_threshold {
                front = Some(i);
            }
        }
        let non_finite_at = if (mass + q_sum).is_finite() {
            None
        } else {
            (1..=nx)
                .position(|j| !(s.h[j].is_finite() && s.hu[j].is_finite() && s.phi[j].is_finite()))
                .or(Some(0))
        };
        Diagnostics {
            mass: mass * mesh.dx,
            kinetic_energy: 0.5 * ke * mesh.dx,
            max_speed,
            signal_speed: cell_max,
            front_x: front.map_or(f64::NAN, |i| mesh.x[i]),
            h_max,
            non_finite_at,
            wet_cells: None,
        }
    }

    /// 0 for the split scheme with K = 0, whose friction step stops a mass exactly (as
    /// the monolayer's); [`REST_SPEED`] for the Appendix B scheme, whose
    /// apparent-topography friction (Bouchut et al. 2021, eq. 3.10) stops it to round-off, and for
    /// the split scheme with K > 0, where a mass that creeps near its static threshold
    /// compacts and stops only asymptotically (backward-Euler friction, `split.rs`).
    fn rest_speed(&self) -> f64 {
        self.rest_speed
    }

    fn bed_layer(&self) -> &[f64] {
        &self.h_bed
    }

    /// The top of the mixture b + h and its thickness h, as for the granular model.
    fn gauge_cell(&self, mesh: &Line, s: &DilatantState, i: usize) -> Option<(f64, f64)> {
        Some((mesh.b[i] + s.h[i + 1], s.h[i + 1]))
    }

    fn snapshot(
        &self,
        _mesh: &Line,
        s: &DilatantState,
        t: f64,
        sink: &mut dyn OutputSink,
    ) -> Result<(), OutputError> {
        let nx = s.nx;
        let u: Vec<f64> = (1..=nx).map(|j| velocity(s.h[j], s.hu[j])).collect();
        let extra = [CellField {
            name: "phi",
            units: "1",
            description: "solid volume fraction of the grains",
            data: &s.phi[1..=nx],
        }];
        sink.snapshot(&SnapshotView {
            t,
            h: &s.h[1..=nx],
            u: &u,
            v: None,
            shape: None,
            w: None,
            p_nh: None,
            layers: 1,
            extra: &extra,
            layer_uv: None,
        })
    }
}
