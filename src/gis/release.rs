//! Release areas: polygons with a thickness, read from a shapefile or GeoJSON and
//! rasterised onto a [`Raster`]'s grid.
//!
//! # Sources
//!
//! * **Shapefile**: `.shp` (Polygon, PolygonZ, PolygonM records; rings marked outer or
//!   inner by their orientation, as the format defines), `.dbf` for the attributes (a
//!   numeric thickness field per polygon, when [`ThicknessSource::Attribute`] names
//!   one), `.prj` for the CRS.
//! * **GeoJSON**: a FeatureCollection, a Feature or a bare geometry; Polygon (first ring
//!   the exterior, the others holes) and MultiPolygon geometries; the thickness in a
//!   feature property. The CRS is read from the (pre-RFC 7946) `crs` member QGIS and
//!   GDAL write for non-WGS 84 files (`urn:ogc:def:crs:EPSG::2056`, `EPSG:2056`,
//!   `CRS84` → 4326); without it the CRS is unknown and not compared.
//!
//! # Rasterisation rules
//!
//! [`CoverageRule::CellCentre`]: a cell is released (fraction 1) when its centre is
//! inside the polygon (inside the exterior, outside every hole; a centre exactly on an
//! edge follows a half-open rule so that two polygons sharing an edge never both take a
//! cell). The released area differs from the polygon's by O(perimeter × cell size).
//!
//! [`CoverageRule::AreaFraction`]: each cell gets the fraction of its area the polygon
//! covers (the polygon clipped to the cell, computed exactly from the edges), so the
//! released area equals the polygon's to rounding, on any grid.
//!
//! Features are rasterised one by one and their thickness × fraction added: overlapping
//! features stack. Within a feature the fraction is clamped to [0, 1]. The released
//! volume is `Σ thickness × fraction × cell area`. Cells where the grid has no data
//! (walls) get nodata and no volume; the volume that fell there is reported apart.
//!
//! A feature entirely outside the raster, or with more than 10⁻⁶ of its area outside,
//! is refused (that mass would be lost); a release and a raster whose CRS are both known
//! by an EPSG code and differ are refused.
//!
//! # Slope-normal thickness
//!
//! Field surveys and AvaFrame give the release thickness *normal to the slope*; the
//! depth-averaged equations on a horizontal grid need the *vertical* thickness
//! `h_v = h_n / cos θ`, θ the local slope of the DEM ([`vertical_thickness`],
//! [`slope_cosine`]: central differences, one-sided at the border and next to nodata).
//! The slab of normal thickness `h_n` over a horizontal area `A` holds `h_n·A / cos θ`:
//! converting raises the released volume by `1 / cos θ` over the naive `h_n·A` (15 % at
//! 30°).

use std::path::Path;

use serde_json::Value;

use super::{io_err, Crs, GisError, Raster, Result};

/// A ring of `[x, y]` vertices (closed or not: the closing edge is implied).
pub type Ring = Vec<[f64; 2]>;

/// A polygon: one exterior ring and its holes (any orientation).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Polygon {
    pub exterior: Ring,
    pub holes: Vec<Ring>,
}

impl Polygon {
    /// A polygon without holes.
    pub fn new(exterior: Ring) -> Polygon {
        Polygon {
            exterior,
            holes: Vec::new(),
        }
    }

    /// Area: the exterior's minus the holes'.
    pub fn area(&self) -> f64 {
        ring_area(&self.exterior).abs() - self.holes.iter().map(|h| ring_area(h).abs()).sum::<f64>()
    }
}

/// One release feature: polygons and the thickness released inside them.
#[derive(Debug, Clone, PartialEq)]
pub struct ReleaseFeature {
    pub polygons: Vec<Polygon>,
    /// Thickness (map units, ≥ 0), vertical or slope-normal as the user states.
    pub thickness: f64,
}

/// Release features and their CRS.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct ReleaseAreas {
    pub features: Vec<ReleaseFeature>,
    pub crs: Crs,
}

/// Where the thickness of each feature comes from.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ThicknessSource<'a> {
    /// The same thickness for every feature.
    Uniform(f64),
    /// A numeric attribute (`.dbf` field, GeoJSON property) of each feature.
    Attribute(&'a str),
}

/// How a polygon covers a cell.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum CoverageRule {
    /// Fraction 1 when the cell centre is inside, else 0.
    CellCentre,
    /// The covered fraction of the cell's area.
    #[default]
    AreaFraction,
}

