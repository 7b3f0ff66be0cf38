//! An avalanche path (thalweg) as a polyline, and the runout measured along it, as
//! AvaFrame's AIMEC and practitioners report it.
//!
//! # The line
//!
//! Read from a shapefile (`.shp`: the first PolyLine, PolyLineZ or PolyLineM record,
//! its parts joined in order; `.prj` for the CRS) or GeoJSON (the first LineString or
//! MultiLineString of a FeatureCollection, a Feature or a bare geometry; the `crs`
//! member as for release polygons). It runs from the top of the path down: s, the
//! horizontal distance along it, grows downhill.
//!
//! # Along the path
//!
//! A point p is projected onto the nearest segment: its s is the distance along the
//! line to the foot of the perpendicular (the first and the last segment extended past
//! the ends, so a point beyond the end has s beyond the line's length). The runout is
//! the largest s of the cells where a map exceeds a threshold; the top of the release
//! its cell of least s; the runout length is the difference, and the runout angle
//! atan(drop / length), the drop from the top of the release to the runout cell
//! (AvaFrame's AIMEC reports these as runout, runout angle).

use std::path::Path;

use serde_json::Value;

use super::{io_err, Crs, GisError, Result};

/// `output.path`: a thalweg line and the map and threshold that define the runout
/// along it (`gis::path`).
#[derive(Debug, Clone, PartialEq)]
pub struct PathSpec {
    /// The line file, as written in the scenario.
    pub file: std::path::PathBuf,
    pub line: PathLine,
    /// The map: `pft` (m) or `ppr` (Pa).
    pub field: PathField,
    /// The value a cell must exceed to count as reached, in the map's units.
    pub threshold: f64,
    /// Width of the band around the line whose cells count (m); `None`: every cell.
    pub width: Option<f64>,
}

/// The map of [`PathSpec`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PathField {
    Pft,
    Ppr,
}

/// A polyline in map coordinates, top of the path first.
#[derive(Debug, Clone, PartialEq)]
pub struct PathLine {
    pub points: Vec<[f64; 2]>,
    pub crs: Crs,
}

fn bad(path: &Path, reason: impl Into<String>) -> GisError {
    GisError::BadLine {
        path: path.to_path_buf(),
        reason: reason.into(),
    }
}

/// Reads the path from a `.shp` or a GeoJSON file, by extension (see the module docs).
pub fn read(path: &Path) -> Result<PathLine> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .unwrap_or("")
        .to_ascii_lowercase();
    let line = if ext == "shp" {
        read_shapefile(path)?
    } else {
        read_geojson(path)?
    };
    let mut points: Vec<[f64; 2]> = Vec::with_capacity(line.points.len());
    for p in line.points {
        if !(p[0].is_finite() && p[1].is_finite()) {
            return Err(bad(
                path,
                format!("a vertex ({}, {}) is not finite", p[0], p[1]),
            ));
        }
        // Repeated vertices make zero-length segments: dropped.
        if points.last() != Some(&p) {
            points.push(p);
        }
    }
    if points.len() < 2 {
        return Err(bad(path, "the line has fewer than two distinct vertices"));
    }
    Ok(PathLine {
        points,
        crs: line.crs,
    })
}

fn read_shapefile(path: &Path) -> Result<PathLine> {
    use shapefile::Shape;
    let sherr = |source| GisError::Shapefile {
        path: path.to_path_buf(),
        source,
    };
    let mut reader = shapefile::ShapeReader::from_path(path).map_err(sherr)?;
    let mut points = Vec::new();
    for shape in reader.iter_shapes() {
        let parts: Vec<Vec<[f64; 2]>> = match shape.map_err(sherr)? {
            Shape::NullShape => continue,
            Shape::Polyline(l) => l.parts().iter().map(|p| xy(p, |q| [q.x, q.y])).collect(),
            Shape::PolylineM(l) => l.parts().iter().map(|p| xy(p, |q| [q.x, q.y])).collect(),
            Shape::PolylineZ(l) => l.parts().iter().map(|p| xy(p, |q| [q.x, q.y])).collect(),
            other => {
                return Err(bad(
                    path,
                    format!("a {} record: the path must be a line", other.shapetype()),
                ))
            }
        };
        points = parts.concat();
        break;
    }
    let prj = path.with_extension("prj");
    let crs = match std::fs::read_to_string(&prj) {
        Ok(text) => Crs::from_wkt(&text),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Crs::default(),
        Err(e) => return Err(io_err(&prj)(e)),
    };
    Ok(PathLine { points, crs })
}

