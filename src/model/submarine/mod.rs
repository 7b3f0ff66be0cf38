//! The two-layer submarine-avalanche model of Fernández-Nieto et al. 2008 (`model.kind = "submarine"`):
//! water (layer 1) over a fluidised granular layer (layer 2) with Coulomb friction,
//! in the Cartesian form eq. (62), solved by [`crate::numerics::two_layer`].
//!
//! Per snapshot: `h` and `u` are the grain layer's H₂ and U₂ (so the front, runout
//! and deposit tools read the slide), and the extra fields `h_water`, `u_water`,
//! `eta` (water free surface b + (H₁ + H₂)cos²θ) and `interface` (b + H₂cos²θ).
//! Diagnostics: `mass` is the grain volume ∫H₂ dx, the front is the slide's, the
//! kinetic energy is ∫ ½(H₂U₂² + r H₁U₁²) dx (per unit grain density), the maximum
//! speed is over both layers (a run stops "at rest" only when the water is still too).

use crate::grid::CurvedLine;
use crate::model::{Diagnostics, Model};
use crate::numerics::two_layer::{max_face_speed, sweep_speeds};
use crate::output::{CellField, OutputError, OutputSink, SnapshotView};
use crate::physics::two_layer::{layer_velocity, max_num, TwoLayerParams};
use crate::state::{TwoLayerState, WaterColumn};

#[derive(Debug, Clone)]
pub struct Submarine {
    pub params: TwoLayerParams,
    pub front_threshold: f64,
    /// No erodible bed: zeros (nx).
    pub h_bed: Vec<f64>,
    /// Initial water surface η₀ per cell (nx) where the water is deeper than the front
    /// threshold at t = 0, NaN elsewhere: the reference of the wave amplitude.
    pub eta0: Vec<f64>,
}

