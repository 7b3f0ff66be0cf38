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
//! [`BandedCholesky`] assembles the lower band by columns (the operator writes it cell
//! by cell, [`PressureRows::assemble_band`]; other row sources row by row) and
//! factorises it in place, right-looking by panels of 4 columns (`factor_to`), a
//! panel as soon as the assembly has finished the columns it touches (so the band is
//! factorised while it is in cache, not in a second pass through it):
//! each column of a panel takes its earlier columns' updates and is scaled, then
//! each of the next p columns takes the panel's rank-4 update in one pass. Every
//! update is an axpy on a contiguous run of a column (no reductions, so the work
//! pipelines), padded to whole 4-wide chunks, written with AVX intrinsics in the
//! AVX2 build (chosen at run time) and as scalar lanes in the portable one; every
//! entry sees the operations of the one-pivot-at-a-time algorithm in the same
//! order, so both builds, and the unblocked algorithm, give the same bits. The
//! forward substitution rides the factorisation sweep; the backward one goes by
//! columns in the order of the row-oriented version. Storage is the band of L
//! (n (p + 8) values), allocated once for the largest system; a step allocates
//! nothing.
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

/// Banded Cholesky factorisation and solve of an SPD stencil system (module
/// documentation).
#[derive(Debug, Clone, Default)]
pub struct BandedCholesky {
    block: usize,
    /// Band of L by columns: column c (relative to the active start) holds
    /// L[c ..= c + p][c] at `band[c w ..]`, the diagonal first, then PADR zeros
    /// (w = p + 1 + PADR, [`band_index`]).
    band: Vec<f64>,
    /// Forward-substituted right-hand side.
    y: Vec<f64>,
    /// The CPU has AVX2 (x86-64): the factorisation uses the AVX2 build of the kernel.
    avx2: bool,
}

