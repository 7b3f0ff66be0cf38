//! Second-order reconstruction (MUSCL, van Leer 1979) inside the hydrostatic
//! reconstruction, in the well-balanced form of Audusse et al. 2004, §3: each cell
//! carries limited linear profiles of its depth h, its velocity u and its free surface
//! η = h + b (over the reference plane: the plane's own potential, linear along the
//! grid, keeps its cell values and its jumps at the faces, as at order 1), and a face
//! sees, instead of the two cell means, the two edge values
//!
//!   w_{i+1/2}⁻ = w_i + ½ σ_i^w,   w_{i−1/2}⁺ = w_i − ½ σ_i^w,   w ∈ {h, u, η},
//!   σ_i^w = φ(w_i − w_{i−1}, w_{i+1} − w_i)   (a difference across one cell),
//!
//! with the bed b = η − h at the edges. The face then runs the first-order face
//! kernel ([`super::face`]: hydrostatic reconstruction over the bed, Coulomb-aware ΔC,
//! HLL/PVM diffusion, own-depth split) on the two edge states, and every reconstructed
//! cell adds the pressure force of its own interior (Audusse et al. 2004, eq. 3.9, in
//! the path-conservative form of the first-order step):
//!
//!   𝓢_i^c = g_n ½(h_{i−1/2}⁺ + h_{i+1/2}⁻)(η_{i+1/2}⁻ − η_{i−1/2}⁺).
//!
//! Its flat-bed part g_n ½(h⁺ + h⁻)(h⁻ − h⁺) = g_n Δ(h²/2) telescopes with the faces'
//! flat-bed parts, so shocks keep their speed; over a lake at rest on a horizontal
//! reference plane (η constant) every σ^η vanishes, the edge η are the cell η, the
//! face kernel sees a lake at rest and 𝓢_i^c = 0: the scheme is well balanced (the
//! property Audusse et al. 2004 build it for). On an inclined plane of potential p
//! (local coordinates) a lake has η = C − p, linear, which the limiters reconstruct
//! exactly: each face sees no jump of h + b and the plane's jump Δp, of which the cell
//! takes ½ g_n h_edge Δp from each face, and the interior force −g_n ½(h_W + h_E) Δp
//! cancels them.
//!
//! Limiters φ(a, b) (all zero when a b ≤ 0; Sweby 1984 for their TVD region):
//! - minmod: sgn(a) min(|a|, |b|),
//! - van Leer: 2ab/(a + b),
//! - MC (monotonised central): sgn(a) min(2|a|, |a + b|/2, 2|b|).
//!
//! All three keep |½σ| ≤ min(|a|, |b|): an edge value lies between the cell's mean and
//! its neighbour's, so edge depths are ≥ 0 and edge speeds bounded by the neighbours'.
//!
//! A cell is reconstructed to first order (σ = 0, its edges are its mean, bit for bit)
//! where
//! - it or a neighbour is dry (h ≤ H_DRY): wet/dry fronts and shorelines keep the
//!   first-order treatment (emerging bed, clipping) that the face kernel was built for;
//! - it is at rest (u = 0 exactly), or (in the 1-D step) slower than its static
//!   friction's impulse per step, |u| ≤ Δt μ_s g_n: a mass at rest sees exactly the
//!   first-order step,
//!   whose Coulomb-aware ΔC and own-depth split hold every profile with
//!   |η_{i+1} − η_{i−1}| ≤ 2Δx μ_s (docs/numerics.md). A limited slope can exceed the
//!   two one-sided slopes' mean at a kink of the surface (minmod at slopes μ, μ, 0 gives
//!   the cell 1.25 μ), which would set moving a deposit that the physics holds.
//!
//! Mixed faces. An edge is reconstructed only where both cells of its face are; at a
//! face beside a first-order cell both sides keep their means, and the reconstructed
//! cell's interior force runs from its other edge to its mean. The face's jump then
//! spans the two centres and is shared as at order 1. With the reconstructed edge
//! facing a first-order cell's mean, the jump would span half a cell, all of it inside
//! the first-order cell, of which that cell takes only its half: a first-order cell
//! between two reconstructed ones felt half the slope of the surface, its neighbours
//! 5/4 of it, and a Coulomb deposit at its repose angle beside moving cells never
//! came to rest (tests/second_order.rs).
//!
//! ΔC. The Coulomb-aware reconstruction of a face decides whether friction holds it
//! from the drive u/Δt − g_n Δη/Δx with Δη the jump between the cell centres (as at
//! order 1), not between the edges: the edges' jump is a fraction of the surface's
//! drop, and a face that saw little more than u/Δt stopped the mass flux of cells that
//! the friction step, which sees the interior forces too, kept moving (a Coulomb
//! deposit at its repose angle slid for ever with its faces closed).
//!
//! N layers ([`super::hydrostatic`], `reconstruct_layers`): the same slopes of h and
//! η, and one limited slope per layer velocity u_α (the velocity slope of [`Slopes`]
//! is then unused); a cell is first order where any layer is slower than the static
//! friction's impulse per step and two cells from a dry cell, besides the rules above
//! (docs/numerics.md, "Second order", N > 1 layers).
//!
//! Walls: the ghost is the mirror image of the edge cell, with mirrored slopes
//! ([`Slopes::mirrored`]), so that no mass crosses the wall.
//!
//! Near-dry rule: a reconstructed cell keeps its whole gravity source (the rule that
//! evaluates it at the new thickness where the depth falls is for first-order cells;
//! in a smooth flow over a curved bed it cost Heun's step its second order,
//! [`super::muscl_2d`]).
//!
//! The functions here see one cell stencil and return values; the 1-D step
//! ([`super::hydrostatic`]) calls [`slopes`] once per cell and [`edges`] for the faces;
//! the 2-D step applies the same reconstruction dimension by dimension
//! ([`super::muscl_2d`]).