/// A rasterised release.
#[derive(Debug, Clone, PartialEq)]
pub struct Release {
    /// Thickness per cell, on the grid it was rasterised on (nodata where the grid is).
    pub thickness: Raster,
    /// `Σ thickness × cell area` over the cells with data.
    pub volume: f64,
    /// The volume that fell on nodata cells (walls) and was dropped.
    pub volume_on_nodata: f64,
}

/// Reads release areas from a `.shp` or a `.geojson`/`.json` file, by extension.
pub fn read(path: &Path, thickness: ThicknessSource) -> Result<ReleaseAreas> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .unwrap_or("")
        .to_ascii_lowercase();
    match ext.as_str() {
        "shp" => read_shapefile(path, thickness),
        _ => read_geojson(path, thickness),
    }
}

fn bad_thickness(path: &Path, feature: usize, value: String) -> GisError {
    GisError::BadThickness {
        path: path.to_path_buf(),
        feature,
        value,
    }
}

/// Refuses a feature with a polygon that is not a simple area ([`super::validity`]).
fn check_polygons(path: &Path, feature: usize, polygons: &[Polygon]) -> Result<()> {
    for (k, p) in polygons.iter().enumerate() {
        if let Some(reason) = super::validity::invalid_reason(p) {
            let which = if polygons.len() > 1 {
                format!("polygon {k}: ")
            } else {
                String::new()
            };
            return Err(GisError::InvalidPolygon {
                path: path.to_path_buf(),
                feature,
                reason: format!("{which}{reason}"),
            });
        }
    }
    Ok(())
}

fn check_thickness(path: &Path, feature: usize, v: f64) -> Result<f64> {
    if v.is_finite() && v >= 0.0 {
        Ok(v)
    } else {
        Err(bad_thickness(path, feature, format!("{v}")))
    }
}

/// Reads a shapefile (`.shp`, the `.dbf` when an attribute is named, the `.prj` if
/// present). Features are numbered from 0 in file order.
pub fn read_shapefile(path: &Path, thickness: ThicknessSource) -> Result<ReleaseAreas> {
    let sherr = |source| GisError::Shapefile {
        path: path.to_path_buf(),
        source,
    };
    if std::fs::metadata(path).map_err(io_err(path))?.len() == 0 {
        return Err(GisError::EmptyFile {
            path: path.to_path_buf(),
        });
    }
    // The shapefile library opens these itself: a FIFO among them would block it.
    let mut present = [false; 5];
    for (seen, ext) in present.iter_mut().zip(["dbf", "shx", "prj", "cpg", "shp"]) {
        *seen = super::regular_if_present(&path.with_extension(ext))?;
    }
    if let (ThicknessSource::Attribute(field), false) = (thickness, present[0]) {
        return Err(GisError::MissingSidecar {
            path: path.with_extension("dbf"),
            reason: format!(
                "the thickness attribute `{field}` is read from the shapefile's attribute \
                 table, which is missing"
            ),
        });
    }
    let mut features = Vec::new();
    match thickness {
        ThicknessSource::Uniform(h) => {
            let h = check_thickness(path, 0, h)?;
            let mut reader = shapefile::ShapeReader::from_path(path).map_err(sherr)?;
            for (i, shape) in reader.iter_shapes().enumerate() {
                let shape = shape.map_err(sherr)?;
                if let Some(polygons) = shape_polygons(path, i, shape)? {
                    features.push(ReleaseFeature {
                        polygons,
                        thickness: h,
                    });
                }
            }
        }
        ThicknessSource::Attribute(field) => {
            let mut reader = shapefile::Reader::from_path(path).map_err(sherr)?;
            for (i, item) in reader.iter_shapes_and_records().enumerate() {
                let (shape, record) = item.map_err(sherr)?;
                let value = record.get(field).ok_or_else(|| {
                    let names = record.clone().into_iter().map(|(name, _)| name).collect();
                    missing_attribute(path, i, field, names)
                })?;
                use shapefile::dbase::FieldValue as F;
                let h = match value {
                    F::Numeric(Some(v)) | F::Double(v) | F::Currency(v) => *v,
                    F::Float(Some(v)) => f64::from(*v),
                    F::Integer(v) => f64::from(*v),
                    F::Character(Some(s)) => s
                        .trim()
                        .parse()
                        .map_err(|_| bad_thickness(path, i, format!("`{s}`")))?,
                    other => return Err(bad_thickness(path, i, format!("{other:?}"))),
                };
                let h = check_thickness(path, i, h)?;
                if let Some(polygons) = shape_polygons(path, i, shape)? {
                    features.push(ReleaseFeature {
                        polygons,
                        thickness: h,
                    });
                }
            }
        }
    }
    if features.is_empty() {
        return Err(GisError::NoPolygons {
            path: path.to_path_buf(),
        });
    }
    let crs = super::read_sidecar(&path.with_extension("prj"))?
        .map(|text| Crs::from_wkt(&text))
        .unwrap_or_default();
    Ok(ReleaseAreas { features, crs })
}

