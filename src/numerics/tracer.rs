//! Passive tracers carried by the hyperbolic step (Garres-Díaz et al. 2021, after eq. 24 for hw; the
//! same upwind transport serves any quantity that moves with the grains).
//!
//! A tracer q = h c (per cell and layer) follows the mass flux 𝓕^h of step 1 with the
//! concentration c = q/h of the upwind cell, taken before the step:
//!
//!   q_i ← q_i − Δt/Δx (𝓕^h_{i+1/2} c^up_{i+1/2} − 𝓕^h_{i−1/2} c^up_{i−1/2}),
//!
//! and q = 0 in cells that are dry after the step. A run without tracers builds
//! nothing here.
//!
//! With N > 1 layers a tracer of layer α (h w_α for the non-hydrostatic model) obeys
//! Escalante et al. 2023, eq. (9c) without its pressure terms,
//!
//!   ∂_t(h c_α) + ∂_X(h u_α c_α) = (c_{α+1/2} G_{α+1/2} − c_{α−1/2} G_{α−1/2})/l_α,
//!
//! with the mass exchange G of eq. (5), G_{1/2} = G_{N+1/2} = 0. Each layer moves with
//! its own mass flux
//!
//!   𝓕^h_{α,i+1/2} = 𝓕^h_{i+1/2} + min(h_i, h_{i+1}) ½((u_α − ū)_i + (u_α − ū)_{i+1})
//!
//! (the step's total flux plus the layer's departure from it, [`HydrostaticStep`];
//! Σ_α l_α (u_α − ū) = 0, so the layers' fluxes sum to the total one), and
//! the exchange through the interface Z_{α+1/2} of cell i is what keeps each layer's
//! mass l_α h consistent with the total one:
//!
//!   Δt G_{α+1/2,i} = Δt/Δx Σ_{β≤α} l_β (𝓕^h_{β,i+1/2} − 𝓕^h_{β,i−1/2} − (𝓕^h_{i+1/2} − 𝓕^h_{i−1/2})),
//!
//! which is, face by face, the ½(ΔG_{i+1/2} + ΔG_{i−1/2}) the momentum's exchange term
//! 𝓑 uses (`hydrostatic.rs`). Both transports are upwind: horizontally with the sign
//! of 𝓕^h_α and the concentrations before the step, vertically c_{α+1/2} = c_{α+1}
//! where G_{α+1/2} > 0 (mass entering layer α from above) and c_α otherwise (the
//! printed scheme centres c_{α+1/2}).
//!
//! **The exchange is implicit** in c: with g = Δt G, g^± = max(±g, 0),
//!
//!   (l_α h^{n+1} + g⁻_{α+1/2} + g⁺_{α−1/2}) c_α^{n+1} − g⁺_{α+1/2} c_{α+1}^{n+1}
//!       − g⁻_{α−1/2} c_{α−1}^{n+1} = l_α (q_α^n − Δt/Δx (𝓕^h_{α,i+1/2} c^up − 𝓕^h_{α,i−1/2} c^up)),
//!
//! a tridiagonal system per column (one Thomas sweep, no pivoting: it is strictly
//! diagonally dominant by columns, an M-matrix). The CFL step bounds the horizontal
//! transport, not the exchange: beside a sheared column several times thicker, a
//! film's layers exchange several times their own content in one step (the face
//! fluxes carry the thick side's departures), and the explicit upwind exchange,
//! c^{n+1} = (1 − ν) c + ν c_above with ν > 1, then gave layer-to-layer alternating
//! values that doubled every step (the w of a 1 mm film beside a 17 mm column in the
//! 10-layer non-hydrostatic run of Escalante et al. 2023, §5.4, grew from 2 to 200 m/s
//! in six steps and the projection turned it into 100 m/s layer velocities). The
//! implicit exchange keeps every c within the range of the values it is formed from
//! for any ν, as long as no layer sends out more than it holds horizontally (tested),
//! and differs from the explicit one by O((Δt G/(l_α h))²) where
//! the exchange is small. A uniform c stays uniform, and Σ_α l_α q_α changes only by
//! the horizontal fluxes (conservative; tested). For N = 1, d = 0 and G = 0: the
//! monolayer transport above, the same code.
//!
//! **The departure's depth is the thinner side's.** With the mean of the two cells'
//! h(u_α − ū) (the printed face value where h_i = h_{i+1}), a face between a film and
//! a sheared column carried the column's shear: the film's layers sent out several
//! times what they hold in one step, in opposite directions, and a near-dry cell
//! between them (1e-7 m beside a 5 mm column) took w = 10² m/s in its bottom layer
//! (the inflow's w times inflow/(inflow − outflow)). With min(h_i, h_{i+1}) a film's
//! layers exchange at most its own depth's shear, as the exchange term 𝓑 of the
//! momentum does (`hydrostatic.rs`, own-depth split); where the depths are equal it is
//! the printed value.
//!
//! [`HydrostaticStep`]: super::hydrostatic::HydrostaticStep

