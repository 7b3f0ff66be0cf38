//! The [`Raster`] type, cropping and coarsening.

use super::{nearly_equal, Crs, GisError, Result};

/// An axis-aligned box in map coordinates.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Bbox {
    pub x_min: f64,
    pub x_max: f64,
    pub y_min: f64,
    pub y_max: f64,
}

/// A north-up grid of square cells with one `f64` per cell; see the [module
/// docs](super) for the conventions (origin at the top-left corner, row 0 at the top).
#[derive(Debug, Clone, PartialEq)]
pub struct Raster {
    /// Columns.
    pub nx: usize,
    /// Rows.
    pub ny: usize,
    /// x of the left edge of column 0.
    pub x_left: f64,
    /// y of the top edge of row 0.
    pub y_top: f64,
    /// Side of the square cells (map units, > 0).
    pub cell_size: f64,
    /// `values[row * nx + col]`, row 0 at the top, `nx * ny` of them.
    pub values: Vec<f64>,
    /// The value that marks a cell without data (NaN allowed), if any.
    pub nodata: Option<f64>,
    /// The coordinate reference system, carried through.
    pub crs: Crs,
}

impl Raster {
    /// A raster of `nx × ny` cells, all `fill`, without nodata or CRS.
    ///
    /// # Panics
    /// When `nx` or `ny` is 0 or `cell_size` is not positive and finite.
    pub fn filled(
        nx: usize,
        ny: usize,
        x_left: f64,
        y_top: f64,
        cell_size: f64,
        fill: f64,
    ) -> Raster {
        assert!(nx > 0 && ny > 0, "empty raster {nx} x {ny}");
        assert!(
            cell_size.is_finite() && cell_size > 0.0,
            "cell size {cell_size} must be positive"
        );
        Raster {
            nx,
            ny,
            x_left,
            y_top,
            cell_size,
            values: vec![fill; nx * ny],
            nodata: None,
            crs: Crs::default(),
        }
    }

    /// A raster on the same grid (and CRS) as `self`, all `fill`, without nodata.
    pub fn same_grid(&self, fill: f64) -> Raster {
        Raster {
            values: vec![fill; self.nx * self.ny],
            nodata: None,
            ..self.header_clone()
        }
    }

    fn header_clone(&self) -> Raster {
        Raster {
            nx: self.nx,
            ny: self.ny,
            x_left: self.x_left,
            y_top: self.y_top,
            cell_size: self.cell_size,
            values: Vec::new(),
            nodata: self.nodata,
            crs: self.crs.clone(),
        }
    }

    /// x of the right edge.
    pub fn x_right(&self) -> f64 {
        self.x_left + self.nx as f64 * self.cell_size
    }

    /// y of the bottom edge.
    pub fn y_bottom(&self) -> f64 {
        self.y_top - self.ny as f64 * self.cell_size
    }

    /// The extent of the grid.
    pub fn bbox(&self) -> Bbox {
        Bbox {
            x_min: self.x_left,
            x_max: self.x_right(),
            y_min: self.y_bottom(),
            y_max: self.y_top,
        }
    }

    /// Area of one cell (map units squared).
    pub fn cell_area(&self) -> f64 {
        self.cell_size * self.cell_size
    }

    /// Index of cell `(col, row)` in [`Raster::values`].
    #[inline]
    pub fn index(&self, col: usize, row: usize) -> usize {
        debug_assert!(col < self.nx && row < self.ny);
        row * self.nx + col
    }

    /// The centre of cell `(col, row)`.
    pub fn cell_centre(&self, col: usize, row: usize) -> (f64, f64) {
        (
            self.x_left + (col as f64 + 0.5) * self.cell_size,
            self.y_top - (row as f64 + 0.5) * self.cell_size,
        )
    }

    /// Whether `v` is the nodata value (NaN matches a NaN nodata).
    #[inline]
    pub fn is_nodata(&self, v: f64) -> bool {
        match self.nodata {
            Some(nd) if nd.is_nan() => v.is_nan(),
            Some(nd) => v == nd,
            None => false,
        }
    }

    /// The value of cell `(col, row)`, or `None` for a nodata cell.
    pub fn get(&self, col: usize, row: usize) -> Option<f64> {
        let v = self.values[self.index(col, row)];
        (!self.is_nodata(v)).then_some(v)
    }

