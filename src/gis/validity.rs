//! Validity of release polygons, checked when they are read: a polygon that is not a
//! simple area would be rasterised into something other than what its printed area
//! says (a bow-tie's two lobes cancel, a hole outside its ring subtracts mass that was
//! never there), or into nothing at all (a shapefile whose rings all run the wrong way
//! holds only holes).
//!
//! A polygon is valid when
//! * every vertex is finite;
//! * it has an exterior ring (in a shapefile: a clockwise ring before its holes);
//! * every ring has three or more distinct vertices and encloses an area;
//! * no ring crosses or touches itself (edges that are not neighbours along the ring
//!   share no point);
//! * no two rings cross (they may touch at a point), and every hole lies inside the
//!   exterior ring;
//! * the holes leave some area.
//!
//! The crossing test sweeps the edges sorted by their smallest x, so that ordinary
//! rings of thousands of vertices cost about n log n, not n².

use super::release::{ring_area, Polygon, Ring};

/// Why `polygon` is not a valid area, or `None`. Rings are numbered 0 (the exterior),
/// 1, 2, … (the holes), vertices from 0 in file order.
pub fn invalid_reason(polygon: &Polygon) -> Option<String> {
    let rings: Vec<&Ring> = std::iter::once(&polygon.exterior)
        .chain(&polygon.holes)
        .collect();
    for (r, ring) in rings.iter().enumerate() {
        if let Some(k) = ring
            .iter()
            .position(|p| !(p[0].is_finite() && p[1].is_finite()))
        {
            return Some(format!(
                "vertex {k} of {} is not finite ({}, {})",
                ring_name(r),
                ring[k][0],
                ring[k][1]
            ));
        }
    }
    if polygon.exterior.is_empty() {
        return Some(
            "it has holes but no exterior ring (in a shapefile the exterior rings run \
             clockwise and the holes counter-clockwise: the rings are mis-oriented)"
                .into(),
        );
    }
    let mut cleaned = Vec::with_capacity(rings.len());
    for (r, ring) in rings.iter().enumerate() {
        let pts = distinct_vertices(ring);
        if pts.len() < 3 {
            return Some(format!(
                "{} has {} distinct vertices (a ring needs 3 or more)",
                ring_name(r),
                pts.len()
            ));
        }
        cleaned.push(pts);
    }
    // Crossings first: a symmetric bow-tie has no net area either, and that is not
    // what is wrong with it.
    if let Some(reason) = first_crossing(&cleaned, false) {
        return Some(reason);
    }
    for (r, pts) in cleaned.iter().enumerate() {
        if ring_area(pts) == 0.0 {
            return Some(format!(
                "{} encloses no area (its vertices lie on one line)",
                ring_name(r)
            ));
        }
    }
    if let Some(reason) = first_crossing(&cleaned, true) {
        return Some(reason);
    }
    for (h, hole) in cleaned.iter().enumerate().skip(1) {
        let outside = hole
            .iter()
            .find(|p| !on_boundary(p, &cleaned[0]))
            .is_some_and(|p| !inside(p, &cleaned[0]));
        if outside {
            return Some(format!(
                "{} lies outside the exterior ring (a hole must be inside its polygon)",
                ring_name(h)
            ));
        }
    }
    if polygon.area() <= 0.0 {
        return Some("its holes cover its exterior ring: the polygon encloses no area".to_string());
    }
    None
}

fn ring_name(r: usize) -> String {
    if r == 0 {
        "the exterior ring".into()
    } else {
        format!("hole {r}")
    }
}

/// The ring without repeated consecutive vertices (the closing vertex of a closed ring
/// included).
fn distinct_vertices(ring: &[[f64; 2]]) -> Vec<[f64; 2]> {
    let mut out: Vec<[f64; 2]> = Vec::with_capacity(ring.len());
    for &p in ring {
        if out.last() != Some(&p) {
            out.push(p);
        }
    }
    while out.len() > 1 && out.first() == out.last() {
        out.pop();
    }
    out
}

/// An edge: its ring, its index along the ring and its end points.
struct Edge {
    ring: usize,
    index: usize,
    a: [f64; 2],
    b: [f64; 2],
}

impl Edge {
    fn x_min(&self) -> f64 {
        self.a[0].min(self.b[0])
    }
    fn x_max(&self) -> f64 {
        self.a[0].max(self.b[0])
    }
}

