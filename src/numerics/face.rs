//! The face kernel shared by the 1-D and 2-D hydrostatic steps: the hydrostatic
//! reconstruction, the Coulomb-aware reconstruction ΔC, the HLL/PVM coefficients and
//! the own-depth split of the pressure source of one face (Garres-Díaz et al. 2021,
//! eq. 17–24; Escalante et al. 2023, eq. 19–21), with the departures documented in
//! [`super::hydrostatic`]. A face is seen along its normal: `u` is the normal velocity,
//! `dx` the cell width across the face, `g_n` the gravity normal to the reference plane.
//! The 1-D step (`hydrostatic.rs`) calls it for every face of a line; the 2-D step
//! (`hydrostatic_2d.rs`) for every x-face and every y-face of a raster, with the
//! tangential velocity carried by [`transverse_flux`].

use crate::physics::shallow::{sheared_celerity, velocity, H_DRY};

/// Left or right state of an interface (ū for the velocity).
#[derive(Debug, Clone, Copy)]
pub struct Side {
    pub h: f64,
    pub u: f64,
    /// Bed over the reference plane.
    pub b: f64,
    /// Potential elevation b + b̃.
    pub z: f64,
    /// Shear contribution to the wave speed, 3 Σ l_α (u_α − ū)² (0 for N = 1).
    pub shear: f64,
    /// Velocity u_1 of the bottom layer, on which the basal friction acts (ū for N = 1).
    pub u_base: f64,
    /// √max(h, 0), computed once per cell: it serves both interfaces of the cell.
    pub sqrt_h: f64,
}

impl Side {
    /// A monolayer cell: ū = u_1 = hu/h, no shear.
    #[inline(always)]
    pub fn monolayer(h: f64, hu: f64, b: f64, z: f64) -> Self {
        let u = velocity(h, hu);
        Side {
            h,
            u,
            b,
            z,
            shear: 0.0,
            u_base: u,
            sqrt_h: h.max(0.0).sqrt(),
        }
    }
}

/// What an interface contributes independently of the layers: HLL coefficients, the
/// Coulomb-aware reconstruction ĥ^±, the pressure sources 𝓢, 𝓢̃, and whether a side
/// is seen at rest (emerging bed).
#[derive(Debug, Clone, Copy)]
pub struct Interface {
    pub alpha0: f64,
    pub alpha1: f64,
    /// Hydrostatically reconstructed depths h^± (over b), at which F_c is evaluated.
    pub h_minus: f64,
    pub h_plus: f64,
    pub hc_minus: f64,
    pub hc_plus: f64,
    /// The pressure sources the left and right cells take (module documentation), and
    /// their gravity parts (bed and plane; taken back in the update for the fraction of
    /// the mass that left the cell).
    pub share_left: f64,
    pub share_right: f64,
    pub body_left: f64,
    pub body_right: f64,
    /// The fractions θ_L − m α_1 and θ_R + m α_1 of the exchange term 𝓑 that the left
    /// and right cells take (N > 1).
    pub exchange_left: f64,
    pub exchange_right: f64,
    pub left_at_rest: bool,
    pub right_at_rest: bool,
}

/// The interface coefficients, or `None` where nothing crosses (both sides dry, or no
/// wave). The returned sides carry the velocity the fluxes see.
#[inline(always)]
pub fn interface<M: Fn(f64, f64) -> f64>(
    mu_of: M,
    l: Side,
    r: Side,
    extra: f64,
    g_n: f64,
    dx: f64,
    dt: f64,
) -> Option<(Interface, Side, Side)> {
    let mu_of = |speed: f64, h: f64, _drive: f64| mu_of(speed, h);
    interface_with_zoned_transverse_drive(mu_of, l, r, extra, (0.0, 0.0), g_n, dx, dt)
}

