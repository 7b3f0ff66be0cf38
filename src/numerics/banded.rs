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
//! [`BandedCholesky`] assembles the lower band (the operator writes it cell by cell,
//! [`PressureRows::assemble_band`]; other row sources row by row) and factorises it in
//! place right-looking: each pivot scales its column and subtracts the rank-one update
//! from the p rows below it, each a contiguous run of the row (an axpy: no reductions,
//! so the work pipelines; padded to whole 4-wide chunks and compiled for AVX2 when the
//! CPU has it, with the same operations in the same order, hence the same bits). The
//! forward substitution rides the factorisation sweep and the backward one is row
//! axpys. Storage is the band of L (n (p + 4) values), allocated once for the largest
//! system; a step allocates nothing.
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
    /// Column of the current pivot (p + 1 values).
    column: Vec<f64>,
    /// The CPU has AVX2 (x86-64): the factorisation uses the AVX2 build of the kernel.
    avx2: bool,
}

impl BandedCholesky {
    /// A solver for `block` unknowns per face, with storage for `faces` faces.
    pub fn new(block: usize, faces: usize) -> Self {
        let p = block + 1;
        BandedCholesky {
            block,
            band: vec![0.0; faces * block * (PAD + p + 1)],
            y: vec![0.0; faces * block],
            column: vec![0.0; PAD + block + 2],
            avx2: avx2(),
        }
    }

    pub fn block(&self) -> usize {
        self.block
    }

    /// Solves the active rows of `rows` into `x` (0 elsewhere). The matrix must be
    /// symmetric positive definite; only its lower triangle is read. A non-positive
    /// pivot (not SPD) leaves NaN in `x`, which the run loop reports.
    ///
    /// The lower band is assembled first (by [`PressureRows::assemble_band`] when the
    /// rows offer it, else row by row), then factorised in place right-looking: pivot
    /// k scales its column and subtracts its rank-one update from the p rows below,
    /// each a contiguous run of that row (an axpy, no reductions, so it pipelines and
    /// vectorises); the forward substitution rides the same sweep, and the backward
    /// one is row-oriented axpys too.
    pub fn solve_rows<R: PressureRows<Row = StencilRow>>(&mut self, rows: &R, x: &mut [f64]) {
        let m = self.block;
        assert!(m >= 1, "block size");
        let p = m + 1;
        let w = PAD + p + 1;
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
        self.column.resize(PAD + p + 1, 0.0);
        let (band, y) = (&mut self.band[..n * w], &mut self.y[..n]);
        if !rows.assemble_band(band, y, p, w) {
            for r in 0..n {
                let row = rows.row(s + r);
                let lr = &mut band[r * w..(r + 1) * w];
                lr.fill(0.0);
                let lr = &mut lr[PAD..];
                // (df = −1, dj) → column r − m + dj − 1 → q = dj; (0, −1) → q = p − 1.
                lr[..3].copy_from_slice(&row.coef[0]);
                // (For N ≤ 2 two stencil entries share a column, of which one is 0.)
                lr[p - 1] += row.coef[1][0];
                lr[p] += row.coef[1][1];
                y[r] = row.rhs;
            }
        }
        // Columns before the active start (rows r < p) are 0.
        for r in 0..p.min(n) {
            band[r * w..r * w + PAD + (p - r)].fill(0.0);
        }
        let col = &mut self.column[..PAD + p + 1];
        col.fill(0.0);
        let xs = &mut x[active.clone()];
        #[cfg(target_arch = "x86_64")]
        if self.avx2 {
            // SAFETY: the CPU supports AVX2 (checked in `new`).
            unsafe { factor_solve_avx2(band, y, col, xs, p) };
            return;
        }
        factor_solve(band, y, col, xs, p);
    }
}

/// Zeros stored before each row's band (and before the pivot column), so that every
/// update is a whole number of 4-wide chunks: a chunk reaching left of the band
/// multiplies a zero of the column (a − c·0 = a).
const PAD: usize = 3;

