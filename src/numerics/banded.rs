//! Exact solver for the pressure system of the N-layer non-hydrostatic model
//! (Escalante et al. 2023, eq. 31–32, Appendix A), in the symmetric positive definite form built by
//! [`super::projection::multilayer`].
//!
//! Unknowns are ordered face by face, N interfaces per face (`k = f·N + j`, the
//! layout of `NonHydrostatic::p`). The unknown of face f at interface j is coupled only
//! to faces f − 1, f, f + 1 and interfaces j − 1, j, j + 1 (a layer touches two
//! interfaces, a cell two faces), so a row is a 3×3 stencil ([`StencilRow`]) and the
//! matrix is banded with half-bandwidth p = N + 1. Its Cholesky factor fills the band
//! and nothing outside it, so the factorisation costs ≈ n p²/2 multiply-adds for
//! n = (nx + 1) N unknowns: O(nx N³) with no iteration, against Escalante et al. 2023's block
//! Gauss–Seidel with a tolerance.
//!
//! [`BandedCholesky`] assembles the lower band by columns (the operator writes it face
//! by face, [`PressureRows::assemble_band`]; other row sources row by row) and
//! factorises it in place, left-looking column by column (`factor_to`), each column
//! as soon as the assembly has finished it (so the band is factorised while it is in
//! cache, not in a second pass through it). Column j is loaded into ⌈(p + 1)/4⌉ AVX
//! registers, takes the updates of its p pivots k = j − p … j − 1 in that order (a
//! broadcast of `L[j][k]` times a run of column k, on the chunks that column reaches),
//! then the square root, 1/d and the scaling, and is stored once: about 2 vector
//! instructions per 4 multiply-adds, every address a constant offset (the column
//! stride depends only on the chunk count). The forward substitution rides the same
//! pivots (`y_j −= L[j][k] y_k`). Every entry of L and y gets the real products of the
//! one-pivot-at-a-time algorithm in the same order, plus some exact zeros that cannot
//! change a value (no entry is ever −0; `factor_to` gives the argument), so the
//! factor is bit for bit that of the textbook algorithm (and of the earlier
//! right-looking panel kernel); the tests compare the bits at N = 1 … 48 with dry
//! faces. The backward substitution goes by columns in the order of the
//! row-oriented version, the products four at a time (for p ≤ 3, one or two layers
//! per face, the last p unknowns carried in registers instead). The kernels are written once
//! over 4-lane vectors, as AVX intrinsics in the AVX2 build (chosen at run time)
//! and as plain arrays in the portable one: the same IEEE operations (no fused
//! multiply-add), so the same bits. Storage is the band of L (n (p + 4 … p + 7)
//! values), allocated once for the largest system; a step allocates nothing.
//!
//! Measured alternatives (benches/nh_multilayer_solver.rs, numbers in
//! docs/performance.md): a block-Thomas (block Cholesky) elimination with dense N×N
//! blocks from nalgebra does the same elimination but fills the whole off-diagonal
//! blocks (N² instead of ≈ N²/2 values) and pays for small-matrix calls. Against
//! the earlier right-looking kernel by panels of 4 columns (rank-4 updates of the
//! next p columns, 7 zeros per column), at 20 layers (callgrind, per NH step of
//! `examples/nh_step_cost.rs`): factorisation with the forward substitution 8.13 →
//! 2.94 M instructions (≈ 1.0 per multiply-add), backward substitution 1.50 → 0.89 M.
//! Tried and dropped: column j − 1 carried in registers for the last pivot (shuffles
//! instead of reloading it; slower), the forward substitution four unknowns at a
//! time after the columns (−0.24 M instructions, +2 % CPU time).

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
    /// L[c ..= c + p][c] at `band[c w ..]`, the diagonal first, then zeros
    /// (w = stride(p), [`band_index`]).
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
            band: vec![0.0; faces * block * stride(p)],
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
        let w = stride(p);
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
        // Columns are factorised as soon as they are final (the assembly reports
        // them), while they are still in cache.
        let mut k = 0; // first column not factorised yet
        let mut ready = |band: &mut [f64], y: &mut [f64], c: usize| {
            #[cfg(target_arch = "x86_64")]
            if avx2 {
                // SAFETY: the CPU supports AVX2 (checked in `new`).
                unsafe { factor_to_avx2(band, y, p, &mut k, c) };
                return;
            }
            factor_to::<[f64; 4]>(band, y, p, &mut k, c);
        };
        if !rows.assemble_band(band, y, p, w, &mut ready) {
            assemble_rows(rows, band, y, p, w);
            ready(band, y, n);
        }
        debug_assert_eq!(k, n, "the assembly reported every column");
        let xs = &mut x[active.clone()];
        #[cfg(target_arch = "x86_64")]
        if avx2 {
            // SAFETY: the CPU supports AVX2 (checked in `new`).
            unsafe { back_substitute_avx2(band, y, xs, p) };
            return;
        }
        back_substitute::<[f64; 4]>(band, y, xs, p);
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

