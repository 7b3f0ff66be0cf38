//! Voellmy friction (Voellmy 1955, in the form of Salm 1993): a Coulomb part and a
//! velocity-squared "turbulent" drag,
//!
//!   τ_b = μ p_b + ρ g |u|² / ξ,
//!
//! with the dry-Coulomb coefficient μ and the turbulence coefficient ξ (m/s²), the
//! law calibrated by the users of r.avaflow, RAMMS and AvaFrame. As an effective
//! coefficient of the basal pressure, μ_eff = μ + g |u|² / (ξ p_b/ρ).
//!
//! The friction step is backward Euler in the speed (like μ(I), [`super::MuI`]): with
//! the speed u* ≥ 0 left by the other steps, the mass stops if u* ≤ Δt μ p_b/(ρh)
//! (the Coulomb part alone holds it), otherwise u solves
//!
//!   u + Δt μ p_b/(ρ h) + Δt g u² / (ξ h) = u*,
//!
//! i.e. k u² + u − A = 0 with A = u* − Δt μ p_b/(ρh) > 0, k = Δt g/(ξ h), whose
//! positive root 2A / (1 + √(1 + 4kA)) lies in (0, A]: unconditionally stable for the
//! quadratic drag, and never reversing the flow.

use super::{BasalFriction, LocalFriction};
use crate::physics::GRAVITY;

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Voellmy {
    /// Dry-Coulomb coefficient μ.
    pub mu: f64,
    /// Turbulence coefficient ξ (m/s²).
    pub xi: f64,
}

impl Voellmy {
    /// The speed after a backward-Euler Voellmy step from the speed `u_star` ≥ 0 of a
    /// layer of thickness `h`, with the Coulomb impulse per unit mass `coulomb` =
    /// Δt μ p_b/(ρ h) and the time step `dt` (module documentation). NaN propagates.
    #[inline(always)]
    pub fn implicit_speed(&self, u_star: f64, h: f64, coulomb: f64, dt: f64) -> f64 {
        let a = u_star - coulomb;
        if a.is_nan() {
            return f64::NAN;
        }
        if a <= 0.0 {
            return 0.0;
        }
        let k = dt * GRAVITY / (self.xi * h);
        2.0 * a / (1.0 + (1.0 + 4.0 * k * a).sqrt())
    }
}

impl BasalFriction for Voellmy {
    /// μ + g |u|²/(ξ p_b/ρ); μ where there is no pressure.
    #[inline(always)]
    fn mu(&self, speed: f64, _h: f64, p_over_rho: f64) -> f64 {
        if p_over_rho <= 0.0 {
            return self.mu;
        }
        self.mu + GRAVITY * speed * speed / (self.xi * p_over_rho)
    }

    /// Backward Euler in the speed (module documentation), p_b/ρ = g_n h.
    #[inline(always)]
    fn friction_update(&self, q: f64, h: f64, dt: f64, g_n: f64) -> f64 {
        if dt * self.mu * g_n * h >= q.abs() {
            return 0.0;
        }
        let u = self.implicit_speed((q / h).abs(), h, dt * self.mu * g_n, dt);
        u * h * q.signum()
    }

    /// The same with the total basal pressure p_total of the non-hydrostatic model.
    #[inline(always)]
    fn nh_friction_update(&self, q: f64, _q_old: f64, h: f64, dt: f64, p_total: f64) -> f64 {
        let weight = p_total.max(0.0);
        if dt * self.mu * weight >= q.abs() {
            return 0.0;
        }
        let u = self.implicit_speed((q / h).abs(), h, dt * self.mu * weight / h, dt);
        u * h * q.signum()
    }
}

/// Inside a multilayer column the Voellmy law has no local form: the bulk friction is
/// its Coulomb part μ (the drag ρ g |u|²/ξ is a basal law). Scenarios pair Voellmy
/// with the monolayer only.
impl LocalFriction for Voellmy {
    #[inline(always)]
    fn inertial_scale(&self, _p_over_rho: f64) -> f64 {
        0.0
    }

    #[inline(always)]
    fn mu_at(&self, _inertial_number: f64) -> f64 {
        self.mu
    }

    #[inline(always)]
    fn mu_slope_at(&self, _inertial_number: f64) -> f64 {
        0.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn law() -> Voellmy {
        Voellmy { mu: 0.2, xi: 500.0 }
    }

    #[test]
    fn effective_coefficient_adds_the_turbulent_drag() {
        let (u, h, g_n) = (10.0, 2.0, 9.0);
        let mu = law().mu(u, h, g_n * h);
        // τ/ρ = μ g_n h + g u²/ξ.
        let tau = 0.2 * g_n * h + GRAVITY * u * u / 500.0;
        assert!((mu * g_n * h - tau).abs() < 1e-12 * tau);
        assert_eq!(law().mu(3.0, 0.0, 0.0), 0.2);
    }

    #[test]
    fn implicit_step_solves_the_backward_euler_equation() {
        let (h, dt, g_n) = (1.5, 0.05, 9.81);
        for u_star in [0.5, 3.0, 20.0, 80.0] {
            let u = law().friction_update(u_star * h, h, dt, g_n) / h;
            assert!(u > 0.0 && u < u_star, "u* = {u_star}: u = {u}");
            let residual = u + dt * (0.2 * g_n + GRAVITY * u * u / (500.0 * h)) - u_star;
            assert!(residual.abs() < 1e-12 * u_star, "residual {residual:e}");
            assert_eq!(law().friction_update(-u_star * h, h, dt, g_n), -u * h);
            let nh = law().nh_friction_update(u_star * h, 0.0, h, dt, g_n * h) / h;
            assert!((nh - u).abs() < 1e-12 * u_star);
        }
        // The Coulomb part alone stops a slow mass; NaN propagates.
        let q = 0.9 * dt * 0.2 * g_n * h;
        assert_eq!(law().friction_update(q, h, dt, g_n), 0.0);
        assert!(law().friction_update(f64::NAN, h, dt, g_n).is_nan());
    }

    #[test]
    fn steady_speed_on_an_incline_is_the_voellmy_one() {
        // Uniform flow on a slope θ: g sin θ = μ g cos θ + g u²/(ξ h), so
        // u = √(ξ h (sin θ − μ cos θ)). Iterate the acceleration and friction steps.
        let (theta, h, dt) = (35f64.to_radians(), 1.0, 0.01);
        let g_n = GRAVITY * theta.cos();
        let mut q = 0.0;
        for _ in 0..20_000 {
            q += dt * GRAVITY * theta.sin() * h;
            q = law().friction_update(q, h, dt, g_n);
        }
        let exact = (500.0 * h * (theta.sin() - 0.2 * theta.cos())).sqrt();
        // The split step's fixed point is u with u + Δt(μ g_n + g u²/(ξh)) = u + Δt g sin θ.
        assert!((q / h - exact).abs() < 1e-9 * exact, "{} vs {exact}", q / h);
    }
}