/// In-place Cholesky factorisation of the lower band `band` (n rows of PAD + p + 1:
/// PAD zeros, then the band, the diagonal last), forward substitution of `y` in the
/// same sweep, and backward substitution into `xs` ([`BandedCholesky::solve_rows`]).
/// `col` (PAD + p + 1 values, the first PAD zero) holds the pivot's column.
#[inline(always)]
fn factor_solve(band: &mut [f64], y: &mut [f64], col: &mut [f64], xs: &mut [f64], p: usize) {
    let n = y.len();
    let w = PAD + p + 1;
    let d0 = PAD + p; // offset of the diagonal in a row
    assert!(band.len() >= n * w && col.len() > PAD + p);
    let (bp, cp) = (band.as_mut_ptr(), col.as_mut_ptr());
    for k in 0..n {
        let below = p.min(n - 1 - k);
        // SAFETY: every index below is < n·w in `band` (rows k..=k + below < n, offsets
        // < w) and < PAD + p + 1 in `col` (checked above); `band` and `col` are distinct
        // slices. The loops are the same as with indexing, without the bounds checks
        // that kept them from pipelining.
        unsafe {
            let diag = bp.add(k * w + d0);
            let d = (*diag).sqrt();
            *diag = d;
            let inv = 1.0 / d;
            let yk = y[k] * inv;
            y[k] = yk;
            // Column k of L: L[k + i][k] sits in row k + i at offset d0 − i; col[PAD + i].
            for i in 1..=below {
                let e = bp.add((k + i) * w + d0 - i);
                let v = *e * inv;
                *e = v;
                *cp.add(PAD + i) = v;
                *y.get_unchecked_mut(k + i) -= v * yk;
            }
            // Row k + i loses col_i col_j for the columns k + j, j = 1..=i (offsets
            // d0 − i + 1 ..= d0), extended to the left to a multiple of 4 entries (the
            // column's zeros before j = 1 make the extension a no-op).
            for i in 1..=below {
                let ci = *cp.add(PAD + i);
                let len = (i + 3) & !3;
                let row = std::slice::from_raw_parts_mut(bp.add((k + i) * w + d0 + 1 - len), len);
                let c = std::slice::from_raw_parts(cp.add(PAD + i + 1 - len), len);
                axpy_chunks(row, c, ci);
            }
        }
    }
    // Back substitution with Lᵀ, by rows of L: x_r = y_r / L[r][r], then y_c −=
    // L[r][c] x_r for the columns c of row r.
    for r in (0..n).rev() {
        let xr = y[r] / band[r * w + d0];
        xs[r] = xr;
        let q0 = p.saturating_sub(r);
        let lr = &band[r * w + PAD + q0..r * w + d0];
        let yc = &mut y[r + q0 - p..r];
        for (yc, &l) in yc.iter_mut().zip(lr) {
            *yc -= l * xr;
        }
    }
}

/// row −= ci · c, both of a length that is a multiple of 4, as 4-wide chunks (two
/// slices, so the compiler knows they do not overlap).
#[inline(always)]
fn axpy_chunks(row: &mut [f64], c: &[f64], ci: f64) {
    let (r4, _) = row.as_chunks_mut::<4>();
    let (c4, _) = c.as_chunks::<4>();
    for (a, b) in r4.iter_mut().zip(c4) {
        a[0] -= ci * b[0];
        a[1] -= ci * b[1];
        a[2] -= ci * b[2];
        a[3] -= ci * b[3];
    }
}

/// [`factor_solve`] compiled for AVX2 (4 doubles per vector instead of SSE2's 2). The
/// same operations in the same order (no fused multiply-add: Rust does not contract
/// a·b + c), so the results are bit-for-bit those of the portable version.
///
/// # Safety
/// The CPU must support AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn factor_solve_avx2(
    band: &mut [f64],
    y: &mut [f64],
    col: &mut [f64],
    xs: &mut [f64],
    p: usize,
) {
    factor_solve(band, y, col, xs, p)
}

/// Whether the AVX2 kernel can run here.
fn avx2() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        std::arch::is_x86_feature_detected!("avx2")
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        false
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

    /// The AVX2 build of the kernel gives the bits of the portable one.
    #[test]
    fn avx2_kernel_gives_the_same_bits() {
        let (sys, _) = spd_system(30, 20, 11);
        let n = 600;
        let mut plain = BandedCholesky::new(20, 30);
        plain.avx2 = false;
        let mut fast = BandedCholesky::new(20, 30);
        let (mut a, mut b) = (vec![0.0; n], vec![0.0; n]);
        plain.solve_rows(&sys, &mut a);
        fast.solve_rows(&sys, &mut b);
        println!("AVX2 available: {}", fast.avx2);
        assert!(a.iter().zip(&b).all(|(x, y)| x.to_bits() == y.to_bits()));
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
