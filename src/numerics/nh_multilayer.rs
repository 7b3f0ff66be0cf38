//! Steps 2 and 3 of the splitting for the multilayer weakly non-hydrostatic model
//! (Escalante et al. 2023, §4 "Step 2", eq. 23–25 and 36 with the explicit
//! non-hydrostatic terms of eq. 17–19, and "Step 3", eq. 26–33), as one stage that owns
//! the projection's operator 𝒯 of [`super::projection::multilayer`].
//!
//! Step 2, the explicit pressure terms of pⁿ, then the implicit μ(I) viscous step with
//! the total pressures:
//!
//!   (h_α u_α)* = h_α u_α + Δt (𝒯_u pⁿ)_α,   (h_α w_α)* = h_α w_α + Δt (𝒯_w pⁿ)_α,
//!
//! with 𝒯 the discrete pressure force of the projection (the same operator, applied
//! to pⁿ: step 3 then applies 𝒯 to p^{n+1} = pⁿ + p̃, the split of eq. 17), and then
//! [`MultilayerViscousStep`] with p_{α+1/2}/ρ = g_n h Σ_{β>α} l_β + p^nh_{α+1/2} in the
//! viscosities (eq. 10), the basal Coulomb friction (eq. 11) and the sidewall force
//! (eq. 36), frozen at tⁿ (`viscous.rs`). As for the monolayer (`nonhydrostatic.rs`),
//! the explicit terms use the thickness after step 1 (h^{n+1/3} = h^{n+1}), so that they
//! are the correction operator of step 3 applied to pⁿ. Normal discharges of dry cells
//! are set to 0.
//!
//! Step 3, the projection: A Π = −𝒞(U*) solved exactly ([`BandedCholesky`]), the
//! correction U^{n+1} = U* + M⁻¹𝒯Π, and p^{n+1} = pⁿ + Π/Δt (over Δt_full for a step
//! shortened to land on an output time, `projection`, "Shortened steps").
//!
//! **One operator.** The coefficients of 𝒯 depend on h only, and neither step changes
//! h: they are computed once per step, from the state after step 1, and serve the
//! explicit terms of step 2 and the system and the correction of step 3.
//!
//! **Which velocities the viscosities are frozen from** (`rheology.viscosity`).
//! Escalante et al. 2023 takes U^n, the state after the previous projection (`"frozen"`). The projection
//! and the pⁿ terms move the layers of a column independently (the mass matrix M =
//! diag(l_α h) of eq. 31 knows nothing of the viscous coupling), so they shear a column
//! that the viscous step holds below its threshold; ν = μ p/√(s² + 4δ²) frozen from that
//! shear is softer, the next step lets the column shear more, and the creep of a mass
//! below the repose slope grows without bound (docs/numerics.md, "Below the repose
//! slope"). With `"lagged"` (the default) ν is frozen from h u_α after the previous
//! viscous solve, before its projection, with h and pⁿ of t^n (the projection moves no
//! mass): the fixed point of the held column is then that of the hydrostatic model. For
//! N = 1 (no interface viscosity) the two are the same and `lagged` is off. Those
//! discharges decide the next step, so they are the state's
//! (`NonHydrostatic::lagged_hu`): a refused step is undone with the rest of it.
//!
//! **Timers.** The stage reports the wall time of step 2 (with its `prepare` and the
//! coefficients of 𝒯, which its explicit terms use first) as `viscous` and that of
//! step 3 as `projection`.

use std::time::{Duration, Instant};

use super::banded::BandedCholesky;
use super::projection::multilayer::MultilayerOperator;
use super::projection::ProjectionOperator;
use super::viscous::MultilayerViscousStep;
use super::{Stage, StageError, StepClock};
use crate::grid::Line;
use crate::physics::rheology::{BasalFriction, LocalFriction};
use crate::physics::shallow::H_DRY;
use crate::state::layered::{fill_tracer_ghosts, LayeredState, HW};

/// Values per piece of the lagged copy of h u_α (1920 bytes).
const COPY_PIECE: usize = 240;

/// Steps 2 and 3 of the N-layer non-hydrostatic model (module documentation).
#[derive(Debug)]
pub struct NhViscousProjection<L: BasalFriction + LocalFriction> {
    /// 𝒯 and the system of step 3, with the coefficients of the current step's h.
    operator: MultilayerOperator,
    solver: BandedCholesky,
    viscous: MultilayerViscousStep<L>,
    /// Δt pⁿ, face-major.
    impulse: Vec<f64>,
    /// Π of the projection, face-major.
    pi: Vec<f64>,
    /// Freeze the viscosities from the velocities of the previous viscous step (before
    /// its projection, kept in the state: `NonHydrostatic::lagged_hu`) instead of
    /// those at tⁿ (after it); N > 1 only.
    lagged: bool,
    /// Wall time of step 2 and of step 3.
    times: [Duration; 2],
}

