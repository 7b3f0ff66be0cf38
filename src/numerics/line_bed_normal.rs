//! Step 1 on a line in the bed-normal frame (`domain.coordinates = "bed_normal"`,
//! docs/numerics.md, "The bed-normal frame"; Bouchut & Westdickenberg 2004): the
//! raster's system reduced to one horizontal dimension x over the bed z = b(x), for
//! H = h/c (volume per horizontal length, h the thickness normal to the bed,
//! c = cos θ = 1/√(1 + b_x²)) and the horizontal discharge H u:
//!
//!   ∂_t H + ∂_x(H u) = 0,
//!   ∂_t(H w) + ∂_x(H w u) = −g c H ∂_x(c H) − g H b_x + H b_x b_xx u² − H F w/|U|,
//!
//! with w = (1 + b_x²) u = u/c² the covariant velocity, |U| = |u|/c the speed along
//! the bed and F the friction per unit mass (μ c (g + b_xx u²)₊ for Coulomb; step 2,
//! [`super::friction::BedNormalFrictionStep`]). On a
//! plane of slope θ this is the local frame over that plane with ∂_X = c ∂_x
//! (docs/numerics.md).
//!
//! The scheme is the raster's ([`super::hydrostatic_2d`]) on one row: every face is
//! `bed_normal::face` (the 1-D face kernel with the face's gravity g c_f², potential
//! b/c_f², wave bounds with G⁻¹_xx = c_f², ΔC against the covariant drive with the
//! normal stress c_f (g + b_xx u²)₊, the drained-face upwinding) and every cell
//! `bed_normal::update` (lower, the faces' flat update, the geodesic term, raise,
//! the desingularised film velocity), the draining-time limiter (Bollermann et al.
//! 2013) as on a raster. Where the raster passes the y-quantities of a state
//! invariant in y (v = 0, b_y = 0, the tangential drive and momentum 0, its y-faces
//! zero) the line passes zeros, so a raster row invariant in y takes the same
//! operations on the same numbers: the same bits (`tests/line_bed_normal.rs`).
//! Ghost cells: the edge cell with the boundary's sign on its velocity and momentum,
//! over the line's ghost bed (a wall keeps the edge bed, an outflow continues its
//! slope); a ghost face takes its edge cell's geometry.

use super::bed_normal::{self, FaceFlux, FaceSide};
use super::face::{drained_fraction, Side};
use super::{Stage, StageError, StepClock};
use crate::grid::{BedMetric, Line};
use crate::physics::rheology::BasalFriction;
use crate::physics::shallow::{velocity, H_DRY};
use crate::state::layered::LayeredState;

/// The hydrostatic step of the monolayer on a bed-normal line.
#[derive(Debug)]
pub struct BedNormalLineStep<L: BasalFriction> {
    law: L,
    /// Per ghost-inclusive cell (nx + 2): the cell as its faces see it.
    sides: Vec<FaceSide>,
    /// Per face (nx + 1, face k between ghost-inclusive cells k and k + 1).
    faces: Vec<FaceFlux>,
    /// Per cell (nx + 2, ghosts unused): the new state, unclipped thickness first.
    new: Vec<(f64, f64)>,
    /// Per ghost-inclusive cell: the draining factor θ (1 at the ghosts).
    drain: Vec<f64>,
}

impl<L: BasalFriction> BedNormalLineStep<L> {
    /// The step with friction law `law` (its ΔC threshold) on a line of `nx` cells.
    pub fn new(law: L, nx: usize) -> Self {
        let side = FaceSide {
            side: Side::monolayer(0.0, 0.0, 0.0, 0.0),
            t: 0.0,
            drive: 0.0,
            speed: 0.0,
            kappa: 0.0,
        };
        BedNormalLineStep {
            law,
            sides: vec![side; nx + 2],
            faces: vec![FaceFlux::default(); nx + 1],
            new: vec![(0.0, 0.0); nx + 2],
            drain: vec![1.0; nx + 2],
        }
    }
}

/// The side of ghost-inclusive cell `j` of a line of `nx` cells: interior cell
/// `j − 1`, or the edge cell with the boundary's `sign` on its normal velocity and
/// momentum (the raster's `covariant_side`), over the ghost-inclusive bed `b`. The
/// tangential momentum and drive are zero (v = 0, b_y = 0).
#[inline(always)]
fn side(m: &BedMetric, mesh: &Line, state: &LayeredState, j: usize) -> FaceSide {
    let nx = mesh.nx;
    let (cell, sign) = if j == 0 {
        (0, mesh.left.discharge_sign())
    } else if j == nx + 1 {
        (nx - 1, mesh.right.discharge_sign())
    } else {
        (j - 1, 1.0)
    };
    let h = state.h[cell + 1];
    let u = velocity(h, state.hu[cell + 1]);
    let (w, _) = m.lower(cell, u, 0.0);
    let b = mesh.b_ghost[j];
    FaceSide {
        side: Side {
            h,
            u: sign * u,
            b,
            z: b,
            shear: 0.0,
            u_base: sign * w,
            sqrt_h: h.max(0.0).sqrt(),
        },
        t: 0.0,
        drive: 0.0,
        speed: m.speed(cell, u, 0.0),
        kappa: m.normal_curvature(cell, u, 0.0),
    }
}

