//! The layered state of the granular family (Savage–Hutter, multilayer,
//! non-hydrostatic): one material split into N layers of fixed fractions.
//!
//! Cell averages of the total thickness h and of the layer discharges (hu)_α = h u_α,
//! α = 1..N (Escalante et al. 2023 notation: layer α has thickness l_α h), with one ghost cell on
//! each side (index 0 and nx + 1). The depth-averaged discharge is Σ_α l_α (hu)_α.
//! Discharges are stored cell-major, `hu[j * N + α]`, so the per-column work of the
//! multilayer viscous step reads contiguous memory. N = 1 is the Savage–Hutter model.
//!
//! Passive quantities per layer (h w_α of the non-hydrostatic model; any other model
//! quantity that moves with the grains) are [`Tracer`]s: the hyperbolic step carries
//! them with its own mass fluxes (`numerics::tracer`), as Basilisk's `tracers` list
//! carries w in `layered/nh.h`. A hydrostatic run has none and pays nothing for them.

use crate::grid::Line;
use crate::physics::shallow::velocity;

#[derive(Debug, PartialEq)]
pub struct LayeredState {
    pub nx: usize,
    pub layers: usize,
    /// Layer fractions l_α (Σ l_α = 1).
    pub l: Vec<f64>,
    /// Total thickness, nx + 2 with ghosts.
    pub h: Vec<f64>,
    /// Layer discharges, (nx + 2)·N, cell-major.
    pub hu: Vec<f64>,
    /// Quantities carried by the mass fluxes of step 1, (nx + 2)·N each, cell-major.
    pub tracers: Vec<Tracer>,
    /// Non-hydrostatic pressure; `None` for hydrostatic runs, which carry nothing.
    pub nh: Option<NonHydrostatic>,
}

/// A passive quantity q_α = h c_α per cell and layer (ghosts included, cell-major like
/// `hu`), transported with the layer's mass flux and the upwind concentration c.
#[derive(Debug, PartialEq)]
pub struct Tracer {
    /// Name of the quantity, e.g. "hw".
    pub name: &'static str,
    pub q: Vec<f64>,
}

// `Clone` by hand: the derived `clone_from` would allocate a new copy, and the run
// loop copies the state into its backup every step (`clone_from` into the buffers
// allocated once).
impl Clone for LayeredState {
    fn clone(&self) -> Self {
        LayeredState {
            nx: self.nx,
            layers: self.layers,
            l: self.l.clone(),
            h: self.h.clone(),
            hu: self.hu.clone(),
            tracers: self.tracers.clone(),
            nh: self.nh.clone(),
        }
    }

    fn clone_from(&mut self, source: &Self) {
        self.nx = source.nx;
        self.layers = source.layers;
        self.l.clone_from(&source.l);
        self.h.clone_from(&source.h);
        self.hu.clone_from(&source.hu);
        self.tracers.clone_from(&source.tracers);
        match (&mut self.nh, &source.nh) {
            (Some(nh), Some(src)) => {
                nh.p.clone_from(&src.p);
                nh.lagged_hu.clone_from(&src.lagged_hu);
            }
            (nh, src) => nh.clone_from(src),
        }
    }
}

impl Clone for Tracer {
    fn clone(&self) -> Self {
        Tracer {
            name: self.name,
            q: self.q.clone(),
        }
    }

    fn clone_from(&mut self, source: &Self) {
        self.name = source.name;
        self.q.clone_from(&source.q);
    }
}

/// Name of the normal-discharge tracer h w_α of the non-hydrostatic models.
pub const HW: &str = "hw";

impl LayeredState {
    /// A state with thickness `h` and depth-averaged velocity `u` (physical cells),
    /// every layer moving with u.
    pub fn from_profiles(line: &Line, l: &[f64], h: &[f64], u: &[f64]) -> LayeredState {
        let nx = line.nx;
        let layers = l.len();
        assert!(h.len() == nx && u.len() == nx && layers >= 1);
        let mut s = LayeredState {
            nx,
            layers,
            l: l.to_vec(),
            h: vec![0.0; nx + 2],
            hu: vec![0.0; (nx + 2) * layers],
            tracers: Vec::new(),
            nh: None,
        };
        for i in 0..nx {
            s.h[i + 1] = h[i];
            for a in 0..layers {
                s.hu[(i + 1) * layers + a] = h[i] * u[i];
            }
        }
        s.fill_ghosts(line);
        s
    }

    /// Ghost cells per Escalante et al. 2023, Remark 6: thickness copied (homogeneous Neumann);
    /// discharge copied (outflow) or reversed (wall).
    pub fn fill_ghosts(&mut self, line: &Line) {
        let (nx, n) = (self.nx, self.layers);
        self.h[0] = self.h[1];
        self.h[nx + 1] = self.h[nx];
        let (sl, sr) = (line.left.discharge_sign(), line.right.discharge_sign());
        for a in 0..n {
            self.hu[a] = sl * self.hu[n + a];
            self.hu[(nx + 1) * n + a] = sr * self.hu[nx * n + a];
        }
    }

