//! Pointwise physics of the compressible (dilatant) μ(I)–φ model of Bouchut et al. 2021, §2
//! (docs/references.md).
//!
//! Unknowns: thickness h, slope-parallel velocity v, solid volume fraction φ. The
//! system is written in the conservative variables of Bouchut et al. 2021, eq. (3.1)–(3.3), (B.10):
//!
//!   U = (m, q, w) = (φh, φhv, φ^α h),   α > 1 (the paper uses α = 2),
//!
//!   ∂_t(φh) + ∂_x(φhv) = 0                                             (3.1)
//!   ∂_t(φhv) + ∂_x(φhv² + ½ g_c φh²) = −g_c φh ∂_x b̂ − (τ_b/ρ_s) sgn(v)    (3.2)
//!   ∂_t(φ^α h) + ∂_x(φ^α h v) = −(α − 1) φ^α h γ̇ tan ψ                   (3.3)
//!
//! with the physical flux F(U) = (φhv, φhv² + ½ g_c φh², φ^α h v) (B.12) and the wave
//! speeds v ± √(g_c h): the system is gas dynamics with γ = 2, density ρ = φh and
//! pressure g_c ρ²/(2φ), so c² = ∂p/∂ρ at fixed φ = g_c h (Bouchut et al. 2021, Appendix B).
//! From U: φ^{α−1} = w/m, h = m/φ, v = q/m.
//!
//! Closure (Bouchut et al. 2021, §2):
//!
//!   γ̇ = (5/2)|v|/h                                   (2.15)
//!   I = γ̇ d / √(p_{s|b}/ρ_s),  p_{s|b}/ρ_s = φ g_c h  (2.10), (2.11)
//!   tan ψ = K (φ − φ_eq)                              (2.8)
//!   φ_eq = φ_stat − K̃ I                               (2.9), regularised by
//!     (f0) max(0, φ_stat − K̃ I),
//!     (f1) φ_stat exp(−K̃ I / φ_stat),
//!     (f2) φ_stat / (1 + K̃ I/(N φ_stat))^N           (§2 after eq. 2.16)
//!   μ(I) = μ_1 + (μ_2 − μ_1) I/(I + I_0)              (2.14)
//!   μ_eff = max(0, μ(I) + tan ψ)                      (2.13)
//!   μ_eff,w = μ_eff + μ_w h / W                        (4.1, lateral walls)
//!
//! and the basal stress τ_b/ρ_s = μ_eff φ g_c h (2.12). K = 0 gives the incompressible
//! μ(I) model: φ is then only transported, and μ_eff = μ(I).

use super::shallow::H_DRY;

/// Regularisation of the critical-state volume fraction φ_eq(I) (Bouchut et al. 2021, §2).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum PhiEq {
    /// φ_stat − K̃ I, eq. (2.9) as printed: negative for large I (tests only).
    Linear,
    /// (f0) max(0, φ_stat − K̃ I).
    F0,
    /// (f1) φ_stat exp(−K̃ I/φ_stat).
    F1,
    /// (f2) φ_stat/(1 + K̃ I/(N φ_stat))^N, N > 0; the paper's runs use N = 1 (§3.2).
    F2 { n: f64 },
}

/// Parameters of the dilatant μ(I)–φ law (Bouchut et al. 2021, Table 1 and eq. 2.8–2.14, 4.1).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DilatantLaw {
    pub mu_1: f64,
    pub mu_2: f64,
    pub i0: f64,
    /// Grain diameter d (m).
    pub d: f64,
    /// Dilatancy coefficient K of eq. (2.8).
    pub k: f64,
    /// K̃ of eq. (2.9).
    pub k_tilde: f64,
    /// φ_stat of eq. (2.9).
    pub phi_stat: f64,
    pub phi_eq: PhiEq,
    /// Grain/wall friction μ_w and channel width W (m) of eq. (4.1); μ_w = 0: no walls.
    pub mu_w: f64,
    pub width: f64,
}

