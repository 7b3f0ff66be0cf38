//! Pointwise physics of the two-layer submarine-avalanche model (Fernández-Nieto et al. 2008): an inviscid
//! water layer (index 1) over a fluidised granular layer (index 2) with Coulomb
//! friction, in the Cartesian form of Fernández-Nieto et al. 2008, eq. (62)/(65).
//!
//! Unknowns per cell W = (H₁, Q₁, H₂, Q₂), H_k = h_k / cos θ (h_k the thickness normal
//! to the bed), Q_k = H_k U_k (U_k the velocity along the bed). θ(x) is the bed angle,
//! tan θ = b'(x) (counter-clockwise, so that the curvature term h₂ U₂² ∂_X θ of eq. 44
//! raises the normal stress where the bed is concave, e.g. at the foot of a slope).
//! The water free surface and the interface are (Fernández-Nieto et al. 2008, §5, Remark 9)
//!
//!   η = b + (H₁ + H₂) cos²θ,   ζ = b + H₂ cos²θ.
//!
//! Flux (Fernández-Nieto et al. 2008, after eq. 72, with α = cos θ, β = cos²θ):
//!
//!   𝓕(α, β, W) = (Q₁ α, Q₁²/H₁ α + g H₁²/2 αβ, Q₂ α, Q₂²/H₂ α + g A₂ H₂²/2 αβ),
//!
//! coupling B(W)∂_x W with B₂₃ = −g H₁ cos³θ, B₄₁ = −r A₁ g H₂ cos³θ (eq. 65), and
//! A₁ = λ₁ + K(1 − λ₁), A₂ = rλ₂ + K(1 − rλ₂) (eq. 50; A₁ = A₂ = 1 for K = 1, Remark 6).
//!
//! Coulomb friction (eq. 46–47 in local form, eq. 63–64 in Cartesian form): the
//! source of the Q₂ equation is 𝒯/cos θ with
//!
//!   𝒯/cos θ = −(g (1 − r) H₂ cos θ + H₂ U₂² ∂_x(sin θ)) tan δ₀ sgn(Q₂),
//!
//! the first term the buoyancy-reduced normal stress (pore water of density r ρ₂), the
//! second the centripetal part (eq. 44). The normal stress is clamped at zero: on a
//! convex bed at high speed the layer would lift off, and a negative "friction" would
//! accelerate it. [`Buoyancy::Submerged`] applies the reduction 1 − r only where water
//! covers the grains (a granular mass in air has no pore water); the paper's printed
//! eq. (46) applies it everywhere ([`Buoyancy::Everywhere`], the default, needed to
//! reproduce Fernández-Nieto et al. 2008, §5.2: with δ₀ = 12° > θ = 11.31° a dry mass would not move at
//! all, yet the paper's deposit is fully submerged).
//!
//! Characteristic speeds: the characteristic polynomial of 𝒜 (eq. 66) is
//!
//!   p₁(λ) p₂(λ) = r A₁ g² H₁ H₂ cos⁸θ,
//!   p₁ = (λ − U₁ cos θ)² − g H₁ cos⁴θ,   p₂ = (λ − U₂ cos θ)² − g A₂ H₂ cos⁴θ
//!
//! (eq. 67 prints it without the powers of cos θ, i.e. in local coordinates). If
//! |λ − U_k cos θ| > c for both k, with c = cos²θ √(g (H₁ + A₂ H₂)), then p₁ > g A₂ H₂ cos⁴θ
//! and p₂ > g H₁ cos⁴θ, so p₁p₂ > g² A₂ H₁ H₂ cos⁸θ ≥ r A₁ g² H₁ H₂ cos⁸θ when A₂ ≥ r A₁
//! (true for K = 1 and r ≤ 1). Hence every real eigenvalue lies in
//!
//!   [min_k U_k cos θ − c, max_k U_k cos θ + c]        ([`speed_bounds`]).
//!
//! When the internal eigenvalues are complex (shear instability, eq. 70) the model is
//! outside its range of validity; the bound then still covers the real parts' spread
//! of the external pair and is used as the (dissipative) HLL bound — the scheme stays
//! stable but cannot represent the Kelvin–Helmholtz mixing (documented in
//! docs/numerics.md).

