//! μ(I) friction of Jop, Forterre & Pouliquen (Garres-Díaz et al. 2021, eq. 6):
//!
//!   μ(I) = μ_s + (μ_2 − μ_s) I / (I_0 + I),
//!
//! with the basal inertial number of Garres-Díaz et al. 2021, eq. (15e),
//!
//!   I = d_s γ̇ / √(p_b / ρ_s),   p_b/ρ_s = φ_s p_b/ρ   (ρ = φ_s ρ_s),
//!
//! and, for the monolayer model, a basal shear rate γ̇ = c_γ |ū| / h chosen by
//! `rheology.monolayer_shear` ([`MonolayerShear`]):
//! - `"bagnold"` (default): c_γ = 5/2, the shear rate at the bed of the Bagnold
//!   profile with depth average ū (Bouchut et al. 2021, eq. 2.15);
//! - `"layer"`: c_γ = 1, the basal shear rate u_1/h_1 of the multilayer model with
//!   one layer (Fernández-Nieto et al. 2016, eq. 26 and 28; Escalante et al. 2023,
//!   eq. 11), the definition under which the papers compare one layer with many.

use super::{BasalFriction, LocalFriction};
use crate::physics::shallow::H_DRY;

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MuI {
    pub mu_s: f64,
    pub mu_2: f64,
    pub i0: f64,
    /// Grain diameter d_s (m).
    pub d_s: f64,
    /// Solid volume fraction φ_s.
    pub phi: f64,
    /// The basal shear rate of a depth-averaged layer.
    pub shear: MonolayerShear,
}

/// The basal shear rate γ̇ = c_γ |ū| / h of a depth-averaged (monolayer) μ(I) layer
/// (module documentation).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum MonolayerShear {
    /// c_γ = 5/2: the bed of a Bagnold profile (Bouchut et al. 2021, eq. 2.15).
    #[default]
    Bagnold,
    /// c_γ = 1: u_1/h_1 of one layer (Fernández-Nieto et al. 2016, eq. 26).
    Layer,
}

impl MonolayerShear {
    /// c_γ = γ̇ h / |ū|.
    #[inline(always)]
    pub fn factor(self) -> f64 {
        match self {
            MonolayerShear::Bagnold => 2.5,
            MonolayerShear::Layer => 1.0,
        }
    }
}

/// Basal inertial number of a monolayer flow with the Bagnold shear rate 5|ū|/(2h)
/// (Garres-Díaz et al. 2021, eq. 15e, Bouchut et al. 2021, eq. 2.15).
#[inline(always)]
pub fn inertial_number(d_s: f64, phi: f64, speed: f64, h: f64, p_over_rho: f64) -> f64 {
    inertial_number_with(MonolayerShear::Bagnold, d_s, phi, speed, h, p_over_rho)
}

/// Basal inertial number of a monolayer flow with the shear rate c_γ |ū|/h of `shear`.
#[inline(always)]
pub fn inertial_number_with(
    shear: MonolayerShear,
    d_s: f64,
    phi: f64,
    speed: f64,
    h: f64,
    p_over_rho: f64,
) -> f64 {
    if h <= H_DRY || p_over_rho <= 0.0 {
        return 0.0;
    }
    let shear_rate = shear.factor() * speed / h;
    d_s * shear_rate / (phi * p_over_rho).sqrt()
}

/// Local inertial number I = d_s |∂_z u| / √(p/ρ_s), p/ρ_s = φ_s p/ρ (Escalante et al. 2023, eq. 10;
/// with it the steady Bagnold profile is Fernández-Nieto et al. 2016, eq. 29). Zero where p ≤ 0.
#[inline(always)]
pub fn local_inertial_number(d_s: f64, phi: f64, shear_rate: f64, p_over_rho: f64) -> f64 {
    if p_over_rho <= 0.0 {
        return 0.0;
    }
    d_s * shear_rate / (phi * p_over_rho).sqrt()
}