use crate::physics::shallow::H_DRY;

/// The slope limiter φ of the reconstruction (`numerics.limiter`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Limiter {
    Minmod,
    VanLeer,
    Mc,
}

impl Limiter {
    /// The scenario's name of the limiter.
    pub fn name(self) -> &'static str {
        match self {
            Limiter::Minmod => "minmod",
            Limiter::VanLeer => "van_leer",
            Limiter::Mc => "mc",
        }
    }

    /// The limiter named `name`, if any.
    pub fn parse(name: &str) -> Option<Limiter> {
        match name {
            "minmod" => Some(Limiter::Minmod),
            "van_leer" => Some(Limiter::VanLeer),
            "mc" => Some(Limiter::Mc),
            _ => None,
        }
    }

    /// The limited slope (a difference across one cell) from the backward difference
    /// `a` = w_i − w_{i−1} and the forward difference `b` = w_{i+1} − w_i.
    #[inline(always)]
    pub fn slope(self, a: f64, b: f64) -> f64 {
        if a * b <= 0.0 {
            return 0.0;
        }
        match self {
            Limiter::Minmod => {
                if a.abs() < b.abs() {
                    a
                } else {
                    b
                }
            }
            Limiter::VanLeer => 2.0 * a * b / (a + b),
            Limiter::Mc => {
                let m = (2.0 * a.abs()).min(2.0 * b.abs()).min(0.5 * (a + b).abs());
                m.copysign(a)
            }
        }
    }
}

/// What the reconstruction reads of a cell: depth, velocity (0 where dry) and surface
/// η = h + b over the reference plane.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Cell {
    pub h: f64,
    pub u: f64,
    pub eta: f64,
}

impl Cell {
    /// The cell of depth `h`, discharge `hu` and surface `eta`.
    #[inline(always)]
    pub fn new(h: f64, hu: f64, eta: f64) -> Cell {
        Cell {
            h,
            u: crate::physics::shallow::velocity(h, hu),
            eta,
        }
    }
}