/// [`interface`] for a face of a raster, with the drives d_t = u_t/Δt − g_n ∂_t(h + z)
/// along the face of its two cells (`drive_t`). The friction that ΔC treats as bed is
/// the Coulomb force against the whole drive d = (d_n, d_t), capped at the disk
/// |f| ≤ g_n μ, and the face takes its normal component: f_n = −d_n min(1, g_n μ/|d|),
/// with d_t the √h-weighted mean of the sides' drives (the weights of the Roe
/// velocity). This is the static threshold of the friction step (a disk); clamping
/// d_n alone at g_n μ (a square) would hold, face by face, a mass that the friction
/// step sets moving along a diagonal slope. With d_t = 0 (a line, or a flow
/// invariant along the face) it is the clamp of the line, to the bit.
///
/// `mu_of(speed, h, d_n)` is the face's μ at the Roe speed and mean depth; it also
/// sees the normal drive d_n, whose sign tells the cell the drive pushes mass out of
/// (d_n > 0: the left one), the cell whose friction holds that mass where the two
/// cells' μ differ (friction zones).
#[inline(always)]
#[allow(clippy::too_many_arguments)]
pub fn interface_with_zoned_transverse_drive<M: Fn(f64, f64, f64) -> f64>(
    mu_of: M,
    l: Side,
    r: Side,
    extra: f64,
    drive_t: (f64, f64),
    g_n: f64,
    dx: f64,
    dt: f64,
) -> Option<(Interface, Side, Side)> {
    let weights = (l.sqrt_h, r.sqrt_h);
    let disk = |drive: f64, mu: f64| disk_friction(drive, g_n * mu, weights, drive_t);
    interface_with_friction(mu_of, l, r, extra, disk, (g_n, g_n), dx, dt)
}

/// The friction force that ΔC treats as bed against the normal drive `drive`: the
/// Coulomb force of radius `threshold` = g_n μ against the whole drive (d_n, d_t),
/// capped at the disk, with d_t the mean of the sides' tangential drives `drive_t`
/// weighted by their √h `(wl, wr)` (0 when both are 0: the scalar clamp).
#[inline(always)]
pub(crate) fn disk_friction(
    drive: f64,
    threshold: f64,
    (wl, wr): (f64, f64),
    drive_t: (f64, f64),
) -> f64 {
    let drive_t = if drive_t == (0.0, 0.0) {
        0.0
    } else {
        (wl * drive_t.0 + wr * drive_t.1) / (wl + wr)
    };
    if drive_t == 0.0 {
        -drive.clamp(-threshold, threshold)
    } else {
        let magnitude = drive.hypot(drive_t);
        if magnitude <= threshold {
            -drive
        } else {
            -drive * (threshold / magnitude)
        }
    }
}

