#![allow(clippy::needless_range_loop)] // index arithmetic mirrors the block algebra
//! The exact solvers for the pressure system of the multilayer non-hydrostatic model
//! (Escalante et al. 2023, eq. 31–32, Appendix A), timed on the Table 2 grid: 640 cells,
//! 20 layers (12 820 unknowns), every face wet, a sheared state on the collapse's
//! geometry (domain [−0.2, 3] m, wall/outflow).
//!
//!     cargo bench --bench nh_multilayer_solver
//!
//! Cases, each the best of several bursts (a shared machine), per projection:
//! - `banded`: the production path, [`BandedCholesky`] with rows formed on demand
//!   (forming the rows included);
//! - `block-nalgebra`: block Cholesky (block Thomas) with dense N×N nalgebra blocks,
//!   from the same rows (storing them included);
//! - `block-gauss-seidel`: Escalante et al. 2023's algorithm (§4, with a Thomas solve per layer,
//!   l2 tolerance 1e-6 on the increments, from a zero guess), for scale.
//!
//! Each reports the time and the relative residual max|AΠ − b| / max|b|.
//! Results: docs/performance.md, "Multilayer non-hydrostatic".

use std::time::Instant;

use granflow::grid::{BoundaryKind, Coordinates};
use granflow::grid::{Line, LineSpec};
use granflow::numerics::banded::{stencil_residual, BandedCholesky, StencilRow};
use granflow::numerics::linalg::{thomas, PressureRows};
use granflow::numerics::projection::multilayer::MultilayerOperator;
use granflow::state::layered::{fill_tracer_ghosts, LayeredState};
use nalgebra::DMatrix;

fn collapse_state(cells: usize, layers: usize) -> (Line, LayeredState) {
    let spec = LineSpec {
        x_min: -0.2,
        x_max: 3.0,
        cells,
        slope_deg: 22.0,
        coordinates: Coordinates::Local,
        left: BoundaryKind::Wall,
        right: BoundaryKind::Outflow,
    };
    let x = spec.centres();
    let mesh = Line::new(&spec, vec![0.0; cells]);
    let h: Vec<f64> = x
        .iter()
        .map(|x| 0.00182 + 0.12 * (-((x - 0.1) / 0.35f64).powi(2)).exp())
        .collect();
    let l = vec![1.0 / layers as f64; layers];
    let mut state = LayeredState::from_profiles(&mesh, &l, &h, &vec![0.0; cells]);
    state.add_nonhydrostatic(&vec![0.0; cells]);
    let mut hw = state.hw().to_vec();
    for i in 0..cells {
        for a in 0..layers {
            let z = (a as f64 + 0.5) / layers as f64;
            let k = (i + 1) * layers + a;
            state.hu[k] = h[i] * 1.5 * z.sqrt() * (-((x[i] - 0.4) / 0.5f64).powi(2)).exp();
            hw[k] = -h[i] * 0.1 * z * (3.0 * x[i]).sin();
        }
    }
    state.fill_ghosts(&mesh);
    fill_tracer_ghosts(&mut hw, cells, layers);
    *state.hw_mut() = hw;
    (mesh, state)
}

fn best<F: FnMut() -> f64>(reps: usize, mut f: F) -> (f64, f64) {
    let mut t_best = f64::INFINITY;
    let mut res = 0.0;
    for _ in 0..reps {
        let t = Instant::now();
        res = f();
        t_best = t_best.min(t.elapsed().as_secs_f64());
    }
    (t_best, res)
}

fn relative_residual<R: PressureRows<Row = StencilRow>>(rows: &R, m: usize, x: &[f64]) -> f64 {
    let mut r = vec![0.0; x.len()];
    stencil_residual(rows, m, x, &mut r);
    let bmax = rows
        .active()
        .map(|k| rows.row(k).rhs.abs())
        .fold(0.0f64, f64::max);
    r.iter().fold(0.0f64, |a, v| a.max(v.abs())) / bmax
}

