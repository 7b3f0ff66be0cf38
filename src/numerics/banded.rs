//! Exact solver for the pressure system of the N-layer non-hydrostatic model
//! (seed 003 eq. 31–32, Appendix A), in the symmetric positive definite form built by
//! [`super::projection::multilayer`].
//!
//! Unknowns are ordered face by face, N interfaces per face (`k = f·N + j`, the
//! layout of `NonHydrostatic::p`). The unknown of face f at interface j is coupled only
//! to faces f − 1, f, f + 1 and interfaces j − 1, j, j + 1 (a layer touches two
//! interfaces, a cell two faces), so a row is a 3×3 stencil ([`StencilRow`]) and the
//! matrix is banded with half-bandwidth p = N + 1. Its Cholesky factor fills the band
//! and nothing outside it, so the factorisation costs ≈ n p²/2 multiply-adds for
//! n = (nx + 1) N unknowns: O(nx N³) with no iteration, against seed 003's block
//! Gauss–Seidel with a tolerance.
//!
//! [`BandedCholesky`] factorises row by row ("up-looking"): row k of L only needs the
//! rows above it in the band, so each row is formed by the operator
//! ([`PressureRows::row`]) just before it is eliminated, and the forward substitution
//! runs in the same sweep. Storage is the band of L (n (p + 1) values), allocated once
//! for the largest system; a step allocates nothing.
//!
//! Measured alternatives (benches/nh_multilayer_solver.rs, numbers in
//! docs/performance.md): a block-Thomas (block Cholesky) elimination with dense N×N
//! blocks from nalgebra does the same elimination but fills the whole off-diagonal
//! blocks (N² instead of ≈ N²/2 values) and pays for small-matrix calls.

use std::ops::Range;

use super::linalg::PressureRows;

/// One row of a system whose unknowns are ordered face-major with `block` unknowns per
/// face: `coef[1 + df][1 + dj]` multiplies the unknown (f + df, j + dj). Entries that
/// leave the face's column (j + dj < 0 or ≥ N) or the system must be 0.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StencilRow {
    pub coef: [[f64; 3]; 3],
    pub rhs: f64,
}

impl StencilRow {
    /// x_k = 0 (an unknown without a constraint: a dry face).
    pub const IDENTITY: StencilRow = StencilRow {
        coef: [[0.0; 3], [0.0, 1.0, 0.0], [0.0; 3]],
        rhs: 0.0,
    };
    pub const ZERO: StencilRow = StencilRow {
        coef: [[0.0; 3]; 3],
        rhs: 0.0,
    };
}

/// A x − b for stencil rows (x = 0 and identity rows outside the active range), e.g.
/// to check a solve. `r` covers all rows.
pub fn stencil_residual<R: PressureRows<Row = StencilRow>>(
    rows: &R,
    block: usize,
    x: &[f64],
    r: &mut [f64],
) {
    let active = rows.active();
    let n = x.len();
    for k in 0..n {
        if !active.contains(&k) {
            r[k] = x[k];
            continue;
        }
        let row = rows.row(k);
        let mut s = -row.rhs;
        for (df, line) in row.coef.iter().enumerate() {
            for (dj, &c) in line.iter().enumerate() {
                if c == 0.0 {
                    continue;
                }
                let col = (k + df * block + dj) as isize - (block + 1) as isize;
                if col >= 0 && (col as usize) < n {
                    s += c * x[col as usize];
                }
            }
        }
        r[k] = s;
    }
}

/// Up-looking banded Cholesky factorisation and solve of an SPD stencil system (module
/// documentation).
#[derive(Debug, Clone, Default)]
pub struct BandedCholesky {
    block: usize,
    /// Band of L: row r (relative to the active start) holds L[r][r − p ..= r] at
    /// `band[r (p + 1) ..]`, the diagonal last.
    band: Vec<f64>,
    /// Forward-substituted right-hand side.
    y: Vec<f64>,
}

