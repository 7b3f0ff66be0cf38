//! Stabilisation viscosity (Bouchut et al. 2021, §3.3, eq. 3.20–3.22): each conservative variable
//! U_c ∈ {φh, φhv, φ^α h} diffuses with the face coefficient
//!
//!   ι_c = max(0, ξ_c v Δz)                                                 (3.21)
//!
//! (v = v_interf of eq. 3.8 and Δz the total topography jump of eq. 3.6 at that face,
//! so ι = O(Δx)), by the centred explicit scheme
//!
//!   U_i ← U_i + Δt/Δx² (ι_{i+1/2}(U_{i+1} − U_i) − ι_{i−1/2}(U_i − U_{i−1})),
//!
//! stable under Δt max ι/Δx² ≤ ½ (3.22). Instead of shortening the time step, the
//! step is sub-cycled into n = ⌈2Δt max ι/Δx²⌉ equal parts.
//!
//! Each sub-step is a convex combination of neighbouring values, so φh ≥ 0 and
//! φ^α h ≥ 0 hold. φ^{α−1} = (φ^α h)/(φh) obeys a maximum principle only when
//! ξ_1 = ξ_3: with the paper's ξ_1 = 2, ξ_3 = 5, the fraction of a thin layer next to
//! a thick one is multiplied by up to ξ_3/ξ_1 (`tests/dilatant.rs`), and a film ahead
//! of a front can reach φ > 1. Our default is ξ = (2, 2, 2); the paper's values are
//! a scenario setting away.

/// The coefficients ξ_1, ξ_2, ξ_3 of eq. (3.21).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Viscosity {
    pub xi: [f64; 3],
}

impl Default for Viscosity {
    fn default() -> Self {
        Viscosity {
            xi: [2.0, 2.0, 2.0],
        }
    }
}

impl Viscosity {
    /// The paper's values ξ = (2, 2, 5) (Bouchut et al. 2021, §3.3).
    pub fn paper() -> Self {
        Viscosity {
            xi: [2.0, 2.0, 5.0],
        }
    }

    pub fn is_off(&self) -> bool {
        self.xi.iter().all(|&x| x == 0.0)
    }

    /// Number of sub-steps for a step `dt` when the largest max(0, vΔz) is `drive`;
    /// `Err(ratio)` when the stability ratio 2Δt ξ drive/Δx² asks for more than
    /// [`MAX_SUBSTEPS`] (or is infinite): the step would then run for hours without a
    /// chance to be interrupted.
    pub fn substeps(&self, drive: f64, dt: f64, dx: f64) -> Result<usize, f64> {
        let xi = self.xi.iter().cloned().fold(0.0, f64::max);
        let ratio = 2.0 * dt * xi * drive / (dx * dx);
        if ratio == f64::INFINITY || ratio > MAX_SUBSTEPS as f64 {
            Err(ratio)
        } else if ratio > 1.0 {
            Ok(ratio.ceil() as usize)
        } else {
            Ok(1)
        }
    }
}

/// Most explicit sub-steps of the stabilisation in one time step.
pub const MAX_SUBSTEPS: usize = 10_000;

/// One explicit sub-step on `u` (ghost-inclusive, nx + 2) with face coefficients
/// `r · ι_{k}` given as `rate[k]` (faces k = 0..=nx between cells k and k + 1),
/// `r = Δt_sub/Δx²`. `scratch` holds the nx + 1 face fluxes.
pub fn diffuse(u: &mut [f64], rate: &[f64], scratch: &mut [f64]) {
    let nx = u.len() - 2;
    for k in 0..=nx {
        scratch[k] = rate[k] * (u[k + 1] - u[k]);
    }
    for i in 1..=nx {
        u[i] += scratch[i] - scratch[i - 1];
    }
}