use super::muscl::Limiter;
use crate::physics::shallow::H_DRY;
use crate::state::layered::{fill_tracer_ghosts, Tracer};

/// Scratch of the transport: concentrations before the step and face fluxes.
#[derive(Debug, Default)]
pub struct TracerTransport {
    /// c = q/h per tracer, cell and layer (with ghosts), before the step.
    concentration: Vec<Vec<f64>>,
    flux: Vec<f64>,
    /// Thomas sweep of one column's implicit exchange (2N).
    column: Vec<f64>,
    /// Order 2: the limiter of the reconstruction of c, and the west and east edge
    /// values c ∓ ½σ of every cell (per tracer, as `concentration`).
    limiter: Option<Limiter>,
    west: Vec<Vec<f64>>,
    east: Vec<Vec<f64>>,
}

impl TracerTransport {
    /// The transport of the second-order hyperbolic step (`numerics.order = 2`): the
    /// face takes the upwind cell's edge value c_i ± ½σ_i of the limited linear
    /// reconstruction of c (σ_i = φ(c_i − c_{i−1}, c_{i+1} − c_i), `muscl`), instead of
    /// its mean, so that h c is carried at second order where c is smooth; σ = 0 in a
    /// cell that is dry or has a dry neighbour, so fronts keep the upwind transport.
    /// The edge values lie between neighbouring means, so the bounds of the upwind
    /// transport on c hold under the same step condition halved (Heun's stages).
    pub fn second_order(limiter: Limiter) -> Self {
        TracerTransport {
            limiter: Some(limiter),
            ..Self::default()
        }
    }

    /// Remembers the concentrations of `tracers` in the state (h, q) before step 1.
    /// The loop is branch-free (selects), so that it vectorises.
    pub fn before_step(&mut self, h: &[f64], layers: usize, tracers: &[Tracer]) {
        self.concentrations(h, layers, tracers);
        if let Some(limiter) = self.limiter {
            self.reconstruct(h, layers, limiter);
        }
    }