use super::GRAVITY;

/// Thickness H (m) below which a layer is treated as absent in a cell: its velocity is
/// taken as zero (mass is never removed, so conservation stays exact).
pub const H_DRY_TWO_LAYER: f64 = 1e-8;

/// Where the buoyancy reduction (1 − r) of the Coulomb normal stress applies.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Buoyancy {
    /// Everywhere (Fernández-Nieto et al. 2008, eq. 46 as printed; the paper's §5 results).
    Everywhere,
    /// Only where water covers the grains (H₁ > dry): a mass in air feels g h₂ cos θ.
    Submerged,
}

/// Material parameters of the two-layer model.
#[derive(Debug, Clone, Copy)]
pub struct TwoLayerParams {
    pub g: f64,
    /// Density ratio r = ρ₁/ρ₂ ∈ [0, 1).
    pub r: f64,
    /// A₁ = λ₁ + K(1 − λ₁).
    pub a1: f64,
    /// A₂ = rλ₂ + K(1 − rλ₂).
    pub a2: f64,
    /// tan δ₀, δ₀ the Coulomb friction angle.
    pub tan_delta: f64,
    pub buoyancy: Buoyancy,
}

impl TwoLayerParams {
    /// Parameters from r, K, λ₁, λ₂ and δ₀ in degrees (Fernández-Nieto et al. 2008, eq. 50).
    pub fn new(r: f64, k: f64, lambda1: f64, lambda2: f64, delta0_deg: f64) -> Self {
        TwoLayerParams {
            g: GRAVITY,
            r,
            a1: lambda1 + k * (1.0 - lambda1),
            a2: r * lambda2 + k * (1.0 - r * lambda2),
            tan_delta: delta0_deg.to_radians().tan(),
            buoyancy: Buoyancy::Everywhere,
        }
    }

    /// The paper's §5 set-up: K = 1 (so A₁ = A₂ = 1), K_in = 0.
    pub fn isotropic(r: f64, delta0_deg: f64) -> Self {
        Self::new(r, 1.0, 0.0, 0.0, delta0_deg)
    }

    /// 1 − r where the reduction applies (see [`Buoyancy`]).
    #[inline(always)]
    pub fn buoyancy_factor(&self, h1: f64) -> f64 {
        match self.buoyancy {
            Buoyancy::Everywhere => 1.0 - self.r,
            Buoyancy::Submerged => {
                if h1 > H_DRY_TWO_LAYER {
                    1.0 - self.r
                } else {
                    1.0
                }
            }
        }
    }

    /// Whether the bound of [`speed_bounds`] is proven (A₂ ≥ r A₁).
    pub fn bound_is_proven(&self) -> bool {
        self.a2 >= self.r * self.a1
    }
}

/// max(a, b) of two numbers by one comparison. `f64::max` also returns the number
/// when the other is NaN, which costs four more instructions per call in the hot loops
/// (x86) and hides a NaN; here a NaN `a` is returned (b > NaN is false).
#[inline(always)]
pub fn max_num(a: f64, b: f64) -> f64 {
    if b > a {
        b
    } else {
        a
    }
}

/// min(a, b) of two numbers by one comparison (see [`max_num`]).
#[inline(always)]
pub fn min_num(a: f64, b: f64) -> f64 {
    if b < a {
        b
    } else {
        a
    }
}

/// Layer velocity U = Q/H, zero where the layer is absent.
#[inline(always)]
pub fn layer_velocity(h: f64, q: f64) -> f64 {
    if h > H_DRY_TWO_LAYER {
        q / h
    } else {
        0.0
    }
}