/// The first pair of edges that cross (or, within one ring, touch) and are not
/// neighbours along their ring, described; with `folds`, instead, the first pair of
/// neighbours that fold back onto each other.
fn first_crossing(rings: &[Vec<[f64; 2]>], folds: bool) -> Option<String> {
    let mut edges: Vec<Edge> = Vec::new();
    for (r, ring) in rings.iter().enumerate() {
        let n = ring.len();
        for i in 0..n {
            edges.push(Edge {
                ring: r,
                index: i,
                a: ring[i],
                b: ring[(i + 1) % n],
            });
        }
    }
    edges.sort_by(|e, f| e.x_min().total_cmp(&f.x_min()));
    for (k, e) in edges.iter().enumerate() {
        for f in &edges[k + 1..] {
            if f.x_min() > e.x_max() {
                break;
            }
            let (first, second) = if (e.ring, e.index) < (f.ring, f.index) {
                (e, f)
            } else {
                (f, e)
            };
            if first.ring == second.ring {
                let n = rings[first.ring].len();
                let neighbours =
                    second.index == first.index + 1 || (first.index == 0 && second.index == n - 1);
                if neighbours != folds {
                    continue;
                }
                if neighbours {
                    // Neighbours share a vertex; they are wrong only when they fold back
                    // onto each other (a spike: collinear and overlapping).
                    if folds_back(first, second) {
                        return Some(format!(
                            "{} folds back on itself at vertex {} ({}, {})",
                            ring_name(first.ring),
                            if second.index == first.index + 1 {
                                second.index
                            } else {
                                0
                            },
                            shared(first, second)[0],
                            shared(first, second)[1]
                        ));
                    }
                    continue;
                }
                if segments_touch(first.a, first.b, second.a, second.b) {
                    return Some(format!(
                        "{} crosses or touches itself (edges {} and {}, near ({}, {})): a \
                         bow-tie or figure of eight; split it into simple rings",
                        ring_name(first.ring),
                        first.index,
                        second.index,
                        second.a[0],
                        second.a[1]
                    ));
                }
            } else if !folds && segments_cross(first.a, first.b, second.a, second.b) {
                return Some(format!(
                    "{} and {} cross or overlap (near ({}, {}))",
                    ring_name(first.ring),
                    ring_name(second.ring),
                    second.a[0],
                    second.a[1]
                ));
            }
        }
    }
    None
}

/// The vertex two neighbouring edges share.
fn shared(e: &Edge, f: &Edge) -> [f64; 2] {
    if e.b == f.a {
        e.b
    } else {
        e.a
    }
}

/// Two neighbouring edges that are collinear and turn back (a zero-width spike).
fn folds_back(e: &Edge, f: &Edge) -> bool {
    let p = shared(e, f);
    let u = if e.a == p { e.b } else { e.a };
    let v = if f.a == p { f.b } else { f.a };
    let d1 = [u[0] - p[0], u[1] - p[1]];
    let d2 = [v[0] - p[0], v[1] - p[1]];
    let cross = d1[0] * d2[1] - d1[1] * d2[0];
    let dot = d1[0] * d2[0] + d1[1] * d2[1];
    cross == 0.0 && dot > 0.0
}