/// The interface with the friction that ΔC treats as bed given by `friction(d_n, μ)`:
/// the friction force (per unit mass, along the face's normal) that the face sees
/// against the normal drive d_n, for the face's μ. [`interface_with_zoned_transverse_drive`]
/// passes the Euclidean disk; the bed-normal frame ([`super::hydrostatic_2d`]) the disk
/// of the surface's metric, with its own normal stress. `(g_n, g_wave)`: the gravity of
/// the pressure and the drive, and that of the wave-speed bounds √(g_wave h) (the same
/// but in the bed-normal frame, whose waves along a face's normal are slower by the
/// metric's factor).
#[inline(always)]
#[allow(clippy::too_many_arguments)]
pub fn interface_with_friction<M: Fn(f64, f64, f64) -> f64, F: Fn(f64, f64) -> f64>(
    mu_of: M,
    mut l: Side,
    mut r: Side,
    extra: f64,
    friction: F,
    (g_n, g_wave): (f64, f64),
    dx: f64,
    dt: f64,
) -> Option<(Interface, Side, Side)> {
    let l_dry = l.h <= H_DRY;
    let r_dry = r.h <= H_DRY;
    if l_dry && r_dry {
        return None;
    }
    // Emerging bed: the wet side cannot push mass up a dry step it does not overtop.
    let left_at_rest = r_dry && l.h + l.b < r.b;
    if left_at_rest {
        l.u = 0.0;
        l.shear = 0.0;
        l.u_base = 0.0;
    }
    let right_at_rest = l_dry && r.h + r.b < l.b;
    if right_at_rest {
        r.u = 0.0;
        r.shear = 0.0;
        r.u_base = 0.0;
    }
    let db = r.b - l.b;
    // `extra` (a potential that is no bed, [`super::hydrostatic::FaceFriction::potential_jump`])
    // enters like the plane's slope: in 𝓢 and in ΔC, not in the reconstruction over b.
    let dz = r.z - l.z + extra;
    let d_plane = dz - db;
    let raw_minus = l.h - db.max(0.0);
    let raw_plus = r.h - (-db).max(0.0);
    let h_minus = raw_minus.max(0.0);
    let h_plus = raw_plus.max(0.0);

    // Roe averages and HLL wave-speed bounds.
    let (sl, sr) = (l.sqrt_h, r.sqrt_h);
    let u_roe = (sl * l.u + sr * r.u) / (sl + sr);
    let h_roe = 0.5 * (l.h + r.h);
    let c_roe = sheared_celerity(g_wave, h_roe, 0.5 * (l.shear + r.shear));
    // √g √h reuses the √h of the Roe average (the monolayer's form).
    let side_celerity = |side: &Side, sqrt_h: f64| {
        if side.shear == 0.0 {
            g_wave.sqrt() * sqrt_h
        } else {
            sheared_celerity(g_wave, side.h, side.shear)
        }
    };
    let s_left = (l.u - side_celerity(&l, sl)).min(u_roe - c_roe);
    let s_right = (r.u + side_celerity(&r, sr)).max(u_roe + c_roe);
    let spread = s_right - s_left;
    if spread <= 0.0 {
        return None;
    }
    let alpha0 = (s_right * s_left.abs() - s_left * s_right.abs()) / spread;
    let alpha1 = (s_right.abs() - s_left.abs()) / spread;

    // Coulomb-aware reconstruction (ΔC): friction up to its threshold acts as bed.
    // The friction acts on the bottom layer (Fernández-Nieto et al. 2016, eq. 28): its velocity u_1 enters
    // the drive (Escalante et al. 2023 prints ū). Over a bottom layer that the viscous step has
    // stopped, the regularised creep of the upper layers divided by Δt would exceed the
    // friction margin, the reconstruction would let mass through, and a deposit would
    // never come to rest (the C-MSM collapse of tests/multilayer.rs). For N = 1, u_1 = ū.
    let u_base = if l.u_base == l.u && r.u_base == r.u {
        u_roe
    } else {
        (sl * l.u_base + sr * r.u_base) / (sl + sr)
    };
    let drive = u_base / dt - g_n * ((r.h + r.z) - (l.h + l.z) + extra) / dx;
    let mu = mu_of(u_roe.abs(), h_roe, drive);
    let f = friction(drive, mu);
    let dz_c = dz - f * dx / g_n;
    let hc_minus = (l.h - dz_c.max(0.0)).max(0.0);
    let hc_plus = (r.h - (-dz_c).max(0.0)).max(0.0);

    // 𝓢 and α_1 𝓢̃ split between the cells in proportion to their own depths.
    let g_hbar = g_n * h_roe;
    let upwind = alpha1 * g_hbar * (hc_plus - hc_minus);
    let theta_left = l.h.max(0.0) / (l.h.max(0.0) + r.h.max(0.0));
    let theta_right = 1.0 - theta_left;
    let m = theta_left.min(theta_right);
    let clipped = g_hbar * (h_plus - h_minus + d_plane);
    // The part of 𝓢 that is the flat-bed pressure g_n h̄ Δh: with it the shares of a
    // face sum to the jump of g_n h²/2 (momentum conservation at shocks).
    let pressure = g_hbar * (r.h - l.h);
    // The lower side thinner than the bed step (h^± clipped at 0): the higher side
    // feels the whole drop of the free surface, the lower side the clipped one plus
    // the part of the drop its neighbour's layer covers (module documentation, "thin
    // layers on steep beds"). Without clipping both see 𝓢 (the printed scheme).
    let (source_left, source_right) = if raw_minus < 0.0 || raw_plus < 0.0 {
        let full = g_hbar * (raw_plus - raw_minus + d_plane);
        let (lower, higher) = if raw_minus < 0.0 {
            (l.h, r.h)
        } else {
            (r.h, l.h)
        };
        let cover = if higher >= lower {
            1.0
        } else {
            higher.max(0.0) / lower
        };
        let lower_source = clipped + cover * (full - clipped);
        if raw_minus < 0.0 {
            (lower_source, full)
        } else {
            (full, lower_source)
        }
    } else {
        (clipped, clipped)
    };
    let coefficients = Interface {
        alpha0,
        alpha1,
        h_minus,
        h_plus,
        hc_minus,
        hc_plus,
        share_left: theta_left * source_left - m * upwind,
        share_right: theta_right * source_right + m * upwind,
        body_left: theta_left * (source_left - pressure),
        body_right: theta_right * (source_right - pressure),
        exchange_left: theta_left - m * alpha1,
        exchange_right: theta_right + m * alpha1,
        left_at_rest,
        right_at_rest,
    };
    Some((coefficients, l, r))
}