fn shape_polygons(
    path: &Path,
    feature: usize,
    shape: shapefile::Shape,
) -> Result<Option<Vec<Polygon>>> {
    use shapefile::{PolygonRing, Shape};
    fn rings<P>(rings: Vec<PolygonRing<P>>, xy: impl Fn(&P) -> [f64; 2]) -> Vec<Polygon> {
        let mut out: Vec<Polygon> = Vec::new();
        for ring in rings {
            match ring {
                PolygonRing::Outer(pts) => out.push(Polygon::new(pts.iter().map(&xy).collect())),
                PolygonRing::Inner(pts) => {
                    let hole = pts.iter().map(&xy).collect();
                    match out.last_mut() {
                        Some(p) => p.holes.push(hole),
                        None => out.push(Polygon {
                            exterior: Vec::new(),
                            holes: vec![hole],
                        }),
                    }
                }
            }
        }
        out
    }
    let polygons = match shape {
        Shape::NullShape => None,
        Shape::Polygon(p) => Some(rings(p.into_inner(), |q| [q.x, q.y])),
        Shape::PolygonM(p) => Some(rings(p.into_inner(), |q| [q.x, q.y])),
        Shape::PolygonZ(p) => Some(rings(p.into_inner(), |q| [q.x, q.y])),
        other => {
            return Err(GisError::NotPolygon {
                path: path.to_path_buf(),
                feature,
                kind: other.shapetype().to_string(),
            })
        }
    };
    if let Some(p) = &polygons {
        check_polygons(path, feature, p)?;
    }
    Ok(polygons)
}

/// Reads GeoJSON release areas (see the [module docs](self)).
pub fn read_geojson(path: &Path, thickness: ThicknessSource) -> Result<ReleaseAreas> {
    super::regular_if_present(path)?;
    let bytes = std::fs::read(path).map_err(io_err(path))?;
    if bytes.is_empty() {
        return Err(GisError::EmptyFile {
            path: path.to_path_buf(),
        });
    }
    let root: Value = serde_json::from_slice(&bytes).map_err(|source| GisError::Json {
        path: path.to_path_buf(),
        source,
    })?;
    let bad = |reason: String| GisError::GeoJson {
        path: path.to_path_buf(),
        reason,
    };
    let crs = geojson_crs(&root);
    let kind = root.get("type").and_then(Value::as_str).unwrap_or("");
    let items: Vec<(Option<&Value>, &Value)> = match kind {
        "FeatureCollection" => root
            .get("features")
            .and_then(Value::as_array)
            .ok_or_else(|| bad("FeatureCollection without a `features` array".into()))?
            .iter()
            .map(|f| {
                (
                    f.get("properties"),
                    f.get("geometry").unwrap_or(&Value::Null),
                )
            })
            .collect(),
        "Feature" => vec![(
            root.get("properties"),
            root.get("geometry").unwrap_or(&Value::Null),
        )],
        "" => return Err(bad("the top-level object has no `type`".into())),
        _ => vec![(None, &root)],
    };
    let mut features = Vec::new();
    for (i, (props, geometry)) in items.into_iter().enumerate() {
        let mut polygons = Vec::new();
        geometry_polygons(geometry, &mut polygons).map_err(|r| bad(format!("feature {i}: {r}")))?;
        if polygons.is_empty() {
            continue;
        }
        check_polygons(path, i, &polygons)?;
        let h = match thickness {
            ThicknessSource::Uniform(h) => h,
            ThicknessSource::Attribute(field) => {
                let value = props.and_then(|p| p.get(field)).ok_or_else(|| {
                    let names = props
                        .and_then(Value::as_object)
                        .map(|o| o.keys().cloned().collect())
                        .unwrap_or_default();
                    missing_attribute(path, i, field, names)
                })?;
                match value {
                    Value::Number(n) => n.as_f64().unwrap_or(f64::NAN),
                    Value::String(s) => s
                        .trim()
                        .parse()
                        .map_err(|_| bad_thickness(path, i, format!("`{s}`")))?,
                    other => return Err(bad_thickness(path, i, other.to_string())),
                }
            }
        };
        features.push(ReleaseFeature {
            polygons,
            thickness: check_thickness(path, i, h)?,
        });
    }
    if features.is_empty() {
        return Err(GisError::NoPolygons {
            path: path.to_path_buf(),
        });
    }
    Ok(ReleaseAreas { features, crs })
}

