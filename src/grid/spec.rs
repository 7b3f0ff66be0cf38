//! What a grid is on the map, as one value: [`GridSpec`], built once from the
//! scenario and carried unchanged to the output file (`/grid` attributes,
//! docs/output-format.md) and back to `granflow export` and `maps`.
//!
//! A line is nx cells of width Δx from x_min to x_max. A raster is nx × ny cells of
//! Δx × Δy covering [x_min, x_max] × [y_min, y_max], with the coordinate reference
//! system of its raster files. The run numbers its cells row-major from the south
//! edge (cell j·nx + i at y_min + (j + ½)Δy); a GIS raster (GeoTIFF, ESRI ASCII grid)
//! starts at the north edge. [`north_up`] is the one place that turns one order into
//! the other.
//!
//! The edges and cell sizes are kept as given: the four edges of a domain given by its
//! keys (Δx = (x_max − x_min)/nx), or the west edge, north edge and cell size of a DEM
//! exactly as read (its east and south edges then follow from them), so that a map
//! written from a run sits on the DEM's very grid.

use crate::gis::Crs;

/// The geometry of a grid.
#[derive(Debug, Clone, PartialEq)]
pub enum GridSpec {
    Line(LineGeometry),
    Raster(RasterGeometry),
}

impl GridSpec {
    /// The raster's geometry, `None` on a line.
    pub fn raster(&self) -> Option<&RasterGeometry> {
        match self {
            GridSpec::Raster(r) => Some(r),
            GridSpec::Line(_) => None,
        }
    }
}

/// A uniform line of nx cells of width Δx from x_min to x_max.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LineGeometry {
    pub nx: usize,
    pub x_min: f64,
    pub x_max: f64,
    pub dx: f64,
}

impl LineGeometry {
    /// The line of nx cells from x_min to x_max: Δx = (x_max − x_min)/nx.
    pub fn of_extent(nx: usize, x_min: f64, x_max: f64) -> LineGeometry {
        LineGeometry {
            nx,
            x_min,
            x_max,
            dx: (x_max - x_min) / nx as f64,
        }
    }
}

/// A uniform raster of nx × ny cells of Δx × Δy on [x_min, x_max] × [y_min, y_max].
#[derive(Debug, Clone, PartialEq)]
pub struct RasterGeometry {
    pub nx: usize,
    pub ny: usize,
    /// West edge.
    pub x_min: f64,
    /// East edge.
    pub x_max: f64,
    /// South edge.
    pub y_min: f64,
    /// North edge.
    pub y_max: f64,
    pub dx: f64,
    pub dy: f64,
    /// The coordinate reference system of the raster files (carried, never used).
    pub crs: Crs,
}

impl RasterGeometry {
    /// The raster of a domain given by its edges: Δx = (x_max − x_min)/nx,
    /// Δy = (y_max − y_min)/ny, no CRS.
    pub fn of_extent(nx: usize, ny: usize, x: [f64; 2], y: [f64; 2]) -> RasterGeometry {
        RasterGeometry {
            nx,
            ny,
            x_min: x[0],
            x_max: x[1],
            y_min: y[0],
            y_max: y[1],
            dx: (x[1] - x[0]) / nx as f64,
            dy: (y[1] - y[0]) / ny as f64,
            crs: Crs::unknown(),
        }
    }

    /// The numbers of the geometry as text that reads back to the same doubles
    /// (`nx ny x_min x_max y_min y_max dx dy`): the `/grid` attribute `spec`, which
    /// granflow reads back (its HDF5 library reads strings from a group's attributes,
    /// not numbers).
    pub fn to_text(&self) -> String {
        let RasterGeometry {
            nx,
            ny,
            x_min,
            x_max,
            y_min,
            y_max,
            dx,
            dy,
            crs: _,
        } = self;
        format!("{nx} {ny} {x_min} {x_max} {y_min} {y_max} {dx} {dy}")
    }

    /// The geometry of [`RasterGeometry::to_text`] with the CRS `crs`; `None` for text
    /// that is not eight numbers, an empty raster or an extent or cell size that is not
    /// finite and positive.
    pub fn from_text(text: &str, crs: Crs) -> Option<RasterGeometry> {
        let words: Vec<&str> = text.split_whitespace().collect();
        let [nx, ny, rest @ ..] = words.as_slice() else {
            return None;
        };
        let v: Vec<f64> = rest
            .iter()
            .map(|w| w.parse())
            .collect::<Result<_, _>>()
            .ok()?;
        let &[x_min, x_max, y_min, y_max, dx, dy] = v.as_slice() else {
            return None;
        };
        let g = RasterGeometry {
            nx: nx.parse().ok()?,
            ny: ny.parse().ok()?,
            x_min,
            x_max,
            y_min,
            y_max,
            dx,
            dy,
            crs,
        };
        let positive = |a: f64| a.is_finite() && a > 0.0;
        (g.nx > 0
            && g.ny > 0
            && v.iter().all(|a| a.is_finite())
            && positive(x_max - x_min)
            && positive(y_max - y_min)
            && positive(dx)
            && positive(dy))
        .then_some(g)
    }
}

/// The values of a raster field in the run's order (row 0 at the south edge) in the
/// order of a GIS raster (row 0 at the north edge); the same flip takes them back.
pub fn north_up<T: Copy>(values: &[T], nx: usize, ny: usize) -> Vec<T> {
    debug_assert_eq!(values.len(), nx * ny);
    let mut out = Vec::with_capacity(nx * ny);
    for row in values.chunks(nx).rev() {
        out.extend_from_slice(row);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_text_reads_back_to_the_same_doubles() {
        let g = RasterGeometry {
            nx: 7,
            ny: 3,
            x_min: 2_600_123.1,
            x_max: 2_600_123.1 + 7.0 * 0.1,
            y_min: 1_200_000.0 - 3.0 * 0.1,
            y_max: 1_200_000.0,
            dx: 0.1,
            dy: 0.1,
            crs: Crs::from_epsg(2056),
        };
        let back = RasterGeometry::from_text(&g.to_text(), Crs::from_epsg(2056)).unwrap();
        assert_eq!(back, g);
        assert_eq!(
            RasterGeometry::from_text("7 3 0 1 0 1 0.1", Crs::unknown()),
            None
        );
        assert_eq!(
            RasterGeometry::from_text("0 3 0 1 0 1 0.1 0.1", Crs::unknown()),
            None
        );
        assert_eq!(
            RasterGeometry::from_text("7 3 1 0 0 1 0.1 0.1", Crs::unknown()),
            None
        );
    }

    #[test]
    fn north_up_flips_the_rows_and_back() {
        let v = [1, 2, 3, 4, 5, 6];
        assert_eq!(north_up(&v, 2, 3), vec![5, 6, 3, 4, 1, 2]);
        assert_eq!(north_up(&north_up(&v, 2, 3), 2, 3), v.to_vec());
    }
}