/// Values stored per column of the band for half-bandwidth p: the p + 1 entries, the
/// diagonal first, then zeros, w = 4 CH + 3 for CH = ⌊(p + 4)/4⌋ chunks (p + 4 ≤ w
/// ≤ p + 7). A column is updated and stored in whole 4-wide chunks, rows 0 ..= p + 3
/// of it at most, and a source run read in whole chunks reaches row p + 3 of its
/// column at most; the zeros read as sources only subtract exact zeros
/// ([`factor_to`]). Fixing w by CH (not p) makes every offset of the register kernels
/// a constant ([`column_in_registers`]).
fn stride(p: usize) -> usize {
    4 * ((p + 4) / 4) + 3
}

/// Largest number of 4-wide chunks per column (p + 1 ≤ 4 · MAXCH: N ≤ 47) for which
/// a column is kept in registers ([`column_in_registers`]); wider bands take the
/// same operations on the column in memory ([`column_in_memory`]).
const MAXCH: usize = 12;

/// Four lanes of f64, as one AVX vector or as a plain array (the portable build): the
/// same IEEE operations lane by lane, so the same bits.
trait Lanes: Copy {
    /// # Safety
    /// `p` valid for 4 reads (with AVX lanes, the CPU must support AVX; likewise below).
    unsafe fn load(p: *const f64) -> Self;
    /// # Safety
    /// `p` valid for 4 writes.
    unsafe fn store(self, p: *mut f64);
    /// # Safety
    /// See [`Lanes::load`].
    unsafe fn splat(x: f64) -> Self;
    /// self − f · b, lane by lane (a product then a difference, no fused operation).
    ///
    /// # Safety
    /// See [`Lanes::load`].
    unsafe fn sub_mul(self, f: Self, b: Self) -> Self;
    /// self · f, lane by lane.
    ///
    /// # Safety
    /// See [`Lanes::load`].
    unsafe fn mul(self, f: Self) -> Self;
    /// Lane 0.
    ///
    /// # Safety
    /// See [`Lanes::load`].
    unsafe fn first(self) -> f64;
    /// Lane 0 replaced by `x`.
    ///
    /// # Safety
    /// See [`Lanes::load`].
    unsafe fn with_first(self, x: f64) -> Self;
    /// The four lanes.
    ///
    /// # Safety
    /// See [`Lanes::load`].
    unsafe fn to_array(self) -> [f64; 4];
}

impl Lanes for [f64; 4] {
    #[inline(always)]
    unsafe fn load(p: *const f64) -> Self {
        *(p as *const [f64; 4])
    }
    #[inline(always)]
    unsafe fn store(self, p: *mut f64) {
        *(p as *mut [f64; 4]) = self;
    }
    #[inline(always)]
    unsafe fn splat(x: f64) -> Self {
        [x; 4]
    }
    #[inline(always)]
    unsafe fn sub_mul(self, f: Self, b: Self) -> Self {
        [
            self[0] - f[0] * b[0],
            self[1] - f[1] * b[1],
            self[2] - f[2] * b[2],
            self[3] - f[3] * b[3],
        ]
    }
    #[inline(always)]
    unsafe fn mul(self, f: Self) -> Self {
        [
            self[0] * f[0],
            self[1] * f[1],
            self[2] * f[2],
            self[3] * f[3],
        ]
    }
    #[inline(always)]
    unsafe fn first(self) -> f64 {
        self[0]
    }
    #[inline(always)]
    unsafe fn with_first(self, x: f64) -> Self {
        [x, self[1], self[2], self[3]]
    }
    #[inline(always)]
    unsafe fn to_array(self) -> [f64; 4] {
        self
    }
}