    /// Depth-averaged velocity of cell j (ghost-inclusive index).
    #[inline(always)]
    pub fn mean_velocity(&self, j: usize) -> f64 {
        let n = self.layers;
        if n == 1 {
            return velocity(self.h[j], self.hu[j]);
        }
        let q: f64 = self.hu[j * n..(j + 1) * n]
            .iter()
            .zip(&self.l)
            .map(|(q, l)| q * l)
            .sum();
        velocity(self.h[j], q)
    }

    /// The tracer `name`, if the state carries it.
    pub fn tracer(&self, name: &str) -> Option<&[f64]> {
        self.tracers
            .iter()
            .find(|t| t.name == name)
            .map(|t| t.q.as_slice())
    }

    /// The normal discharges h w_α of a non-hydrostatic state.
    pub fn hw(&self) -> &[f64] {
        self.tracer(HW).expect("a non-hydrostatic state carries hw")
    }

    /// The normal discharges h w_α of a non-hydrostatic state, to change.
    pub fn hw_mut(&mut self) -> &mut Vec<f64> {
        &mut self
            .tracers
            .iter_mut()
            .find(|t| t.name == HW)
            .expect("a non-hydrostatic state carries hw")
            .q
    }

    /// Adds the non-hydrostatic unknowns: hw = h w from a normal velocity `w` per
    /// physical cell (the same in every layer), and a pressure that starts at 0.
    pub fn add_nonhydrostatic(&mut self, w: &[f64]) {
        let (nx, n) = (self.nx, self.layers);
        assert_eq!(w.len(), nx);
        let mut hw = vec![0.0; (nx + 2) * n];
        for i in 0..nx {
            for a in 0..n {
                hw[(i + 1) * n + a] = self.h[i + 1] * w[i];
            }
        }
        fill_tracer_ghosts(&mut hw, nx, n);
        self.tracers.push(Tracer { name: HW, q: hw });
        self.nh = Some(NonHydrostatic {
            p: vec![0.0; (nx + 1) * n],
            lagged_hu: Vec::new(),
        });
    }

    /// Physical-cell thickness (without ghosts).
    pub fn h_interior(&self) -> &[f64] {
        &self.h[1..=self.nx]
    }
}

/// Ghost values of a tracer: copied at both walls and outflows (w is even under the
/// mirror of a wall, and continued by an outflow).
pub fn fill_tracer_ghosts(q: &mut [f64], nx: usize, n: usize) {
    for a in 0..n {
        q[a] = q[n + a];
        q[(nx + 1) * n + a] = q[nx * n + a];
    }
}

/// The non-hydrostatic pressure (Garres-Díaz et al. 2021, eq. 15, Escalante et al. 2023, §3–4), present only when
/// `model.pressure = "nonhydrostatic"` (its normal discharges h w_α are the tracer
/// [`HW`]).
///
/// `p`: non-hydrostatic pressure over density at the nx + 1 staggered faces (face k
/// lies between the ghost-inclusive cells k and k + 1, at x_min + kΔx) and at the
/// layer interfaces Z_{α−1/2}, α = 1..N (the bed is α = 1), face-major:
/// `p[k * N + α − 1]`. The free-surface value p_{N+1/2} is 0 and is not stored. For
/// the monolayer, p_{1/2} is the basal value 2q̄ of Garres-Díaz et al. 2021 (a linear profile
/// vanishing at the surface; q̄ = p_{1/2}/2 is the depth average).
///
/// `lagged_hu`: the layer discharges h u_α after the last viscous solve (ghosts
/// included, cell-major like `hu`; empty before the first, and in runs that do not
/// lag the viscosities), from which the next step's viscosities are frozen
/// (`numerics::nh_multilayer`). It decides the next step, so it lives here, in the
/// state that a refused step restores, not in the stage.
#[derive(Debug, Clone, PartialEq)]
pub struct NonHydrostatic {
    pub p: Vec<f64>,
    pub lagged_hu: Vec<f64>,
}

impl NonHydrostatic {
    /// Output fields (see docs/output-format.md): w = hw/h per layer (layer-major,
    /// α·nx + i, 0 in dry cells) and p at the nl + 1 layer interfaces and nx + 1 faces
    /// (layer-major, bed first; the surface row is 0).
    pub fn snapshot_fields(&self, state: &LayeredState) -> (Vec<f64>, Vec<f64>) {
        let (nx, n) = (state.nx, state.layers);
        let hw = state.hw();
        let mut w = vec![0.0; n * nx];
        for i in 0..nx {
            for a in 0..n {
                w[a * nx + i] = velocity(state.h[i + 1], hw[(i + 1) * n + a]);
            }
        }
        let mut p = vec![0.0; (n + 1) * (nx + 1)];
        for k in 0..=nx {
            for a in 0..n {
                p[a * (nx + 1) + k] = self.p[k * n + a];
            }
        }
        (w, p)
    }
}