/// Limited slopes of h, u and η across one cell.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Slopes {
    pub h: f64,
    pub u: f64,
    pub eta: f64,
}

impl Slopes {
    /// The slopes of the mirror image of a cell across a wall (its ghost: the same
    /// depth and surface, the velocity reversed): h and η change sign, u does not.
    #[inline(always)]
    pub fn mirrored(self) -> Slopes {
        Slopes {
            h: -self.h,
            u: self.u,
            eta: -self.eta,
        }
    }
}

/// The slopes of `cell` from its neighbours `prev` and `next`, or `None` where the cell
/// is reconstructed to first order (it or a neighbour dry, or the cell at rest; module
/// documentation).
#[inline(always)]
pub fn slopes(limiter: Limiter, prev: Cell, cell: Cell, next: Cell) -> Option<Slopes> {
    if cell.u == 0.0 || cell.h <= H_DRY || prev.h <= H_DRY || next.h <= H_DRY {
        return None;
    }
    let u = cell.u;
    Some(Slopes {
        h: limiter.slope(cell.h - prev.h, next.h - cell.h),
        u: limiter.slope(u - prev.u, next.u - u),
        eta: limiter.slope(cell.eta - prev.eta, next.eta - cell.eta),
    })
}

/// The values at one edge of a reconstructed cell.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Edge {
    pub h: f64,
    pub u: f64,
    pub eta: f64,
}

/// The (west, east) edges of `cell` with slopes `s`: w ∓ ½σ^w. The depth is clipped at
/// 0 against round-off (the limiters keep ½|σ^h| ≤ h).
#[inline(always)]
pub fn edges(cell: Cell, s: Slopes) -> (Edge, Edge) {
    let u = cell.u;
    let (dh, du, de) = (0.5 * s.h, 0.5 * s.u, 0.5 * s.eta);
    (
        Edge {
            h: (cell.h - dh).max(0.0),
            u: u - du,
            eta: cell.eta - de,
        },
        Edge {
            h: (cell.h + dh).max(0.0),
            u: u + du,
            eta: cell.eta + de,
        },
    )
}

/// The pressure force 𝓢^c of a reconstructed cell's interior between its edges `west`
/// and `east` (module documentation), and its gravity part (bed and plane: 𝓢^c minus
/// the flat-bed pressure g_n h̄ (h_E − h_W)).
#[inline(always)]
pub fn interior_source(g_n: f64, west: Edge, east: Edge) -> (f64, f64) {
    let g_hbar = g_n * 0.5 * (west.h + east.h);
    let source = g_hbar * (east.eta - west.eta);
    let pressure = g_hbar * (east.h - west.h);
    (source, source - pressure)
}

/// The states each side of the face between `stencil[1]` and `stencil[2]` (the two
/// cells each side of it): the east edge of `stencil[1]` and the west edge of
/// `stencil[2]` where both cells are reconstructed, else `None` (the two cell means,
/// as they are, are then the face's states: module documentation, "mixed faces").
#[inline(always)]
pub fn face_states(limiter: Limiter, stencil: [Cell; 4]) -> Option<(Edge, Edge)> {
    let [a, l, r, b] = stencil;
    let left = slopes(limiter, a, l, r)?;
    let right = slopes(limiter, l, r, b)?;
    Some((edges(l, left).1, edges(r, right).0))
}

#[cfg(test)]
mod tests {
    use super::*;

    const ALL: [Limiter; 3] = [Limiter::Minmod, Limiter::VanLeer, Limiter::Mc];

    fn cell(h: f64, u: f64, z: f64) -> Cell {
        Cell::new(h, h * u, h + z)
    }