impl<L: BasalFriction + LocalFriction> NhViscousProjection<L> {
    /// The stage on `mesh` for the layer fractions `l`, with the viscous step `viscous`.
    pub fn new(mesh: &Line, l: &[f64], viscous: MultilayerViscousStep<L>) -> Self {
        let faces = (mesh.nx + 1) * l.len();
        NhViscousProjection {
            operator: MultilayerOperator::new(mesh, l),
            solver: BandedCholesky::new(l.len(), mesh.nx + 1),
            viscous,
            impulse: vec![0.0; faces],
            pi: vec![0.0; faces],
            lagged: false,
            times: [Duration::ZERO; 2],
        }
    }

    /// With `lagged`, the viscosities of step 2 are frozen from the velocities after
    /// the previous viscous solve rather than after the previous projection (module
    /// documentation). No effect for N = 1.
    pub fn lagged(mut self, lagged: bool) -> Self {
        self.lagged = lagged && self.operator.layers() > 1;
        self
    }

    /// Step 2 alone, from the state after step 1: the operator's coefficients for its
    /// h, the explicit terms Δt 𝒯 pⁿ, the viscous step, the lagged discharges.
    pub fn viscous_step(
        &mut self,
        mesh: &Line,
        clock: StepClock,
        state: &mut LayeredState,
    ) -> Result<(), StageError> {
        self.operator.update(mesh, state);
        self.explicit_pressure(mesh, clock.dt, state);
        self.viscous.apply(mesh, clock, state)?;
        if self.lagged {
            // Copied in pieces below 2048 bytes, where glibc's `memcpy` uses its vector
            // loop rather than `rep movsb` (callgrind counts the latter per byte: 0.10 M
            // instructions per step for the 100 KB of 20 layers × 640 cells).
            let LayeredState { hu, nh, .. } = state;
            let lagged_hu = &mut nh.as_mut().expect("non-hydrostatic state").lagged_hu;
            lagged_hu.resize(hu.len(), 0.0);
            for (to, from) in lagged_hu.chunks_mut(COPY_PIECE).zip(hu.chunks(COPY_PIECE)) {
                to.copy_from_slice(from);
            }
        }
        let (nx, n) = (mesh.nx, state.layers);
        let LayeredState { h, tracers, .. } = state;
        let hw = &mut tracers
            .iter_mut()
            .find(|t| t.name == HW)
            .expect("a non-hydrostatic state carries hw")
            .q;
        for (column, &h) in hw.chunks_exact_mut(n).zip(h.iter()).take(nx + 1).skip(1) {
            if h <= H_DRY {
                column.fill(0.0);
            }
        }
        fill_tracer_ghosts(hw, nx, n);
        Ok(())
    }

    /// Step 3, after [`viscous_step`](Self::viscous_step) (whose coefficients of 𝒯 it
    /// uses: h has not changed): solves for Π, corrects the discharges, advances p.
    fn projection_step(&mut self, mesh: &Line, clock: StepClock, state: &mut LayeredState) {
        self.solver
            .solve_rows(&self.operator.rows(state), &mut self.pi);
        self.operator
            .correct(mesh, state, &self.pi, clock.rate_step());
    }

    /// Adds the explicit terms Δt 𝒯 pⁿ to hu and hw (the operator holds the
    /// coefficients of the state's h).
    fn explicit_pressure(&mut self, mesh: &Line, dt: f64, state: &mut LayeredState) {
        let nh = state.nh.as_ref().expect("non-hydrostatic state");
        if nh.p.iter().all(|&p| p == 0.0) {
            return;
        }
        for (pi, &p) in self.impulse.iter_mut().zip(&nh.p) {
            *pi = dt * p;
        }
        self.operator.apply_impulses(state, &self.impulse);
        state.fill_ghosts(mesh);
    }
}