impl MuI {
    /// μ(I), written as μ_s + (μ_2 − μ_s)/(1 + I_0/I) so that I = ∞ gives μ_2 and
    /// I = 0 gives μ_s without a 0/0 or ∞/∞.
    #[inline(always)]
    pub fn mu_of_i(&self, i: f64) -> f64 {
        self.mu_s + (self.mu_2 - self.mu_s) / (1.0 + self.i0 / i)
    }
}

/// Backward Euler in the speed for μ(I) friction: the speed u ≥ 0
/// after a friction step that solves
///
///   u + c μ(k u) = u*,   μ(I) = μ_s + (μ_2 − μ_s) I / (I_0 + I),
///
/// for the speed u* ≥ 0 before it, the impulse per unit μ c = Δt W/h (W the weight
/// g_n h, or the total basal pressure of the non-hydrostatic model) and I = k u
/// (k = c_γ d_s / (h √(φ p_b/ρ)), Garres-Díaz et al. 2021, eq. 15e with γ̇ = c_γ u/h). If u* ≤ c μ_s
/// the mass stops (μ ≥ μ_s at any speed). Otherwise, with A = u* − c μ_s and
/// D = c (μ_2 − μ_s), u is the positive root of k u² + (I_0 + k (D − A)) u − I_0 A = 0,
/// which lies in (0, A]. Taking μ at u* instead (the semi-implicit update of Garres-Díaz et al. 2021,
/// §3 step 2) overstates the friction whenever u* exceeds the equilibrium speed: a
/// 1.2 mm layer on a 30° plane (μ_s = tan 25.5°, steady speed 1.03 cm/s) stayed
/// exactly at rest at Δx = 5 cm and 5 mm (tests/robustness.rs). A NaN u* gives NaN.
#[inline(always)]
pub fn backward_euler_speed(mu_s: f64, mu_2: f64, i0: f64, u_star: f64, c: f64, k: f64) -> f64 {
    let a = u_star - c * mu_s;
    if a.is_nan() {
        // NaN must reach the run's NaN check.
        return f64::NAN;
    }
    if a <= 0.0 {
        return 0.0;
    }
    if i0 <= 0.0 {
        // μ = μ_2 at any speed > 0.
        return (u_star - c * mu_2).max(0.0);
    }
    if k == 0.0 {
        // I = 0: μ = μ_s.
        return a;
    }
    let b = i0 + k * (c * (mu_2 - mu_s) - a);
    let root = (b * b + 4.0 * k * i0 * a).sqrt();
    let u = if b >= 0.0 {
        2.0 * i0 * a / (b + root)
    } else {
        (root - b) / (2.0 * k)
    };
    u.min(a)
}

/// Relative round-off allowed in the static test of [`backward_euler_discharge`]. A
/// free surface at exactly the repose slope (Escalante et al. 2023, §5.3, scenarios/at_rest_random_bed
/// .toml: η ≈ 1.7 m, |η_{i+1} − η_{i−1}| ≈ 9 mm on 300 cells) gives |(hu)*| = Δt μ_s g_n h
/// only to within the round-off of Δη amplified by the cancellation: measured up to
/// 1900 ε = 4.2e-13 above it. The semi-implicit step hid this behind μ(I(u*)) > μ_s;
/// without the allowance that mass crept at ~1e-13 m/s. 1e-10 is a slope excess of
/// 1e-10 μ_s, physically nothing, and leaves room for grids ~200× finer.
pub const STATIC_ROUNDOFF: f64 = 1e-10;

/// The discharge after a backward-Euler μ(I) friction step ([`backward_euler_speed`])
/// from the discharge `q` of a layer of thickness h, with the impulse per unit μ
/// `c` = Δt W/h and k = I/u. The stopping test is on the discharge, against the static
/// impulse `static_impulse` = Δt μ_s W computed as the semi-implicit step computed
/// its impulse (up to [`STATIC_ROUNDOFF`]), so that a mass the well-balanced step 1
/// leaves with |(hu)*| ≤ Δt μ_s W stays exactly at rest (`numerics::friction`); a NaN
/// reaches the result.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
pub fn backward_euler_discharge(
    mu_s: f64,
    mu_2: f64,
    i0: f64,
    q: f64,
    h: f64,
    static_impulse: f64,
    c: f64,
    k: f64,
) -> f64 {
    if static_impulse * (1.0 + STATIC_ROUNDOFF) >= q.abs() {
        return 0.0;
    }
    if c == 0.0 {
        return q;
    }
    backward_euler_speed(mu_s, mu_2, i0, (q / h).abs(), c, k) * h * q.signum()
}

