//! The column-local kernel of the multilayer μ(I) viscous step (Escalante et al. 2023,
//! eq. 23–25; Fernández-Nieto et al. 2016, eq. 24–28), shared by the line
//! (`viscous.rs`, [`super::viscous::MultilayerViscousStep`]) and the raster
//! (`viscous_2d.rs`): the frozen coefficients of one column from its strain rates, and
//! the elimination of its symmetric tridiagonal system.
//!
//! A column of thickness h with layer fractions l_α has, at interface α + 1/2, the
//! viscosity over density ν = μ(I) p / R(s) with p/ρ = g_n h Σ_{β>α} l_β and the strain
//! rate s; at the bed μ(I_{1/2}) (Coulomb) or ν_{1/2} (no slip) from the basal shear
//! rate. On the line s = |∂_z u|; on a raster s = |∂_z (u, v)| (the norm of the vector
//! shear, Fernández-Nieto et al. 2016, eq. 24 with ‖D‖ of the horizontal velocity),
//! computed as `hypot` of the two components, which is |∂_z u| to the bit where v ≡ 0.
//!
//! The system l_α h u_α − Δt (couplings) = l_α q*_α is the same for every component of
//! the velocity (the coefficients are scalars): `eliminate_down` reduces any number
//! of right-hand sides (lanes: four columns of the line, or the two components of one
//! raster column) to the bottom equation d u_1 = r − Δt σ s, s ∈ Sgn(u_1), which the
//! caller solves (the line: per lane; the raster: as a vector, the disk
//! |Δt σ s| ≤ Δt σ), and `substitute_up` returns the layers above.

use crate::physics::rheology::LocalFriction;
use crate::physics::GRAVITY;

/// Condition at the bed of the multilayer model (Fernández-Nieto et al. 2016, eq. 28 and end of §3.3).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BasalCondition {
    /// Coulomb friction μ(I_{1/2}) p_b u_1/|u_1| (`rheology.basal = "coulomb"`).
    Coulomb,
    /// u = 0 at the bed, stress from the rheology with ∂_z u ≈ 2u_1/h_1 (`"no_slip"`).
    NoSlip,
}

/// How the μ(I) viscosity η = μ(I) p / |∂_z u| is kept finite where the shear vanishes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Regularization {
    /// η = μ p / √(‖D‖² + δ²) (Escalante et al. 2023, eq. 10), `rheology.delta` = δ in 1/s.
    Delta { delta: f64 },
    /// η = μ p / max(‖D‖, μ p/η_M), η_M = 250 ρ √(g h³) (Fernández-Nieto et al. 2016, eq. 6 and 25).
    Bound,
}

/// Where the sidewall friction of a channel of width W enters the multilayer model.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SidewallForm {
    /// Jop's term μ_w (H − z)/W added to μ(I) (Fernández-Nieto et al. 2016, eq. 30).
    Jop,
    /// A friction force −l_α h (2/W) μ_w p_α u_α/|u_α| on each layer (Escalante et al. 2023, eq. 36).
    Layer,
}

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sidewall {
    /// Wall friction coefficient μ_w.
    pub mu_w: f64,
    /// Channel width W (m).
    pub width: f64,
    pub form: SidewallForm,
}

/// Options of the viscous step (from the scenario's `rheology` table).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ViscousOptions {
    pub basal: BasalCondition,
    pub regularization: Regularization,
    pub sidewall: Option<Sidewall>,
    /// Second-order strain rate of Fernández-Nieto et al. 2016, eq. (32).
    pub c_msm: bool,
    /// Where the viscosities are taken: at t^n (the paper's scheme) or at the new speed.
    pub viscosity: ViscosityTime,
}

/// Where the viscous step takes its viscosities, inertial numbers and basal friction
/// (`rheology.viscosity`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ViscosityTime {
    /// Frozen at t^n: one linear solve per column (Escalante et al. 2023, §4 "Step 2").
    Frozen,
    /// As `Frozen`, but with the non-hydrostatic pressure the velocities they are
    /// frozen from are those of the previous viscous solve, before its projection
    /// ([`crate::numerics::nh_multilayer`]). The same as `Frozen` without a
    /// projection (hydrostatic runs) and for N = 1; the default.
    Lagged,
    /// At the new speed u^{n+1}: the column equations are solved by damped Newton
    /// (module documentation) until the residual of every layer's equation, in m/s,
    /// is at most `tolerance` (plus the round-off of its evaluation) or a full Newton
    /// correction is; a column still above it after `max_iterations` solves fails the
    /// step.
    Implicit {
        tolerance: f64,
        max_iterations: usize,
    },
}

/// Per column: Σ_{β ≥ a} l_β for a = 0 … N (0-based layers), 1/√ of it (a < N), and
/// 2/(l_{a−1} + l_a) (a ≥ 1; 1/h_{α+1/2} in units of 1/h).
pub(crate) fn column_fractions(l: &[f64]) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
    let n = l.len();
    let mut above = vec![0.0; n + 1];
    for a in (0..n).rev() {
        above[a] = above[a + 1] + l[a];
    }
    let inv_sqrt_above = above[..n].iter().map(|a| 1.0 / a.sqrt()).collect();
    let mut inv_gap = vec![0.0; n];
    for a in 1..n {
        inv_gap[a] = 2.0 / (l[a - 1] + l[a]);
    }
    (above, inv_sqrt_above, inv_gap)
}

