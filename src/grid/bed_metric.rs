//! The geometry of a bed z = b(x, y) seen from its horizontal raster, for the
//! bed-normal (terrain-following) frame (docs/numerics.md, "2-D Savage–Hutter model in
//! the bed-normal frame"; Bouchut & Westdickenberg 2004):
//!
//! - the gradient ∇b = (b_x, b_y) and cos θ = c = 1/√(1 + |∇b|²), θ the local slope;
//! - the metric of the surface in the horizontal coordinates, G = I + ∇b ∇bᵀ (the
//!   squared length of a tangent vector with horizontal part u is uᵀ G u), and its
//!   inverse G⁻¹ = I − c² ∇b ∇bᵀ;
//! - the Hessian ∇²b, whose quadratic form uᵀ ∇²b u is the centrifugal acceleration
//!   of a flow over the bed (normal curvature times speed², over c).
//!
//! Derivatives are centred differences of the cell-centre values, one-sided beside the
//! raster's edge or a wall (nodata) cell, zero on a single row or column; the Hessian
//! is the centred difference of the gradient (symmetrised), so a plane has exactly
//! zero curvature and a uniform gradient.

/// Per cell (row-major, nx·ny): the bed's gradient, cos θ and Hessian.
#[derive(Debug, Clone, PartialEq)]
pub struct BedMetric {
    /// ∂b/∂x and ∂b/∂y.
    pub gx: Vec<f64>,
    pub gy: Vec<f64>,
    /// c = cos θ = 1/√(1 + b_x² + b_y²).
    pub cos: Vec<f64>,
    /// ∂²b/∂x², ∂²b/∂x∂y, ∂²b/∂y².
    pub hxx: Vec<f64>,
    pub hxy: Vec<f64>,
    pub hyy: Vec<f64>,
    /// Whether the centrifugal term enters the basal normal stress
    /// ([`Self::normal_curvature`]; `domain.curvature`).
    pub in_friction: bool,
}

/// The centred (or one-sided) difference along one axis of `f` at index `k` of
/// `n`, with `step` between indices, `ok(m)` telling whether index m may be used.
fn difference(
    f: impl Fn(usize) -> f64,
    k: usize,
    n: usize,
    step: f64,
    ok: impl Fn(usize) -> bool,
) -> f64 {
    let lo = if k > 0 && ok(k - 1) { k - 1 } else { k };
    let hi = if k + 1 < n && ok(k + 1) { k + 1 } else { k };
    if lo == hi {
        return 0.0;
    }
    (f(hi) - f(lo)) / ((hi - lo) as f64 * step)
}

impl BedMetric {
    /// The metric of the bed `b` (row-major, nx·ny) on cells of Δx × Δy; `walls` is
    /// empty or one flag per cell (a wall's values are never read).
    pub fn new(nx: usize, ny: usize, dx: f64, dy: f64, b: &[f64], walls: &[bool]) -> BedMetric {
        let cells = nx * ny;
        let ok = |k: usize| walls.is_empty() || !walls[k];
        let along_x = |f: &dyn Fn(usize) -> f64, k: usize| {
            let (i, j) = (k % nx, k / nx);
            difference(|m| f(j * nx + m), i, nx, dx, |m| ok(j * nx + m))
        };
        let along_y = |f: &dyn Fn(usize) -> f64, k: usize| {
            let (i, j) = (k % nx, k / nx);
            difference(|m| f(m * nx + i), j, ny, dy, |m| ok(m * nx + i))
        };
        let bed = |k: usize| b[k];
        let gx: Vec<f64> = (0..cells).map(|k| along_x(&bed, k)).collect();
        let gy: Vec<f64> = (0..cells).map(|k| along_y(&bed, k)).collect();
        let cos = (0..cells)
            .map(|k| 1.0 / (1.0 + gx[k] * gx[k] + gy[k] * gy[k]).sqrt())
            .collect();
        let (fx, fy) = (|k: usize| gx[k], |k: usize| gy[k]);
        let hxx = (0..cells).map(|k| along_x(&fx, k)).collect();
        let hyy = (0..cells).map(|k| along_y(&fy, k)).collect();
        let hxy = (0..cells)
            .map(|k| 0.5 * (along_y(&fx, k) + along_x(&fy, k)))
            .collect();
        BedMetric {
            gx,
            gy,
            cos,
            hxx,
            hxy,
            hyy,
            in_friction: true,
        }
    }

    /// uᵀ ∇²b u of cell `k` where the centrifugal term is in the friction, else 0.
    #[inline(always)]
    pub fn normal_curvature(&self, k: usize, u: f64, v: f64) -> f64 {
        if self.in_friction {
            self.curvature(k, u, v)
        } else {
            0.0
        }
    }