impl MuI {
    #[inline(always)]
    fn implicit_discharge(&self, q: f64, h: f64, static_impulse: f64, c: f64, p: f64) -> f64 {
        let k = inertial_number_with(self.shear, self.d_s, self.phi, 1.0, h, p);
        backward_euler_discharge(self.mu_s, self.mu_2, self.i0, q, h, static_impulse, c, k)
    }
}

impl BasalFriction for MuI {
    #[inline(always)]
    fn mu(&self, speed: f64, h: f64, p_over_rho: f64) -> f64 {
        self.mu_of_i(inertial_number_with(
            self.shear, self.d_s, self.phi, speed, h, p_over_rho,
        ))
    }

    /// The cells' own μ(I), depth-weighted ([`super::depth_weighted_mu`]); μ_s at a face
    /// of Roe speed 0 (a mass at rest, or against an emerging bed), as before.
    #[inline(always)]
    fn face_mu(&self, left: (f64, f64), right: (f64, f64), speed: f64, h: f64, g_n: f64) -> f64 {
        if speed == 0.0 {
            return self.mu(0.0, h, g_n * h);
        }
        super::depth_weighted_mu(left, right, |u, h| self.mu(u, h, g_n * h))
    }

    /// Backward Euler in the speed ([`backward_euler_speed`], c = Δt g_n).
    #[inline(always)]
    fn friction_update(&self, q: f64, h: f64, dt: f64, g_n: f64) -> f64 {
        let static_impulse = dt * self.mu_s * g_n * h;
        self.implicit_discharge(q, h, static_impulse, dt * g_n, g_n * h)
    }

    /// Backward Euler in the speed with c = Δt max(p_total, 0)/h and I at p_total.
    #[inline(always)]
    fn nh_friction_update(&self, q: f64, _q_old: f64, h: f64, dt: f64, p_total: f64) -> f64 {
        let weight = p_total.max(0.0);
        let static_impulse = dt * (self.mu_s * weight);
        self.implicit_discharge(q, h, static_impulse, dt * weight / h, p_total)
    }
}

impl LocalFriction for MuI {
    #[inline(always)]
    fn inertial_scale(&self, p_over_rho: f64) -> f64 {
        local_inertial_number(self.d_s, self.phi, 1.0, p_over_rho)
    }

    #[inline(always)]
    fn mu_at(&self, inertial_number: f64) -> f64 {
        self.mu_of_i(inertial_number)
    }