pub(super) fn geojson_crs(root: &Value) -> Crs {
    let name = root
        .get("crs")
        .and_then(|c| c.get("properties"))
        .and_then(|p| p.get("name"))
        .and_then(Value::as_str);
    let Some(name) = name else {
        return Crs::default();
    };
    let upper = name.to_ascii_uppercase();
    if upper.ends_with("CRS84") {
        return Crs::from_epsg(4326);
    }
    if upper.contains("EPSG") {
        if let Some(code) = upper.rsplit(':').next().and_then(|c| c.trim().parse().ok()) {
            return Crs::from_epsg(code);
        }
    }
    Crs::default()
}

fn geometry_polygons(g: &Value, out: &mut Vec<Polygon>) -> std::result::Result<(), String> {
    if g.is_null() {
        return Ok(());
    }
    let kind = g.get("type").and_then(Value::as_str).unwrap_or("");
    let coords = || {
        g.get("coordinates")
            .ok_or_else(|| format!("{kind} without coordinates"))
    };
    match kind {
        "Polygon" => out.push(json_polygon(coords()?)?),
        "MultiPolygon" => {
            for p in coords()?
                .as_array()
                .ok_or("MultiPolygon coordinates are not an array")?
            {
                out.push(json_polygon(p)?);
            }
        }
        "GeometryCollection" => {
            for child in g
                .get("geometries")
                .and_then(Value::as_array)
                .ok_or("GeometryCollection without `geometries`")?
            {
                geometry_polygons(child, out)?;
            }
        }
        "" => return Err("geometry without `type`".into()),
        other => {
            return Err(format!(
                "a {other} is not a release area (Polygon or MultiPolygon)"
            ))
        }
    }
    Ok(())
}

fn json_polygon(v: &Value) -> std::result::Result<Polygon, String> {
    let rings = v.as_array().ok_or("polygon coordinates are not an array")?;
    let mut rings = rings.iter().map(json_ring);
    let exterior = rings.next().ok_or("polygon without rings")??;
    let holes = rings.collect::<std::result::Result<Vec<_>, _>>()?;
    Ok(Polygon { exterior, holes })
}

fn json_ring(v: &Value) -> std::result::Result<Ring, String> {
    let pts = v.as_array().ok_or("ring is not an array")?;
    let ring = pts
        .iter()
        .map(|p| {
            let xy = p.as_array().filter(|a| a.len() >= 2);
            match xy.map(|a| (a[0].as_f64(), a[1].as_f64())) {
                Some((Some(x), Some(y))) if x.is_finite() && y.is_finite() => Ok([x, y]),
                _ => Err(format!("bad position {p}")),
            }
        })
        .collect::<std::result::Result<Ring, String>>()?;
    if ring.len() < 3 {
        return Err(format!(
            "ring with {} positions (a ring needs 3 or more)",
            ring.len()
        ));
    }
    Ok(ring)
}

/// Signed (shoelace) area: positive for counter-clockwise rings.
pub fn ring_area(ring: &[[f64; 2]]) -> f64 {
    let n = ring.len();
    if n < 3 {
        return 0.0;
    }
    let (ox, oy) = (ring[0][0], ring[0][1]);
    let mut s = 0.0;
    for i in 0..n {
        let a = ring[i];
        let b = ring[(i + 1) % n];
        s += (a[0] - ox) * (b[1] - oy) - (b[0] - ox) * (a[1] - oy);
    }
    0.5 * s
}

/// A sub-window of the grid: columns `c0..c1`, rows `r0..r1` (rows from the top).
#[derive(Debug, Clone, Copy)]
struct Window {
    c0: usize,
    c1: usize,
    r0: usize,
    r1: usize,
}