    /// Checks the invariants (sizes, positive finite cell size, finite origin).
    pub fn check(&self) -> std::result::Result<(), String> {
        if self.nx == 0 || self.ny == 0 {
            return Err(format!("empty grid {} x {}", self.nx, self.ny));
        }
        if self.values.len() != self.nx * self.ny {
            return Err(format!(
                "{} values for {} x {} cells",
                self.values.len(),
                self.nx,
                self.ny
            ));
        }
        if !(self.cell_size.is_finite() && self.cell_size > 0.0) {
            return Err(format!("cell size {} is not positive", self.cell_size));
        }
        if !(self.x_left.is_finite() && self.y_top.is_finite()) {
            return Err(format!(
                "origin ({}, {}) is not finite",
                self.x_left, self.y_top
            ));
        }
        Ok(())
    }

    /// Refuses `other` unless it has the same grid (nx, ny, cell size and origin within
    /// 10⁻⁹ of a cell) and a compatible CRS.
    pub fn check_same_grid(&self, other: &Raster) -> Result<()> {
        let tol = 1e-9 * self.cell_size;
        let reason = if (self.nx, self.ny) != (other.nx, other.ny) {
            Some(format!(
                "{} x {} cells against {} x {}",
                self.nx, self.ny, other.nx, other.ny
            ))
        } else if !nearly_equal(self.cell_size, other.cell_size) {
            Some(format!(
                "cell size {} against {}",
                self.cell_size, other.cell_size
            ))
        } else if (self.x_left - other.x_left).abs() > tol || (self.y_top - other.y_top).abs() > tol
        {
            Some(format!(
                "top-left corner ({}, {}) against ({}, {})",
                self.x_left, self.y_top, other.x_left, other.y_top
            ))
        } else {
            None
        };
        if let Some(reason) = reason {
            return Err(GisError::GridMismatch { reason });
        }
        self.crs
            .check_same("the first raster", &other.crs, "the second raster")
    }

    /// The cells whose centres lie in `bbox` (edges included), as a new raster on the
    /// same grid lines (nothing is resampled). Errors when no centre is inside.
    pub fn crop(&self, bbox: Bbox) -> Result<Raster> {
        let d = self.cell_size;
        // Column c is kept when x_min <= centre_c <= x_max; a centre within 10⁻⁹ of a
        // cell of an edge counts as on it (the edge may be a centre computed in
        // floating point, one ulp off at 1e5 m).
        const EDGE: f64 = 1e-9;
        let c0 = ((bbox.x_min - self.x_left) / d - 0.5 - EDGE)
            .ceil()
            .max(0.0);
        let c1 = ((bbox.x_max - self.x_left) / d - 0.5 + EDGE)
            .floor()
            .min(self.nx as f64 - 1.0);
        let r0 = ((self.y_top - bbox.y_max) / d - 0.5 - EDGE).ceil().max(0.0);
        let r1 = ((self.y_top - bbox.y_min) / d - 0.5 + EDGE)
            .floor()
            .min(self.ny as f64 - 1.0);
        if !(c0 <= c1 && r0 <= r1) {
            return Err(GisError::EmptyCrop {
                x0: bbox.x_min,
                x1: bbox.x_max,
                y0: bbox.y_min,
                y1: bbox.y_max,
            });
        }
        let (c0, c1, r0, r1) = (c0 as usize, c1 as usize, r0 as usize, r1 as usize);
        self.window(c0, r0, c1 - c0 + 1, r1 - r0 + 1)
    }

    /// The `nx` × `ny` cells from column `col0` and row `row0` (rows from the top), as
    /// a new raster on the same grid lines. Indices, not coordinates: a cut by whole
    /// cells cannot lose a row to rounding, as a box in metres can on a grid whose
    /// cell size is not round (4.9977 m at 1.8e5 m). Errors when the window is empty
    /// or leaves the grid.
    pub fn window(&self, col0: usize, row0: usize, nx: usize, ny: usize) -> Result<Raster> {
        if nx == 0 || ny == 0 || col0 + nx > self.nx || row0 + ny > self.ny {
            return Err(GisError::BadWindow(format!(
                "the window of {nx} x {ny} cells from column {col0}, row {row0} is not inside the {} x {} grid",
                self.nx, self.ny
            )));
        }
        let d = self.cell_size;
        let mut values = Vec::with_capacity(nx * ny);
        for row in row0..row0 + ny {
            let start = row * self.nx + col0;
            values.extend_from_slice(&self.values[start..start + nx]);
        }
        Ok(Raster {
            nx,
            ny,
            x_left: self.x_left + col0 as f64 * d,
            y_top: self.y_top - row0 as f64 * d,
            values,
            ..self.header_clone()
        })
    }