fn xy<P>(points: &[P], f: impl Fn(&P) -> [f64; 2]) -> Vec<[f64; 2]> {
    points.iter().map(f).collect()
}

fn read_geojson(path: &Path) -> Result<PathLine> {
    let text = std::fs::read_to_string(path).map_err(io_err(path))?;
    let root: Value =
        serde_json::from_str(&text).map_err(|e| bad(path, format!("not JSON: {e}")))?;
    let crs = super::release::geojson_crs(&root);
    let geometries: Vec<&Value> = match root.get("type").and_then(Value::as_str) {
        Some("FeatureCollection") => root
            .get("features")
            .and_then(Value::as_array)
            .map(|f| f.iter().filter_map(|f| f.get("geometry")).collect())
            .unwrap_or_default(),
        Some("Feature") => root.get("geometry").into_iter().collect(),
        _ => vec![&root],
    };
    let pair = |v: &Value| -> Option<[f64; 2]> {
        let a = v.as_array()?;
        Some([a.first()?.as_f64()?, a.get(1)?.as_f64()?])
    };
    let line = |v: &Value| -> Option<Vec<[f64; 2]>> {
        v.as_array()?.iter().map(pair).collect::<Option<Vec<_>>>()
    };
    for g in geometries {
        let coords = g.get("coordinates");
        let points = match (g.get("type").and_then(Value::as_str), coords) {
            (Some("LineString"), Some(c)) => line(c),
            (Some("MultiLineString"), Some(c)) => c
                .as_array()
                .and_then(|parts| parts.iter().map(line).collect::<Option<Vec<_>>>())
                .map(|parts| parts.concat()),
            _ => continue,
        };
        let points =
            points.ok_or_else(|| bad(path, "a line's coordinates are not [x, y] pairs"))?;
        return Ok(PathLine { points, crs });
    }
    Err(bad(path, "no LineString or MultiLineString in the file"))
}

impl PathLine {
    /// (s, distance) of `p`: s the distance along the line to the foot of the
    /// perpendicular on the nearest segment (the end segments extended), and the
    /// distance to it.
    pub fn project(&self, p: [f64; 2]) -> (f64, f64) {
        let n = self.points.len();
        let mut best = (f64::NAN, f64::INFINITY);
        let mut start = 0.0;
        for i in 0..n - 1 {
            let (a, b) = (self.points[i], self.points[i + 1]);
            let (ex, ey) = (b[0] - a[0], b[1] - a[1]);
            let len = ex.hypot(ey);
            let along = ((p[0] - a[0]) * ex + (p[1] - a[1]) * ey) / len;
            // Clamped to the segment, except past the ends of the line.
            let lo = if i == 0 { f64::NEG_INFINITY } else { 0.0 };
            let hi = if i == n - 2 { f64::INFINITY } else { len };
            let t = along.clamp(lo, hi);
            let foot = [a[0] + ex * t / len, a[1] + ey * t / len];
            let d = (p[0] - foot[0]).hypot(p[1] - foot[1]);
            if d < best.1 {
                best = (start + t, d);
            }
            start += len;
        }
        best
    }

    /// The horizontal length of the line (m).
    pub fn length(&self) -> f64 {
        self.points
            .windows(2)
            .map(|w| (w[1][0] - w[0][0]).hypot(w[1][1] - w[0][1]))
            .sum()
    }

