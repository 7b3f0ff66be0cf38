//! The face and the cell update of the bed-normal frame (docs/numerics.md, "The
//! bed-normal frame"; Bouchut & Westdickenberg 2004), shared by the raster's step
//! ([`super::hydrostatic_2d`]) and the line's ([`super::line_bed_normal`]), so that a
//! raster state invariant in y is, row by row, the line's step: the same functions on
//! the same numbers.
//!
//! A face is the 1-D face kernel ([`super::face`]) along its normal with the face's
//! geometry: with ∂_n b = Δb/d across the face and ∂_t b the mean of its cells' along
//! it, c_f² = 1/(1 + |∇b|²), the kernel's gravity g c_f², potential b/c_f², thickness
//! H = h/c per horizontal area and velocity the horizontal normal component u_n, so
//! that its source g c_f² H̄ Δ(H + b/c_f²)/d is g c H ∂_n(c H) + g H ∂_n b; wave bounds
//! √(g c_f² G⁻¹_nn H); ΔC against the covariant drive up to the disk
//! |d|_{G⁻¹} ≤ μ c_f (g + uᵀ∇²b u)₊. The face carries the covariant momenta H G u. A
//! cell's update lowers its discharges to H G u, applies the faces, adds the geodesic
//! term Δt H (∇b·u) ∇²b u and raises the result back to H u.
//!
//! On a line (one row, ∂_y b = 0, v = 0) the tangential momentum, the tangential drive
//! and ∂_t b are zero; a raster row invariant in y has the same zeros (its y-faces
//! carry exactly nothing), so the line passes zeros where the raster passes them.

use super::face::{interface_with_friction, mass_flux, transverse_flux, Interface, Side};
use crate::grid::BedMetric;
use crate::physics::rheology::BasalFriction;
use crate::physics::shallow::H_DRY;
use crate::physics::GRAVITY;

/// What one face gives its two cells: mass flux, normal and tangential momentum
/// fluxes, the pressure sources of the lower-index (l) and higher-index (r) cell and
/// their gravity parts.
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct FaceFlux {
    pub(crate) h: f64,
    pub(crate) qn: f64,
    pub(crate) qt: f64,
    pub(crate) share_l: f64,
    pub(crate) share_r: f64,
    pub(crate) body_l: f64,
    pub(crate) body_r: f64,
}

impl FaceFlux {
    /// The fluxes scaled by the donor's draining factor θ (sources unchanged).
    #[inline(always)]
    pub(crate) fn drained(mut self, theta: f64) -> FaceFlux {
        self.h *= theta;
        self.qn *= theta;
        self.qt *= theta;
        self
    }
}

/// A cell as a face sees it: the side along the face's normal, the tangential
/// velocity `t`, the tangential drive u_t/Δt − g_n ∂_t(h + z) of the cell (for the
/// disk threshold of ΔC, [`super::face::interface_with_zoned_transverse_drive`]) and the
/// cell's speed |(u, v)| (for a friction law whose face threshold takes the cells'
/// own speeds, [`BasalFriction::face_mu`]).
///
/// In the bed-normal frame `side.u` is the normal component of the horizontal
/// velocity (which carries the mass), `side.u_base` and `t` the normal and tangential
/// covariant components of the tangent velocity (the momenta the face carries,
/// [`BedMetric::lower`]), `drive` the tangential covariant drive, `speed` the speed
/// along the surface, `kappa` the cell's centrifugal term uᵀ∇²b u. In the other
/// frames `side.u_base` = `side.u` and `kappa` = 0.
#[derive(Debug, Clone, Copy)]
pub(crate) struct FaceSide {
    pub(crate) side: Side,
    pub(crate) t: f64,
    pub(crate) drive: f64,
    pub(crate) speed: f64,
    pub(crate) kappa: f64,
}

/// The pressure sources of a face and their gravity parts (its fluxes left at zero,
/// for the frame's own).
#[inline(always)]
pub(crate) fn face_sources(c: &Interface) -> FaceFlux {
    FaceFlux {
        h: 0.0,
        qn: 0.0,
        qt: 0.0,
        share_l: c.share_left,
        share_r: c.share_right,
        body_l: c.body_left,
        body_r: c.body_right,
    }
}