impl Window {
    fn nc(&self) -> usize {
        self.c1 - self.c0
    }
    fn nr(&self) -> usize {
        self.r1 - self.r0
    }
}

/// Rings of some polygons with their weights (+1 exterior, −1 hole) times their
/// orientation, in window cell units (u right, v up from the window's bottom edge).
struct Rings {
    rings: Vec<(Vec<[f64; 2]>, f64)>,
}

impl Rings {
    fn new(polygons: &[Polygon], grid: &Raster, w: Window) -> Rings {
        let d = grid.cell_size;
        let x0 = grid.x_left + w.c0 as f64 * d;
        let y0 = grid.y_top - w.r1 as f64 * d;
        let mut rings = Vec::new();
        for p in polygons {
            let all = std::iter::once((&p.exterior, 1.0)).chain(p.holes.iter().map(|h| (h, -1.0)));
            for (ring, sign) in all {
                let a = ring_area(ring);
                if a == 0.0 {
                    continue;
                }
                let pts = ring
                    .iter()
                    .map(|q| [(q[0] - x0) / d, (q[1] - y0) / d])
                    .collect();
                rings.push((pts, sign * a.signum()));
            }
        }
        Rings { rings }
    }

    /// Σ over rings of weight × (ring ∩ cell area) / cell area, per window cell, row 0
    /// of the result at the window's top; not clamped.
    fn area_fractions(&self, w: Window) -> Vec<f64> {
        let (nc, nr) = (w.nc(), w.nr());
        let (ncf, nrf) = (nc as f64, nr as f64);
        // acc[k * nc + i], k counted from the bottom.
        let mut acc = vec![0.0; nc * nr];
        let mut carry = vec![0.0; nc * nr];
        let mut ts: Vec<f64> = Vec::new();
        for (pts, weight) in &self.rings {
            // frac = −∮ clamp(v − k, 0, 1) du over the column, for a counter-clockwise ring.
            let wgt = -weight;
            let n = pts.len();
            for e in 0..n {
                let [u0, v0] = pts[e];
                let [u1, v1] = pts[(e + 1) % n];
                if u0 == u1 {
                    continue;
                }
                ts.clear();
                ts.push(0.0);
                ts.push(1.0);
                let (ulo, uhi) = (u0.min(u1).max(0.0), u0.max(u1).min(ncf));
                if ulo > uhi {
                    continue;
                }
                let mut k = ulo.ceil();
                while k <= uhi {
                    ts.push((k - u0) / (u1 - u0));
                    k += 1.0;
                }
                if v0 != v1 {
                    let (vlo, vhi) = (v0.min(v1).max(0.0), v0.max(v1).min(nrf));
                    let mut k = vlo.ceil();
                    while k <= vhi {
                        ts.push((k - v0) / (v1 - v0));
                        k += 1.0;
                    }
                }
                ts.retain(|t| (0.0..=1.0).contains(t));
                ts.sort_by(f64::total_cmp);
                for pair in ts.windows(2) {
                    let (ta, tb) = (pair[0], pair[1]);
                    if tb <= ta {
                        continue;
                    }
                    let ua = u0 + ta * (u1 - u0);
                    let ub = u0 + tb * (u1 - u0);
                    let um = 0.5 * (ua + ub);
                    if um <= 0.0 || um >= ncf {
                        continue;
                    }
                    let va = (v0 + ta * (v1 - v0)).clamp(0.0, nrf);
                    let vb = (v0 + tb * (v1 - v0)).clamp(0.0, nrf);
                    let vm = 0.5 * (va + vb);
                    if vm <= 0.0 {
                        continue;
                    }
                    let i = (um.floor() as usize).min(nc - 1);
                    let k = (vm.floor() as usize).min(nr - 1);
                    let du = wgt * (ub - ua);
                    acc[k * nc + i] += du * (vm - k as f64);
                    if k > 0 {
                        carry[(k - 1) * nc + i] += du;
                    }
                }
            }
        }
        let mut out = vec![0.0; nc * nr];
        for i in 0..nc {
            let mut running = 0.0;
            for k in (0..nr).rev() {
                running += carry[k * nc + i];
                // Output row from the top: nr − 1 − k.
                out[(nr - 1 - k) * nc + i] = acc[k * nc + i] + running;
            }
        }
        out
    }

