//! Hydrostatic reconstruction for the shallow-water system with volume fraction
//! (Bouchut et al. 2021, Appendix B, eq. B.16–B.30), for α > 1 (B.19).
//!
//! Given the two sides (h, v, φ) of an interface and the jump Δz = z_r − z_l of the
//! total topography, λ ≥ 0:
//!
//!   Δz*₊ = (Δz − (λ/g_c)(v_l²/2 − v_r²/2)₊)₊,  Δz*₋ = (−Δz − (λ/g_c)(v_r²/2 − v_l²/2)₊)₊   (B.16)
//!   h_l* = (h_l + min(h_l/(2(α−1)) (1 − (φ_r/φ_l)^{α−1})₊, (½/(α−½)) Δz*₊) − Δz*₊)₊       (B.23)
//!   h_r* = (h_r + min(h_r/(2(α−1)) (1 − (φ_l/φ_r)^{α−1})₊, (½/(α−½)) Δz*₋) − Δz*₋)₊       (B.24)
//!   φ_l* = φ_l                                 if Δz ≤ 0 or φ_r ≥ φ_l,                    (B.26)
//!        = max(φ_l (h_l*/h_l)^{1/(α−1)}, φ_r)   otherwise,
//!   φ_r* symmetric (B.27).
//!
//! (B.23) is the branch-free form of (B.20): the two agree (tested below). The
//! reconstruction keeps 0 ≤ h* ≤ h (B.25), φ* ∈ [φ_l, φ_r] (B.28), φ* ≤ φ (B.29), and
//! maps the two families of discrete steady states at rest to U_l* = U_r*: φ constant
//! with h + z constant (B.33–B.34), and h φ^{1−α} constant with
//! ((α−½)/(α−1)) h + z constant (B.37).
//!
//! Printed inconsistency: (B.52) states the switch of (B.20) as
//! Δz*₊ ≤ ((α−½)/(α−1)) h_l (1 − (φ_r/φ_l)^{α−1}), with the factor inverted relative to
//! (B.20), ((α−1)/(α−½)) Δz*₊ ≤ h_l (…)₊. Only (B.20) makes φ_l (h_l*/h_l)^{1/(α−1)} ≥ φ_r
//! exactly on its first branch, which (B.26) and the well-balance proof of (iii) need;
//! `switch_of_b20_is_where_the_rescaled_fraction_meets_phi_r` decides it.

use crate::physics::dilatancy::{phi_from_ratio, phi_power};

/// One side of an interface in primitive variables.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Side {
    pub h: f64,
    pub v: f64,
    pub phi: f64,
}

/// The reconstructed depths and fractions, and the Δz*₊, Δz*₋ they used.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Reconstructed {
    pub h_l: f64,
    pub phi_l: f64,
    pub h_r: f64,
    pub phi_r: f64,
    pub dz_plus: f64,
    pub dz_minus: f64,
}

#[inline(always)]
fn pos(x: f64) -> f64 {
    x.max(0.0)
}

/// Δz*₊ and Δz*₋ of (B.16).
#[inline(always)]
pub fn reduced_jumps(l: Side, r: Side, dz: f64, lambda: f64, g_c: f64) -> (f64, f64) {
    if lambda == 0.0 {
        return (pos(dz), pos(-dz));
    }
    let (kl, kr) = (0.5 * l.v * l.v, 0.5 * r.v * r.v);
    (
        pos(dz - lambda / g_c * pos(kl - kr)),
        pos(-dz - lambda / g_c * pos(kr - kl)),
    )
}

/// h* of the side that is lowered by `dz_star` ≥ 0, (B.23)/(B.24): `own`, `other` are
/// the side's and the opposite side's (h, φ).
#[inline(always)]
pub fn lowered_depth(h: f64, phi: f64, phi_other: f64, dz_star: f64, alpha: f64) -> f64 {
    if dz_star == 0.0 {
        return h;
    }
    let drop = pos(1.0 - phi_power(phi_other / phi, alpha));
    let gain = (h / (2.0 * (alpha - 1.0)) * drop).min(0.5 / (alpha - 0.5) * dz_star);
    pos(h + gain - dz_star)
}