impl BandedCholesky {
    /// A solver for `block` unknowns per face, with storage for `faces` faces.
    pub fn new(block: usize, faces: usize) -> Self {
        let p = block + 1;
        BandedCholesky {
            block,
            band: vec![0.0; faces * block * (p + 1 + PADR)],
            y: vec![0.0; faces * block],
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
    /// The lower band is assembled by columns first (by [`PressureRows::assemble_band`]
    /// when the rows offer it, else row by row with [`assemble_rows`]), then
    /// factorised in place by panels of 4 columns (`factor_to`) as the columns become
    /// final, then back-substituted.
    pub fn solve_rows<R: PressureRows<Row = StencilRow>>(&mut self, rows: &R, x: &mut [f64]) {
        let m = self.block;
        assert!(m >= 1, "block size");
        let p = m + 1;
        let w = p + 1 + PADR;
        let active = rows.active();
        x[..active.start].fill(0.0);
        x[active.end..].fill(0.0);
        let n = active.len();
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
        let avx2 = self.avx2;
        // Panels are factorised as soon as the columns they touch are final (the
        // assembly reports them), while those columns are still in cache.
        let mut k = 0; // first column not factorised yet
        let mut ready = |band: &mut [f64], y: &mut [f64], c: usize| {
            #[cfg(target_arch = "x86_64")]
            if avx2 {
                // SAFETY: the CPU supports AVX2 (checked in `new`).
                unsafe { factor_to_avx2(band, y, p, &mut k, c) };
                return;
            }
            factor_to::<false>(band, y, p, &mut k, c);
        };
        if !rows.assemble_band(band, y, p, w, &mut ready) {
            assemble_rows(rows, band, y, p, w);
            ready(band, y, n);
        }
        debug_assert_eq!(k, n, "the assembly reported every column");
        back_substitute(band, y, &mut x[active.clone()], p);
    }
}

/// Where entry (r, c) of the lower band (0 ≤ r − c ≤ p) is stored: column c from
/// `c · stride`, the diagonal first ([`PressureRows::assemble_band`]).
#[inline(always)]
pub fn band_index(r: usize, c: usize, stride: usize) -> usize {
    c * stride + (r - c)
}

/// The lower band of the active rows of `rows`, formed row by row (the layout of
/// [`PressureRows::assemble_band`]; entries of rows past the end are 0).
pub fn assemble_rows<R: PressureRows<Row = StencilRow>>(
    rows: &R,
    band: &mut [f64],
    rhs: &mut [f64],
    p: usize,
    stride: usize,
) {
    let active = rows.active();
    let (s, n) = (active.start, active.len());
    band[..n * stride].fill(0.0);
    for r in 0..n {
        let row = rows.row(s + r);
        // (df = −1, dj) → column r − p + dj; (0, −1) → column r − 1; (0, 0) → r.
        // (For N ≤ 2 two stencil entries share a column, of which one is 0.) Columns
        // before the active start are not part of the system.
        for (dj, &v) in row.coef[0].iter().enumerate() {
            if r + dj >= p {
                band[band_index(r, r + dj - p, stride)] += v;
            }
        }
        if r >= 1 {
            band[band_index(r, r - 1, stride)] += row.coef[1][0];
        }
        band[band_index(r, r, stride)] += row.coef[1][1];
        rhs[r] = row.rhs;
    }
}

/// Zeros stored after each column's band, so that every update is a whole number of
/// 4-wide chunks: a chunk reaching past the band multiplies zeros of the source
/// column (a − b·0 = a) and writes the target's zeros back.
const PADR: usize = 7;

/// Columns per panel of the blocked factorisation ([`factor_to`]).
const PANEL: usize = 4;

/// In-place Cholesky factorisation of the lower band `band` (n columns of p + 1 +
/// PADR: the band, the diagonal first, then zeros) and forward substitution of `y`
/// in the same sweep, from column `*k` on, as far as the columns 0 .. `ready` allow
/// (a panel and its rank-4 update touch columns up to k + 3 + p); `*k` becomes the
/// first column not factorised ([`BandedCholesky::solve_rows`]).
///
/// Blocked right-looking by panels of [`PANEL`] columns, each step an axpy on a
/// contiguous run of a column (no reductions, so the work pipelines and vectorises;
/// the runs are padded to whole 4-wide chunks): each column of the panel receives
/// the updates of the panel's earlier columns and is scaled; the next p columns then
/// receive the panel's rank-4 update in one pass each (each chunk loaded and stored
/// once, losing the four products in pivot order). Every entry of L undergoes the
/// operations of the one-pivot-at-a-time right-looking algorithm in the same order,
/// so the blocking does not change the factor, and the substitutions keep their
/// order too: the results are those of the unblocked version, bit for bit. (Each
/// entry is final before its first update, so when the factorisation runs does not
/// change it either.)
#[inline(always)]
fn factor_to<const AVX: bool>(
    band: &mut [f64],
    y: &mut [f64],
    p: usize,
    k: &mut usize,
    ready: usize,
) {
    let n = y.len();
    let w = p + 1 + PADR;
    let full = (p + 1 + 3) & !3; // d = 0..=p in whole chunks
    assert!(band.len() >= n * w && full + 3 <= w && ready <= n);
    let bp = band.as_mut_ptr();
    let mut k0 = *k;
    while k0 < n && (k0 + PANEL + p).min(n) <= ready {
        let b = PANEL.min(n - k0);
        // SAFETY (this block): columns k0 .. k0 + b < n, each read and written at
        // offsets < w (`full` + 3 ≤ w, asserted), so every access is < n·w ≤
        // band.len(); within a column update the source column differs from the
        // target, and every chunk is loaded before it is stored.
        unsafe {
            for t in 0..b {
                let c = bp.add((k0 + t) * w);
                // Updates of the panel's earlier columns: L[k+t+d][k+s] L[k+t][k+s].
                for s in 0..t {
                    let src = bp.add((k0 + s) * w + (t - s));
                    axpy_chunks::<AVX>(c, src, *src, full / 4);
                }
                let d = (*c).sqrt();
                *c = d;
                let inv = 1.0 / d;
                // Rows 1 ..= p, in whole chunks (past p: PADR zeros, 0·inv = 0).
                scale_chunks::<AVX>(c.add(1), inv, p.div_ceil(4));
                let yk = y[k0 + t] * inv;
                y[k0 + t] = yk;
                let len = p.min(n - 1 - (k0 + t));
                let yp = y.as_mut_ptr().add(k0 + t + 1);
                axpy_chunks::<AVX>(yp, c.add(1), yk, len / 4);
                for q in len / 4 * 4..len {
                    *yp.add(q) -= *c.add(1 + q) * yk;
                }
            }
            if b < PANEL {
                k0 = n;
                break;
            }
            // Rank-4 update of the columns j = k + 4 + m (m = 0..p, within the
            // system): rows j ..= k + 3 + p lose Σ_t L[i][k+t] L[j][k+t], the run
            // rounded up to whole chunks (rows past k + 3 + p read the PADR zeros).
            let cols = (k0 + PANEL + p).min(n) - (k0 + PANEL);
            rank4_update::<AVX>(bp.add(k0 * w), w, p, cols);
        }
        k0 += PANEL;
    }
    *k = k0;
}

/// Back substitution with Lᵀ by columns: x_c = (y_c − L[c+p][c] x_{c+p} − … −
/// L[c+1][c] x_{c+1}) / L[c][c], subtracted in that order (r descending: the order
/// in which the row-oriented version, y_c −= L[r][c] x_r for r = n − 1 … 0, reaches
/// y_c, so the same bits). A column is contiguous, and only its last term waits for
/// the previous unknown.
fn back_substitute(band: &[f64], y: &[f64], xs: &mut [f64], p: usize) {
    let n = y.len();
    let w = p + 1 + PADR;
    assert!(band.len() >= n * w && xs.len() == n);
    for c in (0..n).rev() {
        let len = p.min(n - 1 - c);
        let col = &band[c * w + 1..c * w + 1 + len];
        let mut s = y[c];
        for (&l, &x) in col.iter().zip(&xs[c + 1..c + 1 + len]).rev() {
            s -= l * x;
        }
        xs[c] = s / band[c * w];
    }
}

/// The rank-4 update of a panel (columns 0..4 from `panel`, stride `w`) applied to
/// the `cols` columns after it: column 4 + m, rows 4 + m ..= 3 + p, loses Σ_t
/// L[i][t] L[4+m][t], its run rounded up to whole chunks (rows past 3 + p read the
/// PADR zeros of the panel's columns).
///
/// # Safety
/// `panel` valid for (4 + cols) w values, w ≥ p + 8.
#[inline(always)]
unsafe fn rank4_update<const AVX: bool>(panel: *mut f64, w: usize, p: usize, cols: usize) {
    let src = [
        panel.add(4) as *const f64,
        panel.add(w + 3) as *const f64,
        panel.add(2 * w + 2) as *const f64,
        panel.add(3 * w + 1) as *const f64,
    ];
    for m in 0..cols {
        let target = panel.add((PANEL + m) * w);
        let c = [src[0].add(m), src[1].add(m), src[2].add(m), src[3].add(m)];
        axpy4_chunks::<AVX>(target, c, [*c[0], *c[1], *c[2], *c[3]], (p - m).div_ceil(4));
    }
}

/// a −= f · c over `chunks` 4-wide chunks. With `AVX` the chunks are AVX vectors
/// (written with intrinsics, so the compiler adds no runtime alias checks or
/// unrolling around these short loops); the same operations, so the same bits.
///
/// # Safety
/// `a` and `c` valid for 4 `chunks` values; a chunk of `a` may overlap only the
/// same chunk of `c`'s run if at all (each is loaded before it is stored). With
/// `AVX`, the CPU must support AVX (only called from [`factor_to_avx2`]).
#[inline(always)]
unsafe fn axpy_chunks<const AVX: bool>(a: *mut f64, c: *const f64, f: f64, chunks: usize) {
    #[cfg(target_arch = "x86_64")]
    if AVX {
        use std::arch::x86_64::{_mm256_loadu_pd, _mm256_mul_pd, _mm256_set1_pd};
        use std::arch::x86_64::{_mm256_storeu_pd, _mm256_sub_pd};
        let fv = _mm256_set1_pd(f);
        for m in 0..chunks {
            let (pa, pc) = (a.add(4 * m), c.add(4 * m));
            let x = _mm256_loadu_pd(pa);
            _mm256_storeu_pd(pa, _mm256_sub_pd(x, _mm256_mul_pd(fv, _mm256_loadu_pd(pc))));
        }
        return;
    }
    for m in 0..chunks {
        let (pa, pc) = (
            a.add(4 * m) as *mut [f64; 4],
            c.add(4 * m) as *const [f64; 4],
        );
        let (x, y) = (*pa, *pc);
        *pa = [
            x[0] - f * y[0],
            x[1] - f * y[1],
            x[2] - f * y[2],
            x[3] - f * y[3],
        ];
    }
}

/// a *= f over `chunks` 4-wide chunks (AVX vectors with `AVX`).
///
/// # Safety
/// `a` valid for 4 `chunks` values; with `AVX`, the CPU must support AVX.
#[inline(always)]
unsafe fn scale_chunks<const AVX: bool>(a: *mut f64, f: f64, chunks: usize) {
    #[cfg(target_arch = "x86_64")]
    if AVX {
        use std::arch::x86_64::_mm256_storeu_pd;
        use std::arch::x86_64::{_mm256_loadu_pd, _mm256_mul_pd, _mm256_set1_pd};
        let fv = _mm256_set1_pd(f);
        for m in 0..chunks {
            let pa = a.add(4 * m);
            _mm256_storeu_pd(pa, _mm256_mul_pd(_mm256_loadu_pd(pa), fv));
        }
        return;
    }
    for m in 0..chunks {
        let pa = a.add(4 * m) as *mut [f64; 4];
        let x = *pa;
        *pa = [x[0] * f, x[1] * f, x[2] * f, x[3] * f];
    }
}

/// a −= b[0] c[0]; −= b[1] c[1]; … (in that order, element by element) over
/// `chunks` 4-wide chunks (AVX vectors with `AVX`, as [`axpy_chunks`]).
///
/// # Safety
/// As [`axpy_chunks`], for each of the four sources.
#[inline(always)]
unsafe fn axpy4_chunks<const AVX: bool>(
    a: *mut f64,
    c: [*const f64; 4],
    b: [f64; 4],
    chunks: usize,
) {
    #[cfg(target_arch = "x86_64")]
    if AVX {
        use std::arch::x86_64::{_mm256_loadu_pd, _mm256_mul_pd, _mm256_set1_pd};
        use std::arch::x86_64::{_mm256_storeu_pd, _mm256_sub_pd};
        let bv = [
            _mm256_set1_pd(b[0]),
            _mm256_set1_pd(b[1]),
            _mm256_set1_pd(b[2]),
            _mm256_set1_pd(b[3]),
        ];
        for m in 0..chunks {
            let pa = a.add(4 * m);
            let mut x = _mm256_loadu_pd(pa);
            for t in 0..4 {
                x = _mm256_sub_pd(x, _mm256_mul_pd(bv[t], _mm256_loadu_pd(c[t].add(4 * m))));
            }
            _mm256_storeu_pd(pa, x);
        }
        return;
    }
    for m in 0..chunks {
        let pa = a.add(4 * m) as *mut [f64; 4];
        let x = *pa;
        let y0 = *(c[0].add(4 * m) as *const [f64; 4]);
        let y1 = *(c[1].add(4 * m) as *const [f64; 4]);
        let y2 = *(c[2].add(4 * m) as *const [f64; 4]);
        let y3 = *(c[3].add(4 * m) as *const [f64; 4]);
        let lane = |e: usize| x[e] - b[0] * y0[e] - b[1] * y1[e] - b[2] * y2[e] - b[3] * y3[e];
        *pa = [lane(0), lane(1), lane(2), lane(3)];
    }
}

/// [`factor_to`] compiled for AVX2 (4 doubles per vector instead of SSE2's 2). The
/// same operations in the same order (no fused multiply-add: Rust does not contract
/// a·b + c), so the results are bit-for-bit those of the portable version.
///
/// # Safety
/// The CPU must support AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn factor_to_avx2(band: &mut [f64], y: &mut [f64], p: usize, k: &mut usize, ready: usize) {
    factor_to::<true>(band, y, p, k, ready)
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