/// An AVX vector of 4 f64 (the kernels written with intrinsics, so that the compiler
/// adds no runtime alias checks or loop versions around the short runs).
#[cfg(target_arch = "x86_64")]
#[derive(Clone, Copy)]
struct Avx(std::arch::x86_64::__m256d);

#[cfg(target_arch = "x86_64")]
impl Lanes for Avx {
    #[inline(always)]
    unsafe fn load(p: *const f64) -> Self {
        Avx(std::arch::x86_64::_mm256_loadu_pd(p))
    }
    #[inline(always)]
    unsafe fn store(self, p: *mut f64) {
        std::arch::x86_64::_mm256_storeu_pd(p, self.0)
    }
    #[inline(always)]
    unsafe fn splat(x: f64) -> Self {
        Avx(std::arch::x86_64::_mm256_set1_pd(x))
    }
    #[inline(always)]
    unsafe fn sub_mul(self, f: Self, b: Self) -> Self {
        use std::arch::x86_64::{_mm256_mul_pd, _mm256_sub_pd};
        Avx(_mm256_sub_pd(self.0, _mm256_mul_pd(f.0, b.0)))
    }
    #[inline(always)]
    unsafe fn mul(self, f: Self) -> Self {
        Avx(std::arch::x86_64::_mm256_mul_pd(self.0, f.0))
    }
    #[inline(always)]
    unsafe fn first(self) -> f64 {
        std::arch::x86_64::_mm256_cvtsd_f64(self.0)
    }
    #[inline(always)]
    unsafe fn with_first(self, x: f64) -> Self {
        use std::arch::x86_64::{_mm256_blend_pd, _mm256_set1_pd};
        Avx(_mm256_blend_pd::<1>(self.0, _mm256_set1_pd(x)))
    }
    #[inline(always)]
    unsafe fn to_array(self) -> [f64; 4] {
        std::mem::transmute::<std::arch::x86_64::__m256d, [f64; 4]>(self.0)
    }
}

/// In-place Cholesky factorisation of the lower band `band` (n columns of w = [`stride`]
/// (p): the band, the diagonal first, then zeros) and forward substitution of `y`,
/// left-looking column by column, from column `*k` up to the final columns 0 ..
/// `ready`; `*k` becomes `ready` ([`BandedCholesky::solve_rows`]).
///
/// Column j takes its updates from the p columns before it, in pivot order k = j −
/// p … j − 1: a_ij −= L[j][k] · L[i][k] for the rows i = j ..= j + p (an axpy of a
/// contiguous run of column k, from its row j, onto the column), then d = √a_jj,
/// L[j][j] = d and L[i][j] = a_ij · (1/d). The column stays in registers while its p
/// updates are applied ([`column_in_registers`]: each target chunk is loaded and
/// stored once, each update is a product and a difference per chunk), and a pivot k
/// updates only the chunks its column reaches (rows up to k + p; the rest of the
/// last chunk reads the zeros below column k's band). So every entry of L gets the
/// products of the textbook algorithm, the real ones in pivot order, plus some exact
/// zeros L[j][k]·0. Subtracting a zero changes nothing but the sign of a −0, and no
/// entry is ever −0: the assembly adds onto +0 (+0 + −0 = +0), a difference of equal
/// nonzero values is +0, −0 − ±0 needs a −0 already, and the scaling is by 1/d > 0.
/// So the factor is, bit for bit, that of one pivot at a time, right-looking or
/// left-looking, whichever zeros each adds (the earlier right-looking kernel by
/// panels of 4 included). The forward substitution rides the same pivots: y_j −=
/// L[j][k] y_k for k = j − p … j − 1 (the order in which the column-oriented
/// version reaches y_j), then y_j ·= 1/d.
#[inline(always)]
fn factor_to<V: Lanes>(band: &mut [f64], y: &mut [f64], p: usize, k: &mut usize, ready: usize) {
    let n = y.len();
    let w = stride(p);
    assert!(band.len() >= n * w && ready <= n && *k <= ready);
    let bp = band.as_mut_ptr();
    let yp = y.as_mut_ptr();
    let ch = (p + 4) / 4; // chunks of a column (rows 0 ..= p, up to p + 3)
                          // SAFETY: columns < n, each read and written at offsets ≤ 4 ch − 1 ≤ p + 3 < w
                          // (so < n w ≤ band.len(), asserted above), y at indices < n; a column is written
                          // only while no other pointer to it is used.
    unsafe {
        macro_rules! columns {
            ($($c:literal)*) => {
                match ch {
                    $($c => {
                        let first = ready.min(p);
                        for j in *k..first {
                            column_in_memory::<V>(bp, yp, w, p, j);
                        }
                        for j in (*k).max(first)..ready {
                            column_in_registers::<V, $c>(bp, yp, w, p, j);
                        }
                    })*
                    _ => {
                        for j in *k..ready {
                            column_in_memory::<V>(bp, yp, w, p, j);
                        }
                    }
                }
            };
        }
        columns!(1 2 3 4 5 6 7 8 9 10 11 12);
    }
    *k = ready;
}

