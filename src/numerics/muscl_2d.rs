//! The second-order reconstruction (`numerics.order = 2`) of the 2-D hydrostatic step
//! ([`super::hydrostatic_2d`]): the line's MUSCL reconstruction inside the hydrostatic
//! reconstruction ([`super::muscl`], van Leer 1979, Audusse et al. 2004, §3) applied
//! dimension by dimension. An x-face sees the edge values of its two cells from their
//! limited slopes along x, a y-face those from the slopes along y:
//!
//!   w_{i±1/2,j} = w_ij ± ½ σˣ_ij,   σˣ_ij = φ(w_ij − w_{i−1,j}, w_{i+1,j} − w_ij),
//!   w_{i,j±1/2} = w_ij ± ½ σʸ_ij,   σʸ_ij = φ(w_ij − w_{i,j−1}, w_{i,j+1} − w_ij),
//!
//! for w ∈ {h, u_n, u_t, η}: the thickness, the velocity normal to the faces (u for
//! the x-faces, v for the y-faces), the tangential one (carried by the mass flux) and
//! the surface η = h + b over the reference plane (in the bed-normal frame H + b, H the
//! thickness per horizontal area and b the bed's elevation). The slopes along x see no
//! variation along y (and the reverse): the reconstruction is second order for the
//! fluxes of each direction, as the unsplit update needs, without the cross terms of a
//! genuinely multi-dimensional one.
//!
//! Each cell adds, per direction, the pressure force of its own interior between its
//! two edges (Audusse et al. 2004, eq. 3.9; [`super::muscl::interior_source`]):
//!
//!   𝓢ˣ_ij = g_n ½(h_W + h_E)(η_E − η_W)
//!
//! in the flat frames, and in the bed-normal frame the covariant pressure and gravity
//! of the faces' kernel with the cell's own c = cos of the bed's slope,
//!
//!   𝓢ˣ_ij = g c² ½(H_W + H_E)(H_E − H_W) + g ½(H_W + H_E)(b_E − b_W),
//!
//! whose first part, as the faces' g c_f² H̄ ΔH, is the pressure (the flat-bed part).
//!
//! The first-order rules of the line hold per direction. A cell is first order in both
//! directions where it is dry or slower than its static friction's impulse per step,
//! |u| ≤ Δt μ_s g_n (this covers the cell at rest), and first order along an axis where
//! a neighbour along that axis is dry. An edge is reconstructed only where both cells
//! of its face are (mixed faces), a reconstructed cell's interior force runs from its
//! other edge to its mean where one neighbour along the axis is first order, and ΔC
//! decides from the drive between the cell centres. A wall at the raster's edge
//! mirrors the slopes of its edge cell, an outflow is first order, and a wall cell
//! inside the raster is dry: its faces are first order.
//!
//! The slopes are computed once per stage for the cells of the stepped tiles
//! (`state::tiles`), before the faces; a cell outside them is dry (not live), which
//! the faces test first, so that stale slopes are never read.

use super::muscl::Limiter;
use crate::physics::shallow::H_DRY;
use crate::physics::GRAVITY;

/// A cell as the reconstruction along one axis reads it: thickness, normal and
/// tangential velocity (0 where dry) and surface η = h + b.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Mean {
    pub h: f64,
    pub n: f64,
    pub t: f64,
    pub eta: f64,
}

/// Limited slopes (differences across one cell) of h, the normal and tangential
/// velocities and η along one axis.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AxisSlopes {
    pub h: f64,
    pub n: f64,
    pub t: f64,
    pub eta: f64,
}

impl AxisSlopes {
    /// The slopes of a cell's mirror image across a wall (its ghost: the same depth,
    /// surface and tangential velocity, the normal velocity reversed).
    #[inline(always)]
    pub fn mirrored(self) -> AxisSlopes {
        AxisSlopes {
            h: -self.h,
            n: self.n,
            t: -self.t,
            eta: -self.eta,
        }
    }
}

/// The slopes of `cell` along an axis from its neighbours `prev` and `next` on it, or
/// `None` where one of the three is dry (the cell is first order along the axis). The
/// same operations as [`super::muscl::slopes`] for h, u_n and η.
#[inline(always)]
pub fn axis_slopes(limiter: Limiter, prev: Mean, cell: Mean, next: Mean) -> Option<AxisSlopes> {
    if cell.h <= H_DRY || prev.h <= H_DRY || next.h <= H_DRY {
        return None;
    }
    Some(AxisSlopes {
        h: limiter.slope(cell.h - prev.h, next.h - cell.h),
        n: limiter.slope(cell.n - prev.n, next.n - cell.n),
        t: limiter.slope(cell.t - prev.t, next.t - cell.t),
        eta: limiter.slope(cell.eta - prev.eta, next.eta - cell.eta),
    })
}