/// (h^n − h^{n+1})/h^n where the depth fell, else 0: the fraction of a cell's mass that
/// left during the step, whose gravity source is taken back (module documentation,
/// "near-dry cells"). Exactly 0 at rest and wherever the depth did not fall, so such
/// cells keep their source to the bit.
#[inline(always)]
pub fn drained_fraction(h_new: f64, h_old: f64) -> f64 {
    if h_old > 0.0 && h_new < h_old {
        (h_old - h_new) / h_old
    } else {
        0.0
    }
}

/// Total mass flux through the interface (the sides carry ū), F_c at h^±.
#[inline(always)]
pub fn mass_flux(c: &Interface, l: Side, r: Side) -> f64 {
    let (q_l, q_r) = (c.h_minus * l.u, c.h_plus * r.u);
    0.5 * (q_l + q_r) - 0.5 * (c.alpha0 * (c.hc_plus - c.hc_minus) + c.alpha1 * (q_r - q_l))
}

/// Momentum flux of one layer with velocities `u_l`, `u_r` on the two sides (already
/// zero on a side seen at rest); `exchange` is the layer's 𝓑 term (N > 1) or `None`.
#[inline(always)]
pub fn layer_momentum_flux(c: &Interface, h_l: f64, h_r: f64, u_l: f64, u_r: f64) -> f64 {
    let (q_l, q_r) = (h_l * u_l, h_r * u_r);
    let (m_l, m_r) = (q_l * u_l, q_r * u_r);
    0.5 * (m_l + m_r)
        - 0.5 * (c.alpha0 * (c.hc_plus * u_r - c.hc_minus * u_l) + c.alpha1 * (m_r - m_l))
}

/// (F^h, F^hu, sources of the left and right cells, their gravity parts) of a
/// monolayer interface; all zero where nothing crosses.
#[inline(always)]
pub fn monolayer_fluxes<M: Fn(f64, f64) -> f64>(
    mu_of: M,
    l: Side,
    r: Side,
    extra: f64,
    g_n: f64,
    dx: f64,
    dt: f64,
) -> (f64, f64, f64, f64, f64, f64) {
    match interface(mu_of, l, r, extra, g_n, dx, dt) {
        None => (0.0, 0.0, 0.0, 0.0, 0.0, 0.0),
        Some((c, l, r)) => (
            mass_flux(&c, l, r),
            layer_momentum_flux(&c, c.h_minus, c.h_plus, l.u, r.u),
            c.share_left,
            c.share_right,
            c.body_left,
            c.body_right,
        ),
    }
}

/// Flux of a quantity carried by the mass (the tangential discharge h u_t of a 2-D
/// face, with `t_l`, `t_r` the tangential velocities of the two sides), upwinded like
/// each layer's momentum in [`layer_momentum_flux`]: ½(q⁻ t_L + q⁺ t_R) −
/// ½[α_0 (ĥ⁺ t_R − ĥ⁻ t_L) + α_1 (q⁺ t_R − q⁻ t_L)], q^± = h^± u_n^± (Audusse et al.
/// 2004, §2, for a passive quantity). Zero where the normal velocities and the jump of
/// t ĥ vanish: a flow along a face carries nothing through it.
#[inline(always)]
pub fn transverse_flux(c: &Interface, l: Side, r: Side, t_l: f64, t_r: f64) -> f64 {
    let (q_l, q_r) = (c.h_minus * l.u, c.h_plus * r.u);
    let (m_l, m_r) = (q_l * t_l, q_r * t_r);
    0.5 * (m_l + m_r)
        - 0.5 * (c.alpha0 * (c.hc_plus * t_r - c.hc_minus * t_l) + c.alpha1 * (m_r - m_l))
}