/// One pivot: acc −= L[j][k] · (column k from row j) on the first `G` chunks, and
/// y_j −= L[j][k] y_k; `src` points at L[j][k] (column k, row j).
///
/// # Safety
/// The rows read lie in the band, `yk` in y ([`factor_to`]).
#[allow(clippy::needless_range_loop)] // chunk m at offset 4m, in registers
#[inline(always)]
unsafe fn apply<V: Lanes, const G: usize>(
    acc: &mut [V; MAXCH],
    yj: &mut f64,
    src: *const f64,
    yk: *const f64,
) {
    let l = *src;
    *yj -= l * *yk;
    let f = V::splat(l);
    for m in 0..G {
        acc[m] = acc[m].sub_mul(f, V::load(src.add(4 * m)));
    }
}

/// Column j ≥ p of L and y_j, left-looking, the column kept in `CH` vector registers
/// (p + 1 ≤ 4 CH): its p updates in pivot order k = j − p … j − 1, each on the
/// chunks pivot k's column reaches (rows up to k + p: ⌈(p + 1 − s)/4⌉ chunks for k
/// = j − s, so 4 pivots per chunk count, fewer in the last group), then √, 1/d and
/// the scaling ([`factor_to`]).
///
/// # Safety
/// As [`factor_to`]: columns j − p ..= j valid, w = stride(p), j ≥ p.
#[allow(clippy::needless_range_loop)] // chunk m at offset 4m, in registers
#[inline(always)]
unsafe fn column_in_registers<V: Lanes, const CH: usize>(
    bp: *mut f64,
    yp: *mut f64,
    w: usize,
    p: usize,
    j: usize,
) {
    let col = bp.add(j * w);
    debug_assert_eq!(w, 4 * CH + 3);
    let step = 4 * CH + 2; // from L[j][k] to L[j][k + 1]: w − 1, a constant
    let mut acc = [V::splat(0.0); MAXCH];
    for m in 0..CH {
        acc[m] = V::load(col.add(4 * m));
    }
    let mut yj = *yp.add(j);
    let mut src = col.sub(p * step) as *const f64;
    let mut yk = yp.add(j - p) as *const f64;
    // Groups g = 1 .. CH − 1: pivots s = p + 4 − 4g down to p + 1 − 4g reach g chunks.
    macro_rules! groups {
        ($($g:literal)*) => {
            $(if $g < CH {
                for _ in 0..4 {
                    apply::<V, $g>(&mut acc, &mut yj, src, yk);
                    src = src.add(step);
                    yk = yk.add(1);
                }
            })*
        };
    }
    groups!(1 2 3 4 5 6 7 8 9 10 11);
    // The last group: s = p + 4 − 4 CH down to 1 (1 to 4 pivots).
    let r = p + 4 - 4 * CH;
    for i in 0..4 {
        if i < r {
            apply::<V, CH>(&mut acc, &mut yj, src, yk);
            src = src.add(step);
            yk = yk.add(1);
        }
    }
    let d = acc[0].first().sqrt();
    let inv = 1.0 / d;
    *yp.add(j) = yj * inv;
    let f = V::splat(inv);
    for m in 0..CH {
        let v = acc[m].mul(f);
        let v = if m == 0 { v.with_first(d) } else { v };
        v.store(col.add(4 * m));
    }
}