/// Sign of the turn a → b → c: > 0 counter-clockwise, < 0 clockwise, 0 collinear.
fn orient(a: [f64; 2], b: [f64; 2], c: [f64; 2]) -> f64 {
    (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
}

/// Whether `p` (collinear with a–b) lies on the segment a–b.
fn within(a: [f64; 2], b: [f64; 2], p: [f64; 2]) -> bool {
    p[0] >= a[0].min(b[0])
        && p[0] <= a[0].max(b[0])
        && p[1] >= a[1].min(b[1])
        && p[1] <= a[1].max(b[1])
}

/// Whether the segments share any point.
fn segments_touch(a: [f64; 2], b: [f64; 2], c: [f64; 2], d: [f64; 2]) -> bool {
    let (o1, o2, o3, o4) = (
        orient(a, b, c),
        orient(a, b, d),
        orient(c, d, a),
        orient(c, d, b),
    );
    if o1 * o2 < 0.0 && o3 * o4 < 0.0 {
        return true;
    }
    (o1 == 0.0 && within(a, b, c))
        || (o2 == 0.0 && within(a, b, d))
        || (o3 == 0.0 && within(c, d, a))
        || (o4 == 0.0 && within(c, d, b))
}

/// Whether the segments cross properly (each one's ends strictly on both sides of the
/// other), or overlap along a stretch.
fn segments_cross(a: [f64; 2], b: [f64; 2], c: [f64; 2], d: [f64; 2]) -> bool {
    let (o1, o2, o3, o4) = (
        orient(a, b, c),
        orient(a, b, d),
        orient(c, d, a),
        orient(c, d, b),
    );
    if o1 * o2 < 0.0 && o3 * o4 < 0.0 {
        return true;
    }
    // Collinear and sharing more than a point.
    if o1 == 0.0 && o2 == 0.0 {
        let axis = if (a[0] - b[0]).abs() >= (a[1] - b[1]).abs() {
            0
        } else {
            1
        };
        let (lo1, hi1) = (a[axis].min(b[axis]), a[axis].max(b[axis]));
        let (lo2, hi2) = (c[axis].min(d[axis]), c[axis].max(d[axis]));
        return lo1.max(lo2) < hi1.min(hi2);
    }
    false
}

fn on_boundary(p: &[f64; 2], ring: &[[f64; 2]]) -> bool {
    let n = ring.len();
    (0..n).any(|i| {
        let (a, b) = (ring[i], ring[(i + 1) % n]);
        orient(a, b, *p) == 0.0 && within(a, b, *p)
    })
}

/// Even-odd point in ring (the point not on the boundary).
fn inside(p: &[f64; 2], ring: &[[f64; 2]]) -> bool {
    let n = ring.len();
    let mut inside = false;
    for i in 0..n {
        let (a, b) = (ring[i], ring[(i + 1) % n]);
        if (a[1] > p[1]) != (b[1] > p[1]) {
            let x = a[0] + (p[1] - a[1]) / (b[1] - a[1]) * (b[0] - a[0]);
            if x > p[0] {
                inside = !inside;
            }
        }
    }
    inside
}

#[cfg(test)]
mod tests {
    use super::*;

    fn square(x0: f64, y0: f64, s: f64) -> Ring {
        vec![
            [x0, y0],
            [x0 + s, y0],
            [x0 + s, y0 + s],
            [x0, y0 + s],
            [x0, y0],
        ]
    }

    #[test]
    fn simple_polygons_pass_and_each_defect_is_named() {
        let mut p = Polygon::new(square(0.0, 0.0, 10.0));
        assert_eq!(invalid_reason(&p), None);
        p.holes.push(square(2.0, 2.0, 3.0));
        assert_eq!(invalid_reason(&p), None);
        // A hole touching the exterior at a corner is allowed.
        p.holes = vec![vec![[0.0, 0.0], [3.0, 1.0], [1.0, 3.0]]];
        assert_eq!(invalid_reason(&p), None);
        let cases: [(Polygon, &str); 7] = [
            (
                Polygon::new(vec![[0.0, 0.0], [10.0, 10.0], [10.0, 0.0], [0.0, 10.0]]),
                "crosses or touches itself",
            ),
            (
                Polygon {
                    exterior: square(0.0, 0.0, 10.0),
                    holes: vec![square(20.0, 20.0, 3.0)],
                },
                "hole 1 lies outside",
            ),
            (
                Polygon {
                    exterior: square(0.0, 0.0, 10.0),
                    holes: vec![square(8.0, 8.0, 3.0)],
                },
                "cross",
            ),
            (
                Polygon {
                    exterior: Vec::new(),
                    holes: vec![square(0.0, 0.0, 1.0)],
                },
                "no exterior ring",
            ),
            (
                Polygon::new(vec![[0.0, 0.0], [f64::NAN, 1.0], [1.0, 1.0]]),
                "vertex 1 of the exterior ring is not finite",
            ),
            (
                Polygon::new(vec![[0.0, 0.0], [1.0, 1.0], [2.0, 2.0], [0.0, 0.0]]),
                "encloses no area",
            ),
            (
                Polygon {
                    exterior: square(0.0, 0.0, 10.0),
                    holes: vec![square(0.0, 0.0, 10.0)],
                },
                "the exterior ring and hole 1 cross or overlap",
            ),
        ];
        for (polygon, words) in cases {
            let reason = invalid_reason(&polygon).unwrap_or_default();
            assert!(reason.contains(words), "{polygon:?}: `{reason}`");
        }
    }
}