/// Block Cholesky with dense nalgebra blocks: L_k L_kᵀ = A_kk − B_k B_kᵀ,
/// B_k = A_{k,k−1} L_{k−1}^{−T}; storage allocated once.
struct BlockCholesky {
    m: usize,
    l: Vec<DMatrix<f64>>,
    b: Vec<DMatrix<f64>>,
    y: Vec<f64>,
    tmp: DMatrix<f64>,
}

impl BlockCholesky {
    fn new(m: usize, faces: usize) -> Self {
        BlockCholesky {
            m,
            l: vec![DMatrix::zeros(m, m); faces],
            b: vec![DMatrix::zeros(m, m); faces],
            y: vec![0.0; faces * m],
            tmp: DMatrix::zeros(m, m),
        }
    }

    fn solve<R: PressureRows<Row = StencilRow>>(&mut self, rows: &R, x: &mut [f64]) {
        let m = self.m;
        let active = rows.active();
        let (f0, f1) = (active.start / m, active.end / m);
        x.fill(0.0);
        for f in f0..f1 {
            // Store the diagonal block in l[f] and the lower block in b[f].
            self.l[f].fill(0.0);
            self.b[f].fill(0.0);
            for j in 0..m {
                let row = rows.row(f * m + j);
                self.y[f * m + j] = row.rhs;
                for dj in 0..3 {
                    let c = (j + dj) as isize - 1;
                    if c < 0 || c as usize >= m {
                        continue;
                    }
                    let c = c as usize;
                    self.l[f][(j, c)] = row.coef[1][dj];
                    if f > f0 {
                        self.b[f][(j, c)] = row.coef[0][dj];
                    }
                }
            }
            if f > f0 {
                // B = A_{f,f−1} L_{f−1}^{−T}: solve L_{f−1} Bᵀ = A_{f,f−1}ᵀ.
                self.tmp.copy_from(&self.b[f].transpose());
                self.l[f - 1].solve_lower_triangular_mut(&mut self.tmp);
                self.b[f].copy_from(&self.tmp.transpose());
                // S = A_ff − B Bᵀ
                let bt = self.b[f].transpose();
                self.l[f].gemm(-1.0, &self.b[f], &bt, 1.0);
                // y_f −= B y_{f−1}
                let (prev, cur) = self.y.split_at_mut(f * m);
                let yp = &prev[(f - 1) * m..];
                for i in 0..m {
                    let s: f64 = (0..m).map(|k| self.b[f][(i, k)] * yp[k]).sum();
                    cur[i] -= s;
                }
            }
            let a = std::mem::replace(&mut self.l[f], DMatrix::zeros(0, 0));
            let chol = a.cholesky().expect("SPD block");
            self.l[f] = chol.unpack();
            let yf = &mut self.y[f * m..(f + 1) * m];
            // Forward: L y = y.
            for i in 0..m {
                let s: f64 = (0..i).map(|k| self.l[f][(i, k)] * yf[k]).sum();
                yf[i] = (yf[i] - s) / self.l[f][(i, i)];
            }
        }
        // Backward: L_fᵀ x_f = y_f − B_{f+1}ᵀ x_{f+1}.
        for f in (f0..f1).rev() {
            let mut v: Vec<f64> = self.y[f * m..(f + 1) * m].to_vec();
            if f + 1 < f1 {
                for i in 0..m {
                    let s: f64 = (0..m)
                        .map(|k| self.b[f + 1][(k, i)] * x[(f + 1) * m + k])
                        .sum();
                    v[i] -= s;
                }
            }
            for i in (0..m).rev() {
                let s: f64 = (i + 1..m).map(|k| self.l[f][(k, i)] * x[f * m + k]).sum();
                x[f * m + i] = (v[i] - s) / self.l[f][(i, i)];
            }
        }
    }
}