/// [`diffuse`] on one run of active faces, in one pass: `u` holds the cells a..=b + 1
/// of the faces a..=b whose drives max(0, vΔz) are `drive` (the faces a − 1 and b + 1
/// carry none), face k's coefficient is `rate · drive[k]` (rate = ξ_c Δt_sub/Δx²).
/// The same operations as [`diffuse`] on these cells with zero rates outside: each
/// face flux is formed from values not yet updated, the last cell's from the one
/// before.
#[inline(always)]
pub fn diffuse_run(u: &mut [f64], drive: &[f64], rate: f64) {
    let faces = drive.len();
    assert!(u.len() == faces + 1);
    let mut before = 0.0;
    for k in 0..faces {
        let flux = rate * drive[k] * (u[k + 1] - u[k]);
        u[k] += flux - before;
        before = flux;
    }
    u[faces] += 0.0 - before;
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn substeps_keep_the_parabolic_cfl() {
        let v = Viscosity::paper();
        // Δt ξ_max drive/Δx² = 1e-3 · 5 · 0.01 / 1e-4 = 0.5: one step is enough.
        assert_eq!(v.substeps(0.01, 1e-3, 1e-2), Ok(1));
        assert_eq!(v.substeps(0.011, 1e-3, 1e-2), Ok(2));
        assert_eq!(v.substeps(0.0, 1e-3, 1e-2), Ok(1));
        assert!(v.substeps(1.0, 1e300, 1e-2).is_err());
    }

    #[test]
    fn unequal_coefficients_break_the_fraction_bound_beside_a_film() {
        // A 10 cm layer beside a 1 µm film, both at φ = 0.6 (α = 2: w = φ m), face
        // rate r ξ_c max(0, vΔz) with r max(0, vΔz) = 0.09 (parabolic CFL holds for
        // ξ ≤ 5.5). With ξ = (2, ·, 5) the film's φ = w/m becomes ≈ 0.6 · 5/2 > 1.
        let (m_thick, m_film) = (0.06, 6e-7);
        let fraction_after = |xi: Viscosity| {
            let mut m = vec![m_thick, m_thick, m_film, m_film];
            let mut w: Vec<f64> = m.iter().map(|m| 0.6 * m).collect();
            let mut scratch = vec![0.0; 3];
            let rate = |x: f64| [0.0, 0.09 * x, 0.0];
            diffuse(&mut m, &rate(xi.xi[0]), &mut scratch);
            diffuse(&mut w, &rate(xi.xi[2]), &mut scratch);
            w[2] / m[2]
        };
        let paper = fraction_after(Viscosity::paper());
        assert!(paper > 1.0, "{paper}");
        let ours = fraction_after(Viscosity::default());
        assert!((ours - 0.6).abs() < 1e-14, "{ours}");
    }

    #[test]
    fn runs_of_active_faces_diffuse_as_the_whole_row() {
        // Faces 1..=3 and 6 active (drive > 0), the others without drive: diffusing
        // each run of active faces over its cells gives the whole row's sub-step bit
        // for bit, and the cells next to no active face are not touched.
        let u0: Vec<f64> = (0..10)
            .map(|i| 0.1 + (i as f64 * 0.37).sin().abs())
            .collect();
        let drive = [0.0, 0.3, 0.05, 0.7, 0.0, 0.0, 0.2, 0.0, 0.0];
        let rate = 0.4;
        let mut whole = u0.clone();
        let rates: Vec<f64> = drive.iter().map(|d| rate * d).collect();
        diffuse(&mut whole, &rates, &mut [0.0; 9]);
        let mut runs = u0.clone();
        diffuse_run(&mut runs[1..=4], &drive[1..=3], rate);
        diffuse_run(&mut runs[6..=7], &drive[6..=6], rate);
        assert_eq!(whole, runs);
        assert_eq!(runs[5], u0[5]);
        assert_ne!(runs[4], u0[4]);
    }

    #[test]
    fn diffusion_conserves_and_stays_between_neighbours() {
        let mut u = vec![1.0, 1.0, 0.0, 0.0, 3.0, 3.0];
        let rate = [0.0, 0.5, 0.25, 0.5, 0.0];
        let mut scratch = vec![0.0; 5];
        let before: f64 = u[1..5].iter().sum();
        diffuse(&mut u, &rate, &mut scratch);
        let after: f64 = u[1..5].iter().sum();
        assert_eq!(before, after);
        assert_eq!(u[1..5], [0.5, 0.5, 1.5, 1.5]);
    }
}