impl<L: BasalFriction + LocalFriction> Stage<Line, LayeredState> for NhViscousProjection<L> {
    fn name(&self) -> &'static str {
        "viscous+projection"
    }

    fn prepare(&mut self, mesh: &Line, clock: StepClock, state: &LayeredState) {
        let start = Instant::now();
        let lagged_hu = &state.nh.as_ref().expect("non-hydrostatic state").lagged_hu;
        if !self.lagged || lagged_hu.len() != state.hu.len() {
            // The paper's freezing at tⁿ, and the first step of a lagged run.
            self.viscous.prepare(mesh, clock, state);
        } else {
            // tⁿ with the discharges of the last viscous solve: h is that of tⁿ (the
            // projection moves no mass) and so is pⁿ (the total pressures of eq. 10).
            self.viscous.prepare_with_discharges(mesh, state, lagged_hu);
        }
        self.times[0] += start.elapsed();
    }

    fn apply(
        &mut self,
        mesh: &Line,
        clock: StepClock,
        state: &mut LayeredState,
    ) -> Result<(), StageError> {
        let start = Instant::now();
        let viscous = self.viscous_step(mesh, clock, state);
        let middle = Instant::now();
        self.times[0] += middle - start;
        viscous?;
        self.projection_step(mesh, clock, state);
        self.times[1] += middle.elapsed();
        Ok(())
    }

    fn part_times(&self) -> Vec<(&'static str, Duration)> {
        vec![("viscous", self.times[0]), ("projection", self.times[1])]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::LineSpec;
    use crate::grid::{BoundaryKind, Coordinates};
    use crate::numerics::projection::ProjectionStage;
    use crate::numerics::viscous::ViscousOptions;
    use crate::numerics::viscous::{BasalCondition, Regularization};
    use crate::physics::rheology::{MonolayerShear, MuI};

    fn law() -> MuI {
        // Escalante et al. 2023, Table 1
        MuI {
            mu_s: 25.5f64.to_radians().tan(),
            mu_2: 36f64.to_radians().tan(),
            i0: 0.279,
            d_s: 0.7e-3,
            phi: 0.62,
            shear: MonolayerShear::Bagnold,
        }
    }

    fn options() -> ViscousOptions {
        ViscousOptions {
            basal: BasalCondition::Coulomb,
            regularization: Regularization::Delta { delta: 1e-5 },
            sidewall: None,
            c_msm: false,
            viscosity: crate::numerics::viscous::ViscosityTime::Frozen,
        }
    }

    /// The explicit terms Δt 𝒯 pⁿ alone, with the operator's coefficients for the
    /// state's h.
    fn explicit<L: BasalFriction + LocalFriction>(
        step: &mut NhViscousProjection<L>,
        mesh: &Line,
        dt: f64,
        state: &mut LayeredState,
    ) {
        step.operator.update(mesh, state);
        step.explicit_pressure(mesh, dt, state);
    }

    fn setup(layers: usize) -> (Line, LayeredState) {
        let spec = LineSpec {
            x_min: 0.0,
            x_max: 0.5,
            cells: 50,
            slope_deg: 22.0,
            coordinates: Coordinates::Local,
            left: BoundaryKind::Wall,
            right: BoundaryKind::Wall,
        };
        let x = spec.centres();
        let mesh = Line::new(&spec, vec![0.0; 50]);
        let h: Vec<f64> = x
            .iter()
            .map(|x| 0.02 + 0.05 * (-(x - 0.25f64).powi(2) / 0.01).exp())
            .collect();
        let u: Vec<f64> = x.iter().map(|x| 0.3 * (6.0 * x).sin()).collect();
        let l = vec![1.0 / layers as f64; layers];
        let mut state = LayeredState::from_profiles(&mesh, &l, &h, &u);
        for i in 1..=50 {
            for a in 0..layers {
                state.hu[i * layers + a] *= 0.5 + (a as f64 + 0.5) / layers as f64;
            }
        }
        state.fill_ghosts(&mesh);
        state.add_nonhydrostatic(&vec![0.0; 50]);
        (mesh, state)
    }

    /// The explicit terms are the projection's correction applied to Δt pⁿ: zero
    /// pressure changes nothing, and a pressure field gives the same change of hu, hw
    /// as `apply_impulses` (checked against the correction of a projection).
    #[test]
    fn explicit_terms_are_the_correction_operator_applied_to_p() {
        let layers = 4;
        let (mesh, mut state) = setup(layers);
        let viscous = MultilayerViscousStep::new(law(), mesh.nx, &state.l, options());
        let mut step = NhViscousProjection::new(&mesh, &state.l, viscous);
        let before = state.clone();
        explicit(&mut step, &mesh, 1e-3, &mut state);
        assert_eq!(state, before, "p = 0: nothing to add");
        // A smooth pressure, largest at the bed, vanishing at the surface.
        {
            let nh = state.nh.as_mut().unwrap();
            for f in 0..=mesh.nx {
                for j in 0..layers {
                    nh.p[f * layers + j] =
                        2.0 * (1.0 - j as f64 / layers as f64) * (0.3 * f as f64).cos();
                }
            }
        }
        let mut a = state.clone();
        explicit(&mut step, &mesh, 1e-3, &mut a);
        let mut b = state.clone();
        let mut op = MultilayerOperator::new(&mesh, &b.l);
        op.update(&mesh, &b);
        let pi: Vec<f64> = b.nh.as_ref().unwrap().p.iter().map(|p| 1e-3 * p).collect();
        op.apply_impulses(&mut b, &pi);
        b.fill_ghosts(&mesh);
        assert_eq!(a.hu, b.hu);
        assert_eq!(a.hw(), b.hw());
        assert!(a.hu != state.hu, "the pressure must act");
        // Total hw gained by the column: Σ_α l_α δ(hw_α) = Δt p_{1/2} at the cell (the
        // pressure force on the whole column is the basal one).
        let (hw, hw0) = (a.hw(), state.hw());
        let nh0 = state.nh.as_ref().unwrap();
        for i in 2..mesh.nx {
            let gain: f64 = (0..layers)
                .map(|k| state.l[k] * (hw[i * layers + k] - hw0[i * layers + k]))
                .sum();
            let p_bed = 0.5 * (nh0.p[(i - 1) * layers] + nh0.p[i * layers]);
            assert!(
                (gain - 1e-3 * p_bed).abs() < 1e-15,
                "cell {i}: {gain} vs {}",
                1e-3 * p_bed
            );
        }
    }

    /// With p^nh = 0 step 2 is the hydrostatic viscous step (to round-off); a positive
    /// non-hydrostatic basal pressure adds friction (a faster stop), a negative one
    /// removes some.
    #[test]
    fn nonhydrostatic_pressure_enters_the_friction() {
        let layers = 5;
        let (mesh, state) = setup(layers);
        let run = |p_bed: f64| {
            let mut s = state.clone();
            if p_bed != 0.0 {
                let nh = s.nh.as_mut().unwrap();
                for f in 0..=mesh.nx {
                    for j in 0..layers {
                        nh.p[f * layers + j] = p_bed * (1.0 - j as f64 / layers as f64);
                    }
                }
            }
            let viscous = MultilayerViscousStep::new(law(), mesh.nx, &s.l, options());
            let mut step = NhViscousProjection::new(&mesh, &s.l, viscous);
            let clock = StepClock::at(0.0, 1e-3);
            step.prepare(&mesh, clock, &s);
            // Remove the explicit terms' effect by comparing against them separately:
            // a uniform p in x has no horizontal force in the interior except via the
            // depth slopes, so compare only the total (friction) effect below.
            step.viscous_step(&mesh, clock, &mut s).unwrap();
            s
        };
        let mut hydro = state.clone();
        hydro.nh = None;
        hydro.tracers.clear();
        let mut plain = MultilayerViscousStep::new(law(), mesh.nx, &hydro.l, options());
        let clock = StepClock::at(0.0, 1e-3);
        plain.prepare(&mesh, clock, &hydro);
        plain.apply(&mesh, clock, &mut hydro).unwrap();
        let zero = run(0.0);
        // p^nh = 0: the hydrostatic step's equations (the pressures are formed per
        // interface instead of scaled from the bed, so only to round-off).
        for (a, b) in zero.hu.iter().zip(&hydro.hu) {
            assert!((a - b).abs() <= 1e-14 * b.abs().max(1e-3), "{a} vs {b}");
        }
        assert!(zero.hu != state.hu, "the step must act");
        // Column momentum Σ l_α hu_α of a cell where the column moves forwards.
        let momentum = |s: &LayeredState, i: usize| -> f64 {
            (0..layers).map(|a| s.l[a] * s.hu[i * layers + a]).sum()
        };
        let i = 10; // u > 0 there
        assert!(momentum(&state, i) > 0.0);
        let g_n = mesh.g_n;
        let h = state.h[i];
        let (more, less) = (run(0.5 * g_n * h), run(-0.5 * g_n * h));
        // Explicit pressure force of a p uniform in x on a flat bed: from the depth
        // slopes only; remove it by comparing with the explicit-only update.
        let explicit = |p_bed: f64| {
            let mut s = state.clone();
            let nh = s.nh.as_mut().unwrap();
            for f in 0..=mesh.nx {
                for j in 0..layers {
                    nh.p[f * layers + j] = p_bed * (1.0 - j as f64 / layers as f64);
                }
            }
            let viscous = MultilayerViscousStep::new(law(), mesh.nx, &s.l, options());
            let mut step = NhViscousProjection::new(&mesh, &s.l, viscous);
            explicit(&mut step, &mesh, 1e-3, &mut s);
            momentum(&s, i) - momentum(&state, i)
        };
        let lost = |s: &LayeredState, p: f64| momentum(&state, i) + explicit(p) - momentum(s, i);
        let (lost0, lost_more, lost_less) = (
            lost(&zero, 0.0),
            lost(&more, 0.5 * g_n * h),
            lost(&less, -0.5 * g_n * h),
        );
        println!("friction impulse: {lost0:.3e} (p = 0), {lost_more:.3e} (+), {lost_less:.3e} (−)");
        assert!(lost_more > 1.4 * lost0 && lost_less < 0.6 * lost0 && lost_less > 0.0);
    }

    /// Step 3 on the coefficients of 𝒯 that step 2 computed gives the bits of a
    /// projection stage with an operator of its own (h does not change between the
    /// two), for a step of full length and for one shortened from it (the pressure's
    /// rate over Δt_full).
    #[test]
    fn the_projection_half_is_the_projection_with_an_operator_of_its_own() {
        let layers = 4;
        let (mesh, mut state) = setup(layers);
        let nh = state.nh.as_mut().unwrap();
        for f in 0..=mesh.nx {
            for j in 0..layers {
                nh.p[f * layers + j] = (1.0 - j as f64 / layers as f64) * (0.2 * f as f64).sin();
            }
        }
        let viscous = || MultilayerViscousStep::new(law(), mesh.nx, &state.l, options());
        for clock in [StepClock::at(0.0, 1e-3), StepClock::new(0.0, 1e-5, 1e-3)] {
            let mut a = state.clone();
            let mut one = NhViscousProjection::new(&mesh, &state.l, viscous());
            one.prepare(&mesh, clock, &a);
            one.apply(&mesh, clock, &mut a).unwrap();

            let mut b = state.clone();
            let mut half = NhViscousProjection::new(&mesh, &state.l, viscous());
            let mut projection = ProjectionStage::new(
                MultilayerOperator::new(&mesh, &state.l),
                BandedCholesky::new(layers, mesh.nx + 1),
                mesh.nx,
            );
            half.prepare(&mesh, clock, &b);
            half.viscous_step(&mesh, clock, &mut b).unwrap();
            let before = b.clone();
            projection.apply(&mesh, clock, &mut b).unwrap();
            assert!(b.hu != before.hu, "the projection must act");
            assert_eq!(a, b, "{clock:?}");
        }
    }

    /// The lagged discharges belong to the state: an attempt that the run loop refuses
    /// and undoes (restoring its backup of tⁿ) leaves no trace in the retried step,
    /// which gives the bits of a run that never made the attempt. Kept in the stage,
    /// the retry froze its viscosities from the refused attempt's discharges.
    #[test]
    fn a_refused_attempt_leaves_no_trace_in_the_lagged_viscosities() {
        let layers = 4;
        let (mesh, state0) = setup(layers);
        let opts = ViscousOptions {
            viscosity: crate::numerics::viscous::ViscosityTime::Lagged,
            ..options()
        };
        let new_step = || {
            let viscous = MultilayerViscousStep::new(law(), mesh.nx, &state0.l, opts);
            NhViscousProjection::new(&mesh, &state0.l, viscous).lagged(true)
        };
        let advance = |step: &mut NhViscousProjection<MuI>, s: &mut LayeredState, dt: f64| {
            let clock = StepClock::at(0.0, dt);
            step.prepare(&mesh, clock, s);
            step.apply(&mesh, clock, s).unwrap();
        };
        let dt = 1e-3;
        let mut clean = state0.clone();
        let mut step = new_step();
        advance(&mut step, &mut clean, dt);
        advance(&mut step, &mut clean, dt);

        let mut s = state0.clone();
        let mut step = new_step();
        advance(&mut step, &mut s, dt);
        let mut backup = state0.clone();
        backup.clone_from(&s);
        advance(&mut step, &mut s, 4.0 * dt);
        let refused = s.nh.as_ref().unwrap().lagged_hu.clone();
        s.clone_from(&backup);
        let mut tainted = s.clone();
        advance(&mut step, &mut s, dt);
        assert_eq!(s, clean, "the retried step is the clean run's");
        // The refused attempt's discharges would have changed the step.
        tainted.nh.as_mut().unwrap().lagged_hu = refused;
        advance(&mut step, &mut tainted, dt);
        assert!(tainted.hu != clean.hu, "the lagged discharges must matter");
    }
}
