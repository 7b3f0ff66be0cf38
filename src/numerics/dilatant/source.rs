//! Semi-implicit dilatancy step (Bouchut et al. 2021, §3.2, eq. 3.15–3.19): with (φ*, h*, v*) the
//! state after the transport steps, γ̇* = (5/2)|v*|/h*, I* = γ̇* d/√(φ* g_c h*) and
//! φ_eq* = φ_eq(I*) (f2 with N = 1 in the paper),
//!
//!   (1 + Δt γ̇* K φ*)(φ − φ_eq*) = φ* − φ_eq*                             (3.16)
//!   φ = φ_eq* + (φ* − φ_eq*)/(1 + Δt γ̇* K φ*)                           (3.17)
//!   or φ = φ_eq* + (φ* − φ_eq*) exp(−Δt γ̇* K φ*)                        (3.18)
//!   φh = φ*h*,  v = v*                                                   (3.19)
//!
//! Both updates put φ between φ* and φ_eq* for every Δt ≥ 0 and K ≥ 0: the step is
//! stable for stiff K and tiny d and never limits Δt, and φ stays in (0, 1) when φ* and
//! φ_eq* do (φ_eq* ∈ (0, φ_stat] for f1, f2).

use crate::physics::dilatancy::{shear_rate, DilatantLaw};

/// Which update of §3.2.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum DilatancyUpdate {
    /// (3.17), the implicit Euler solution of (3.16).
    #[default]
    Implicit,
    /// (3.18), the exponential form.
    Exponential,
}

/// The new φ of one cell with thickness `h`, velocity `v` and fraction `phi` after a
/// step `dt` (3.17 or 3.18). Dry or resting cells (γ̇* = 0) keep φ.
#[inline(always)]
pub fn relax_fraction(
    law: &DilatantLaw,
    update: DilatancyUpdate,
    g_c: f64,
    dt: f64,
    h: f64,
    v: f64,
    phi: f64,
) -> f64 {
    let rate = shear_rate(h, v);
    if rate == 0.0 || law.k == 0.0 {
        return phi;
    }
    let i = rate * law.d / (phi * g_c * h).sqrt();
    relax_towards(law, update, dt, rate, phi, law.phi_eq(i))
}

