//! Banded linear algebra for the implicit sub-steps.
//!
//! The pressure systems of the projection (Garres-Díaz et al. 2021, §3 step 3, Escalante et al. 2023, eq. 31–32) are
//! (block-)tridiagonal: row k couples the unknowns of faces k − 1, k and k + 1. A
//! system is seen through [`PressureRows`], which hands out one row at a time, so a
//! solver can eliminate each row as soon as it is formed ("matrix-free" assembly: the
//! coefficients are never stored, and forming a row overlaps with the division of the
//! previous one). [`BlockTridiagonal`] is the stored form, for systems assembled ahead
//! (and for tests). The monolayer system has scalar rows ([`ScalarRow`]) and is solved
//! exactly in O(n) by [`thomas_rows`]; an N-layer system has N×N blocks per row
//! (Escalante et al. 2023, eq. 32, ordered face-major) and its own row type.

use std::ops::Range;

/// Called by [`PressureRows::assemble_band`] as `ready(band, rhs, c)` when the
/// columns 0 .. c of the band are final.
pub type BandReady<'a> = dyn FnMut(&mut [f64], &mut [f64], usize) + 'a;

/// A (block-)tridiagonal system, one row at a time.
pub trait PressureRows {
    /// One row: its couplings to the unknowns k − 1, k, k + 1 and its right-hand side.
    type Row;
    /// Rows outside this range are identity rows with a zero right-hand side: the
    /// solution is 0 there (e.g. the dry part of the domain) and they are never formed.
    fn active(&self) -> Range<usize>;
    /// Row k, for k in [`active`](Self::active). The coupling of the first active row
    /// to k − 1 and of the last to k + 1 are ignored (those unknowns are 0).
    fn row(&self, k: usize) -> Self::Row;
    /// For banded solvers (`banded.rs`): writes the lower band of the active rows and
    /// their right-hand sides into `rhs`, and returns true. The band is stored by
    /// columns: column c takes `stride` ≥ p + 1 values from `band[c·stride]`, entry
    /// (r, c) for c ≤ r ≤ c + p at `c·stride + r − c` (the diagonal first), zeros
    /// after it and for rows past the last. Whenever the columns and right-hand sides
    /// 0 .. c are final (nothing more will be added to them), it may call
    /// `ready(band, rhs, c)`, with c not decreasing and the last call with c = the
    /// number of active rows, so that a solver can factorise those columns while the
    /// band is in cache; `ready` changes only columns < c and rhs[..c]. The default
    /// returns false and the solver forms the rows one by one with [`row`](Self::row).
    fn assemble_band(
        &self,
        _band: &mut [f64],
        _rhs: &mut [f64],
        _p: usize,
        _stride: usize,
        _ready: &mut BandReady,
    ) -> bool {
        false
    }
}

/// A row of a scalar tridiagonal system: lower x_{k−1} + diag x_k + upper x_{k+1} = rhs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ScalarRow {
    pub lower: f64,
    pub diag: f64,
    pub upper: f64,
    pub rhs: f64,
}

impl ScalarRow {
    /// x_k = 0.
    pub const IDENTITY: ScalarRow = ScalarRow {
        lower: 0.0,
        diag: 1.0,
        upper: 0.0,
        rhs: 0.0,
    };
}

/// A stored (block-)tridiagonal system A x = rhs with `rows` block rows of size `block`
/// (m×m coefficient blocks, row-major).
#[derive(Debug, Clone, PartialEq)]
pub struct BlockTridiagonal {
    pub rows: usize,
    pub block: usize,
    /// Coupling of row k to block k − 1 (rows·m², row 0 unused).
    pub lower: Vec<f64>,
    /// Diagonal blocks (rows·m²).
    pub diag: Vec<f64>,
    /// Coupling of row k to block k + 1 (rows·m², last row unused).
    pub upper: Vec<f64>,
    /// Right-hand side (rows·m).
    pub rhs: Vec<f64>,
    /// See [`PressureRows::active`].
    pub active: Range<usize>,
}