/// [`column_in_registers`] for any p and j, the column updated in memory (the same
/// operations in the same order).
///
/// # Safety
/// As [`factor_to`]: columns j − min(p, j) ..= j valid, w = stride(p).
#[inline(always)]
unsafe fn column_in_memory<V: Lanes>(bp: *mut f64, yp: *mut f64, w: usize, p: usize, j: usize) {
    let col = bp.add(j * w);
    let mut yj = *yp.add(j);
    for s in (1..=p.min(j)).rev() {
        let src = col.sub(s * (w - 1)) as *const f64;
        let l = *src;
        yj -= l * *yp.add(j - s);
        let f = V::splat(l);
        for m in 0..(p + 4 - s) / 4 {
            let t = col.add(4 * m);
            V::load(t).sub_mul(f, V::load(src.add(4 * m))).store(t);
        }
    }
    let d = (*col).sqrt();
    let inv = 1.0 / d;
    *yp.add(j) = yj * inv;
    let f = V::splat(inv);
    for m in 0..(p + 4) / 4 {
        let t = col.add(4 * m);
        let v = V::load(t).mul(f);
        let v = if m == 0 { v.with_first(d) } else { v };
        v.store(t);
    }
}

/// [`factor_to`] with AVX vectors (AVX2 build, chosen at run time). The same
/// operations in the same order (no fused multiply-add: Rust does not contract
/// a·b + c), so the results are bit-for-bit those of the portable version.
///
/// # Safety
/// The CPU must support AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn factor_to_avx2(band: &mut [f64], y: &mut [f64], p: usize, k: &mut usize, ready: usize) {
    factor_to::<Avx>(band, y, p, k, ready)
}

/// Back substitution with Lᵀ by columns: x_c = (y_c − L[c+p][c] x_{c+p} − … −
/// L[c+1][c] x_{c+1}) / L[c][c], subtracted in that order (r descending: the order
/// in which the row-oriented version, y_c −= L[r][c] x_r for r = n − 1 … 0, reaches
/// y_c, so the same bits). A column is contiguous, and only its last term waits for
/// the previous unknown. With p ≥ 4, the columns with all p terms take the products
/// of rows c + 5 … c + 4⌊p/4⌋ four at a time (one vector product, the four lanes then
/// subtracted one by one, highest row first), and the last four terms from x_{c+1}
/// … x_{c+4} kept in registers (just computed: a vector load of them would wait for
/// their stores). With p ≤ 3 the columns with all p terms keep x_{c+1} … x_{c+p} in
/// registers ([`back_narrow`]).
#[inline(always)]
fn back_substitute<V: Lanes>(band: &[f64], y: &[f64], xs: &mut [f64], p: usize) {
    let n = y.len();
    let w = stride(p);
    assert!(band.len() >= n * w && xs.len() == n);
    let scalar = |xs: &mut [f64], c: usize| {
        let len = p.min(n - 1 - c);
        let col = &band[c * w + 1..c * w + 1 + len];
        let mut s = y[c];
        for (&l, &x) in col.iter().zip(&xs[c + 1..c + 1 + len]).rev() {
            s -= l * x;
        }
        xs[c] = s / band[c * w];
    };
    if p < 4 && n > p {
        // The last p columns (fewer than p terms), then the columns with p terms.
        for c in (n - p..n).rev() {
            scalar(xs, c);
        }
        match p {
            1 => back_narrow::<1>(band, y, xs, w),
            2 => back_narrow::<2>(band, y, xs, w),
            _ => back_narrow::<3>(band, y, xs, w),
        }
        return;
    }
    if p < 4 || n <= p + 4 {
        for c in (0..n).rev() {
            scalar(xs, c);
        }
        return;
    }
    // The last p columns (fewer than p terms), then x_{n−1−p} … x_0 with p terms.
    for c in (n - p..n).rev() {
        scalar(xs, c);
    }
    // SAFETY: columns < n − p from offset 0 to p, x_{c} … x_{c+p} with c + p < n,
    // y_c: within the band, xs and y (asserted above).
    unsafe {
        macro_rules! chunks {
            ($($f:literal)*) => {
                match p / 4 {
                    $($f => back_columns::<V, $f>(band.as_ptr(), y.as_ptr(), xs.as_mut_ptr(), w, p, n),)*
                    _ => back_columns::<V, 0>(band.as_ptr(), y.as_ptr(), xs.as_mut_ptr(), w, p, n),
                }
            };
        }
        chunks!(1 2 3 4 5 6 7 8 9 10 11 12);
    }
}