impl Submarine {
    /// η₀ of [`Submarine::eta0`] for the initial state `s`.
    pub fn initial_surface(g: &CurvedLine, s: &TwoLayerState, threshold: f64) -> Vec<f64> {
        (1..=g.line.nx)
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

/// The largest |λ| over the faces, from the same bounds the scheme upwinds with.
pub fn signal_speed(p: &TwoLayerParams, g: &CurvedLine, s: &TwoLayerState) -> f64 {
    max_face_speed(p, g, s)
}

impl Model for Submarine {
    type Grid = CurvedLine;
    type State = TwoLayerState;

    fn kind(&self) -> &'static str {
        "submarine"
    }

    /// One sweep over the cells and faces ([`sweep_speeds`]): the signal speed of the
    /// face bounds, and the per-cell sums from the same views.
    fn diagnose(&self, g: &CurvedLine, s: &TwoLayerState) -> Diagnostics {
        let nx = g.line.nx;
        let (r, dx) = (self.params.r, g.line.dx);
        let mut d = Diagnostics {
            mass: 0.0,
            kinetic_energy: 0.0,
            max_speed: 0.0,
            signal_speed: 0.0,
            front_x: f64::NAN,
            h_max: 0.0,
            non_finite_at: None,
            wet_cells: None,
        };
        let (mut front, mut all) = (None, 0.0f64);
        let smax = sweep_speeds(&self.params, g, s, |i, c| {
            // The view's velocities are those of layer_velocity.
            all += c.h1 + c.q1 + c.h2 + c.q2;
            d.mass += c.h2 * dx;
            d.kinetic_energy += 0.5 * (c.h2 * c.u2 * c.u2 + r * c.h1 * c.u1 * c.u1) * dx;
            d.max_speed = max_num(max_num(d.max_speed, c.u1.abs()), c.u2.abs());
            d.h_max = max_num(d.h_max, c.h2);
            if c.h2 > self.front_threshold {
                front = Some(i - 1);
            }
        });
        d.signal_speed = smax;
        d.front_x = front.map_or(f64::NAN, |i| g.line.x[i]);
        // A non-finite value poisons the sum; only then search for the cell (a sum of
        // finite values that overflows finds none).
        if !all.is_finite() {
            d.non_finite_at = (1..=nx).position(|i| {
                !(s.h1[i].is_finite()
                    && s.q1[i].is_finite()
                    && s.h2[i].is_finite()
                    && s.q2[i].is_finite())
            });
        }
        d
    }

    /// The first cell with the largest max(|u₁|, |u₂|), from the views of
    /// [`Self::diagnose`].
    fn fastest_cell(&self, g: &CurvedLine, s: &TwoLayerState) -> Option<usize> {
        let mut speeds = vec![0.0; g.line.nx];
        sweep_speeds(&self.params, g, s, |i, c| {
            speeds[i - 1] = max_num(c.u1.abs(), c.u2.abs());
        });
        crate::model::first_maximum(speeds.into_iter())
    }

    fn bed_layer(&self) -> &[f64] {
        &self.h_bed
    }

    /// The water surface η = b + (H₁ + H₂)cos²θ (the grain top where there is no
    /// water) and the grain depth H₂ (the `h` of the snapshots).
    fn gauge_cell(&self, g: &CurvedLine, s: &TwoLayerState, i: usize) -> Option<(f64, f64)> {
        Some((s.eta(g, i + 1), s.h2[i + 1]))
    }

    /// max |η − η₀| over the cells with H₁ above the front threshold now and at t = 0.
    fn wave_amplitude(&self, g: &CurvedLine, s: &TwoLayerState) -> Option<f64> {
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
        g: &CurvedLine,
        s: &TwoLayerState,
        t: f64,
        sink: &mut dyn OutputSink,
    ) -> Result<(), OutputError> {
        let nx = g.line.nx;
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
        let mut extra = vec![
            CellField {
                name: "h_water",
                units: "m",
                description: "water layer thickness",
                data: &s.h1[1..=nx],
            },
            CellField {
                name: "u_water",
                units: "m/s",
                description: "depth-averaged velocity of the water layer",
                data: &u1,
            },
            CellField {
                name: "eta",
                units: "m",
                description: "water surface elevation",
                data: &eta,
            },
            CellField {
                name: "interface",
                units: "m",
                description: "elevation of the interface between grains and water",
                data: &interface,
            },
        ];
        // Non-hydrostatic water: w_α per cell and p_{α−1/2} (mean of the cell's two
        // faces) per layer, α = 1 at the grains.
        let columns = s.water.as_ref().map(|w| water_fields(w, nx));
        if let Some((w, p)) = &columns {
            let layers = w.len() / nx;
            for a in 0..layers {
                extra.push(CellField {
                    name: W_WATER[a],
                    units: "m/s",
                    description: "vertical velocity of the water at a level",
                    data: &w[a * nx..(a + 1) * nx],
                });
                extra.push(CellField {
                    name: P_WATER[a],
                    units: "m2/s2",
                    description:
                        "non-hydrostatic pressure of the water per unit density at a level",
                    data: &p[a * nx..(a + 1) * nx],
                });
            }
        }
        sink.snapshot(&SnapshotView {
            t,
            h: &s.h2[1..=nx],
            u: &u2,
            v: None,
            shape: None,
            w: None,
            p_nh: None,
            layers: 1,
            extra: &extra,
            layer_uv: None,
        })
    }
}

/// Snapshot names of the water layers' w_α and p_{α−1/2} (α = 1 at the grains).
/// Most water layers (`submarine.water_layers`), the length of the name tables below.
pub const MAX_WATER_LAYERS: usize = 16;

const W_WATER: [&str; MAX_WATER_LAYERS] = [
    "w_water_1",
    "w_water_2",
    "w_water_3",
    "w_water_4",
    "w_water_5",
    "w_water_6",
    "w_water_7",
    "w_water_8",
    "w_water_9",
    "w_water_10",
    "w_water_11",
    "w_water_12",
    "w_water_13",
    "w_water_14",
    "w_water_15",
    "w_water_16",
];
const P_WATER: [&str; MAX_WATER_LAYERS] = [
    "p_water_1",
    "p_water_2",
    "p_water_3",
    "p_water_4",
    "p_water_5",
    "p_water_6",
    "p_water_7",
    "p_water_8",
    "p_water_9",
    "p_water_10",
    "p_water_11",
    "p_water_12",
    "p_water_13",
    "p_water_14",
    "p_water_15",
    "p_water_16",
];

/// w_α per physical cell and the mean of p_{α−1/2} over each cell's two faces, both
/// layer-major (α·nx + i).
fn water_fields(water: &WaterColumn, nx: usize) -> (Vec<f64>, Vec<f64>) {
    let n = water.layers;
    let mut w = vec![0.0; n * nx];
    let mut p = vec![0.0; n * nx];
    for i in 0..nx {
        for a in 0..n {
            w[a * nx + i] = water.w[(i + 1) * n + a];
            p[a * nx + i] = 0.5 * (water.p[i * n + a] + water.p[(i + 1) * n + a]);
        }
    }
    (w, p)
}

/// The validated `[submarine]` keys (Fernández-Nieto et al. 2008, eq. 50).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SubmarineSpec {
    /// Density ratio r = ρ₁/ρ₂ (water over the grain layer's bulk density).
    pub r: f64,
    /// Earth-pressure coefficient K (1: isotropic, the paper's §5).
    pub k: f64,
    pub lambda1: f64,
    pub lambda2: f64,
    pub buoyancy: crate::physics::two_layer::Buoyancy,
    /// `submarine.water_pressure` and `submarine.water_layers`.
    pub water: WaterPressure,
}

/// The water's pressure: hydrostatic (Fernández-Nieto et al. 2008, the default) or
/// non-hydrostatic in M layers ([`crate::numerics::water_nh`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum WaterPressure {
    Hydrostatic,
    NonHydrostatic { layers: usize },
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