    /// c = q/h of every tracer, cell and layer (0 where dry).
    fn concentrations(&mut self, h: &[f64], layers: usize, tracers: &[Tracer]) {
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx2") {
            // SAFETY: the CPU supports AVX2.
            unsafe { self.before_step_avx2(h, layers, tracers) };
            return;
        }
        self.before_step_portable(h, layers, tracers);
    }

    /// Order 2: the edge values of the limited reconstruction of c (see
    /// [`Self::second_order`]).
    fn reconstruct(&mut self, h: &[f64], n: usize, limiter: Limiter) {
        self.west.resize_with(self.concentration.len(), Vec::new);
        self.east.resize_with(self.concentration.len(), Vec::new);
        let edges = self.west.iter_mut().zip(self.east.iter_mut());
        for (c, (west, east)) in self.concentration.iter().zip(edges) {
            west.clone_from(c);
            east.clone_from(c);
            for j in 1..h.len() - 1 {
                if h[j - 1] <= H_DRY || h[j] <= H_DRY || h[j + 1] <= H_DRY {
                    continue;
                }
                for a in 0..n {
                    let k = j * n + a;
                    let half = 0.5 * limiter.slope(c[k] - c[k - n], c[k + n] - c[k]);
                    west[k] = c[k] - half;
                    east[k] = c[k] + half;
                }
            }
        }
    }

    /// [`before_step`](Self::before_step) compiled for AVX2 (the same operations).
    ///
    /// # Safety
    /// The CPU must support AVX2.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    unsafe fn before_step_avx2(&mut self, h: &[f64], layers: usize, tracers: &[Tracer]) {
        self.before_step_portable(h, layers, tracers)
    }

    #[inline(always)]
    fn before_step_portable(&mut self, h: &[f64], layers: usize, tracers: &[Tracer]) {
        self.concentration.resize_with(tracers.len(), Vec::new);
        for (c, tracer) in self.concentration.iter_mut().zip(tracers) {
            c.resize(tracer.q.len(), 0.0);
            let columns = c
                .chunks_exact_mut(layers)
                .zip(tracer.q.chunks_exact(layers));
            for ((c, q), &hj) in columns.zip(h) {
                for (c, &q) in c.iter_mut().zip(q) {
                    let v = q / hj.max(H_DRY);
                    *c = if hj > H_DRY { v } else { 0.0 };
                }
            }
        }
    }

    /// Transports every tracer with the mass fluxes `mass_flux` (faces 0..=nx) of the
    /// step just taken; `h` is the thickness after it, `r` = Δt/Δx. With N > 1,
    /// `layers` carries each layer's departure from the mean flux ½(d_L + d_R) per face
    /// and layer and the layer fractions l_α (module documentation); `None` for N = 1.
    pub fn after_step(
        &mut self,
        mass_flux: &[f64],
        layers: Option<(&[f64], &[f64])>,
        h: &[f64],
        r: f64,
        n: usize,
        tracers: &mut [Tracer],
    ) {
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx2") {
            // SAFETY: the CPU supports AVX2.
            unsafe { self.after_step_avx2(mass_flux, layers, h, r, n, tracers) };
            return;
        }
        self.after_step_portable(mass_flux, layers, h, r, n, tracers);
    }

    /// [`after_step`](Self::after_step) compiled for AVX2: the same operations in the
    /// same order (no fused multiply-add: Rust does not contract a·b + c), the same
    /// bits.
    ///
    /// # Safety
    /// The CPU must support AVX2.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    unsafe fn after_step_avx2(
        &mut self,
        mass_flux: &[f64],
        layers: Option<(&[f64], &[f64])>,
        h: &[f64],
        r: f64,
        n: usize,
        tracers: &mut [Tracer],
    ) {
        self.after_step_portable(mass_flux, layers, h, r, n, tracers)
    }

    #[inline(always)]
    fn after_step_portable(
        &mut self,
        mass_flux: &[f64],
        layers: Option<(&[f64], &[f64])>,
        h: &[f64],
        r: f64,
        n: usize,
        tracers: &mut [Tracer],
    ) {
        let nx = mass_flux.len() - 1;
        self.flux.resize(mass_flux.len() * n, 0.0);
        self.column.resize(2 * n, 0.0);
        for (t, (c, tracer)) in self
            .concentration
            .iter()
            .zip(tracers.iter_mut())
            .enumerate()
        {
            // The values a face takes from its west (east) cell: the means at order 1,
            // the cells' east (west) edges at order 2.
            let (from_west, from_east) = match self.limiter {
                None => (c, c),
                Some(_) => (&self.east[t], &self.west[t]),
            };
            match layers {
                None => {
                    for (k, &f) in mass_flux.iter().enumerate() {
                        for a in 0..n {
                            let up = if f > 0.0 {
                                from_west[k * n + a]
                            } else {
                                from_east[(k + 1) * n + a]
                            };
                            self.flux[k * n + a] = f * up;
                        }
                    }
                }
                Some((departure, _)) => {
                    for (k, &f) in mass_flux.iter().enumerate() {
                        // Slices of length n: a select per layer, no bounds checks.
                        let (cl, cr) = (&from_west[k * n..][..n], &from_east[(k + 1) * n..][..n]);
                        let d = &departure[k * n..][..n];
                        let flux = &mut self.flux[k * n..][..n];
                        for a in 0..n {
                            let fa = f + d[a];
                            flux[a] = fa * if fa > 0.0 { cl[a] } else { cr[a] };
                        }
                    }
                }
            }
            for (i, &hi) in h.iter().enumerate().take(nx + 1).skip(1) {
                let wet = hi > H_DRY;
                if let (Some((departure, l)), true) = (layers, wet) {
                    // Slices of equal length: one bounds check each, not one per layer.
                    let (right, left) = (&departure[i * n..][..n], &departure[(i - 1) * n..][..n]);
                    let (fr, fl) = (&self.flux[i * n..][..n], &self.flux[(i - 1) * n..][..n]);
                    let qs = &mut tracer.q[i * n..][..n];
                    let l = &l[..n];
                    // Δt G_{α+1/2} from the layers' flux departures (running sum g),
                    // then the implicit exchange (module documentation): row α of
                    //   (l_α h + g⁻_{α+1/2} + g⁺_{α−1/2}) c_α − g⁺_{α+1/2} c_{α+1}
                    //     − g⁻_{α−1/2} c_{α−1} = l_α (q_α − r (F_α,R − F_α,L)),
                    // solved by one Thomas sweep down the column and one back up.
                    let (upper, rhs) = self.column.split_at_mut(n);
                    let (mut g, mut g_below) = (0.0f64, 0.0f64);
                    let mut prev_upper = 0.0;
                    let mut prev_rhs = 0.0;
                    for a in 0..n {
                        if a + 1 < n {
                            g += r * l[a] * (right[a] - left[a]);
                        } else {
                            g = 0.0;
                        }
                        let (gp, gm) = (g.max(0.0), (-g).max(0.0));
                        let (gp_below, gm_below) = (g_below.max(0.0), (-g_below).max(0.0));
                        let known = l[a] * (qs[a] - r * (fr[a] - fl[a]));
                        // Eliminate c_{α−1} (coefficient −g⁻_{α−1/2}).
                        let diag = l[a] * hi + gm + gp_below + gm_below * prev_upper;
                        let inv = 1.0 / diag;
                        upper[a] = -gp * inv;
                        rhs[a] = (known + gm_below * prev_rhs) * inv;
                        prev_upper = upper[a];
                        prev_rhs = rhs[a];
                        g_below = g;
                    }
                    let mut c_above = 0.0;
                    for a in (0..n).rev() {
                        let c = rhs[a] - upper[a] * c_above;
                        qs[a] = hi * c;
                        c_above = c;
                    }
                    continue;
                }
                for a in 0..n {
                    let q = &mut tracer.q[i * n + a];
                    let v = *q - r * (self.flux[i * n + a] - self.flux[(i - 1) * n + a]);
                    *q = if wet { v } else { 0.0 };
                }
            }
            fill_tracer_ghosts(&mut tracer.q, nx, n);
        }
    }
}