    /// Coarsens by an integer `factor`: each `factor × factor` block becomes one cell,
    /// the mean of its valid (non-nodata) cells, or nodata when the block has none.
    /// `nx` and `ny` must be multiples of `factor` (crop first). The top-left corner is
    /// kept; the cell size becomes `factor × cell_size`.
    pub fn coarsen(&self, factor: usize) -> Result<Raster> {
        if factor == 0 {
            return Err(GisError::BadCoarsen {
                factor,
                reason: "the factor must be at least 1".into(),
            });
        }
        if !self.nx.is_multiple_of(factor) || !self.ny.is_multiple_of(factor) {
            return Err(GisError::BadCoarsen {
                factor,
                reason: format!(
                    "{} x {} cells is not a multiple of {factor} in both directions; crop first",
                    self.nx, self.ny
                ),
            });
        }
        let nx = self.nx / factor;
        let ny = self.ny / factor;
        let mut sum = vec![0.0; nx * ny];
        let mut count = vec![0u32; nx * ny];
        for row in 0..self.ny {
            let out_row = (row / factor) * nx;
            let line = &self.values[row * self.nx..(row + 1) * self.nx];
            for (col, &v) in line.iter().enumerate() {
                if !self.is_nodata(v) {
                    sum[out_row + col / factor] += v;
                    count[out_row + col / factor] += 1;
                }
            }
        }
        let empty = self.nodata.unwrap_or(f64::NAN);
        let values = sum
            .iter()
            .zip(&count)
            .map(|(&s, &n)| if n == 0 { empty } else { s / n as f64 })
            .collect::<Vec<_>>();
        let nodata = if count.contains(&0) {
            Some(empty)
        } else {
            self.nodata
        };
        Ok(Raster {
            nx,
            ny,
            cell_size: self.cell_size * factor as f64,
            values,
            nodata,
            ..self.header_clone()
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ramp() -> Raster {
        let mut r = Raster::filled(6, 4, 100.0, 50.0, 2.0, 0.0);
        for (i, v) in r.values.iter_mut().enumerate() {
            *v = i as f64;
        }
        r
    }

    #[test]
    fn crop_keeps_cells_whose_centres_are_inside() {
        let r = ramp();
        // Centres x: 101, 103, ... 111; y: 49, 47, 45, 43.
        let c = r
            .crop(Bbox {
                x_min: 102.5,
                x_max: 106.9,
                y_min: 44.0,
                y_max: 48.0,
            })
            .unwrap();
        assert_eq!((c.nx, c.ny), (2, 2));
        assert_eq!((c.x_left, c.y_top), (102.0, 48.0));
        assert_eq!(c.values, vec![7.0, 8.0, 13.0, 14.0]);
        // A centre on the box edge is inside.
        let c = r
            .crop(Bbox {
                x_min: 103.0,
                x_max: 107.0,
                y_min: 45.0,
                y_max: 47.0,
            })
            .unwrap();
        assert_eq!((c.nx, c.ny, c.x_left, c.y_top), (3, 2, 102.0, 48.0));
        assert!(matches!(
            r.crop(Bbox {
                x_min: 0.0,
                x_max: 1.0,
                y_min: 0.0,
                y_max: 1.0
            }),
            Err(GisError::EmptyCrop { .. })
        ));
    }

    #[test]
    fn coarsen_is_a_nodata_aware_block_mean() {
        let mut r = ramp();
        r.nodata = Some(-9999.0);
        r.values[0] = -9999.0;
        let c = r.coarsen(2).unwrap();
        assert_eq!((c.nx, c.ny, c.cell_size), (3, 2, 4.0));
        assert_eq!((c.x_left, c.y_top), (100.0, 50.0));
        // Block (0, 0) holds 0 (nodata), 1, 6, 7.
        assert_eq!(c.values[0], (1.0 + 6.0 + 7.0) / 3.0);
        assert_eq!(c.values[1], (2.0 + 3.0 + 8.0 + 9.0) / 4.0);
        r.values[1] = -9999.0;
        r.values[6] = -9999.0;
        r.values[7] = -9999.0;
        let c = r.coarsen(2).unwrap();
        assert_eq!(c.values[0], -9999.0);
        assert!(c.get(0, 0).is_none());
        assert!(matches!(r.coarsen(4), Err(GisError::BadCoarsen { .. })));
    }
}