    /// 1 where the cell centre is inside (weighted winding > 0), per window cell, row 0
    /// at the window's top.
    fn centre_inside(&self, w: Window) -> Vec<f64> {
        let (nc, nr) = (w.nc(), w.nr());
        let mut out = vec![0.0; nc * nr];
        let mut crossings: Vec<(f64, f64)> = Vec::new();
        for k in 0..nr {
            let vc = k as f64 + 0.5;
            crossings.clear();
            for (pts, weight) in &self.rings {
                let n = pts.len();
                for e in 0..n {
                    let [u0, v0] = pts[e];
                    let [u1, v1] = pts[(e + 1) % n];
                    let up = v0 <= vc && vc < v1;
                    let down = v1 <= vc && vc < v0;
                    if up || down {
                        let u = u0 + (vc - v0) * (u1 - u0) / (v1 - v0);
                        let dir = if up { 1.0 } else { -1.0 };
                        crossings.push((u, -dir * weight));
                    }
                }
            }
            if crossings.is_empty() {
                continue;
            }
            crossings.sort_by(|a, b| a.0.total_cmp(&b.0));
            let row = nr - 1 - k;
            let mut cum = 0.0;
            let mut next = 0;
            for i in 0..nc {
                let uc = i as f64 + 0.5;
                while next < crossings.len() && crossings[next].0 < uc {
                    cum += crossings[next].1;
                    next += 1;
                }
                if cum > 0.5 {
                    out[row * nc + i] = 1.0;
                }
            }
        }
        out
    }
}

fn polygons_bbox(polygons: &[Polygon]) -> Option<[f64; 4]> {
    let mut b = [
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
    ];
    for q in polygons
        .iter()
        .flat_map(|p| p.exterior.iter().chain(p.holes.iter().flatten()))
    {
        b[0] = b[0].min(q[0]);
        b[1] = b[1].max(q[0]);
        b[2] = b[2].min(q[1]);
        b[3] = b[3].max(q[1]);
    }
    (b[0] <= b[1] && b[2] <= b[3]).then_some(b)
}

/// The window of `grid` cells touched by the box, or `None` if they are disjoint.
fn window(grid: &Raster, b: [f64; 4]) -> Option<Window> {
    let d = grid.cell_size;
    let c0 = ((b[0] - grid.x_left) / d).floor().max(0.0);
    let c1 = ((b[1] - grid.x_left) / d).ceil().min(grid.nx as f64);
    let r0 = ((grid.y_top - b[3]) / d).floor().max(0.0);
    let r1 = ((grid.y_top - b[2]) / d).ceil().min(grid.ny as f64);
    (c0 < c1 && r0 < r1).then_some(Window {
        c0: c0 as usize,
        c1: c1 as usize,
        r0: r0 as usize,
        r1: r1 as usize,
    })
}

/// Fraction of each cell of `grid` covered by `polygons` under `rule`, in `[0, 1]`,
/// in the grid's cell order. Parts outside the grid are ignored.
pub fn coverage(polygons: &[Polygon], grid: &Raster, rule: CoverageRule) -> Vec<f64> {
    let mut out = vec![0.0; grid.nx * grid.ny];
    let Some(w) = polygons_bbox(polygons).and_then(|b| window(grid, b)) else {
        return out;
    };
    let rings = Rings::new(polygons, grid, w);
    let local = match rule {
        CoverageRule::AreaFraction => rings.area_fractions(w),
        CoverageRule::CellCentre => rings.centre_inside(w),
    };
    for r in 0..w.nr() {
        for c in 0..w.nc() {
            out[grid.index(w.c0 + c, w.r0 + r)] = local[r * w.nc() + c].clamp(0.0, 1.0);
        }
    }
    out
}