/// The rheology of one column: the law, the options and the fractions of
/// [`column_fractions`].
#[derive(Debug, Clone, Copy)]
pub(crate) struct ColumnRheology<'a, L> {
    pub law: L,
    pub opts: ViscousOptions,
    pub above: &'a [f64],
    pub inv_sqrt_above: &'a [f64],
}

impl<L: LocalFriction> ColumnRheology<'_, L> {
    /// Jop's sidewall friction μ_w (H − z)/W at depth `depth` below the surface.
    #[inline(always)]
    pub fn jop(&self, depth: f64) -> f64 {
        match self.opts.sidewall {
            Some(Sidewall {
                mu_w,
                width,
                form: SidewallForm::Jop,
            }) => mu_w * depth / width,
            _ => 0.0,
        }
    }

    /// ν = μ p / R(s): the frozen viscosity over density for strain rate `s`, friction
    /// `mu` and pressure over density `p`; `nu_max` = ν_M of the bound regularisation.
    #[inline(always)]
    pub fn viscosity(&self, mu: f64, p: f64, s: f64, nu_max: f64) -> f64 {
        let stress = mu * p;
        let r = match self.opts.regularization {
            Regularization::Delta { delta } => (s * s + 4.0 * delta * delta).sqrt(),
            Regularization::Bound => s.max(stress / nu_max),
        };
        if r > 0.0 {
            stress / r
        } else {
            0.0
        }
    }

    /// ν_M = 250 √(g h³) of the bound regularisation (∞ with δ).
    #[inline(always)]
    pub fn nu_max(&self, h: f64) -> f64 {
        match self.opts.regularization {
            Regularization::Bound => 250.0 * (GRAVITY * h * h * h).sqrt(),
            Regularization::Delta { .. } => f64::INFINITY,
        }
    }

    /// The bed's coefficient of a column of thickness `h` under p_b/ρ = `p_b`, with
    /// the law's inertial `scale` at p_b, from the basal shear rate `shear` (|u_1|/h_1
    /// for a Coulomb bed, 2|u_1|/h_1 without slip): μ_b, or ν_{1/2} without slip.
    #[inline(always)]
    pub fn bed(&self, h: f64, p_b: f64, scale: f64, nu_max: f64, shear: f64) -> f64 {
        match self.opts.basal {
            BasalCondition::Coulomb => self.law.mu_at(shear * scale) + self.jop(h),
            BasalCondition::NoSlip => {
                let mu = self.law.mu_at(shear * scale) + self.jop(h);
                self.viscosity(mu, p_b, shear, nu_max)
            }
        }
    }

    /// μ and ν_{α+1/2} at the interface above 0-based layer a − 1 (a ≥ 1) of a column
    /// of thickness `h` with strain rate `s`.
    #[inline(always)]
    pub fn interface(
        &self,
        a: usize,
        (h, p_b, scale, nu_max): (f64, f64, f64, f64),
        s: f64,
    ) -> (f64, f64) {
        let p = p_b * self.above[a];
        let mu = self.law.mu_at(s * scale * self.inv_sqrt_above[a]) + self.jop(h * self.above[a]);
        (mu, self.viscosity(mu, p, s, nu_max))
    }
}

/// Eliminates K column systems at once (lanes) from the top down: couplings `c` (c[0]
/// unused), diagonals `d` without the couplings and right-hand sides `r`, per layer.
/// The reduced diagonal of layer a is e_a + c_a, with
/// e_{a−1} = d_{a−1} + c_a e_a/(e_a + c_a): written so, no coupling is subtracted from
/// another, and a rigid column (couplings ≫ l_a h, e.g. δ → 0 at rest) keeps its mass
/// e ≈ Σ l h to round-off. Leaves the bottom equation d[0] u_1 = r[0] (less the bed's
/// friction) and, in d[a] (a ≥ 1), 1/(e_a + c_a) for [`substitute_up`].
#[inline(always)]
pub(crate) fn eliminate_down<const K: usize>(
    c: &[[f64; K]],
    d: &mut [[f64; K]],
    r: &mut [[f64; K]],
) {
    let n = d.len();
    for a in (1..n).rev() {
        let (lower, upper) = d.split_at_mut(a);
        let (r_lower, r_upper) = r.split_at_mut(a);
        let (d_a, d_below) = (&mut upper[0], &mut lower[a - 1]);
        let (r_a, r_below) = (&r_upper[0], &mut r_lower[a - 1]);
        for k in 0..K {
            let inv = 1.0 / (d_a[k] + c[a][k]);
            let m = c[a][k] * inv;
            d_below[k] += m * d_a[k];
            r_below[k] += m * r_a[k];
            d_a[k] = inv;
        }
    }
}

/// The layers above the bottom one, whose velocities `u_below` the caller solved:
/// `put(a, u)` receives the new velocities of layer a, bottom first.
#[inline(always)]
pub(crate) fn substitute_up<const K: usize>(
    c: &[[f64; K]],
    d: &[[f64; K]],
    r: &[[f64; K]],
    mut u_below: [f64; K],
    mut put: impl FnMut(usize, [f64; K]),
) {
    put(0, u_below);
    for a in 1..d.len() {
        for k in 0..K {
            u_below[k] = (r[a][k] + c[a][k] * u_below[k]) * d[a][k];
        }
        put(a, u_below);
    }
}
