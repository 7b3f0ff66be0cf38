//! Banded linear algebra for the implicit sub-steps.
//!
//! [`BlockTridiagonal`] stores a system whose row k couples the unknown blocks k − 1,
//! k and k + 1 (blocks of `block` unknowns, m×m coefficient blocks, row-major). The
//! monolayer pressure projection (seed 000 §3 step 3) has m = 1: a scalar tridiagonal
//! system solved by [`thomas`] in O(n). The multilayer projection (seed 003 eq. 31–32)
//! has m = N unknowns per face; ordered face-major it is block-tridiagonal with the
//! same storage.

/// A (block-)tridiagonal system A x = rhs with `rows` block rows of size `block`.
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
    /// Rows outside this range are identity rows with a zero right-hand side, so the
    /// solution is 0 there and nothing outside needs to be assembled or eliminated
    /// (e.g. the dry part of the domain).
    pub active: std::ops::Range<usize>,
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

    /// A x − rhs for a scalar system (block = 1), e.g. to check a solve.
    pub fn residual(&self, x: &[f64]) -> Vec<f64> {
        assert_eq!(self.block, 1);
        let n = self.rows;
        (0..n)
            .map(|k| {
                if !self.active.contains(&k) {
                    return x[k];
                }
                let mut r = self.diag[k] * x[k] - self.rhs[k];
                if k > 0 {
                    r += self.lower[k] * x[k - 1];
                }
                if k + 1 < n {
                    r += self.upper[k] * x[k + 1];
                }
                r
            })
            .collect()
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
    debug_assert!(lower.len() == n && upper.len() == n && rhs.len() == n);
    debug_assert!(x.len() == n && scratch.len() == n);
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

/// The Thomas algorithm run from both ends at once ("twisted" factorisation): rows
/// 0..m are eliminated downwards and rows m+1..n upwards, the two sweeps meet at row
/// m = n/2 and the back-substitution runs outwards from it. Same operation count as
/// [`thomas`], but the two independent recurrences overlap in the processor, which
/// nearly halves the time of this latency-bound loop (one division per row on the
/// critical path). Same stability as [`thomas`] for diagonally dominant systems.
pub fn thomas_two_sided(
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
    if n < 4 {
        return thomas(lower, diag, upper, rhs, x, scratch);
    }
    let m = n / 2;
    // scratch[k]: upper[k]/pivot for the downward rows, lower[k]/pivot for the upward.
    let inv = 1.0 / diag[0];
    scratch[0] = upper[0] * inv;
    x[0] = rhs[0] * inv;
    let inv = 1.0 / diag[n - 1];
    scratch[n - 1] = lower[n - 1] * inv;
    x[n - 1] = rhs[n - 1] * inv;
    let pairs = (n - 1 - m).min(m);
    for j in 1..pairs {
        let (k, kb) = (j, n - 1 - j);
        let inv = 1.0 / (diag[k] - lower[k] * scratch[k - 1]);
        let inv_b = 1.0 / (diag[kb] - upper[kb] * scratch[kb + 1]);
        scratch[k] = upper[k] * inv;
        x[k] = (rhs[k] - lower[k] * x[k - 1]) * inv;
        scratch[kb] = lower[kb] * inv_b;
        x[kb] = (rhs[kb] - upper[kb] * x[kb + 1]) * inv_b;
    }
    // n odd leaves one more downward row than upward rows.
    for k in pairs.max(1)..m {
        let inv = 1.0 / (diag[k] - lower[k] * scratch[k - 1]);
        scratch[k] = upper[k] * inv;
        x[k] = (rhs[k] - lower[k] * x[k - 1]) * inv;
    }
    let den = diag[m] - lower[m] * scratch[m - 1] - upper[m] * scratch[m + 1];
    x[m] = (rhs[m] - lower[m] * x[m - 1] - upper[m] * x[m + 1]) / den;
    for j in 1..=m {
        let k = m - j;
        x[k] -= scratch[k] * x[k + 1];
        let kb = m + j;
        if kb < n {
            x[kb] -= scratch[kb] * x[kb - 1];
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
    fn two_sided_thomas_matches_thomas_for_every_size() {
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
            thomas_two_sided(
                &sys.lower,
                &sys.diag,
                &sys.upper,
                &sys.rhs,
                &mut b,
                &mut scratch,
            );
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