impl BandedCholesky {
    /// A solver for `block` unknowns per face, with storage for `faces` faces.
    pub fn new(block: usize, faces: usize) -> Self {
        let p = block + 1;
        BandedCholesky {
            block,
            band: vec![0.0; faces * block * (p + 1)],
            y: vec![0.0; faces * block],
        }
    }

    pub fn block(&self) -> usize {
        self.block
    }

    /// Solves the active rows of `rows` into `x` (0 elsewhere). The matrix must be
    /// symmetric positive definite; only its lower triangle is read. A non-positive
    /// pivot (not SPD) leaves NaN in `x`, which the run loop reports.
    pub fn solve_rows<R: PressureRows<Row = StencilRow>>(&mut self, rows: &R, x: &mut [f64]) {
        let m = self.block;
        assert!(m >= 1, "block size");
        let p = m + 1;
        let w = p + 1;
        let active = rows.active();
        x[..active.start].fill(0.0);
        x[active.end..].fill(0.0);
        let (s, n) = (active.start, active.len());
        if n == 0 {
            return;
        }
        if self.band.len() < n * w {
            self.band.resize(n * w, 0.0);
        }
        if self.y.len() < n {
            self.y.resize(n, 0.0);
        }
        let (band, y) = (&mut self.band[..n * w], &mut self.y[..n]);
        for r in 0..n {
            let row = rows.row(s + r);
            // The lower part of row r in band order: entry q is column r − p + q.
            let (done, rest) = band.split_at_mut(r * w);
            let lr = &mut rest[..w];
            lr.fill(0.0);
            // (df = −1, dj) → column r − m + dj − 1 → q = dj; (0, −1) → q = p − 1.
            lr[..3].copy_from_slice(&row.coef[0]);
            // (For N ≤ 2 two stencil entries share a column, of which one is 0.)
            lr[p - 1] += row.coef[1][0];
            lr[p] += row.coef[1][1];
            let q0 = p.saturating_sub(r); // columns before the active start
            lr[..q0].fill(0.0);
            let mut yr = row.rhs;
            for q in q0..p {
                let j = r + q - p; // column
                let lj = &done[j * w..(j + 1) * w];
                // Σ L[r][c] L[j][c] over the columns c = r − p + q' (q' in q0..q) that
                // both rows hold; in row j column c sits at offset q' − q + p.
                let lo = q0;
                let first_in_j = lo + p - q;
                let dot: f64 = lr[lo..q]
                    .iter()
                    .zip(&lj[first_in_j..p])
                    .map(|(a, b)| a * b)
                    .sum();
                let v = (lr[q] - dot) / lj[p];
                lr[q] = v;
                yr -= v * y[j];
            }
            let sq: f64 = lr[q0..p].iter().map(|v| v * v).sum();
            let d = (lr[p] - sq).sqrt();
            lr[p] = d;
            y[r] = yr / d;
        }
        // Back substitution with Lᵀ: x_r = (y_r − Σ_{k = r+1}^{r+p} L[k][r] x_k) / L[r][r].
        let xs = &mut x[active.clone()];
        for r in (0..n).rev() {
            let mut v = y[r];
            for k in r + 1..(r + p + 1).min(n) {
                v -= band[k * w + (r + p - k)] * xs[k];
            }
            xs[r] = v / band[r * w + p];
        }
    }
}

/// Rows stored densely per stencil (for tests and benchmarks).
#[derive(Debug, Clone)]
pub struct StoredStencil {
    pub rows: Vec<StencilRow>,
    pub active: Range<usize>,
}

impl PressureRows for StoredStencil {
    type Row = StencilRow;
    fn active(&self) -> Range<usize> {
        self.active.clone()
    }
    fn row(&self, k: usize) -> StencilRow {
        self.rows[k]
    }
}

#[cfg(test)]
#[allow(clippy::needless_range_loop)] // index arithmetic mirrors the matrices
mod tests {
    use super::*;