#[cfg(test)]
mod tests {
    use crate::grid::{BoundaryKind, Coordinates, Line, LineSpec};
    use crate::numerics::hydrostatic::HydrostaticStep;
    use crate::numerics::{Stage, StepClock};
    use crate::physics::rheology::Coulomb;
    use crate::state::layered::LayeredState;
    use std::f64::consts::PI;

    const N: usize = 4;
    const NX: usize = 400;

    fn mesh() -> Line {
        let spec = LineSpec {
            x_min: 0.0,
            x_max: 1.0,
            cells: NX,
            slope_deg: 0.0,
            coordinates: Coordinates::Local,
            left: BoundaryKind::Wall,
            right: BoundaryKind::Wall,
        };
        Line::new(&spec, vec![0.0; NX])
    }

    /// A sheared column: u_α = ū + s_α sin(2πx), Σ l_α s_α = 0, w_α given per layer.
    fn state(mesh: &Line, h: impl Fn(f64) -> f64, u_mean: f64, w: [f64; N]) -> LayeredState {
        let l = vec![1.0 / N as f64; N];
        let x = &mesh.x;
        let hs: Vec<f64> = x.iter().map(|&x| h(x)).collect();
        let us: Vec<f64> = x.iter().map(|_| u_mean).collect();
        let mut s = LayeredState::from_profiles(mesh, &l, &hs, &us);
        for i in 1..=NX {
            for a in 0..N {
                let shear = 0.2 * (a as f64 - 1.5) * (2.0 * PI * x[i - 1]).sin();
                s.hu[i * N + a] = s.h[i] * (u_mean + shear);
            }
        }
        s.fill_ghosts(mesh);
        s.add_nonhydrostatic(&vec![0.0; NX]);
        for i in 0..NX + 2 {
            for (a, wa) in w.iter().enumerate() {
                s.hw_mut()[i * N + a] = s.h[i] * wa;
            }
        }
        s
    }

    fn step(mesh: &Line, s: &mut LayeredState, dt: f64) {
        // μ = 0: no Coulomb-aware diffusion, so that only the transport acts on hw.
        let mut hyp = HydrostaticStep::with_layers(Coulomb { mu: 0.0 }, NX, N);
        hyp.apply(mesh, StepClock::at(0.0, dt), s).unwrap();
    }

