//! The two-layer submarine-avalanche model of seed 004 (`model.kind = "submarine"`):
//! water (layer 1) over a fluidised granular layer (layer 2) with Coulomb friction,
//! in the Cartesian form eq. (62), solved by [`crate::numerics::two_layer`].
//!
//! Per snapshot: `h` and `u` are the grain layer's H₂ and U₂ (so the front, runout
//! and deposit tools read the slide), and the extra fields `h_water`, `u_water`,
//! `eta` (water free surface b + (H₁ + H₂)cos²θ) and `interface` (b + H₂cos²θ).
//! Diagnostics: `mass` is the grain volume ∫H₂ dx, the front is the slide's, the
//! kinetic energy is ∫ ½(H₂U₂² + r H₁U₁²) dx (per unit grain density), the maximum
//! speed is over both layers (a run stops "at rest" only when the water is still too).

use crate::mesh::Mesh;
use crate::model::{Diagnostics, Model};
use crate::numerics::two_layer::face::{face_speeds, CellView};
use crate::numerics::two_layer::{TwoLayerGeometry, TwoLayerState};
use crate::output::{CellField, OutputError, OutputSink, SnapshotView};
use crate::physics::two_layer::{layer_velocity, TwoLayerParams};

#[derive(Debug, Clone)]
pub struct Submarine {
    pub params: TwoLayerParams,
    pub geometry: TwoLayerGeometry,
    pub front_threshold: f64,
    /// No erodible bed: zeros (nx).
    pub h_bed: Vec<f64>,
    /// Initial water surface η₀ per cell (nx) where the water is deeper than the front
    /// threshold at t = 0, NaN elsewhere: the reference of the wave amplitude.
    pub eta0: Vec<f64>,
}

impl Submarine {
    /// η₀ of [`Submarine::eta0`] for the initial state `s`.
    pub fn initial_surface(g: &TwoLayerGeometry, s: &TwoLayerState, threshold: f64) -> Vec<f64> {
        (1..=g.nx)
            .map(|i| {
                if s.h1[i] > threshold {
                    s.eta(g, i)
                } else {
                    f64::NAN
                }
            })
            .collect()
    }
}

fn view(p: &TwoLayerParams, g: &TwoLayerGeometry, s: &TwoLayerState, i: usize) -> CellView {
    CellView::new(
        p, s.h1[i], s.q1[i], s.h2[i], s.q2[i], g.b[i], g.cos[i], g.cos2[i], g.sin[i],
    )
}

/// The largest |λ| over the faces, from the same bounds the scheme upwinds with.
pub fn signal_speed(p: &TwoLayerParams, g: &TwoLayerGeometry, s: &TwoLayerState) -> f64 {
    let mut left = view(p, g, s, 0);
    let mut smax = 0.0f64;
    for j in 0..=g.nx {
        let right = view(p, g, s, j + 1);
        let (a, b) = face_speeds(p, &left, &right);
        smax = smax.max(a.abs()).max(b.abs());
        left = right;
    }
    smax
}

impl Model for Submarine {
    type State = TwoLayerState;

    fn kind(&self) -> &'static str {
        "submarine"
    }

    fn diagnose(&self, mesh: &Mesh, s: &TwoLayerState) -> Diagnostics {
        let g = &self.geometry;
        let mut d = Diagnostics {
            mass: 0.0,
            kinetic_energy: 0.0,
            max_speed: 0.0,
            signal_speed: 0.0,
            front_x: f64::NAN,
            h_max: 0.0,
            non_finite_at: None,
        };
        for i in 1..=g.nx {
            let (h1, q1, h2, q2) = (s.h1[i], s.q1[i], s.h2[i], s.q2[i]);
            if d.non_finite_at.is_none()
                && !(h1.is_finite() && q1.is_finite() && h2.is_finite() && q2.is_finite())
            {
                d.non_finite_at = Some(i - 1);
            }
            let (u1, u2) = (layer_velocity(h1, q1), layer_velocity(h2, q2));
            d.mass += h2 * mesh.dx;
            d.kinetic_energy += 0.5 * (h2 * u2 * u2 + self.params.r * h1 * u1 * u1) * mesh.dx;
            d.max_speed = d.max_speed.max(u1.abs()).max(u2.abs());
            d.h_max = d.h_max.max(h2);
            if h2 > self.front_threshold {
                d.front_x = mesh.x[i - 1];
            }
        }
        d.signal_speed = signal_speed(&self.params, g, s);
        d
    }

    fn bed_layer(&self) -> &[f64] {
        &self.h_bed
    }

    /// The water surface η = b + (H₁ + H₂)cos²θ (the grain top where there is no
    /// water) and the grain depth H₂ (the `h` of the snapshots).
    fn gauge_cell(&self, _mesh: &Mesh, s: &TwoLayerState, i: usize) -> Option<(f64, f64)> {
        Some((s.eta(&self.geometry, i + 1), s.h2[i + 1]))
    }

    /// max |η − η₀| over the cells with H₁ above the front threshold now and at t = 0.
    fn wave_amplitude(&self, _mesh: &Mesh, s: &TwoLayerState) -> Option<f64> {
        let g = &self.geometry;
        let mut a = 0.0f64;
        for (i, &eta0) in self.eta0.iter().enumerate() {
            if s.h1[i + 1] > self.front_threshold && eta0.is_finite() {
                a = a.max((s.eta(g, i + 1) - eta0).abs());
            }
        }
        Some(a)
    }

    fn snapshot(
        &self,
        mesh: &Mesh,
        s: &TwoLayerState,
        t: f64,
        sink: &mut dyn OutputSink,
    ) -> Result<(), OutputError> {
        let nx = mesh.nx;
        let g = &self.geometry;
        let mut u2 = vec![0.0; nx];
        let mut u1 = vec![0.0; nx];
        let mut eta = vec![0.0; nx];
        let mut interface = vec![0.0; nx];
        for i in 0..nx {
            u1[i] = layer_velocity(s.h1[i + 1], s.q1[i + 1]);
            u2[i] = layer_velocity(s.h2[i + 1], s.q2[i + 1]);
            eta[i] = s.eta(g, i + 1);
            interface[i] = s.interface(g, i + 1);
        }
        let extra = [
            CellField {
                name: "h_water",
                units: "m",
                data: &s.h1[1..=nx],
            },
            CellField {
                name: "u_water",
                units: "m/s",
                data: &u1,
            },
            CellField {
                name: "eta",
                units: "m",
                data: &eta,
            },
            CellField {
                name: "interface",
                units: "m",
                data: &interface,
            },
        ];
        sink.snapshot(&SnapshotView {
            t,
            h: &s.h2[1..=nx],
            u: &u2,
            w: None,
            p_nh: None,
            layers: 1,
            extra: &extra,
        })
    }
}

/// The validated `[submarine]` keys (seed 004 eq. 50).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SubmarineSpec {
    /// Density ratio r = ρ₁/ρ₂ (water over the grain layer's bulk density).
    pub r: f64,
    /// Earth-pressure coefficient K (1: isotropic, the paper's §5).
    pub k: f64,
    pub lambda1: f64,
    pub lambda2: f64,
    pub buoyancy: crate::physics::two_layer::Buoyancy,
}

impl SubmarineSpec {
    /// The model's parameters with the Coulomb coefficient μ = tan δ₀.
    pub fn params(&self, mu: f64) -> TwoLayerParams {
        let mut p = TwoLayerParams::new(self.r, self.k, self.lambda1, self.lambda2, 0.0);
        p.tan_delta = mu;
        p.buoyancy = self.buoyancy;
        p
    }
}