impl<L: BasalFriction> BedNormalLineStep<L> {
    /// The new state of every cell from the faces (times their donors' draining
    /// factors where `limited`); returns the smallest unclipped thickness and its
    /// ghost-inclusive cell, first in cell order.
    fn update(
        &mut self,
        m: &BedMetric,
        state: &LayeredState,
        (dt, r): (f64, f64),
        limited: bool,
    ) -> (f64, usize) {
        let nx = self.faces.len() - 1;
        let mut worst = (f64::INFINITY, 1usize);
        for j in 1..=nx {
            let (mut w, mut e) = (self.faces[j - 1], self.faces[j]);
            if limited {
                let donor = |f: &FaceFlux, k: usize| if f.h > 0.0 { k } else { k + 1 };
                w = w.drained(self.drain[donor(&w, j - 1)]);
                e = e.drained(self.drain[donor(&e, j)]);
            }
            let old = (state.h[j], state.hu[j], 0.0);
            let (hn, qu, _) = bed_normal::update(m, j - 1, old, dt, |lowered| {
                flat_update(lowered, r, [&w, &e])
            });
            self.new[j] = (hn, qu);
            if hn < worst.0 {
                worst = (hn, j);
            }
        }
        worst
    }
}

/// The raster's update of one cell (its `update_cell`) from its old state and its
/// west and east faces, `rx` = Δt/Δx: (unclipped new thickness, H w_x, H w_y). On a
/// raster row invariant in y the y-faces' terms are exact zeros, and adding a zero
/// changes no number: the same bits.
#[inline(always)]
fn flat_update(
    (h_old, hu_old, hv_old): (f64, f64, f64),
    rx: f64,
    [w, e]: [&FaceFlux; 2],
) -> (f64, f64, f64) {
    let hn = h_old - rx * (e.h - w.h);
    // Clip round-off below zero; `f64::max` would also turn a NaN into 0.
    let h = if hn < 0.0 { 0.0 } else { hn };
    let drained = drained_fraction(h, h_old);
    let source = e.share_l + w.share_r - (e.body_l + w.body_r) * drained;
    let qu = hu_old - rx * (e.qn - w.qn + source);
    if h <= H_DRY {
        (hn, 0.0, 0.0)
    } else {
        (hn, qu, hv_old)
    }
}

impl<L: BasalFriction> Stage<Line, LayeredState> for BedNormalLineStep<L> {
    fn name(&self) -> &'static str {
        "hyperbolic"
    }

    fn apply(
        &mut self,
        mesh: &Line,
        clock: StepClock,
        state: &mut LayeredState,
    ) -> Result<(), StageError> {
        let dt = clock.dt;
        debug_assert_eq!(state.layers, 1);
        let m = mesh.metric().expect("a bed-normal line");
        let nx = mesh.nx;
        let r = dt / mesh.dx;
        for j in 0..nx + 2 {
            self.sides[j] = side(m, mesh, state, j);
        }
        let law = self.law;
        for k in 0..=nx {
            // The face's cells; a ghost takes its edge cell.
            let (cl, cr) = (k.clamp(1, nx) - 1, (k + 1).clamp(1, nx) - 1);
            let (l, rt) = (&self.sides[k], &self.sides[k + 1]);
            let (cos, slopes) = ((m.cos[cl], m.cos[cr]), (m.gy[cl], m.gy[cr]));
            self.faces[k] = bed_normal::face(l, rt, cos, slopes, |_| law, None, (mesh.dx, dt));
        }
        let mut worst = self.update(m, state, (dt, r), false);
        if worst.0 < 0.0 {
            // The draining factors θ = min(1, H/(Δt outflow)) of the unlimited faces,
            // then every outgoing flux times its donor's θ.
            for j in 1..=nx {
                let (w, e) = (&self.faces[j - 1], &self.faces[j]);
                let need = r * (e.h.max(0.0) + (-w.h).max(0.0));
                let h = state.h[j];
                self.drain[j] = if need > h { h.max(0.0) / need } else { 1.0 };
            }
            worst = self.update(m, state, (dt, r), true);
            self.drain.fill(1.0);
        }
        let tolerance = -1e-14 * (1.0 + state.h[worst.1].abs());
        if worst.0 < tolerance {
            return Err(StageError::NegativeThickness {
                cell: worst.1 - 1,
                h: worst.0,
            });
        }
        for j in 1..=nx {
            let (hn, q) = self.new[j];
            state.h[j] = if hn < 0.0 { 0.0 } else { hn };
            state.hu[j] = q;
        }
        state.fill_ghosts(mesh);
        Ok(())
    }
}