    /// The AVX2 build of the transport gives the bits of the portable one (wet and
    /// dry cells, fluxes of both signs, N = 1 and N > 1).
    #[test]
    fn both_builds_give_the_same_bits() {
        use super::TracerTransport;
        use crate::state::layered::Tracer;
        for n in [1, 3, 20] {
            let nx = 50;
            let wave = |k: usize, a: f64| (0.37 * k as f64 + a).sin();
            let h: Vec<f64> = (0..nx + 2)
                .map(|i| {
                    if i % 17 == 5 {
                        0.0
                    } else {
                        0.1 + 0.05 * wave(i, 0.0)
                    }
                })
                .collect();
            let flux: Vec<f64> = (0..=nx).map(|k| 0.02 * wave(k, 1.0)).collect();
            let departure: Vec<f64> = (0..(nx + 1) * n).map(|k| 0.01 * wave(k, 2.0)).collect();
            let l = vec![1.0 / n as f64; n];
            let tracer = Tracer {
                name: "hw",
                q: (0..(nx + 2) * n).map(|k| wave(k, 3.0) * h[k / n]).collect(),
            };
            let layers = (n > 1).then_some((departure.as_slice(), l.as_slice()));
            let run = |portable: bool| {
                let mut t = TracerTransport::default();
                let mut tracers = vec![tracer.clone()];
                if portable {
                    t.before_step_portable(&h, n, &tracers);
                    t.after_step_portable(&flux, layers, &h, 0.3, n, &mut tracers);
                } else {
                    t.before_step(&h, n, &tracers);
                    t.after_step(&flux, layers, &h, 0.3, n, &mut tracers);
                }
                tracers[0].q.iter().map(|v| v.to_bits()).collect::<Vec<_>>()
            };
            assert_eq!(run(true), run(false), "N = {n}");
            assert!(run(true) != tracer.q.iter().map(|v| v.to_bits()).collect::<Vec<_>>());
        }
    }

    /// Escalante et al. 2023, eq. (9c) without pressure: over a uniform depth H with ū = 0 and
    /// layer velocities s_α sin(2πx), a w_α uniform in x changes only through the layer
    /// fluxes and the exchange, ∂_t(H w_α) = −H w_α ∂_X u_α + (w_{α+1/2} G_{α+1/2} −
    /// w_{α−1/2} G_{α−1/2})/l_α, G_{α+1/2} = Σ_{β≤α} l_β H ∂_X u_β (upwind w_{α+1/2}).
    /// One step matches it to O(Δx²); transporting hw with the mean flux alone (without
    /// the exchange terms) leaves every w_α unchanged and fails.
    #[test]
    fn layered_tracer_follows_the_layer_fluxes_and_the_exchange() {
        let mesh = mesh();
        let big_h = 0.1;
        let w = [0.3, -0.1, 0.5, 0.2];
        let mut s = state(&mesh, |_| big_h, 0.0, w);
        let before = s.clone();
        let dt = 1e-4;
        step(&mesh, &mut s, dt);
        let l = 1.0 / N as f64;
        let (mut worst, mut scale) = (0.0f64, 0.0f64);
        for i in 1..=NX {
            let x = mesh.x[i - 1];
            let du = |a: usize| 0.2 * (a as f64 - 1.5) * 2.0 * PI * (2.0 * PI * x).cos();
            // G at the interfaces 0..=N (bed and surface 0).
            let mut g = [0.0; N + 1];
            for a in 0..N - 1 {
                g[a + 1] = g[a] + l * big_h * du(a);
            }
            let up = |j: usize| {
                if j == 0 || j == N {
                    0.0
                } else if g[j] > 0.0 {
                    w[j]
                } else {
                    w[j - 1]
                }
            };
            for a in 0..N {
                let rhs = -big_h * w[a] * du(a) + (up(a + 1) * g[a + 1] - up(a) * g[a]) / l;
                let change = s.hw()[i * N + a] - before.hw()[i * N + a];
                worst = worst.max((change - dt * rhs).abs());
                scale = scale.max((dt * rhs).abs());
            }
        }
        println!("largest departure {worst:.3e} of changes up to {scale:.3e}");
        assert!(scale > 1e-5);
        assert!(worst <= 1e-3 * scale, "{worst:e} vs {scale:e}");
    }