/// The value at the lower (`upper` false: west or south) or upper edge of `cell` with
/// slopes `s`: w ∓ ½σ, the depth clipped at 0 against round-off (as
/// [`super::muscl::edges`]).
#[inline(always)]
pub fn edge(cell: Mean, s: AxisSlopes, upper: bool) -> Mean {
    let (dh, dn, dt, de) = (0.5 * s.h, 0.5 * s.n, 0.5 * s.t, 0.5 * s.eta);
    if upper {
        Mean {
            h: (cell.h + dh).max(0.0),
            n: cell.n + dn,
            t: cell.t + dt,
            eta: cell.eta + de,
        }
    } else {
        Mean {
            h: (cell.h - dh).max(0.0),
            n: cell.n - dn,
            t: cell.t - dt,
            eta: cell.eta - de,
        }
    }
}

/// The interior pressure force of a cell between its `lower` and `upper` edges along
/// one axis, and its gravity part (module documentation): with `bed_normal` =
/// Some(c²) the bed-normal frame's, else the flat frames' with gravity `g_n`.
#[inline(always)]
pub fn interior_force(g_n: f64, bed_normal: Option<f64>, lower: Mean, upper: Mean) -> (f64, f64) {
    match bed_normal {
        None => super::muscl::interior_source(
            g_n,
            super::muscl::Edge {
                h: lower.h,
                u: lower.n,
                eta: lower.eta,
            },
            super::muscl::Edge {
                h: upper.h,
                u: upper.n,
                eta: upper.eta,
            },
        ),
        Some(c2) => {
            let g_hbar = GRAVITY * 0.5 * (lower.h + upper.h);
            let pressure = c2 * g_hbar * (upper.h - lower.h);
            let body = g_hbar * ((upper.eta - upper.h) - (lower.eta - lower.h));
            (pressure + body, body)
        }
    }
}

/// The slopes of a stage: per cell (row-major) along x and along y, `None` where first
/// order. Only the entries of the cells of the stepped tiles are current.
#[derive(Debug, Clone)]
pub struct Reconstruction {
    pub limiter: Limiter,
    pub x: Vec<Option<AxisSlopes>>,
    pub y: Vec<Option<AxisSlopes>>,
}

impl Reconstruction {
    /// The (not yet computed) slopes of `cells` cells with `limiter`.
    pub fn new(limiter: Limiter, cells: usize) -> Reconstruction {
        Reconstruction {
            limiter,
            x: vec![None; cells],
            y: vec![None; cells],
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::numerics::muscl;

    #[test]
    fn the_normal_part_is_the_line_reconstruction_to_the_bit() {
        let m = |h: f64, u: f64, eta: f64| Mean {
            h,
            n: u,
            t: 0.3,
            eta,
        };
        let c = |h: f64, u: f64, eta: f64| muscl::Cell { h, u, eta };
        let data = [(1.0, 0.2, 1.5), (1.3, 0.5, 1.7), (1.4, 0.55, 2.2)];
        for lim in [Limiter::Minmod, Limiter::VanLeer, Limiter::Mc] {
            let [a, b, d] = data.map(|(h, u, e)| m(h, u, e));
            let [p, q, r] = data.map(|(h, u, e)| c(h, u, e));
            let s2 = axis_slopes(lim, a, b, d).unwrap();
            let s1 = muscl::slopes(lim, p, q, r).unwrap();
            assert_eq!((s2.h, s2.n, s2.eta), (s1.h, s1.u, s1.eta));
            assert_eq!(s2.t, 0.0);
            let (w, e) = muscl::edges(q, s1);
            let (w2, e2) = (edge(b, s2, false), edge(b, s2, true));
            assert_eq!((w2.h, w2.n, w2.eta), (w.h, w.u, w.eta));
            assert_eq!((e2.h, e2.n, e2.eta), (e.h, e.u, e.eta));
            assert_eq!(
                interior_force(9.81, None, w2, e2),
                muscl::interior_source(9.81, w, e)
            );
        }
    }

    #[test]
    fn a_dry_neighbour_makes_the_axis_first_order_and_mirroring_reverses_the_normal() {
        let wet = Mean {
            h: 1.0,
            n: 0.1,
            t: 0.2,
            eta: 1.0,
        };
        let dry = Mean::default();
        assert!(axis_slopes(Limiter::Mc, dry, wet, wet).is_none());
        let s = AxisSlopes {
            h: 0.1,
            n: 0.2,
            t: 0.3,
            eta: 0.4,
        };
        let g = s.mirrored();
        // The ghost's upper edge is the mirror of the cell's lower edge.
        let ghost = Mean { n: -wet.n, ..wet };
        let (ge, cw) = (edge(ghost, g, true), edge(wet, s, false));
        assert_eq!((ge.h, ge.n, ge.t, ge.eta), (cw.h, -cw.n, cw.t, cw.eta));
    }

    #[test]
    fn the_bed_normal_interior_force_on_a_flat_bed_is_the_pressure() {
        let (w, e) = (
            Mean {
                h: 1.0,
                n: 0.0,
                t: 0.0,
                eta: 3.0,
            },
            Mean {
                h: 1.2,
                n: 0.0,
                t: 0.0,
                eta: 3.2,
            },
        );
        let (s, body) = interior_force(0.0, Some(0.81), w, e);
        assert_eq!(body, 0.0);
        assert!((s - 0.81 * GRAVITY * 1.1 * 0.2).abs() < 1e-14);
    }
}