/// (B.20) as printed (two branches), for the tests of (B.23).
pub fn lowered_depth_b20(h: f64, phi: f64, phi_other: f64, dz_star: f64, alpha: f64) -> f64 {
    let drop = pos(1.0 - phi_power(phi_other / phi, alpha));
    let c = (alpha - 1.0) / (alpha - 0.5);
    if c * dz_star <= h * drop {
        h - c * dz_star
    } else {
        pos(h + h / (2.0 * (alpha - 1.0)) * drop - dz_star)
    }
}

/// φ* of the side lowered when `lowered` (Δz ≥ 0 for the left side, ≤ 0 for the right)
/// and its fraction is the larger, (B.26)/(B.27).
#[inline(always)]
fn reconstructed_fraction(h: f64, h_star: f64, phi: f64, phi_other: f64, alpha: f64) -> f64 {
    if phi_other >= phi {
        return phi;
    }
    let ratio = if h > 0.0 { h_star / h } else { 0.0 };
    if ratio >= 1.0 {
        return phi;
    }
    // φ (h*/h)^{1/(α−1)} = (φ^{α−1} h*/h)^{1/(α−1)}; ≤ φ since h* ≤ h (`min` only
    // removes the round-off of the two powers).
    phi_from_ratio(phi_power(phi, alpha) * ratio, alpha)
        .min(phi)
        .max(phi_other)
}