/// A face in the bed-normal frame (module documentation) between the sides `l` and
/// `r`, whose cells have cos θ `cos` and the bed's slope `slope_t` along the face
/// (0 on a line), across a cell width `d`, for the step `dt`. The kernel's gravity is
/// g c_f², its potential b/c_f² (Δz = Δb/c_f², the bed itself flat in the face's
/// plane: no step), its thickness H and its velocity the horizontal normal component.
/// ΔC treats as bed the friction against the covariant drive d = (d_n, d_t) up to the
/// disk |d|_{G⁻¹} ≤ μ g_N in the surface's metric, with g_N = c_f (g + uᵀ∇²b u)₊ the
/// normal stress of the friction step (the mean of the cells' centrifugal terms), μ
/// that of `law_of(d_n)` (the law of the cell the normal drive pushes mass out of,
/// with friction zones). The face carries the covariant momenta (normal and
/// tangential) with the mass. At order 2 (`centres`: the (H, b) of the two cells'
/// centres, the sides being the reconstructed edges) the face's slope is that of the
/// centres and ΔC adds the drive between the centres that the edges miss.
#[inline(always)]
pub(crate) fn face<L: BasalFriction>(
    l: &FaceSide,
    r: &FaceSide,
    (cos_l, cos_r): (f64, f64),
    (slope_l, slope_r): (f64, f64),
    law_of: impl Fn(f64) -> L,
    centres: Option<((f64, f64), (f64, f64))>,
    (d, dt): (f64, f64),
) -> FaceFlux {
    // The normal thickness of the cells (a ghost's geometry is its edge cell's).
    let (hn_l, hn_r) = (cos_l * l.side.h, cos_r * r.side.h);
    // At order 2 the sides are edges: the face's geometry is that of the centres.
    let db = match centres {
        Some((c_l, c_r)) => c_r.1 - c_l.1,
        None => r.side.b - l.side.b,
    };
    let (gn, gt) = (db / d, 0.5 * (slope_l + slope_r));
    let inv_c2 = 1.0 + gn * gn + gt * gt;
    let c2 = 1.0 / inv_c2;
    let (gi_nn, gi_nt, gi_tt) = (1.0 - c2 * gn * gn, -c2 * gn * gt, 1.0 - c2 * gt * gt);
    let g_normal = c2.sqrt() * (GRAVITY + 0.5 * (l.kappa + r.kappa)).max(0.0);
    // Absolute potentials (not Δb/c_f² on one side): a face and its mirror image
    // then give the same bits with the sign changed, as in the other frames. The
    // bed lies in the face's plane (b = 0: no step to reconstruct over) between two
    // wet cells; beside a dry cell it is the potential itself, so that a dry cell
    // whose bed stands above the wet one's surface is an emerging bed, as in the
    // Cartesian system: it neither takes mass nor pushes the layer down.
    let (zl, zr) = (l.side.b * inv_c2, r.side.b * inv_c2);
    let step = l.side.h <= H_DRY || r.side.h <= H_DRY;
    let ls = Side {
        b: if step { zl } else { 0.0 },
        z: zl,
        ..l.side
    };
    let rs = Side {
        b: if step { zr } else { 0.0 },
        z: zr,
        ..r.side
    };
    let (wl, wr) = (ls.sqrt_h, rs.sqrt_h);
    // Order 2: ΔC decides from the drive between the centres (`muscl`, "ΔC").
    let missing = centres.map(|(c_l, c_r)| {
        let centre = (c_r.0 + c_r.1 * inv_c2) - (c_l.0 + c_l.1 * inv_c2);
        let edges = (rs.h + rs.z) - (ls.h + ls.z);
        -GRAVITY * c2 * (centre - edges) / d
    });
    let friction = |drive: f64, mu: f64| {
        let drive = match missing {
            Some(extra) => drive + extra,
            None => drive,
        };
        let threshold = mu * g_normal;
        let drive_t = (wl * l.drive + wr * r.drive) / (wl + wr);
        let metric2 =
            gi_nn * drive * drive + 2.0 * gi_nt * drive * drive_t + gi_tt * drive_t * drive_t;
        let magnitude = metric2.max(0.0).sqrt();
        if magnitude <= threshold {
            -drive
        } else {
            -drive * (threshold / magnitude)
        }
    };
    let mu_of = |_speed: f64, _h: f64, drive: f64| {
        let law = law_of(drive);
        let (speed, h) = (0.5 * (l.speed + r.speed), 0.5 * (hn_l + hn_r));
        law.face_mu((l.speed, hn_l), (r.speed, hn_r), speed, h, g_normal)
    };
    // The kernel's gravity, and that of its wave speeds: along the face's normal
    // the waves of H run at √(g c_f² H G⁻¹_nn) in horizontal coordinates.
    let g_k = GRAVITY * c2;
    let gravities = (g_k, g_k * gi_nn);
    match interface_with_friction(mu_of, ls, rs, 0.0, friction, gravities, d, dt) {
        None => FaceFlux::default(),
        Some((c, sl, sr)) => {
            let t_l = if c.left_at_rest { 0.0 } else { l.t };
            let t_r = if c.right_at_rest { 0.0 } else { r.t };
            // Both momenta go with the mass (HLL's form, or the donor's own where
            // the face drains it: `drained_upwind`).
            let h = mass_flux(&c, sl, sr);
            let drain = dt / d;
            FaceFlux {
                h,
                qn: drained_upwind(h, drain, (sl.h, sr.h), (sl.u_base, sr.u_base))
                    .unwrap_or_else(|| transverse_flux(&c, sl, sr, sl.u_base, sr.u_base)),
                qt: drained_upwind(h, drain, (sl.h, sr.h), (t_l, t_r))
                    .unwrap_or_else(|| transverse_flux(&c, sl, sr, t_l, t_r)),
                ..face_sources(&c)
            }
        }
    }
}