impl BlockTridiagonal {
    pub fn new(rows: usize, block: usize) -> Self {
        let m2 = block * block;
        BlockTridiagonal {
            rows,
            block,
            lower: vec![0.0; rows * m2],
            diag: vec![0.0; rows * m2],
            upper: vec![0.0; rows * m2],
            rhs: vec![0.0; rows * block],
            active: 0..rows,
        }
    }

    /// Stores the rows of a scalar system.
    pub fn from_rows<R: PressureRows<Row = ScalarRow>>(rows: &R, n: usize) -> Self {
        let mut sys = BlockTridiagonal::new(n, 1);
        sys.active = rows.active();
        for k in 0..n {
            let row = if sys.active.contains(&k) {
                rows.row(k)
            } else {
                ScalarRow::IDENTITY
            };
            (sys.lower[k], sys.diag[k], sys.upper[k], sys.rhs[k]) =
                (row.lower, row.diag, row.upper, row.rhs);
        }
        sys
    }

    /// A x − rhs for a scalar system (block = 1), e.g. to check a solve.
    pub fn residual(&self, x: &[f64]) -> Vec<f64> {
        assert_eq!(self.block, 1);
        let (n, a) = (self.rows, &self.active);
        (0..n)
            .map(|k| {
                if !a.contains(&k) {
                    return x[k];
                }
                let mut r = self.diag[k] * x[k] - self.rhs[k];
                if k > a.start {
                    r += self.lower[k] * x[k - 1];
                }
                if k + 1 < a.end {
                    r += self.upper[k] * x[k + 1];
                }
                r
            })
            .collect()
    }
}

impl PressureRows for BlockTridiagonal {
    type Row = ScalarRow;

    fn active(&self) -> Range<usize> {
        self.active.clone()
    }

    fn row(&self, k: usize) -> ScalarRow {
        debug_assert_eq!(self.block, 1, "scalar rows of a block system");
        ScalarRow {
            lower: self.lower[k],
            diag: self.diag[k],
            upper: self.upper[k],
            rhs: self.rhs[k],
        }
    }
}

/// Thomas algorithm (Gaussian elimination without pivoting) for a scalar tridiagonal
/// system: `lower[k] x[k−1] + diag[k] x[k] + upper[k] x[k+1] = rhs[k]`. `scratch` holds
/// the modified super-diagonal (same length). Stable for diagonally dominant systems; a
/// zero pivot yields non-finite values, which the run loop reports.
pub fn thomas(
    lower: &[f64],
    diag: &[f64],
    upper: &[f64],
    rhs: &[f64],
    x: &mut [f64],
    scratch: &mut [f64],
) {
    let n = diag.len();
    assert!(lower.len() == n && upper.len() == n && rhs.len() == n);
    assert!(x.len() == n && scratch.len() == n);
    if n == 0 {
        return;
    }
    let inv = 1.0 / diag[0];
    scratch[0] = upper[0] * inv;
    x[0] = rhs[0] * inv;
    for k in 1..n {
        let inv = 1.0 / (diag[k] - lower[k] * scratch[k - 1]);
        scratch[k] = upper[k] * inv;
        x[k] = (rhs[k] - lower[k] * x[k - 1]) * inv;
    }
    for k in (0..n - 1).rev() {
        x[k] -= scratch[k] * x[k + 1];
    }
}

/// Magnitude below which [`thomas_rows`] sets a value to zero. Away from its sources
/// the solution of the pressure system decays exponentially (by e^(−2Δx/h) per face in
/// a layer at rest), down to subnormal numbers, whose arithmetic is up to a hundred
/// times slower, in the solve and later in every stage that reads the state. 1e-100 is
/// far below any physical value in SI units and keeps squares and cubes normal.
pub const FLUSH_TO_ZERO: f64 = 1e-100;

#[inline(always)]
fn flush(v: f64) -> f64 {
    if v.abs() < FLUSH_TO_ZERO {
        0.0
    } else {
        v
    }
}