impl DilatantLaw {
    /// Bouchut et al. 2021, Table 1 (glass beads): μ_1 0.48, μ_2 0.73, I_0 0.279, d 0.7 mm, K 4.09,
    /// K̃ 0.2, φ_stat 0.582 (§4.1's text prints 0.585; Table 1 has 0.582, used here),
    /// regularisation (f2) with N = 1 (§3.2), no walls.
    pub fn table1() -> DilatantLaw {
        DilatantLaw {
            mu_1: 0.48,
            mu_2: 0.73,
            i0: 0.279,
            d: 7e-4,
            k: 4.09,
            k_tilde: 0.2,
            phi_stat: 0.582,
            phi_eq: PhiEq::F2 { n: 1.0 },
            mu_w: 0.0,
            width: 0.2,
        }
    }

    /// Critical-state volume fraction φ_eq(I) (eq. 2.9 and f0–f2).
    #[inline(always)]
    pub fn phi_eq(&self, i: f64) -> f64 {
        // The slope is dead code here once inlined.
        self.phi_eq_and_slope(i).0
    }

    /// φ_eq(I) (the regularisations' one definition) and its derivative dφ_eq/dI ≤ 0: every
    /// regularisation is convex and non-increasing in I, which the backward-Euler
    /// friction of the split scheme relies on (`numerics::dilatant::split`).
    #[inline(always)]
    pub fn phi_eq_and_slope(&self, i: f64) -> (f64, f64) {
        let (ps, kt) = (self.phi_stat, self.k_tilde);
        match self.phi_eq {
            PhiEq::Linear => (ps - kt * i, -kt),
            PhiEq::F0 => {
                let p = ps - kt * i;
                if p > 0.0 {
                    (p, -kt)
                } else {
                    (0.0, 0.0)
                }
            }
            PhiEq::F1 => {
                let p = ps * (-kt * i / ps).exp();
                (p, -kt * p / ps)
            }
            PhiEq::F2 { n } => {
                // d/dI [φ_stat b^−N] = −K̃ b^−N−1 = −K̃ φ_eq/(φ_stat b), b = 1 + K̃ I/(N φ_stat).
                let base = 1.0 + kt * i / (n * ps);
                let p = if n == 1.0 {
                    ps / base
                } else {
                    ps / base.powf(n)
                };
                (p, -kt * p / (ps * base))
            }
        }
    }

    /// An upper bound of |G''(I)| over I ≥ 0 for G = μ(I) + K(φ − φ_eq(I)) (the
    /// dilatant friction before its cut): 2(μ_2 − μ_1)/I_0² + K max|φ_eq''|, with
    /// max|φ_eq''| = 0 (2.9), K̃²/φ_stat (f1), (N + 1)K̃²/(N φ_stat) (f2); ∞ for f0,
    /// whose kink has none.
    pub fn friction_curvature_bound(&self) -> f64 {
        let (ps, kt) = (self.phi_stat, self.k_tilde);
        let phi_eq = match self.phi_eq {
            PhiEq::Linear => 0.0,
            PhiEq::F0 => f64::INFINITY,
            PhiEq::F1 => kt * kt / ps,
            PhiEq::F2 { n } => (n + 1.0) * kt * kt / (n * ps),
        };
        let dilatancy = if self.k == 0.0 { 0.0 } else { self.k * phi_eq };
        2.0 * (self.mu_2 - self.mu_1).abs() / (self.i0 * self.i0) + dilatancy
    }

    /// μ(I) of eq. (2.14), as μ_1 + (μ_2 − μ_1)/(1 + I_0/I): I = 0 gives μ_1 and I = ∞
    /// gives μ_2 without 0/0.
    #[inline(always)]
    pub fn mu_of_i(&self, i: f64) -> f64 {
        self.mu_1 + (self.mu_2 - self.mu_1) / (1.0 + self.i0 / i)
    }

    /// tan ψ = K(φ − φ_eq) (eq. 2.8).
    #[inline(always)]
    pub fn tan_psi(&self, phi: f64, phi_eq: f64) -> f64 {
        self.k * (phi - phi_eq)
    }

    /// Inertial number of a cell (eq. 2.10, 2.11, 2.15); 0 in a dry cell.
    #[inline(always)]
    pub fn inertial_number(&self, g_c: f64, h: f64, v: f64, phi: f64) -> f64 {
        if h <= H_DRY {
            return 0.0;
        }
        shear_rate(h, v) * self.d / (phi * g_c * h).sqrt()
    }