/// The columns c = n − 1 − P … 0 of [`back_substitute`] for a narrow band (P = p ≤ 3:
/// one or two layers per face), x_{c+1} … x_{c+P} carried in registers from column to
/// column: the products of the scalar loop, subtracted in
/// its order (row c + P first), and the same division, so the same bits.
#[inline(always)]
fn back_narrow<const P: usize>(band: &[f64], y: &[f64], xs: &mut [f64], w: usize) {
    let n = y.len();
    debug_assert!(n > P && w > P);
    // x[q] = x_{c+1+q} for the column c being solved.
    let mut x = [0.0; P];
    x.copy_from_slice(&xs[n - P..]);
    let m = n - P;
    for ((col, &yc), xc) in band[..m * w]
        .chunks_exact(w)
        .zip(&y[..m])
        .zip(&mut xs[..m])
        .rev()
    {
        let col = &col[..=P];
        let mut s = yc;
        for q in (0..P).rev() {
            s -= col[q + 1] * x[q];
        }
        let v = s / col[0];
        *xc = v;
        for q in (1..P).rev() {
            x[q] = x[q - 1];
        }
        x[0] = v;
    }
}

/// The columns c = n − 1 − p … 0 of [`back_substitute`] (all p terms), with `F` = p/4
/// chunks (0: any p ≥ 4, read at run time).
///
/// # Safety
/// As [`back_substitute`]: n > p + 4, p ≥ 4, x_{n−p} … x_{n−1} computed.
#[inline(always)]
unsafe fn back_columns<V: Lanes, const F: usize>(
    bp: *const f64,
    yp: *const f64,
    xp: *mut f64,
    w: usize,
    p: usize,
    n: usize,
) {
    let chunks = if F == 0 { p / 4 } else { F };
    // w = 4 (p/4) + 7 ([`stride`]), a constant for F > 0.
    let w = if F == 0 { w } else { 4 * F + 7 };
    let c = n - 1 - p;
    let (mut x1, mut x2, mut x3, mut x4) = (
        *xp.add(c + 1),
        *xp.add(c + 2),
        *xp.add(c + 3),
        *xp.add(c + 4),
    );
    let mut col = bp.add(c * w);
    let mut xc = xp.add(c);
    let mut yc = yp.add(c);
    for _ in 0..n - p {
        let mut s = *yc;
        for q in (4 * chunks + 1..=p).rev() {
            s -= *col.add(q) * *xc.add(q);
        }
        for m in (1..chunks).rev() {
            let v = V::load(col.add(4 * m + 1)).mul(V::load(xc.add(4 * m + 1)));
            let v = v.to_array();
            s -= v[3];
            s -= v[2];
            s -= v[1];
            s -= v[0];
        }
        s -= *col.add(4) * x4;
        s -= *col.add(3) * x3;
        s -= *col.add(2) * x2;
        s -= *col.add(1) * x1;
        let x = s / *col;
        *xc = x;
        (x4, x3, x2, x1) = (x3, x2, x1, x);
        col = col.wrapping_sub(w);
        xc = xc.wrapping_sub(1);
        yc = yc.wrapping_sub(1);
    }
}