    /// G u = (u + b_x (∇b·u), v + b_y (∇b·u)) of cell `k`: the covariant components of
    /// the tangent velocity with horizontal part (u, v).
    #[inline(always)]
    pub fn lower(&self, k: usize, u: f64, v: f64) -> (f64, f64) {
        let (bx, by) = (self.gx[k], self.gy[k]);
        let slope = bx * u + by * v;
        (u + bx * slope, v + by * slope)
    }

    /// G⁻¹ w = w − c² ∇b (∇b·w) of cell `k`: the inverse of [`Self::lower`].
    #[inline(always)]
    pub fn raise(&self, k: usize, wx: f64, wy: f64) -> (f64, f64) {
        let (bx, by, c) = (self.gx[k], self.gy[k], self.cos[k]);
        let slope = c * c * (bx * wx + by * wy);
        (wx - bx * slope, wy - by * slope)
    }

    /// uᵀ ∇²b u of cell `k` for the horizontal velocity (u, v).
    #[inline(always)]
    pub fn curvature(&self, k: usize, u: f64, v: f64) -> f64 {
        self.hxx[k] * u * u + 2.0 * self.hxy[k] * u * v + self.hyy[k] * v * v
    }

    /// The speed along the surface √(uᵀ G u) of cell `k`.
    #[inline(always)]
    pub fn speed(&self, k: usize, u: f64, v: f64) -> f64 {
        let (bx, by) = (self.gx[k], self.gy[k]);
        let slope = bx * u + by * v;
        (u * u + v * v + slope * slope).sqrt()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_plane_has_its_gradient_and_no_curvature() {
        let (nx, ny, dx, dy) = (5, 4, 2.0, 3.0);
        let b: Vec<f64> = (0..nx * ny)
            .map(|k| 0.7 * (k % nx) as f64 * dx - 0.2 * (k / nx) as f64 * dy)
            .collect();
        let m = BedMetric::new(nx, ny, dx, dy, &b, &[]);
        for k in 0..nx * ny {
            assert!((m.gx[k] - 0.7).abs() < 1e-14 && (m.gy[k] + 0.2).abs() < 1e-14);
            assert!(m.hxx[k].abs() < 1e-13 && m.hxy[k].abs() < 1e-13 && m.hyy[k].abs() < 1e-13);
            assert!((m.cos[k] - 1.0 / (1.0f64 + 0.49 + 0.04).sqrt()).abs() < 1e-15);
            // raise inverts lower; the speed is the length of the tangent vector.
            let (wx, wy) = m.lower(k, 1.3, -0.4);
            let (u, v) = m.raise(k, wx, wy);
            assert!((u - 1.3).abs() < 1e-14 && (v + 0.4).abs() < 1e-14);
            let w = 0.7 * 1.3 + 0.2 * 0.4;
            assert!((m.speed(k, 1.3, -0.4) - (1.3f64 * 1.3 + 0.16 + w * w).sqrt()).abs() < 1e-14);
            assert!((m.speed(k, 1.3, -0.4).powi(2) - (1.3 * wx - 0.4 * wy)).abs() < 1e-13);
        }
    }

    #[test]
    fn a_paraboloid_has_its_hessian() {
        let (nx, ny, dx) = (7, 7, 0.5);
        let b: Vec<f64> = (0..nx * ny)
            .map(|k| {
                let (x, y) = ((k % nx) as f64 * dx, (k / nx) as f64 * dx);
                0.3 * x * x + 0.1 * x * y - 0.2 * y * y
            })
            .collect();
        let m = BedMetric::new(nx, ny, dx, dx, &b, &[]);
        // Interior cells two away from the edges: centred differences are exact for a
        // quadratic.
        for j in 2..ny - 2 {
            for i in 2..nx - 2 {
                let k = j * nx + i;
                assert!((m.hxx[k] - 0.6).abs() < 1e-12, "{}", m.hxx[k]);
                assert!((m.hxy[k] - 0.1).abs() < 1e-12);
                assert!((m.hyy[k] + 0.4).abs() < 1e-12);
                assert!((m.curvature(k, 1.0, 2.0) - (0.6 + 0.4 - 1.6)).abs() < 1e-11);
            }
        }
    }

    #[test]
    fn walls_make_the_differences_one_sided() {
        let (nx, ny) = (3, 1);
        let b = [0.0, 1.0, 5.0];
        let m = BedMetric::new(nx, ny, 1.0, 1.0, &b, &[false, false, true]);
        assert_eq!(m.gx[1], 1.0);
        assert_eq!(m.gx[0], 1.0);
        assert_eq!(m.gy[1], 0.0);
    }
}
