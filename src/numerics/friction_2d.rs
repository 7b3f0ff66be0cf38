//! Step 2 on a raster: the basal friction with the vector Coulomb rule,
//!
//!   q* = (hu, hv)* after step 1,   σ = μ g_n h (Coulomb), the law's τ/ρ otherwise,
//!   q ← 0                               if Δt μ_s g_n h ≥ |q*|  (static: a disk),
//!   q ← q* |q|/|q*|                     otherwise,
//!
//! with |q| the law's scalar friction update of the monolayer (`numerics::friction`:
//! Coulomb semi-implicit, μ(I) and Voellmy backward Euler in the speed) applied to the
//! magnitude |q*|: friction acts against the velocity and never turns it. The static
//! threshold is a disk |τ| ≤ μ p in the (x, y) plane, not the square |τ_x|, |τ_y| ≤ μ p
//! of a dimensionally split step: a mass on a bed sloping (a, a) with a < μ < √2 a
//! must move (|∇z| = √2 a > μ), and does. Where one component is zero the scalar rule
//! acts on the other (the same operations as the 1-D step, so a flow invariant in y
//! reproduces the line to the bit).
//!
//! Friction zones ([`CellFriction`]): where the scenario gives μ (or Voellmy's ξ) as a
//! field, every cell carries its own law and the rule above uses the cell's; a
//! uniform law is stored once and the loop is the one without zones.
//!
//! In the bed-normal frame ([`bed_normal_friction`]) the same rule acts on the speed
//! along the surface |U| = √(uᵀ G u) of the horizontal velocity u = (hu, hv)/H, with
//! the normal thickness h = c H and the basal normal stress per unit mass
//! g_N = c (g + uᵀ∇²b u)₊ (gravity's normal part and the centrifugal part of the
//! bed's curvature, zero where the flow would leave the bed; Bouchut & Westdickenberg
//! 2004, the Coulomb term; docs/numerics.md): friction acts against the tangent
//! velocity, so it scales u and keeps its direction.

use super::workers::{Disjoint, Workers};
use super::{Stage, StageError, StepClock};
use crate::grid::{BedMetric, Raster2d};
use crate::physics::rheology::BasalFriction;
use crate::physics::shallow::H_DRY;
use crate::physics::GRAVITY;
use crate::state::State2d;
use std::sync::Arc;

/// The basal friction law of every cell of a raster: one law for all (`Uniform`), or
/// one per cell (`PerCell`, row-major, friction zones), shared by the stages.
#[derive(Debug, Clone)]
pub enum CellFriction<L: BasalFriction> {
    Uniform(L),
    PerCell(Arc<[L]>),
}

impl<L: BasalFriction> CellFriction<L> {
    /// The law of cell `cell` (row-major).
    #[inline(always)]
    pub fn at(&self, cell: usize) -> L {
        match self {
            CellFriction::Uniform(law) => *law,
            CellFriction::PerCell(laws) => laws[cell],
        }
    }
}

/// The vector friction step of the 2-D monolayer.
#[derive(Debug)]
pub struct FrictionStep2d<L: BasalFriction> {
    friction: CellFriction<L>,
    workers: Workers,
}

impl<L: BasalFriction> FrictionStep2d<L> {
    /// The step with one friction law `law`.
    pub fn new(law: L, workers: Workers) -> Self {
        Self::with_friction(CellFriction::Uniform(law), workers)
    }

    /// The step with the friction of every cell (friction zones).
    pub fn with_friction(friction: CellFriction<L>, workers: Workers) -> Self {
        FrictionStep2d { friction, workers }
    }
}

/// The discharge (qx, qy) after the friction step of a cell of thickness `h`.
#[inline(always)]
pub fn vector_friction<L: BasalFriction>(
    law: &L,
    qx: f64,
    qy: f64,
    h: f64,
    dt: f64,
    g_n: f64,
) -> (f64, f64) {
    if qx == 0.0 && qy == 0.0 {
        return (qx, qy);
    }
    if h <= H_DRY {
        return (0.0, 0.0);
    }
    if qy == 0.0 {
        return (law.friction_update(qx, h, dt, g_n), qy);
    }
    if qx == 0.0 {
        return (qx, law.friction_update(qy, h, dt, g_n));
    }
    let q = qx.hypot(qy);
    let q_new = law.friction_update(q, h, dt, g_n);
    let scale = q_new / q;
    (qx * scale, qy * scale)
}

/// The discharge (H u, H v) after the friction step of cell `k` in the bed-normal
/// frame, with H its thickness per horizontal area (module documentation).
#[inline(always)]
pub fn bed_normal_friction<L: BasalFriction>(
    law: &L,
    m: &BedMetric,
    k: usize,
    (qx, qy): (f64, f64),
    h: f64,
    dt: f64,
) -> (f64, f64) {
    if qx == 0.0 && qy == 0.0 {
        return (qx, qy);
    }
    if h <= H_DRY {
        return (0.0, 0.0);
    }
    let (u, v) = (qx / h, qy / h);
    let c = m.cos[k];
    let g_normal = c * (GRAVITY + m.normal_curvature(k, u, v)).max(0.0);
    let h_n = c * h;
    let q = h_n * m.speed(k, u, v);
    let scale = law.friction_update(q, h_n, dt, g_normal) / q;
    (qx * scale, qy * scale)
}