    /// The point at distance `s` along the line, the end segments extended past the
    /// ends (negative s before the first vertex).
    pub fn point_at(&self, s: f64) -> [f64; 2] {
        let n = self.points.len();
        let mut start = 0.0;
        for i in 0..n - 1 {
            let (a, b) = (self.points[i], self.points[i + 1]);
            let len = (b[0] - a[0]).hypot(b[1] - a[1]);
            if s <= start + len || i == n - 2 {
                let t = (s - start) / len;
                return [a[0] + (b[0] - a[0]) * t, a[1] + (b[1] - a[1]) * t];
            }
            start += len;
        }
        unreachable!("a line has at least two vertices")
    }
}

/// The runout along a path.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PathRunout {
    /// s of the runout cell (m from the line's first vertex).
    pub runout_s: f64,
    /// s of the top of the release.
    pub top_s: f64,
    /// runout_s − top_s (m).
    pub length: f64,
    /// atan(drop / length) (degrees).
    pub angle_deg: f64,
    /// The runout cell's centre.
    pub runout_xy: [f64; 2],
}

/// The runout along `line` of the cells `(x, y, z)` where `over` holds, from the top
/// of the release (the cells where `release` holds); `None` when either set is empty.
pub fn runout(
    line: &PathLine,
    cells: impl Fn(usize) -> [f64; 3],
    n: usize,
    over: impl Fn(usize) -> bool,
    release: impl Fn(usize) -> bool,
) -> Option<PathRunout> {
    let s = |k: usize| {
        let c = cells(k);
        line.project([c[0], c[1]]).0
    };
    let extreme = |keep: &dyn Fn(usize) -> bool, largest: bool| {
        (0..n)
            .filter(|&k| keep(k))
            .map(|k| (k, s(k)))
            .reduce(|a, b| {
                if (b.1 > a.1) == largest && b.1 != a.1 {
                    b
                } else {
                    a
                }
            })
    };
    let (r, runout_s) = extreme(&over, true)?;
    let (t, top_s) = extreme(&release, false)?;
    let length = runout_s - top_s;
    let drop = cells(t)[2] - cells(r)[2];
    let c = cells(r);
    Some(PathRunout {
        runout_s,
        top_s,
        length,
        angle_deg: drop.atan2(length).to_degrees(),
        runout_xy: [c[0], c[1]],
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn l() -> PathLine {
        PathLine {
            points: vec![[0.0, 0.0], [10.0, 0.0], [10.0, -10.0]],
            crs: Crs::default(),
        }
    }

    #[test]
    fn points_project_onto_the_nearest_segment_and_past_the_ends() {
        let line = l();
        assert_eq!(line.project([5.0, 1.0]), (5.0, 1.0));
        assert_eq!(line.project([11.0, -4.0]), (14.0, 1.0));
        // Beyond the end of the last segment: s beyond the length (20 m).
        assert_eq!(line.project([10.0, -13.0]), (23.0, 0.0));
        // Before the first vertex: negative s.
        assert_eq!(line.project([-2.0, 0.0]), (-2.0, 0.0));
    }

    #[test]
    fn points_at_s_lie_on_the_line_and_past_its_ends() {
        let line = l();
        assert_eq!(line.length(), 20.0);
        assert_eq!(line.point_at(4.0), [4.0, 0.0]);
        assert_eq!(line.point_at(14.0), [10.0, -4.0]);
        assert_eq!(line.point_at(23.0), [10.0, -13.0]);
        assert_eq!(line.point_at(-2.0), [-2.0, 0.0]);
    }

    #[test]
    fn the_runout_is_the_farthest_cell_over_the_threshold_from_the_release_top() {
        // Cells along the line, z falling 1 m per m of s.
        let cells = [
            [1.0, 0.0, 20.0],
            [5.0, 0.0, 15.0],
            [10.0, -5.0, 5.0],
            [10.0, -8.0, 2.0],
        ];
        let r = runout(&l(), |k| cells[k], 4, |k| k <= 2, |k| k <= 1).unwrap();
        assert_eq!((r.top_s, r.runout_s, r.length), (1.0, 15.0, 14.0));
        assert!((r.angle_deg - (15.0f64 / 14.0).atan().to_degrees()).abs() < 1e-12);
        assert_eq!(r.runout_xy, [10.0, -5.0]);
        assert!(runout(&l(), |k| cells[k], 4, |_| false, |_| true).is_none());
    }
}