/// [`back_substitute`] with AVX vectors (the products are the same IEEE operations,
/// so the same bits).
///
/// # Safety
/// The CPU must support AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn back_substitute_avx2(band: &[f64], y: &[f64], xs: &mut [f64], p: usize) {
    back_substitute::<Avx>(band, y, xs, p)
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

    /// `spd_system` with the faces `dry` made identity rows (x = 0 there, no coupling
    /// to them), as the projection writes dry faces.
    fn with_dry(sys: &mut StoredStencil, dense: &mut [Vec<f64>], m: usize, dry: &[usize]) {
        let n = dense.len();
        for &f in dry {
            for k in f * m..(f + 1) * m {
                for i in 0..n {
                    dense[k][i] = 0.0;
                    dense[i][k] = 0.0;
                }
                dense[k][k] = 1.0;
                sys.rows[k] = StencilRow::IDENTITY;
            }
        }
        // Rows next to a dry face lose their couplings to it.
        for k in 0..n {
            let (f, j) = ((k / m) as isize, (k % m) as isize);
            for df in -1..=1isize {
                for dj in -1..=1isize {
                    let (g, i) = (f + df, j + dj);
                    if g >= 0 && (g as usize) < n / m && i >= 0 && (i as usize) < m {
                        let col = g as usize * m + i as usize;
                        sys.rows[k].coef[(df + 1) as usize][(dj + 1) as usize] = dense[k][col];
                    }
                }
            }
        }
    }

    /// The textbook algorithm on the dense matrix, one pivot at a time (right-looking:
    /// each entry loses L[i][k] L[j][k] for k increasing, over the band only), the
    /// forward substitution by columns and the backward one by rows, r descending.
    fn textbook_solve(dense: &[Vec<f64>], rhs: &[f64], p: usize) -> Vec<f64> {
        let n = dense.len();
        let mut a = dense.to_vec();
        let mut y = rhs.to_vec();
        for k in 0..n {
            let last = (k + p).min(n - 1);
            let d = a[k][k].sqrt();
            let inv = 1.0 / d;
            a[k][k] = d;
            for i in k + 1..=last {
                a[i][k] *= inv;
            }
            y[k] *= inv;
            for i in k + 1..=last {
                y[i] -= a[i][k] * y[k];
            }
            for j in k + 1..=last {
                for i in j..=last {
                    a[i][j] -= a[i][k] * a[j][k];
                }
            }
        }
        let mut x = vec![0.0; n];
        for c in (0..n).rev() {
            let mut s = y[c];
            for r in (c + 1..=(c + p).min(n - 1)).rev() {
                s -= a[r][c] * x[r];
            }
            x[c] = s / a[c][c];
        }
        x
    }

    /// Rows that hand the band to the solver in pieces (`ready` every `every`
    /// columns), as the projection's assembly does.
    struct Pieces<'a>(&'a StoredStencil, usize);

    impl PressureRows for Pieces<'_> {
        type Row = StencilRow;
        fn active(&self) -> Range<usize> {
            self.0.active()
        }
        fn row(&self, k: usize) -> StencilRow {
            self.0.row(k)
        }
        fn assemble_band(
            &self,
            band: &mut [f64],
            rhs: &mut [f64],
            p: usize,
            stride: usize,
            ready: &mut crate::numerics::linalg::BandReady,
        ) -> bool {
            assemble_rows(self.0, band, rhs, p, stride);
            let n = self.0.active().len();
            let mut c = 0;
            while c < n {
                c = (c + self.1).min(n);
                ready(band, rhs, c);
            }
            true
        }
    }

    /// The AVX2 build of the kernel gives the bits of the portable one, and both the
    /// bits of the textbook algorithm (so of the earlier kernels), whether the band
    /// is handed over at once or in pieces, with and without dry faces, for block
    /// sizes on either side of the chunk boundaries and past the register kernel
    /// (N = 48: the column in memory).
    #[test]
    fn avx2_kernel_gives_the_same_bits() {
        for (m, faces) in [
            (1, 40),
            (2, 30),
            (3, 30),
            (4, 20),
            (5, 20),
            (7, 16),
            (8, 16),
            (20, 30),
            (23, 10),
            (33, 10),
            (48, 8),
        ] {
            for dry in [&[][..], &[0, 3, 4, faces - 1][..]] {
                let (mut sys, mut dense) = spd_system(faces, m, 11 + m as u64);
                with_dry(&mut sys, &mut dense, m, dry);
                let n = faces * m;
                let rhs: Vec<f64> = sys.rows.iter().map(|r| r.rhs).collect();
                let reference = textbook_solve(&dense, &rhs, m + 1);
                for every in [n, 7, 1] {
                    let mut plain = BandedCholesky::new(m, faces);
                    plain.avx2 = false;
                    let mut fast = BandedCholesky::new(m, faces);
                    let (mut a, mut b) = (vec![0.0; n], vec![0.0; n]);
                    plain.solve_rows(&Pieces(&sys, every), &mut a);
                    fast.solve_rows(&Pieces(&sys, every), &mut b);
                    let same = |u: &[f64]| {
                        u.iter()
                            .zip(&reference)
                            .all(|(x, y)| x.to_bits() == y.to_bits())
                    };
                    assert!(
                        same(&a),
                        "portable, N = {m}, dry {dry:?}, pieces of {every}"
                    );
                    assert!(
                        same(&b),
                        "AVX2 {}, N = {m}, dry {dry:?}, pieces of {every}",
                        fast.avx2
                    );
                    assert!(a.iter().all(|v| v.is_finite()));
                }
                // The whole band at once (`assemble_rows`).
                let mut x = vec![0.0; n];
                BandedCholesky::new(m, faces).solve_rows(&sys, &mut x);
                assert!(x
                    .iter()
                    .zip(&reference)
                    .all(|(x, y)| x.to_bits() == y.to_bits()));
            }
        }
        println!("AVX2 available: {}", avx2());
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