    /// Σ_α l_α h w_α is conserved between walls, and a w uniform in x and z stays
    /// uniform over a varying depth with a mean flow.
    #[test]
    fn layered_tracer_is_conservative_and_keeps_a_uniform_value() {
        let mesh = mesh();
        let depth = |x: f64| 0.1 + 0.03 * (3.0 * x).sin();
        let w = [0.3, -0.1, 0.5, 0.2];
        let mut s = state(&mesh, depth, 0.2, w);
        let total =
            |s: &LayeredState| -> f64 { s.hw()[N..(NX + 1) * N].iter().sum::<f64>() / N as f64 };
        let t0 = total(&s);
        for _ in 0..20 {
            step(&mesh, &mut s, 1e-4);
        }
        let t1 = total(&s);
        assert!(
            (t1 - t0).abs() <= 1e-14 * t0.abs().max(1e-3),
            "{t0} -> {t1}"
        );
        assert!(s.hw() != state(&mesh, depth, 0.2, w).hw());

        let mut s = state(&mesh, depth, 0.2, [0.7; N]);
        for _ in 0..20 {
            step(&mesh, &mut s, 1e-4);
        }
        for i in 1..=NX {
            for a in 0..N {
                let w = s.hw()[i * N + a] / s.h[i];
                assert!((w - 0.7).abs() < 1e-13, "cell {i}, layer {a}: {w}");
            }
        }
    }
    /// A thin column between faces whose layer fluxes shear it strongly: the lower
    /// layers leave through both faces (0.8 of their content per step), the upper
    /// ones receive as much, so the exchange through the middle interfaces moves four
    /// times a layer's content within the step (vertical Courant number 4, N = 10).
    /// Every new concentration must stay within the range of the old ones (a discrete
    /// maximum principle). The explicit upwind exchange gives c_new = (1 − ν) c + ν
    /// c_above with ν up to 4: layer to layer alternating values that grow step after
    /// step (the film of the 10-layer non-hydrostatic run of Escalante et al. 2023,
    /// §5.4 at a thick column's edge); the exchange taken implicitly keeps the range.
    #[test]
    fn strong_vertical_exchange_keeps_the_tracer_within_its_range() {
        use super::TracerTransport;
        use crate::state::layered::Tracer;
        let (nx, n) = (3, 10);
        let h = vec![1e-3; nx + 2];
        let flux = vec![0.0; nx + 1];
        let r = 0.5;
        // r d = 0.4 h per face: lower layers leave through both faces of cell 2.
        let d = 0.4e-3 / r;
        let mut departure = vec![0.0; (nx + 1) * n];
        for a in 0..n {
            let lower = if a < n / 2 { 1.0 } else { -1.0 };
            departure[n + a] = -lower * d; // face 1 (left of cell 2)
            departure[2 * n + a] = lower * d; // face 2 (right of cell 2)
        }
        let l = vec![1.0 / n as f64; n];
        let c0: Vec<f64> = (0..(nx + 2) * n)
            .map(|k| if (k % n) % 2 == 0 { 1.0 } else { -1.0 })
            .collect();
        let mut tracers = vec![Tracer {
            name: "hw",
            q: c0.iter().zip(0..).map(|(c, k)| c * h[k / n]).collect(),
        }];
        let mut t = TracerTransport::default();
        t.before_step(&h, n, &tracers);
        t.after_step(&flux, Some((&departure, &l)), &h, r, n, &mut tracers);
        let c: Vec<f64> = (n..(nx + 1) * n)
            .map(|k| tracers[0].q[k] / h[k / n])
            .collect();
        println!("cell 2 after the step: {:?}", &c[n..2 * n]);
        for (k, v) in c.iter().enumerate() {
            assert!(
                (-1.0 - 1e-12..=1.0 + 1e-12).contains(v),
                "cell {}, layer {}: c = {v} outside [-1, 1]",
                k / n + 1,
                k % n
            );
        }
        // Conservative: Σ_α l_α q_α over the cells is unchanged (the faces 0 and 3
        // carry nothing).
        let total = |q: &[f64]| q[n..(nx + 1) * n].iter().sum::<f64>();
        let before: Vec<f64> = c0.iter().zip(0..).map(|(c, k)| c * h[k / n]).collect();
        assert!((total(&tracers[0].q) - total(&before)).abs() < 1e-15);
    }
}