/// The reconstruction (B.16)–(B.27) for the jump `dz` = z_r − z_l.
#[inline(always)]
pub fn reconstruct(l: Side, r: Side, dz: f64, lambda: f64, g_c: f64, alpha: f64) -> Reconstructed {
    let (dz_plus, dz_minus) = reduced_jumps(l, r, dz, lambda, g_c);
    let h_l = lowered_depth(l.h, l.phi, r.phi, dz_plus, alpha);
    let h_r = lowered_depth(r.h, r.phi, l.phi, dz_minus, alpha);
    let phi_l = if dz <= 0.0 {
        l.phi
    } else {
        reconstructed_fraction(l.h, h_l, l.phi, r.phi, alpha)
    };
    let phi_r = if dz >= 0.0 {
        r.phi
    } else {
        reconstructed_fraction(r.h, h_r, r.phi, l.phi, alpha)
    };
    Reconstructed {
        h_l,
        phi_l,
        h_r,
        phi_r,
        dz_plus,
        dz_minus,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;
    use proptest::prelude::*;

    const G: f64 = 9.81;

    fn side(h: f64, v: f64, phi: f64) -> Side {
        Side { h, v, phi }
    }

    #[test]
    fn constant_fraction_at_rest_reconstructs_equal_states() {
        // (B.33)–(B.34): h_l + z_l = h_r + z_r, φ_l = φ_r, v = 0.
        // Binary-exact data: the equality is exact.
        let (l, r) = (side(0.75, 0.0, 0.6), side(0.5, 0.0, 0.6));
        let rec = reconstruct(l, r, 0.25, 0.0, G, 2.0);
        assert_eq!((rec.h_l, rec.h_r), (0.5, 0.5));
        assert_eq!((rec.phi_l, rec.phi_r), (0.6, 0.6));
        let rec = reconstruct(r, l, -0.25, 0.0, G, 2.0);
        assert_eq!((rec.h_l, rec.h_r), (0.5, 0.5));
    }

    #[test]
    fn h_phi_family_at_rest_reconstructs_equal_states() {
        // (B.37) with α = 2 and α = 3: h φ^{1−α} = const and ((α−½)/(α−1)) h + z const.
        for alpha in [2.0, 3.0, 1.5] {
            let (h_l, phi_l): (f64, f64) = (0.3, 0.62);
            let phi_r = 0.55;
            let h_r = h_l * (phi_r / phi_l).powf(alpha - 1.0);
            let dz = (alpha - 0.5) / (alpha - 1.0) * (h_l - h_r);
            let rec = reconstruct(
                side(h_l, 0.0, phi_l),
                side(h_r, 0.0, phi_r),
                dz,
                0.0,
                G,
                alpha,
            );
            assert_relative_eq!(rec.h_l, h_r, max_relative = 1e-12);
            assert_relative_eq!(rec.phi_l, phi_r, max_relative = 1e-12);
            assert_eq!((rec.h_r, rec.phi_r), (h_r, phi_r));
        }
    }

    #[test]
    fn switch_of_b20_is_where_the_rescaled_fraction_meets_phi_r() {
        // At the switch of (B.20), h_l* = h_l − ((α−1)/(α−½)) Δz*₊ makes
        // φ_l (h_l*/h_l)^{1/(α−1)} = φ_r exactly. (B.52)'s inverted factor does not.
        let (alpha, h, phi_l, phi_r): (f64, f64, f64, f64) = (3.0, 0.2, 0.62, 0.5);
        let drop = 1.0 - (phi_r / phi_l).powf(alpha - 1.0);
        let switch_b20 = (alpha - 0.5) / (alpha - 1.0) * h * drop;
        let h_star = lowered_depth_b20(h, phi_l, phi_r, switch_b20, alpha);
        assert_relative_eq!(
            phi_l * (h_star / h).powf(1.0 / (alpha - 1.0)),
            phi_r,
            max_relative = 1e-12
        );
        let switch_b52 = (alpha - 1.0) / (alpha - 0.5) * h * drop;
        let h_star = lowered_depth_b20(h, phi_l, phi_r, switch_b52, alpha);
        let rescaled = phi_l * (h_star / h).powf(1.0 / (alpha - 1.0));
        assert!((rescaled - phi_r).abs() > 1e-3, "{rescaled} vs {phi_r}");
    }

    #[test]
    fn lambda_one_keeps_kinetic_energy_in_the_jump() {
        // (B.16)–(B.18): 0 ≤ (Δz)₊ − Δz*₊ ≤ (λ/g_c) v_l²/2.
        let (l, r) = (side(0.2, 1.0, 0.6), side(0.1, 0.5, 0.6));
        let (p, m) = reduced_jumps(l, r, 0.1, 1.0, G);
        assert_relative_eq!(p, 0.1 - (0.5 - 0.125) / G, epsilon = 1e-15);
        assert_eq!(m, 0.0);
        // A kinetic-energy drop larger than the jump removes it entirely.
        let (p, _) = reduced_jumps(side(0.2, 2.0, 0.6), r, 0.1, 1.0, G);
        assert_eq!(p, 0.0);
    }

    fn fraction() -> impl Strategy<Value = f64> {
        0.05f64..0.95
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(2000))]

        #[test]
        fn reconstruction_bounds(
            h_l in 0.0f64..1.0, h_r in 0.0f64..1.0,
            v_l in -3.0f64..3.0, v_r in -3.0f64..3.0,
            phi_l in fraction(), phi_r in fraction(),
            dz in -0.5f64..0.5, lambda in prop_oneof![Just(0.0), Just(1.0)],
            alpha in prop_oneof![Just(2.0), Just(1.5), Just(3.0)],
        ) {
            let (l, r) = (side(h_l, v_l, phi_l), side(h_r, v_r, phi_r));
            let rec = reconstruct(l, r, dz, lambda, G, alpha);
            // (B.17)
            prop_assert!(0.0 <= rec.dz_plus && rec.dz_plus <= dz.max(0.0));
            prop_assert!(0.0 <= rec.dz_minus && rec.dz_minus <= (-dz).max(0.0));
            // (B.25)
            prop_assert!(0.0 <= rec.h_l && rec.h_l <= h_l);
            prop_assert!(0.0 <= rec.h_r && rec.h_r <= h_r);
            // (B.28), (B.29)
            let (lo, hi) = (phi_l.min(phi_r), phi_l.max(phi_r));
            for phi in [rec.phi_l, rec.phi_r] {
                prop_assert!(lo <= phi && phi <= hi);
            }
            prop_assert!(rec.phi_l <= phi_l && rec.phi_r <= phi_r);
            // (B.23) is (B.20).
            let b20 = lowered_depth_b20(h_l, phi_l, phi_r, rec.dz_plus, alpha);
            prop_assert!((b20 - rec.h_l).abs() <= 1e-14 * (1.0 + h_l), "{} {}", b20, rec.h_l);
            let b21 = lowered_depth_b20(h_r, phi_r, phi_l, rec.dz_minus, alpha);
            prop_assert!((b21 - rec.h_r).abs() <= 1e-14 * (1.0 + h_r));
            // (B.22): a side whose fraction is not the larger is simply lowered.
            if phi_r >= phi_l {
                prop_assert_eq!(rec.h_l, (h_l - rec.dz_plus).max(0.0));
            }
        }
    }
}