impl<L: BasalFriction> FrictionStep2d<L> {
    /// The discharge (hu, hv) = `q` of cell `k` of thickness `h` after the friction
    /// step of `dt` on `raster`: the rule of the module documentation, in the raster's
    /// frame, with the cell's law. The stage applies it to every cell of the stepped
    /// tiles; the order-1 hyperbolic step applies it as it writes its new state
    /// (`HydrostaticStep2d::then_friction`), with the same operations.
    #[inline(always)]
    pub fn cell(&self, raster: &Raster2d, k: usize, q: (f64, f64), h: f64, dt: f64) -> (f64, f64) {
        match (raster.metric(), &self.friction) {
            (Some(m), friction) => bed_normal_friction(&friction.at(k), m, k, q, h, dt),
            (None, CellFriction::Uniform(law)) => vector_friction(law, q.0, q.1, h, dt, raster.g_n),
            (None, CellFriction::PerCell(laws)) => {
                vector_friction(&laws[k], q.0, q.1, h, dt, raster.g_n)
            }
        }
    }
}

impl<L: BasalFriction> Stage<Raster2d, State2d> for FrictionStep2d<L> {
    fn name(&self) -> &'static str {
        "friction"
    }

    /// Over the stepped tiles only (`state::tiles`), one task per tile: a cell outside
    /// them holds no discharge, which the friction leaves as it is. The tiles it wrote
    /// are pending (a discharge it stops may leave a tile with no live cell).
    fn apply(
        &mut self,
        raster: &Raster2d,
        clock: StepClock,
        state: &mut State2d,
    ) -> Result<(), StageError> {
        let dt = clock.dt;
        state.ensure_tiles(raster.nx(), raster.ny());
        let State2d { h, hu, hv, tiles } = state;
        let (h, tiles) = (&*h, &*tiles);
        let (hu, hv) = (Disjoint::new(hu), Disjoint::new(hv));
        let this = &*self;
        self.workers.tiles(tiles.stepped_by_load(), |_, t| {
            for k in tiles.row_segments(t).flatten() {
                // SAFETY: cell k is in tile t, this task's alone.
                let q = unsafe { (hu.get(k), hv.get(k)) };
                let (qx, qy) = this.cell(raster, k, q, h[k], dt);
                // SAFETY: as above.
                unsafe {
                    hu.set(k, qx);
                    hv.set(k, qy);
                }
            }
        });
        state.tiles.mark_pending();
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::physics::rheology::{Coulomb, MuI, Voellmy};

    /// The static threshold is a disk: a drive of (a, a) with a < μ < √2 a moves.
    #[test]
    fn static_threshold_is_a_disk() {
        let law = Coulomb { mu: 0.5 };
        let (h, dt, g) = (0.2, 0.01, 9.81);
        let a = 0.4; // a < μ = 0.5 < √2 a = 0.566
        let q = dt * g * h * a;
        let (qx, qy) = vector_friction(&law, q, q, h, dt, g);
        assert!(qx > 0.0 && qy > 0.0, "a diagonal drive above μ moves");
        // The speed lost is Δt μ g h along the direction of q.
        let lost = 2f64.sqrt() * q - qx.hypot(qy);
        assert!((lost - dt * 0.5 * g * h).abs() < 1e-15);
        assert!((qx - qy).abs() < 1e-18);
        // Each component alone is held.
        assert_eq!(vector_friction(&law, q, 0.0, h, dt, g), (0.0, 0.0));
        assert_eq!(vector_friction(&law, 0.0, -q, h, dt, g), (0.0, 0.0));
    }

    #[test]
    fn the_rule_is_the_scalar_one_along_the_velocity() {
        let (h, dt, g) = (0.05, 1e-3, 9.0);
        let mui = MuI {
            mu_s: 0.4,
            mu_2: 0.6,
            i0: 0.3,
            d_s: 1e-3,
            phi: 0.6,
            shear: Default::default(),
        };
        let voellmy = Voellmy { mu: 0.3, xi: 400.0 };
        let angle = 0.7f64;
        let q = 0.2;
        let (qx, qy) = (q * angle.cos(), q * angle.sin());
        for (x, y, scalar) in [
            {
                let (x, y) = vector_friction(&mui, qx, qy, h, dt, g);
                (x, y, mui.friction_update(q, h, dt, g))
            },
            {
                let (x, y) = vector_friction(&voellmy, qx, qy, h, dt, g);
                (x, y, voellmy.friction_update(q, h, dt, g))
            },
        ] {
            assert!((x.hypot(y) - scalar).abs() < 1e-15);
            assert!((y.atan2(x) - angle).abs() < 1e-12);
        }
        // Dry cells lose their discharge; NaN propagates.
        assert_eq!(vector_friction(&mui, qx, qy, 0.0, dt, g), (0.0, 0.0));
        assert!(vector_friction(&mui, f64::NAN, qy, h, dt, g).0.is_nan());
    }
}