    #[test]
    fn limiters_are_exact_on_linear_data_and_vanish_at_extrema() {
        for lim in ALL {
            assert_eq!(lim.slope(0.25, 0.25), 0.25, "{lim:?}");
            assert_eq!(lim.slope(-0.5, -0.5), -0.5, "{lim:?}");
            assert_eq!(lim.slope(0.3, -0.1), 0.0, "{lim:?}");
            assert_eq!(lim.slope(0.0, 1.0), 0.0, "{lim:?}");
            assert_eq!(Limiter::parse(lim.name()), Some(lim));
        }
        assert_eq!(Limiter::Minmod.slope(1.0, 3.0), 1.0);
        assert_eq!(Limiter::VanLeer.slope(1.0, 3.0), 1.5);
        assert_eq!(Limiter::Mc.slope(1.0, 3.0), 2.0);
        assert_eq!(Limiter::Mc.slope(1.0, 1.5), 1.25);
    }

    #[test]
    fn edge_values_stay_between_the_neighbours() {
        // Random-ish triples: every edge lies between the cell mean and the neighbour
        // on its side (so edge depths are never negative).
        let mut x = 0.123_f64;
        let mut next = || {
            x = (x * 7.77 + 0.311).fract();
            x
        };
        for _ in 0..2000 {
            let (h0, h1, h2) = (next(), next(), next());
            let (u0, u1, u2) = (next() - 0.5, next() - 0.5, next() - 0.5);
            let (c0, c1, c2) = (cell(h0, u0, 0.0), cell(h1, u1, 0.0), cell(h2, u2, 0.0));
            for lim in ALL {
                let s = slopes(lim, c0, c1, c2).unwrap();
                let (w, e) = edges(c1, s);
                let between =
                    |v: f64, a: f64, b: f64| v >= a.min(b) - 1e-15 && v <= a.max(b) + 1e-15;
                assert!(between(w.h, h0, h1) && between(e.h, h1, h2), "{lim:?}");
                assert!(
                    between(w.u, c0.u, c1.u) && between(e.u, c1.u, c2.u),
                    "{lim:?}"
                );
                assert!(w.h >= 0.0 && e.h >= 0.0);
            }
        }
    }

    #[test]
    fn first_order_at_rest_and_beside_dry_cells() {
        let wet = cell(1.0, 0.5, 0.0);
        for lim in ALL {
            assert!(slopes(lim, wet, cell(1.2, 0.0, 0.0), wet).is_none());
            assert!(slopes(lim, cell(0.0, 0.0, 0.0), cell(1.2, 0.3, 0.0), wet).is_none());
            assert!(slopes(lim, wet, cell(1.2, 0.3, 0.0), cell(0.0, 0.0, 0.0)).is_none());
            assert!(slopes(lim, wet, cell(1.2, 0.3, 0.0), wet).is_some());
            assert_eq!(face_states(lim, [wet, wet, cell(1.2, 0.0, 0.0), wet]), None);
        }
    }

    #[test]
    fn lake_at_rest_edges_keep_the_surface_and_the_interior_feels_nothing() {
        // A lake over a bed z = 0.1, 0.4, 0.2 (η = 1): moving slowly, so reconstructed.
        let c = [
            cell(0.9, 1e-3, 0.1),
            cell(0.6, 1e-3, 0.4),
            cell(0.8, 1e-3, 0.2),
        ];
        for lim in ALL {
            let s = slopes(lim, c[0], c[1], c[2]).unwrap();
            assert_eq!(s.eta, 0.0);
            let (w, e) = edges(c[1], s);
            assert_eq!((w.eta, e.eta), (1.0, 1.0));
            assert_eq!(interior_source(9.81, w, e).0, 0.0);
        }
    }

    #[test]
    fn face_states_read_the_two_cells_each_side() {
        let c = [
            cell(1.0, 0.1, 0.0),
            cell(1.1, 0.2, 0.0),
            cell(1.2, 0.3, 0.0),
            cell(1.3, 0.4, 0.0),
        ];
        let (l, r) = face_states(Limiter::Minmod, c).unwrap();
        assert!((l.h - 1.15).abs() < 1e-14 && (r.h - 1.15).abs() < 1e-14);
        assert!((l.u - 0.25).abs() < 1e-14 && (r.u - 0.25).abs() < 1e-14);
    }
}