/// The block Gauss–Seidel of Escalante et al. 2023, §4: per layer (interface) j, a tridiagonal solve over
/// the faces with the other interfaces frozen; l2 stopping test on the increments.
fn gauss_seidel<R: PressureRows<Row = StencilRow>>(
    rows: &R,
    m: usize,
    x: &mut [f64],
    tol: f64,
) -> usize {
    let active = rows.active();
    let (f0, f1) = (active.start / m, active.end / m);
    let nf = f1 - f0;
    let (mut lo, mut di, mut up, mut rhs, mut sol, mut scratch) = (
        vec![0.0; nf],
        vec![0.0; nf],
        vec![0.0; nf],
        vec![0.0; nf],
        vec![0.0; nf],
        vec![0.0; nf],
    );
    let stored: Vec<StencilRow> = active.clone().map(|k| rows.row(k)).collect();
    x.fill(0.0);
    for it in 1..100_000 {
        let mut err = 0.0;
        for j in 0..m {
            for f in f0..f1 {
                let row = &stored[(f - f0) * m + j];
                let k = f * m + j;
                let mut r = row.rhs;
                for df in 0..3 {
                    for dj in [0, 2] {
                        let c = (k + df * m + dj) as isize - (m + 1) as isize;
                        if row.coef[df][dj] != 0.0 {
                            r -= row.coef[df][dj] * x[c as usize];
                        }
                    }
                }
                let i = f - f0;
                (lo[i], di[i], up[i], rhs[i]) = (
                    if f > f0 { row.coef[0][1] } else { 0.0 },
                    row.coef[1][1],
                    if f + 1 < f1 { row.coef[2][1] } else { 0.0 },
                    r,
                );
            }
            thomas(&lo, &di, &up, &rhs, &mut sol, &mut scratch);
            for (i, &s) in sol.iter().enumerate() {
                let k = (f0 + i) * m + j;
                err += (x[k] - s).powi(2);
                x[k] = s;
            }
        }
        if err.sqrt() < tol {
            return it;
        }
    }
    usize::MAX
}

fn main() {
    let quick = std::env::args().any(|a| a == "--quick");
    let reps = if quick { 3 } else { 20 };
    println!("pressure solve of the multilayer NH model, best of {reps}");
    for (cells, layers) in [(640, 1), (640, 5), (640, 10), (640, 20), (1600, 32)] {
        let (mesh, state) = collapse_state(cells, layers);
        let mut op = MultilayerOperator::new(&mesh, &state.l);
        op.update(&mesh, &state);
        let n = (cells + 1) * layers;
        let mut x = vec![0.0; n];
        let mut banded = BandedCholesky::new(layers, cells + 1);
        let (t_band, r_band) = best(reps, || {
            banded.solve_rows(&op.rows(&state), &mut x);
            relative_residual(&op.rows(&state), layers, &x)
        });
        // Time without the residual check.
        let (t_band, _) = best(reps, || {
            banded.solve_rows(&op.rows(&state), &mut x);
            x[0]
        })
        .min_by_time(t_band);
        let mut block = BlockCholesky::new(layers, cells + 1);
        let mut xb = vec![0.0; n];
        let (t_block, _) = best(reps, || {
            block.solve(&op.rows(&state), &mut xb);
            xb[0]
        });
        let r_block = relative_residual(&op.rows(&state), layers, &xb);
        let diff = x
            .iter()
            .zip(&xb)
            .fold(0.0f64, |a, (p, q)| a.max((p - q).abs()))
            / x.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        print!(
            "{cells:5} cells × {layers:2} layers: banded {:8.3} ms (residual {r_band:.1e}), block-nalgebra {:8.3} ms (residual {r_block:.1e}, max diff {diff:.1e})",
            t_band * 1e3,
            t_block * 1e3
        );
        if layers <= 20 && cells <= 640 {
            let mut xg = vec![0.0; n];
            let mut its = 0;
            let (t_gs, _) = best(1, || {
                its = gauss_seidel(&op.rows(&state), layers, &mut xg, 1e-6);
                xg[0]
            });
            let r_gs = relative_residual(&op.rows(&state), layers, &xg);
            print!(
                ", block Gauss–Seidel {:8.1} ms ({its} sweeps, residual {r_gs:.1e})",
                t_gs * 1e3
            );
        }
        println!();
    }
}

trait MinByTime {
    fn min_by_time(self, t: f64) -> (f64, f64);
}

impl MinByTime for (f64, f64) {
    fn min_by_time(self, t: f64) -> (f64, f64) {
        (self.0.min(t), self.1)
    }
}