    /// Effective friction μ_eff = max(0, μ(I) + tan ψ) (eq. 2.13–2.14), plus the wall
    /// term μ_w h/W of eq. (4.1) when μ_w > 0.
    #[inline(always)]
    pub fn mu_eff(&self, g_c: f64, h: f64, v: f64, phi: f64) -> f64 {
        let i = self.inertial_number(g_c, h, v, phi);
        let mu = (self.mu_of_i(i) + self.tan_psi(phi, self.phi_eq(i))).max(0.0);
        if self.mu_w > 0.0 {
            mu + self.mu_w * h / self.width
        } else {
            mu
        }
    }
}

/// Shear rate γ̇ = (5/2)|v|/h (eq. 2.15); 0 in a dry cell.
#[inline(always)]
pub fn shear_rate(h: f64, v: f64) -> f64 {
    if h <= H_DRY {
        0.0
    } else {
        2.5 * v.abs() / h
    }
}

/// Primitive state (h, v, φ).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Primitive {
    pub h: f64,
    pub v: f64,
    pub phi: f64,
}

/// Conservative state U = (φh, φhv, φ^α h) (eq. B.10).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Conserved {
    pub m: f64,
    pub q: f64,
    pub w: f64,
}

impl Primitive {
    /// U = (φh, φhv, φ^α h).
    #[inline(always)]
    pub fn conserved(&self, alpha: f64) -> Conserved {
        let m = self.phi * self.h;
        Conserved {
            m,
            q: m * self.v,
            w: m * phi_power(self.phi, alpha),
        }
    }

    /// Physical flux F(U) = (φhv, φhv² + ½ g_c φh², φ^α h v) (eq. B.12).
    #[inline(always)]
    pub fn flux(&self, g_c: f64, alpha: f64) -> Conserved {
        let m = self.phi * self.h;
        let mass = m * self.v;
        Conserved {
            m: mass,
            q: mass * self.v + pressure(g_c, self.h, self.phi),
            w: mass * phi_power(self.phi, alpha),
        }
    }

    /// The wave speeds v ∓ √(g_c h) (Bouchut et al. 2021, Appendix B: gas dynamics with γ = 2).
    #[inline(always)]
    pub fn wave_speeds(&self, g_c: f64) -> (f64, f64) {
        let c = (g_c * self.h.max(0.0)).sqrt();
        (self.v - c, self.v + c)
    }

    /// Energy φh v²/2 + g_c φh²/2 + g_c φh z (eq. B.14–B.15, per ρ_s).
    #[inline(always)]
    pub fn energy(&self, g_c: f64, z: f64) -> f64 {
        let m = self.phi * self.h;
        0.5 * m * self.v * self.v + pressure(g_c, self.h, self.phi) + g_c * m * z
    }
}

impl Conserved {
    /// (h, v, φ) from U with φ^{α−1} = w/m; `None` where m ≤ 0 (φ undetermined: the
    /// caller supplies it, Bouchut et al. 2021, eq. 3.14).
    #[inline(always)]
    pub fn primitive(&self, alpha: f64) -> Option<Primitive> {
        if self.m <= 0.0 {
            return None;
        }
        let phi = phi_from_ratio(self.w / self.m, alpha);
        Some(Primitive {
            h: self.m / phi,
            v: self.q / self.m,
            phi,
        })
    }
}

/// φ^{α−1} (α = 2: φ itself, no `powf`).
#[inline(always)]
pub fn phi_power(phi: f64, alpha: f64) -> f64 {
    if alpha == 2.0 {
        phi
    } else {
        phi.powf(alpha - 1.0)
    }
}

/// φ from φ^{α−1}.
#[inline(always)]
pub fn phi_from_ratio(ratio: f64, alpha: f64) -> f64 {
    if alpha == 2.0 {
        ratio
    } else {
        ratio.powf(1.0 / (alpha - 1.0))
    }
}