/// The new state (unclipped H, H u, H v) of cell `k` of metric `m` from its old state
/// `(h, qx, qy)` in the bed-normal frame: the discharges lowered to the covariant
/// momenta H G u, moved by `faces` (the flat update of the frame's faces, which
/// returns the unclipped new thickness and the new momenta), given the geodesic
/// source Δt H (∇b·u) ∇²b u of the bed's curvature (the term that keeps a mass on a
/// curved bed on it with its energy, docs/numerics.md) and raised back to the
/// horizontal discharges H u.
#[inline(always)]
pub(crate) fn update(
    m: &BedMetric,
    k: usize,
    (h, qx, qy): (f64, f64, f64),
    dt: f64,
    faces: impl FnOnce((f64, f64, f64)) -> (f64, f64, f64),
) -> (f64, f64, f64) {
    let (px, py) = m.lower(k, qx, qy);
    let (hn, mut px, mut py) = faces((h, px, py));
    if hn <= H_DRY {
        return (hn, 0.0, 0.0);
    }
    if h > H_DRY {
        let (u, v) = (qx / h, qy / h);
        let s = dt * h * (m.gx[k] * u + m.gy[k] * v);
        px += s * (m.hxx[k] * u + m.hxy[k] * v);
        py += s * (m.hxy[k] * u + m.hyy[k] * v);
    }
    let (qu, qv) = m.raise(k, px, py);
    // A film that the step drained: its velocity desingularised (Kurganov &
    // Petrova 2007, eq. 2.17), so that momentum exported through a face with its
    // neighbour's mass (the HLL flux's central part) cannot leave it racing.
    let scale = desingularised(hn);
    (hn, qu * scale, qv * scale)
}

/// The momentum flux h w_donor of the face's donor cell (upwind of the mass flux
/// `h`) when the face alone takes more than half of the donor's thickness in the step
/// (`drain` = Δt/d), else `None` (the HLL flux). A cell's own flux takes at most the
/// CFL number's fraction of it; more happens across a strong thickness jump held by ΔC
/// (its diffusion cancelled), where HLL's central part drains a film at the rate of
/// the thick side's flux and carries the thick side's momentum out of it: the film was
/// left with the opposite momentum and raced off, up to 1e5 m/s, on the flank of a
/// valley.
#[inline(always)]
fn drained_upwind(
    h: f64,
    drain: f64,
    (h_l, h_r): (f64, f64),
    (w_l, w_r): (f64, f64),
) -> Option<f64> {
    let (donor, w) = if h > 0.0 { (h_l, w_l) } else { (h_r, w_r) };
    (drain * h.abs() > 0.5 * donor).then_some(h * w)
}

/// Films thinner than this (m, thickness per horizontal area) have their velocity
/// desingularised in the bed-normal frame ([`desingularised`]).
const H_FILM: f64 = 1e-6;

/// The factor 2H²/(H² + max(H², ε²)) (ε = [`H_FILM`]) on the discharge of a cell of
/// thickness `h`: 1 (to the bit) for H ≥ ε, the velocity q/H otherwise replaced by
/// 2Hq/(H² + ε²) (Kurganov & Petrova 2007, eq. 2.17), bounded as H → 0.
#[inline(always)]
fn desingularised(h: f64) -> f64 {
    if h >= H_FILM {
        1.0
    } else {
        2.0 * h * h / (h * h + H_FILM * H_FILM)
    }
}