/// Rasterises `areas` onto `grid` (its cells, nodata and CRS; its values are not
/// used) under `rule`: the thickness field and the released volume. Errors when the CRS
/// differ or a feature is outside the grid, or partly (see the [module docs](self)).
pub fn rasterise(areas: &ReleaseAreas, grid: &Raster, rule: CoverageRule) -> Result<Release> {
    grid.crs
        .check_same("the raster", &areas.crs, "the release areas")?;
    let mut thickness = grid.same_grid(0.0);
    let cell_area = grid.cell_area();
    for (f, feature) in areas.features.iter().enumerate() {
        let Some(b) = polygons_bbox(&feature.polygons) else {
            continue;
        };
        let outside = || {
            let g = grid.bbox();
            GisError::PolygonOutsideRaster {
                feature: f,
                px0: b[0],
                px1: b[1],
                py0: b[2],
                py1: b[3],
                rx0: g.x_min,
                rx1: g.x_max,
                ry0: g.y_min,
                ry1: g.y_max,
            }
        };
        let w = window(grid, b).ok_or_else(outside)?;
        let rings = Rings::new(&feature.polygons, grid, w);
        let fractions = rings.area_fractions(w);
        let area: f64 = feature.polygons.iter().map(Polygon::area).sum();
        let inside = fractions.iter().sum::<f64>() * cell_area;
        if area > 0.0 && inside <= 0.0 {
            return Err(outside());
        }
        if area > 0.0 && inside < area * (1.0 - 1e-6) {
            return Err(GisError::PolygonPartlyOutside {
                feature: f,
                percent: 100.0 * (1.0 - inside / area),
            });
        }
        let local = match rule {
            CoverageRule::AreaFraction => fractions,
            CoverageRule::CellCentre => rings.centre_inside(w),
        };
        for r in 0..w.nr() {
            let row = &mut thickness.values[(w.r0 + r) * grid.nx + w.c0..][..w.nc()];
            for (v, frac) in row.iter_mut().zip(&local[r * w.nc()..][..w.nc()]) {
                *v += feature.thickness * frac.clamp(0.0, 1.0);
            }
        }
    }
    let mut volume = 0.0;
    let mut volume_on_nodata = 0.0;
    if let Some(nd) = grid.nodata {
        thickness.nodata = Some(nd);
    }
    for (h, &g) in thickness.values.iter_mut().zip(&grid.values) {
        if grid.is_nodata(g) {
            volume_on_nodata += *h * cell_area;
            *h = g;
        } else {
            volume += *h * cell_area;
        }
    }
    Ok(Release {
        thickness,
        volume,
        volume_on_nodata,
    })
}

/// cos θ of the DEM's slope per cell, from central differences (one-sided at the border
/// and next to nodata, flat when both neighbours are missing); nodata where the DEM is.
pub fn slope_cosine(dem: &Raster) -> Raster {
    let (nx, ny, d) = (dem.nx, dem.ny, dem.cell_size);
    let mut out = dem.same_grid(1.0);
    out.nodata = dem.nodata;
    let z = |c: usize, r: usize| dem.get(c, r);
    let diff = |here: f64, lo: Option<f64>, hi: Option<f64>| match (lo, hi) {
        (Some(a), Some(b)) => (b - a) / (2.0 * d),
        (Some(a), None) => (here - a) / d,
        (None, Some(b)) => (b - here) / d,
        (None, None) => 0.0,
    };
    for r in 0..ny {
        for c in 0..nx {
            let i = dem.index(c, r);
            let Some(here) = z(c, r) else {
                out.values[i] = dem.values[i];
                continue;
            };
            let west = (c > 0).then(|| z(c - 1, r)).flatten();
            let east = (c + 1 < nx).then(|| z(c + 1, r)).flatten();
            let north = (r > 0).then(|| z(c, r - 1)).flatten();
            let south = (r + 1 < ny).then(|| z(c, r + 1)).flatten();
            let gx = diff(here, west, east);
            let gy = diff(here, south, north);
            out.values[i] = 1.0 / (1.0 + gx * gx + gy * gy).sqrt();
        }
    }
    out
}

/// Converts a slope-normal thickness field to vertical: `h / cos θ` with θ the DEM's
/// local slope ([`slope_cosine`]). Both rasters must share the grid. Nodata cells of
/// `normal` stay nodata; cells where only the DEM has no data keep `h`.
pub fn vertical_thickness(normal: &Raster, dem: &Raster) -> Result<Raster> {
    normal.check_same_grid(dem)?;
    let cos = slope_cosine(dem);
    let mut out = normal.clone();
    for (i, h) in out.values.iter_mut().enumerate() {
        if normal.is_nodata(*h) || cos.is_nodata(cos.values[i]) {
            continue;
        }
        *h /= cos.values[i];
    }
    Ok(out)
}

/// The error for feature `feature` of `path` lacking the thickness attribute `field`,
/// listing the attributes it has (sorted).
fn missing_attribute(path: &Path, feature: usize, field: &str, mut names: Vec<String>) -> GisError {
    names.sort();
    GisError::MissingAttribute {
        path: path.to_path_buf(),
        feature,
        field: field.to_string(),
        available: names.join(", "),
    }
}