/// Hydrostatic pressure over density ½ g_c φ h² (eq. 2.6, B.12).
#[inline(always)]
pub fn pressure(g_c: f64, h: f64, phi: f64) -> f64 {
    0.5 * g_c * phi * h * h
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    const G: f64 = 9.81;

    // Reference values computed by hand (Python, double precision) from eq. 2.8–2.15
    // and Table 1 for h = 2 cm, v = 0.5 m/s, φ = 0.6, g_c = 9.81:
    // γ̇ = 62.5 1/s, I = 62.5 · 7e-4 / √(0.6 · 9.81 · 0.02).
    const I_REF: f64 = 0.127_512_549_934_340_7;

    #[test]
    fn inertial_number_and_phi_eq_match_hand_values() {
        let mut law = DilatantLaw::table1();
        assert_eq!(shear_rate(0.02, -0.5), 62.5);
        assert_relative_eq!(
            law.inertial_number(G, 0.02, 0.5, 0.6),
            I_REF,
            max_relative = 1e-14
        );
        let cases = [
            (PhiEq::Linear, 0.556_497_490_013_131_9),
            (PhiEq::F0, 0.556_497_490_013_131_9),
            (PhiEq::F1, 0.557_048_161_484_135_2),
            (PhiEq::F2 { n: 1.0 }, 0.557_568_066_685_554_7),
            (PhiEq::F2 { n: 3.0 }, 0.557_224_735_491_729_1),
        ];
        for (reg, expected) in cases {
            law.phi_eq = reg;
            assert_relative_eq!(law.phi_eq(I_REF), expected, max_relative = 1e-14);
        }
    }

    #[test]
    fn regularisations_stay_in_the_unit_interval_and_agree_at_small_i() {
        let mut law = DilatantLaw::table1();
        for reg in [
            PhiEq::F0,
            PhiEq::F1,
            PhiEq::F2 { n: 1.0 },
            PhiEq::F2 { n: 5.0 },
        ] {
            law.phi_eq = reg;
            assert_eq!(law.phi_eq(0.0), law.phi_stat);
            for i in [1e-3, 1.0, 10.0, 1e3, 1e8] {
                let p = law.phi_eq(i);
                assert!((0.0..=law.phi_stat).contains(&p), "{reg:?} I={i}: {p}");
            }
            // Same slope −K̃ at I = 0 as eq. (2.9).
            let slope = (law.phi_eq(1e-7) - law.phi_stat) / 1e-7;
            assert_relative_eq!(slope, -law.k_tilde, max_relative = 1e-5);
        }
        law.phi_eq = PhiEq::Linear;
        assert!(law.phi_eq(10.0) < 0.0, "(2.9) leaves [0, 1] at large I");
        law.phi_eq = PhiEq::F0;
        assert_eq!(law.phi_eq(10.0), 0.0);
        // (f2) tends to (f1) as N grows (Bouchut et al. 2021, Fig. 2 discussion).
        let f1 = DilatantLaw {
            phi_eq: PhiEq::F1,
            ..law
        }
        .phi_eq(2.0);
        let f2 = DilatantLaw {
            phi_eq: PhiEq::F2 { n: 1e6 },
            ..law
        }
        .phi_eq(2.0);
        assert_relative_eq!(f1, f2, max_relative = 1e-6);
    }

    #[test]
    fn phi_eq_slope_is_the_derivative() {
        let mut law = DilatantLaw::table1();
        for reg in [
            PhiEq::Linear,
            PhiEq::F0,
            PhiEq::F1,
            PhiEq::F2 { n: 1.0 },
            PhiEq::F2 { n: 3.0 },
        ] {
            law.phi_eq = reg;
            for i in [0.0, 1e-3, 0.07, 0.5, 2.0] {
                let (p, slope) = law.phi_eq_and_slope(i);
                assert_eq!(p, law.phi_eq(i), "{reg:?} I={i}");
                let e = 1e-6;
                let fd =
                    (law.phi_eq(i + e) - law.phi_eq((i - e).max(0.0))) / (i + e - (i - e).max(0.0));
                assert_relative_eq!(slope, fd, max_relative = 1e-6, epsilon = 1e-12);
                assert!(slope <= 0.0);
            }
        }
    }

    #[test]
    fn friction_curvature_bound_holds() {
        let mut law = DilatantLaw::table1();
        for reg in [
            PhiEq::Linear,
            PhiEq::F1,
            PhiEq::F2 { n: 1.0 },
            PhiEq::F2 { n: 3.0 },
        ] {
            law.phi_eq = reg;
            let g = |i: f64| law.mu_of_i(i) - law.k * law.phi_eq(i);
            let bound = law.friction_curvature_bound();
            for i in [1e-4, 1e-2, 0.1, 1.0] {
                let e = 0.5 * i;
                let second = (g(i + e) - 2.0 * g(i) + g(i - e)) / (e * e);
                assert!(
                    second <= 0.0 && -second <= bound * (1.0 + 1e-3),
                    "{reg:?} I={i}: {second} vs {bound}"
                );
            }
        }
    }

    #[test]
    fn effective_friction_matches_hand_values() {
        let mut law = DilatantLaw::table1();
        let mu = 0.558_418_581_391_236_5;
        assert_relative_eq!(law.mu_of_i(I_REF), mu, max_relative = 1e-14);
        // tan ψ = 4.09 (0.6 − φ_eq) with (f2), N = 1: the dense mass dilates (ψ > 0).
        assert_relative_eq!(
            law.mu_eff(G, 0.02, 0.5, 0.6),
            0.731_965_188_647_317_6,
            max_relative = 1e-13
        );
        law.mu_w = 0.18;
        assert_relative_eq!(
            law.mu_eff(G, 0.02, 0.5, 0.6),
            0.749_965_188_647_317_6,
            max_relative = 1e-13
        );
        law.mu_w = 0.0;
        // At rest: μ_1 + K(φ − φ_stat); a very loose mass is cut at 0 (eq. 2.13).
        assert_relative_eq!(law.mu_eff(G, 0.1, 0.0, 0.55), 0.48 + 4.09 * (0.55 - 0.582));
        assert_eq!(law.mu_eff(G, 0.1, 0.0, 0.2), 0.0);
        // K = 0: the incompressible μ(I).
        law.k = 0.0;
        assert_eq!(law.mu_eff(G, 0.02, 0.5, 0.6), law.mu_of_i(I_REF));
        assert_eq!(law.mu_of_i(0.0), 0.48);
        assert_eq!(law.mu_of_i(f64::INFINITY), 0.73);
    }

    #[test]
    fn conserved_variables_round_trip_and_flux() {
        for alpha in [2.0, 1.5, 3.0] {
            let p = Primitive {
                h: 0.1,
                v: -0.7,
                phi: 0.58,
            };
            let u = p.conserved(alpha);
            assert_relative_eq!(u.m, 0.058, max_relative = 1e-15);
            assert_relative_eq!(u.w, 0.1 * 0.58f64.powf(alpha), max_relative = 1e-14);
            let back = u.primitive(alpha).unwrap();
            assert_relative_eq!(back.h, p.h, max_relative = 1e-14);
            assert_relative_eq!(back.v, p.v, max_relative = 1e-14);
            assert_relative_eq!(back.phi, p.phi, max_relative = 1e-14);
            let f = p.flux(G, alpha);
            assert_relative_eq!(f.m, 0.058 * -0.7, max_relative = 1e-15);
            assert_relative_eq!(
                f.q,
                0.058 * 0.49 + 0.5 * G * 0.58 * 0.01,
                max_relative = 1e-14
            );
            assert_relative_eq!(f.w, u.w * -0.7, max_relative = 1e-14);
        }
        let dry = Conserved {
            m: 0.0,
            q: 0.0,
            w: 0.0,
        };
        assert!(dry.primitive(2.0).is_none());
        let (sl, sr) = Primitive {
            h: 0.1,
            v: 1.0,
            phi: 0.6,
        }
        .wave_speeds(G);
        assert_relative_eq!(sl, 1.0 - (G * 0.1f64).sqrt());
        assert_relative_eq!(sr, 1.0 + (G * 0.1f64).sqrt());
    }

    #[test]
    fn pressure_jump_is_the_nonconservative_form() {
        // ∂_x(g φ h²/2) = g φ h ∂_x h + g (h²/2) ∂_x φ (eq. 2.4 vs 2.6): a finite-
        // difference check of the product rule the scheme's X (eq. 3.9) relies on.
        let (h0, phi0, dh, dphi, e) = (0.1, 0.6, 0.3, -0.2, 1e-6);
        let p = |s: f64| pressure(G, h0 + dh * s, phi0 + dphi * s);
        let derivative = (p(e) - p(-e)) / (2.0 * e);
        assert_relative_eq!(
            derivative,
            G * phi0 * h0 * dh + G * 0.5 * h0 * h0 * dphi,
            max_relative = 1e-8
        );
    }
}