/// (3.17) or (3.18) for a shear rate γ̇* = `rate` and φ_eq* = `phi_eq` already known.
#[inline(always)]
pub fn relax_towards(
    law: &DilatantLaw,
    update: DilatancyUpdate,
    dt: f64,
    rate: f64,
    phi: f64,
    phi_eq: f64,
) -> f64 {
    let stiffness = dt * rate * law.k * phi;
    match update {
        DilatancyUpdate::Implicit => phi_eq + (phi - phi_eq) / (1.0 + stiffness),
        DilatancyUpdate::Exponential => phi_eq + (phi - phi_eq) * (-stiffness).exp(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::physics::dilatancy::PhiEq;
    use approx::assert_relative_eq;
    use proptest::prelude::*;

    const G: f64 = 9.81;

    #[test]
    fn one_step_matches_eq_3_17_by_hand() {
        // h = 2 cm, v = 0.5, φ* = 0.6, Δt = 1e-3: γ̇* = 62.5, φ_eq* = 0.5575680666855547
        // (physics::dilatancy tests), 1 + Δt γ̇* K φ* = 1 + 1e-3·62.5·4.09·0.6.
        let law = DilatantLaw::table1();
        let phi_eq = 0.557_568_066_685_554_7;
        let expected = phi_eq + (0.6 - phi_eq) / (1.0 + 1e-3 * 62.5 * 4.09 * 0.6);
        let phi = relax_fraction(&law, DilatancyUpdate::Implicit, G, 1e-3, 0.02, 0.5, 0.6);
        assert_relative_eq!(phi, expected, max_relative = 1e-14);
        let expected = phi_eq + (0.6 - phi_eq) * (-1e-3 * 62.5 * 4.09 * 0.6f64).exp();
        let phi = relax_fraction(&law, DilatancyUpdate::Exponential, G, 1e-3, 0.02, 0.5, 0.6);
        assert_relative_eq!(phi, expected, max_relative = 1e-14);
        // Dense dilates, loose contracts; at rest nothing happens.
        assert!(relax_fraction(&law, DilatancyUpdate::Implicit, G, 1e-3, 0.02, 0.5, 0.5) > 0.5);
        assert_eq!(
            relax_fraction(&law, DilatancyUpdate::Implicit, G, 1.0, 0.02, 0.0, 0.62),
            0.62
        );
    }

    #[test]
    fn repeated_steps_converge_to_the_ode_solution() {
        // At fixed (h, v) the ODE dφ/dt = −φ γ̇ K (φ − φ_eq) (φ_eq frozen at the initial
        // I would be exact only for fixed I; here I depends on φ, so compare two Δt:
        // the implicit update is first order, the error halves with Δt).
        let law = DilatantLaw::table1();
        let run = |n: usize| {
            let dt = 0.01 / n as f64;
            let mut phi = 0.62;
            for _ in 0..n {
                phi = relax_fraction(&law, DilatancyUpdate::Implicit, G, dt, 0.02, 0.5, phi);
            }
            phi
        };
        let (a, b, c) = (run(100), run(200), run(400));
        let ratio = (a - b) / (b - c);
        assert!((ratio - 2.0).abs() < 0.05, "observed order ratio {ratio}");
    }

    #[test]
    fn stiff_coefficients_do_not_limit_the_step() {
        // K = 1e3 and d = 1e-9 m: one huge step lands on φ_eq, small ones approach it
        // monotonically, never overshooting.
        let law = DilatantLaw {
            k: 1e3,
            d: 1e-9,
            ..DilatantLaw::table1()
        };
        for dt in [1e-6, 1e-3, 1.0, 1e6] {
            let mut phi = 0.62;
            for _ in 0..100 {
                let eq = law.phi_eq(law.inertial_number(G, 1e-3, 2.0, phi));
                let next = relax_fraction(&law, DilatancyUpdate::Implicit, G, dt, 1e-3, 2.0, phi);
                assert!(next <= phi && next >= eq, "dt={dt}: {next} vs φ_eq {eq}");
                phi = next;
            }
            if dt >= 1.0 {
                // Stiffness Δt γ̇ K φ ≥ 3e6: at the fixed point φ = φ_eq(I(φ)).
                let eq = law.phi_eq(law.inertial_number(G, 1e-3, 2.0, phi));
                assert!((phi - eq).abs() < 1e-9, "dt={dt}: {phi} vs {eq}");
            }
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(3000))]

        #[test]
        fn fraction_stays_between_start_and_equilibrium(
            h in 1e-9f64..1.0, v in -10.0f64..10.0, phi in 1e-3f64..0.999,
            dt in 0.0f64..10.0, k in 0.0f64..1e3, d in 1e-9f64..1e-2,
            reg in prop_oneof![Just(PhiEq::F0), Just(PhiEq::F1), Just(PhiEq::F2 { n: 1.0 })],
            exponential in any::<bool>(),
        ) {
            let law = DilatantLaw { k, d, phi_eq: reg, ..DilatantLaw::table1() };
            let update = if exponential { DilatancyUpdate::Exponential } else { DilatancyUpdate::Implicit };
            let next = relax_fraction(&law, update, G, dt, h, v, phi);
            let i = law.inertial_number(G, h, v, phi);
            let eq = law.phi_eq(i);
            let (lo, hi) = (phi.min(eq), phi.max(eq));
            prop_assert!(next.is_finite());
            prop_assert!(lo - 1e-15 <= next && next <= hi + 1e-15, "{} not in [{}, {}]", next, lo, hi);
            prop_assert!(next < 1.0);
            // φ_eq underflows to 0 for f0, and for f1 in thin fast films (I ~ 1e6):
            // then φ may reach 0 and the step reports it. f2 (N = 1) only decays as 1/I.
            if eq > 0.0 { prop_assert!(next > 0.0); }
            if reg == (PhiEq::F2 { n: 1.0 }) { prop_assert!(eq > 0.0); }
        }
    }
}