/// The Thomas algorithm run from both ends at once ("twisted" factorisation) on the
/// active rows of `rows`, x = 0 elsewhere: rows are eliminated downwards from the first
/// and upwards from the last, the two sweeps meet in the middle row and the
/// back-substitution runs outwards from it. Same operations as [`thomas`] (and the same
/// stability for diagonally dominant systems), but the two independent recurrences
/// overlap in the processor, which nearly halves the time of this latency-bound loop
/// (a division per row on the critical path); forming each row (`rows.row(k)`) overlaps
/// with it too. Values below [`FLUSH_TO_ZERO`] are set to 0. `x` and `scratch` cover
/// all rows.
pub fn thomas_rows<R: PressureRows<Row = ScalarRow>>(rows: &R, x: &mut [f64], scratch: &mut [f64]) {
    let active = rows.active();
    assert!(active.end <= x.len() && scratch.len() >= x.len());
    x[..active.start].fill(0.0);
    x[active.end..].fill(0.0);
    let (s, n) = (active.start, active.len());
    let (x, c) = (&mut x[active.clone()], &mut scratch[active]);
    let row = |k: usize| rows.row(s + k);
    match n {
        0 => return,
        1 => {
            x[0] = row(0).rhs / row(0).diag;
            return;
        }
        _ => {}
    }
    // c[k]: upper/pivot for the downward rows, lower/pivot for the upward ones; x holds
    // the eliminated right-hand sides until the back-substitution.
    let m = n / 2;
    let (top, bottom) = (row(0), row(n - 1));
    let inv = 1.0 / top.diag;
    (c[0], x[0]) = (top.upper * inv, top.rhs * inv);
    let inv = 1.0 / bottom.diag;
    (c[n - 1], x[n - 1]) = (bottom.lower * inv, bottom.rhs * inv);
    // Rows 1..m downwards and n−2..m upwards (one more downward row when n is even).
    let upward = n - 1 - m;
    for j in 1..m {
        let (k, r) = (j, row(j));
        let inv = 1.0 / (r.diag - r.lower * c[k - 1]);
        c[k] = r.upper * inv;
        x[k] = flush((r.rhs - r.lower * x[k - 1]) * inv);
        if j < upward {
            let (k, r) = (n - 1 - j, row(n - 1 - j));
            let inv = 1.0 / (r.diag - r.upper * c[k + 1]);
            c[k] = r.lower * inv;
            x[k] = flush((r.rhs - r.upper * x[k + 1]) * inv);
        }
    }
    if m == n - 1 {
        // n = 2: the meeting row is the last row, already eliminated upwards.
        let r = row(m);
        x[m] = (r.rhs - r.lower * x[m - 1]) / (r.diag - r.lower * c[m - 1]);
    } else {
        let r = row(m);
        let den = r.diag - r.lower * c[m - 1] - r.upper * c[m + 1];
        x[m] = (r.rhs - r.lower * x[m - 1] - r.upper * x[m + 1]) / den;
    }
    for j in 1..=m {
        let k = m - j;
        x[k] = flush(x[k] - c[k] * x[k + 1]);
        let k = m + j;
        if k < n {
            x[k] = flush(x[k] - c[k] * x[k - 1]);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Dense Gaussian elimination with partial pivoting, as a reference.
    fn dense_solve(mut a: Vec<Vec<f64>>, mut b: Vec<f64>) -> Vec<f64> {
        let n = b.len();
        for c in 0..n {
            let p = (c..n)
                .max_by(|&i, &j| a[i][c].abs().total_cmp(&a[j][c].abs()))
                .unwrap();
            a.swap(c, p);
            b.swap(c, p);
            let pivot_row = a[c].clone();
            for r in c + 1..n {
                let f = a[r][c] / pivot_row[c];
                for (ark, ack) in a[r].iter_mut().zip(&pivot_row).skip(c) {
                    *ark -= f * ack;
                }
                b[r] -= f * b[c];
            }
        }
        let mut x = vec![0.0; n];
        for r in (0..n).rev() {
            let s: f64 = (r + 1..n).map(|k| a[r][k] * x[k]).sum();
            x[r] = (b[r] - s) / a[r][r];
        }
        x
    }

    #[test]
    fn thomas_matches_dense_elimination() {
        let n = 37;
        let mut sys = BlockTridiagonal::new(n, 1);
        for k in 0..n {
            let t = k as f64;
            sys.lower[k] = if k > 0 {
                -1.0 - 0.3 * (t * 0.7).sin()
            } else {
                0.0
            };
            sys.upper[k] = if k + 1 < n {
                0.8 - 0.2 * (t * 1.3).cos()
            } else {
                0.0
            };
            sys.diag[k] = 2.5 + 0.5 * (t * 0.4).sin();
            sys.rhs[k] = (t * 0.9).cos() + 0.1 * t;
        }
        let mut x = vec![0.0; n];
        let mut scratch = vec![0.0; n];
        thomas(
            &sys.lower,
            &sys.diag,
            &sys.upper,
            &sys.rhs,
            &mut x,
            &mut scratch,
        );
        let mut dense = vec![vec![0.0; n]; n];
        for k in 0..n {
            dense[k][k] = sys.diag[k];
            if k > 0 {
                dense[k][k - 1] = sys.lower[k];
            }
            if k + 1 < n {
                dense[k][k + 1] = sys.upper[k];
            }
        }
        let reference = dense_solve(dense, sys.rhs.clone());
        for (a, b) in x.iter().zip(&reference) {
            assert!((a - b).abs() <= 1e-13 * (1.0 + b.abs()), "{a} vs {b}");
        }
        assert!(sys.residual(&x).iter().all(|r| r.abs() < 1e-13));
    }

    #[test]
    fn two_sided_thomas_on_rows_matches_thomas_for_every_size() {
        for n in 1..40 {
            let mut sys = BlockTridiagonal::new(n, 1);
            for k in 0..n {
                let t = k as f64;
                sys.lower[k] = -1.0 - 0.3 * (t * 0.7).sin();
                sys.upper[k] = 0.8 - 0.2 * (t * 1.3).cos();
                sys.diag[k] = 2.5 + 0.5 * (t * 0.4).sin();
                sys.rhs[k] = (t * 0.9).cos() + 0.1 * t;
            }
            let (mut a, mut b, mut scratch) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
            thomas(
                &sys.lower,
                &sys.diag,
                &sys.upper,
                &sys.rhs,
                &mut a,
                &mut scratch,
            );
            thomas_rows(&sys, &mut b, &mut scratch);
            for (a, b) in a.iter().zip(&b) {
                assert!(
                    (a - b).abs() <= 1e-13 * (1.0 + a.abs()),
                    "n = {n}: {a} vs {b}"
                );
            }
        }
    }

    #[test]
    fn zero_right_hand_side_gives_exact_zeros() {
        let n = 9;
        let mut sys = BlockTridiagonal::new(n, 1);
        sys.diag.iter_mut().for_each(|d| *d = 3.0);
        sys.lower.iter_mut().for_each(|d| *d = -1.2);
        sys.upper.iter_mut().for_each(|d| *d = 0.7);
        let mut x = vec![1.0; n];
        let mut scratch = vec![0.0; n];
        thomas(
            &sys.lower,
            &sys.diag,
            &sys.upper,
            &sys.rhs,
            &mut x,
            &mut scratch,
        );
        assert!(x.iter().all(|&v| v == 0.0));
    }
}

#[cfg(test)]
mod active_range_tests {
    use super::*;

    #[test]
    fn rows_outside_the_active_range_are_zero() {
        let n = 12;
        let mut sys = BlockTridiagonal::new(n, 1);
        for k in 0..n {
            (sys.lower[k], sys.diag[k], sys.upper[k], sys.rhs[k]) = (-1.0, 3.0, -0.5, k as f64);
        }
        sys.active = 3..9;
        let (mut x, mut scratch) = (vec![7.0; n], vec![0.0; n]);
        thomas_rows(&sys, &mut x, &mut scratch);
        assert!(x[..3].iter().chain(&x[9..]).all(|&v| v == 0.0));
        assert!(sys.residual(&x).iter().all(|r| r.abs() < 1e-13));
    }
}
