//! Passive tracers carried by the hyperbolic step (seed 000 after eq. 24 for hw; the
//! same upwind transport serves any quantity that moves with the grains).
//!
//! A tracer q = h c (per cell and layer) follows the mass flux 𝓕^h of step 1 with the
//! concentration c = q/h of the upwind cell, taken before the step:
//!
//!   q_i ← q_i − Δt/Δx (𝓕^h_{i+1/2} c^up_{i+1/2} − 𝓕^h_{i−1/2} c^up_{i−1/2}),
//!
//! and q = 0 in cells that are dry after the step. With N > 1 layers every layer's
//! tracer rides the total mass flux with its own concentration (the exchange terms of
//! seed 003 eq. 5 do not move tracers). A run without tracers builds nothing here.

use crate::model::granular::state::{fill_tracer_ghosts, Tracer};
use crate::physics::shallow::H_DRY;

/// Scratch of the transport: concentrations before the step and face fluxes.
#[derive(Debug, Default)]
pub struct TracerTransport {
    /// c = q/h per tracer, cell and layer (with ghosts), before the step.
    concentration: Vec<Vec<f64>>,
    flux: Vec<f64>,
}

impl TracerTransport {
    /// Remembers the concentrations of `tracers` in the state (h, q) before step 1.
    /// The loop is branch-free (selects), so that it vectorises.
    pub fn before_step(&mut self, h: &[f64], layers: usize, tracers: &[Tracer]) {
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
    /// step just taken; `h` is the thickness after it, `r` = Δt/Δx.
    pub fn after_step(
        &mut self,
        mass_flux: &[f64],
        h: &[f64],
        r: f64,
        layers: usize,
        tracers: &mut [Tracer],
    ) {
        let nx = mass_flux.len() - 1;
        let n = layers;
        self.flux.resize(mass_flux.len() * n, 0.0);
        for (c, tracer) in self.concentration.iter().zip(tracers) {
            for (k, &f) in mass_flux.iter().enumerate() {
                let donor = if f > 0.0 { k } else { k + 1 };
                for a in 0..n {
                    self.flux[k * n + a] = f * c[donor * n + a];
                }
            }
            for (i, &hi) in h.iter().enumerate().take(nx + 1).skip(1) {
                let wet = hi > H_DRY;
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