/// 𝓕(α, β, W) of Fernández-Nieto et al. 2008 (after eq. 72) for one state; `u1`, `u2` the velocities.
#[inline(always)]
pub fn flux(p: &TwoLayerParams, alpha: f64, beta: f64, w: [f64; 4], u1: f64, u2: f64) -> [f64; 4] {
    let half_g_ab = 0.5 * p.g * alpha * beta;
    [
        w[1] * alpha,
        w[1] * u1 * alpha + half_g_ab * w[0] * w[0],
        w[3] * alpha,
        w[3] * u2 * alpha + p.a2 * half_g_ab * w[2] * w[2],
    ]
}

/// Bounds (λ_min, λ_max) of the real eigenvalues of 𝒜 (eq. 66) at a state with
/// velocities u1, u2, thicknesses h1, h2 and cos θ = `cos`: see the module docs.
#[inline(always)]
pub fn speed_bounds(
    p: &TwoLayerParams,
    cos: f64,
    h1: f64,
    h2: f64,
    u1: f64,
    u2: f64,
) -> (f64, f64) {
    let c = cos * cos * (p.g * (max_num(h1, 0.0) + p.a2 * max_num(h2, 0.0))).sqrt();
    // Branch-free min/max (the same numbers as sorting u1, u2; a −0/+0 tie may give
    // hi = −0, which c ≥ 0 turns into the same bound).
    let (lo, hi) = (min_num(u1, u2), max_num(u1, u2));
    (lo * cos - c, hi * cos + c)
}

/// The transport matrix 𝒜(θ, W) of Fernández-Nieto et al. 2008, eq. (66), row-major (tests and docs).
pub fn transport_matrix(
    p: &TwoLayerParams,
    cos: f64,
    h1: f64,
    h2: f64,
    u1: f64,
    u2: f64,
) -> [[f64; 4]; 4] {
    let c3 = cos * cos * cos;
    [
        [0.0, cos, 0.0, 0.0],
        [
            -u1 * u1 * cos + p.g * h1 * c3,
            2.0 * u1 * cos,
            p.g * h1 * c3,
            0.0,
        ],
        [0.0, 0.0, 0.0, cos],
        [
            p.r * p.a1 * p.g * h2 * c3,
            0.0,
            -u2 * u2 * cos + p.a2 * p.g * h2 * c3,
            2.0 * u2 * cos,
        ],
    ]
}

/// Characteristic polynomial det(𝒜 − λI) in the factored form of eq. (67) with the
/// Cartesian powers of cos θ: p₁(λ) p₂(λ) − r A₁ g² H₁ H₂ cos⁸θ.
pub fn characteristic(
    p: &TwoLayerParams,
    cos: f64,
    h1: f64,
    h2: f64,
    u1: f64,
    u2: f64,
    lambda: f64,
) -> f64 {
    let c4 = cos.powi(4);
    let p1 = (lambda - u1 * cos).powi(2) - p.g * h1 * c4;
    let p2 = (lambda - u2 * cos).powi(2) - p.g * p.a2 * h2 * c4;
    p1 * p2 - p.r * p.a1 * p.g * p.g * h1 * h2 * c4 * c4
}