    /// (μ_2 − μ_s) I_0 / (I_0 + I)².
    #[inline(always)]
    fn mu_slope_at(&self, inertial_number: f64) -> f64 {
        let d = self.i0 + inertial_number;
        (self.mu_2 - self.mu_s) * self.i0 / (d * d)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    fn beads() -> MuI {
        MuI {
            mu_s: 25.5f64.to_radians().tan(),
            mu_2: 36f64.to_radians().tan(),
            i0: 0.279,
            d_s: 0.7e-3,
            phi: 0.62,
            shear: MonolayerShear::Bagnold,
        }
    }

    #[test]
    fn mu_is_static_at_rest_and_tends_to_mu2() {
        let law = beads();
        assert_eq!(law.mu(0.0, 0.1, 9.81 * 0.1), law.mu_s);
        assert_relative_eq!(law.mu_of_i(1e12), law.mu_2, max_relative = 1e-10);
        assert_relative_eq!(law.mu_of_i(law.i0), 0.5 * (law.mu_s + law.mu_2));
        assert_eq!(law.mu_of_i(f64::INFINITY), law.mu_2);
        assert_eq!(law.mu_of_i(0.0), law.mu_s);
    }

    #[test]
    fn local_friction_uses_the_local_shear_rate() {
        let law = beads();
        // γ̇ = 100 1/s under p/ρ = 9.81·0.05: I = d_s γ̇ / √(φ p/ρ).
        let i = 0.7e-3 * 100.0 / (0.62f64 * 9.81 * 0.05).sqrt();
        assert_relative_eq!(
            law.mu_local(100.0, 9.81 * 0.05),
            law.mu_of_i(i),
            max_relative = 1e-14
        );
        assert_eq!(law.mu_local(0.0, 1.0), law.mu_s);
        assert_eq!(law.mu_local(1.0, 0.0), law.mu_s);
    }

    #[test]
    fn implicit_friction_solves_the_backward_euler_equation() {
        let law = beads();
        let (h, dt, g_n) = (2e-3, 1e-2, 9.0);
        for u_star in [0.2, 0.5, 1.0, 5.0] {
            let u = law.friction_update(u_star * h, h, dt, g_n) / h;
            assert!(u > 0.0 && u < u_star);
            let residual = u + dt * g_n * law.mu(u, h, g_n * h) - u_star;
            assert!(
                residual.abs() < 1e-12,
                "u* = {u_star}: residual {residual:e}"
            );
            // Never reverses, and symmetric in the sign.
            assert_eq!(law.friction_update(-u_star * h, h, dt, g_n), -u * h);
            // The non-hydrostatic update with p̄ = 0 is the same solve.
            let nh = law.nh_friction_update(u_star * h, 0.0, h, dt, g_n * h) / h;
            assert!((nh - u).abs() < 1e-12 * u_star, "{nh} vs {u}");
        }
        // Below the static impulse the mass stops; NaN propagates; no pressure, no
        // friction.
        let q = 0.9 * dt * g_n * law.mu_s * h;
        assert_eq!(law.friction_update(q, h, dt, g_n), 0.0);
        assert!(law.friction_update(f64::NAN, h, dt, g_n).is_nan());
        assert_eq!(law.nh_friction_update(q, q, h, dt, -1.0), q);
    }

    /// `MonolayerShear::Layer` is the basal friction of the multilayer model with one
    /// layer: μ at the local inertial number of the shear rate u_1/h_1 = ū/h under the
    /// basal pressure g h (`LocalFriction::mu_local`, the viscous step's bed), and
    /// the friction update solves backward Euler with it; the Bagnold closure's I is
    /// 5/2 times larger.
    #[test]
    fn layer_shear_is_the_one_layer_basal_friction() {
        let layer = MuI {
            shear: MonolayerShear::Layer,
            ..beads()
        };
        let (h, g) = (0.012, 9.81);
        for u in [0.01, 0.3, 2.0] {
            assert_relative_eq!(
                layer.mu(u, h, g * h),
                layer.mu_local(u / h, g * h),
                max_relative = 1e-14
            );
            assert_relative_eq!(
                beads().mu(u, h, g * h),
                layer.mu_local(2.5 * u / h, g * h),
                max_relative = 1e-14
            );
            assert!(layer.mu(u, h, g * h) < beads().mu(u, h, g * h));
        }
        let (dt, u_star) = (1e-2, 1.0);
        let u = layer.friction_update(u_star * h, h, dt, g) / h;
        let residual = u + dt * g * layer.mu(u, h, g * h) - u_star;
        assert!(residual.abs() < 1e-12, "residual {residual:e}");
        assert!(u > beads().friction_update(u_star * h, h, dt, g) / h);
    }

    #[test]
    fn inertial_number_matches_hand_computation() {
        // u = 1 m/s, h = 1 cm: γ̇ = 250 1/s, p/ρ_s = 0.62·9.81·0.01.
        let i = inertial_number(0.7e-3, 0.62, 1.0, 0.01, 9.81 * 0.01);
        assert_relative_eq!(
            i,
            0.7e-3 * 250.0 / (0.62f64 * 0.0981).sqrt(),
            max_relative = 1e-14
        );
    }
}