    /// A random SPD stencil system: Tᵀ D T for a random local operator, so it has the
    /// structure of the pressure system (block 4, 9 faces).
    fn spd_system(faces: usize, m: usize, seed: u64) -> (StoredStencil, Vec<Vec<f64>>) {
        let n = faces * m;
        let mut state = seed;
        let mut rnd = || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((state >> 11) as f64) / ((1u64 << 53) as f64) - 0.5
        };
        // Each "cell" c couples faces c, c+1; each layer a couples interfaces a, a+1.
        let mut dense = vec![vec![0.0; n]; n];
        for c in 0..faces - 1 {
            for a in 0..m {
                for _comp in 0..2 {
                    let mut t = vec![0.0; n];
                    for f in [c, c + 1] {
                        for j in [a, a + 1] {
                            if j < m {
                                t[f * m + j] = rnd() + if j == a { 1.0 } else { 0.0 };
                            }
                        }
                    }
                    let wgt = 0.5 + rnd().abs();
                    for i in 0..n {
                        for k in 0..n {
                            dense[i][k] += wgt * t[i] * t[k];
                        }
                    }
                }
            }
        }
        let mut rows = Vec::with_capacity(n);
        for k in 0..n {
            let mut row = StencilRow::ZERO;
            let (f, j) = ((k / m) as isize, (k % m) as isize);
            for df in -1..=1isize {
                for dj in -1..=1isize {
                    let (g, i) = (f + df, j + dj);
                    if g < 0 || g >= faces as isize || i < 0 || i >= m as isize {
                        continue;
                    }
                    row.coef[(df + 1) as usize][(dj + 1) as usize] =
                        dense[k][(g as usize) * m + i as usize];
                }
            }
            row.rhs = rnd();
            rows.push(row);
        }
        (StoredStencil { rows, active: 0..n }, dense)
    }

    #[test]
    fn banded_cholesky_solves_an_spd_stencil_system() {
        for m in [1, 2, 4, 7] {
            let faces = 9;
            let (sys, dense) = spd_system(faces, m, 7 + m as u64);
            let n = faces * m;
            // The stencil holds the whole matrix (nothing outside the 3×3 pattern).
            let mut x = vec![0.0; n];
            let mut solver = BandedCholesky::new(m, faces);
            solver.solve_rows(&sys, &mut x);
            let mut r = vec![0.0; n];
            stencil_residual(&sys, m, &x, &mut r);
            let rmax = r.iter().fold(0.0f64, |a, v| a.max(v.abs()));
            let bmax = sys.rows.iter().fold(0.0f64, |a, v| a.max(v.rhs.abs()));
            assert!(rmax <= 1e-12 * bmax, "m = {m}: residual {rmax:e}");
            // Also against the dense matrix.
            for k in 0..n {
                let ax: f64 = (0..n).map(|i| dense[k][i] * x[i]).sum();
                assert!((ax - sys.rows[k].rhs).abs() <= 1e-12 * bmax);
            }
        }
    }

    #[test]
    fn active_range_and_reuse() {
        let (mut sys, _) = spd_system(8, 3, 3);
        let n = 24;
        let mut solver = BandedCholesky::new(3, 8);
        // A sub-range: rows outside are identity, x = 0 there.
        sys.active = 6..18;
        let mut x = vec![5.0; n];
        solver.solve_rows(&sys, &mut x);
        assert!(x[..6].iter().chain(&x[18..]).all(|&v| v == 0.0));
        let mut r = vec![0.0; n];
        stencil_residual(&sys, 3, &x, &mut r);
        assert!(r.iter().all(|v| v.abs() < 1e-12), "{r:?}");
        // The same solver again on the full range gives the same as a fresh one.
        sys.active = 0..n;
        let (mut a, mut b) = (vec![0.0; n], vec![0.0; n]);
        solver.solve_rows(&sys, &mut a);
        BandedCholesky::new(3, 8).solve_rows(&sys, &mut b);
        assert_eq!(a, b);
    }

    #[test]
    fn a_matrix_that_is_not_positive_definite_gives_nan() {
        let (mut sys, _) = spd_system(4, 2, 1);
        sys.rows[3].coef[1][1] = -100.0;
        let mut x = vec![0.0; 8];
        BandedCholesky::new(2, 4).solve_rows(&sys, &mut x);
        assert!(x.iter().any(|v| v.is_nan()));
    }
}