/// The magnitude of the Coulomb source of the Q₂ equation divided by tan δ₀:
/// N = max(0, g f_b H₂ cos θ + H₂ U₂² ∂_x sin θ) (f_b the buoyancy factor).
#[inline(always)]
pub fn coulomb_normal_stress(
    p: &TwoLayerParams,
    h1: f64,
    h2: f64,
    cos: f64,
    u2: f64,
    dsin_dx: f64,
) -> f64 {
    max_num(
        p.g * p.buoyancy_factor(h1) * h2 * cos + h2 * u2 * u2 * dsin_dx,
        0.0,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    /// det(M − λI) of a 4×4 matrix by cofactor expansion.
    fn det_shift(m: &[[f64; 4]; 4], lambda: f64) -> f64 {
        let mut a = *m;
        for (i, row) in a.iter_mut().enumerate() {
            row[i] -= lambda;
        }
        let det3 = |r: [usize; 3], c: [usize; 3]| {
            a[r[0]][c[0]] * (a[r[1]][c[1]] * a[r[2]][c[2]] - a[r[1]][c[2]] * a[r[2]][c[1]])
                - a[r[0]][c[1]] * (a[r[1]][c[0]] * a[r[2]][c[2]] - a[r[1]][c[2]] * a[r[2]][c[0]])
                + a[r[0]][c[2]] * (a[r[1]][c[0]] * a[r[2]][c[1]] - a[r[1]][c[1]] * a[r[2]][c[0]])
        };
        let mut det = 0.0;
        for (j, &a0j) in a[0].iter().enumerate() {
            let cols: Vec<usize> = (0..4).filter(|&c| c != j).collect();
            let sign = if j % 2 == 0 { 1.0 } else { -1.0 };
            det += sign * a0j * det3([1, 2, 3], [cols[0], cols[1], cols[2]]);
        }
        det
    }

    #[test]
    fn characteristic_polynomial_is_the_determinant_of_the_transport_matrix() {
        let p = TwoLayerParams::new(0.2, 1.3, 0.4, 0.7, 25.0);
        let (cos, h1, h2, u1, u2) = (0.93, 1.7, 0.6, 0.8, -0.3);
        let m = transport_matrix(&p, cos, h1, h2, u1, u2);
        for lambda in [-3.0, -0.4, 0.0, 1.1, 5.0] {
            let a = det_shift(&m, lambda);
            let b = characteristic(&p, cos, h1, h2, u1, u2, lambda);
            assert!(
                (a - b).abs() < 1e-9 * (1.0 + a.abs()),
                "{lambda}: {a} vs {b}"
            );
        }
    }

    /// All real roots of det(𝒜 − λI) lie inside the proven bounds: the polynomial has
    /// no sign change outside them, and (for hyperbolic states) four roots inside.
    #[test]
    fn speed_bounds_contain_every_real_eigenvalue() {
        let mut seed = 12345u64;
        let mut rand = || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        for _ in 0..2000 {
            let p = TwoLayerParams::isotropic(0.9 * rand(), 20.0);
            let cos = 0.5 + 0.5 * rand();
            let (h1, h2) = (3.0 * rand(), 3.0 * rand());
            let (u1, u2) = (8.0 * rand() - 4.0, 8.0 * rand() - 4.0);
            let (lo, hi) = speed_bounds(&p, cos, h1, h2, u1, u2);
            // The leading coefficient is +1: outside the bounds the polynomial must be
            // positive (no root), scanned on a fine grid up to 3× the span.
            let span = hi - lo + 1.0;
            for k in 1..=400 {
                let d = span * 3.0 * k as f64 / 400.0;
                assert!(characteristic(&p, cos, h1, h2, u1, u2, hi + d) > 0.0);
                assert!(characteristic(&p, cos, h1, h2, u1, u2, lo - d) > 0.0);
            }
        }
    }

    #[test]
    fn bound_is_attained_by_the_external_wave_of_a_layer_at_rest_as_r_tends_to_one() {
        // r = 1, A = 1, U = 0: λ_ext = ±cos²θ √(g(H₁ + H₂)) exactly (eq. 68).
        let p = TwoLayerParams::isotropic(1.0, 20.0);
        let (lo, hi) = speed_bounds(&p, 0.8, 1.0, 2.0, 0.0, 0.0);
        assert!(characteristic(&p, 0.8, 1.0, 2.0, 0.0, 0.0, hi).abs() < 1e-9);
        assert!(characteristic(&p, 0.8, 1.0, 2.0, 0.0, 0.0, lo).abs() < 1e-9);
    }
}
