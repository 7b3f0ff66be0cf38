//! Coordinate reference systems, carried through and compared, never transformed.

use super::{GisError, Result};

/// A coordinate reference system as files state it: an EPSG code, WKT text (from a
/// `.prj`, a NetCDF `crs_wkt`), both, or neither (unknown).
///
/// The EPSG code of a WKT is the authority of its root node (`AUTHORITY["EPSG","32632"]`
/// in WKT 1, `ID["EPSG",32632]` in WKT 2) when it has one; ESRI-flavoured `.prj` files
/// usually have none, and their CRS then counts as unknown for comparisons.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Crs {
    /// EPSG code, if stated or found in the WKT.
    pub epsg: Option<u32>,
    /// WKT text, as read (trimmed).
    pub wkt: Option<String>,
}

impl Crs {
    /// The unknown CRS.
    pub fn unknown() -> Crs {
        Crs::default()
    }

    /// A CRS known by its EPSG code only.
    pub fn from_epsg(code: u32) -> Crs {
        Crs {
            epsg: Some(code),
            wkt: None,
        }
    }

    /// A CRS from WKT text; its EPSG code is the root authority, if any.
    pub fn from_wkt(text: &str) -> Crs {
        let wkt = text
            .trim()
            .trim_start_matches('\u{feff}')
            .trim()
            .to_string();
        if wkt.is_empty() {
            return Crs::default();
        }
        Crs {
            epsg: root_epsg(&wkt),
            wkt: Some(wkt),
        }
    }

    /// The WKT to write where a file needs one (an ESRI ASCII grid's `.prj`, a
    /// NetCDF `crs_wkt`): the stated one, else one made from the EPSG code for the
    /// systems `wkt_of_epsg` knows; `None` otherwise.
    pub fn wkt_text(&self) -> Option<std::borrow::Cow<'_, str>> {
        match (&self.wkt, self.epsg) {
            (Some(wkt), _) => Some(std::borrow::Cow::Borrowed(wkt)),
            (None, Some(code)) => wkt_of_epsg(code).map(std::borrow::Cow::Owned),
            (None, None) => None,
        }
    }

    /// Whether the WKT is an engineering (local) system, `LOCAL_CS[…]` or
    /// `ENGCRS[…]`: coordinates in metres with no place on Earth, as some DEMs' `.prj`
    /// say when their real CRS was lost.
    pub fn is_local(&self) -> bool {
        self.epsg.is_none()
            && self.wkt.as_deref().is_some_and(|w| {
                let root = w.trim_start().to_ascii_uppercase();
                root.starts_with("LOCAL_CS") || root.starts_with("ENGCRS")
            })
    }

    /// True when neither a code nor a WKT is known.
    pub fn is_unknown(&self) -> bool {
        self.epsg.is_none() && self.wkt.is_none()
    }

    /// Whether this is a geographic (longitude/latitude) CRS: the WKT root is
    /// `GEOGCS`/`GEOGCRS`/`GEODCRS`, or, without WKT, the EPSG code is in 4000..5000
    /// (where EPSG keeps its geographic 2-D systems). Unknown counts as projected.
    pub fn is_geographic(&self) -> bool {
        if let Some(wkt) = &self.wkt {
            let root: String = wkt
                .chars()
                .take_while(|c| c.is_ascii_alphanumeric() || *c == '_')
                .collect::<String>()
                .to_ascii_uppercase();
            return matches!(root.as_str(), "GEOGCS" | "GEOGCRS" | "GEODCRS");
        }
        matches!(self.epsg, Some(4000..=4999))
    }

    /// Refuses two CRS that are both known by an EPSG code and differ. A CRS without a
    /// code (unknown, or WKT without a root authority) is not compared.
    pub fn check_same(&self, what: &str, other: &Crs, what_other: &str) -> Result<()> {
        match (self.epsg, other.epsg) {
            (Some(a), Some(b)) if a != b => Err(GisError::CrsMismatch {
                what_a: what.to_string(),
                a,
                what_b: what_other.to_string(),
                b,
            }),
            _ => Ok(()),
        }
    }
}

impl std::fmt::Display for Crs {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match (self.epsg, &self.wkt) {
            (Some(code), _) => write!(f, "EPSG:{code}"),
            // The WKT's own name, e.g. `MGI_Austria_Lambert`, says more than nothing.
            (None, Some(wkt)) => match wkt.split('"').nth(1).filter(|n| !n.is_empty()) {
                Some(name) => write!(f, "\"{name}\" (WKT without EPSG code)"),
                None => write!(f, "WKT without EPSG code"),
            },
            (None, None) => write!(f, "unknown CRS"),
        }
    }
}

/// WGS 84 (EPSG:4326) as WKT 1.
const WGS84_GEOGCS: &str = r#"GEOGCS["WGS 84",DATUM["WGS_1984",SPHEROID["WGS 84",6378137,298.257223563,AUTHORITY["EPSG","7030"]],AUTHORITY["EPSG","6326"]],PRIMEM["Greenwich",0,AUTHORITY["EPSG","8901"]],UNIT["degree",0.0174532925199433,AUTHORITY["EPSG","9122"]],AUTHORITY["EPSG","4326"]]"#;

/// A GEOGCS of WKT 1: its name, datum (name, EPSG code, `TOWGS84` to WGS 84 or none),
/// ellipsoid (name, a, 1/f, EPSG code), its own EPSG code.
struct Geog {
    name: &'static str,
    datum: &'static str,
    datum_code: u32,
    towgs84: Option<&'static str>,
    ellipsoid: (&'static str, f64, f64, u32),
    code: u32,
}

impl Geog {
    fn wkt(&self) -> String {
        let (ename, a, rf, ecode) = self.ellipsoid;
        let towgs = self
            .towgs84
            .map_or(String::new(), |t| format!(",TOWGS84[{t}]"));
        format!(
            r#"GEOGCS["{}",DATUM["{}",SPHEROID["{ename}",{a},{rf},AUTHORITY["EPSG","{ecode}"]]{towgs},AUTHORITY["EPSG","{}"]],PRIMEM["Greenwich",0,AUTHORITY["EPSG","8901"]],UNIT["degree",0.0174532925199433,AUTHORITY["EPSG","9122"]],AUTHORITY["EPSG","{}"]]"#,
            self.name, self.datum, self.datum_code, self.code
        )
    }
}

const GRS80: (&str, f64, f64, u32) = ("GRS 1980", 6378137.0, 298.257222101, 7019);
const BESSEL: (&str, f64, f64, u32) = ("Bessel 1841", 6377397.155, 299.1528128, 7004);
const NAD83: Geog = Geog {
    name: "NAD83",
    datum: "North_American_Datum_1983",
    datum_code: 6269,
    towgs84: None,
    ellipsoid: GRS80,
    code: 4269,
};
const RGF93: Geog = Geog {
    name: "RGF93 v1",
    datum: "Reseau_Geodesique_Francais_1993_v1",
    datum_code: 6171,
    towgs84: None,
    ellipsoid: GRS80,
    code: 4171,
};
const MGI: Geog = Geog {
    name: "MGI",
    datum: "Militar_Geographische_Institut",
    datum_code: 6312,
    towgs84: Some("577.326,90.129,463.919,5.137,1.474,5.297,2.4232"),
    ellipsoid: BESSEL,
    code: 4312,
};
const DHDN: Geog = Geog {
    name: "DHDN",
    datum: "Deutsches_Hauptdreiecksnetz",
    datum_code: 6314,
    towgs84: Some("598.1,73.7,418.2,0.202,0.045,-2.455,6.7"),
    ellipsoid: BESSEL,
    code: 4314,
};
const CH1903: Geog = Geog {
    name: "CH1903",
    datum: "CH1903",
    datum_code: 6149,
    towgs84: Some("674.374,15.056,405.346,0,0,0,0"),
    ellipsoid: BESSEL,
    code: 4149,
};
const CH1903P: Geog = Geog {
    name: "CH1903+",
    datum: "CH1903+",
    datum_code: 6150,
    towgs84: Some("674.374,15.056,405.346,0,0,0,0"),
    ellipsoid: BESSEL,
    code: 4150,
};
const MONTE_MARIO: Geog = Geog {
    name: "Monte Mario",
    datum: "Monte_Mario",
    datum_code: 6265,
    towgs84: Some("-104.1,-49.1,-9.9,0.971,-2.917,0.714,-11.68"),
    ellipsoid: ("International 1924", 6378388.0, 297.0, 7022),
    code: 4265,
};
const AMERSFOORT: Geog = Geog {
    name: "Amersfoort",
    datum: "Amersfoort",
    datum_code: 6289,
    towgs84: Some("565.4171,50.3319,465.5524,1.9342,-1.6677,9.1019,4.0725"),
    ellipsoid: BESSEL,
    code: 4289,
};
const ETRS89: Geog = Geog {
    name: "ETRS89",
    datum: "European_Terrestrial_Reference_System_1989",
    datum_code: 6258,
    towgs84: None,
    ellipsoid: GRS80,
    code: 4258,
};

/// A PROJCS of WKT 1 in metres, easting and northing.
fn projcs(name: &str, geog: &str, projection: &str, params: &[(&str, f64)], code: u32) -> String {
    let params: String = params
        .iter()
        .map(|(p, v)| format!(r#",PARAMETER["{p}",{v}]"#))
        .collect();
    format!(
        r#"PROJCS["{name}",{geog},PROJECTION["{projection}"]{params},UNIT["metre",1,AUTHORITY["EPSG","9001"]],AXIS["Easting",EAST],AXIS["Northing",NORTH],AUTHORITY["EPSG","{code}"]]"#
    )
}

/// Transverse Mercator parameters: (latitude of origin, central meridian, scale
/// factor, false easting, false northing).
fn tm(lat0: f64, lon0: f64, k: f64, x0: f64, y0: f64) -> [(&'static str, f64); 5] {
    [
        ("latitude_of_origin", lat0),
        ("central_meridian", lon0),
        ("scale_factor", k),
        ("false_easting", x0),
        ("false_northing", y0),
    ]
}

/// The Swiss oblique Mercator (Hotine variant B) with false easting and northing.
fn swiss(name: &str, geog: &Geog, x0: f64, y0: f64, code: u32) -> String {
    projcs(
        name,
        &geog.wkt(),
        "Hotine_Oblique_Mercator_Azimuth_Center",
        &[
            ("latitude_of_center", 46.9524055555556),
            ("longitude_of_center", 7.43958333333333),
            ("azimuth", 90.0),
            ("rectified_grid_angle", 90.0),
            ("scale_factor", 1.0),
            ("false_easting", x0),
            ("false_northing", y0),
        ],
        code,
    )
}

/// WKT 1 for an EPSG code without a database, from the systems' published
/// definitions (the EPSG registry's parameters): WGS 84 (4326), its UTM zones (32601–
/// 32660 north, 32701–32760 south), ETRS89's (25828–25838) and ETRS89-LAEA Europe
/// (3035), NAD83's UTM zones (26901–26923), CH1903+ / LV95 (2056) and CH1903 / LV03
/// (21781), MGI / Austria GK West, Central, East (31254–31256), M28, M31, M34
/// (31257–31259) and Austria Lambert (31287), RGF93 / Lambert-93 (2154), DHDN / 3-degree
/// Gauss-Kruger zones 2–5 (31466–31469), Monte Mario / Italy zones 1 and 2 (3003, 3004)
/// and Amersfoort / RD New (28992): the systems a DEM known only by its code (a
/// GeoTIFF's key) is most often in where avalanches are studied. Datums other than
/// WGS 84, ETRS89, NAD83 and RGF93 carry the `TOWGS84` the registry gives as their
/// usual transformation (as GDAL writes them). `None` for the others.
pub fn wkt_of_epsg(code: u32) -> Option<String> {
    let wgs84 = WGS84_GEOGCS;
    let utm = |geogcs: &str, base: &str, zone: u32, south: bool| {
        let central = 6.0 * zone as f64 - 183.0;
        let hemisphere = if south { 'S' } else { 'N' };
        let false_northing = if south { 10_000_000.0 } else { 0.0 };
        projcs(
            &format!("{base} / UTM zone {zone}{hemisphere}"),
            geogcs,
            "Transverse_Mercator",
            &tm(0.0, central, 0.9996, 500_000.0, false_northing),
            code,
        )
    };
    let mgi_gk = |name: &str, lon0: f64, x0: f64| {
        projcs(
            &format!("MGI / Austria GK {name}"),
            &MGI.wkt(),
            "Transverse_Mercator",
            &tm(0.0, lon0, 1.0, x0, -5_000_000.0),
            code,
        )
    };
    let lcc = |name: &str, geog: &Geog, [lat1, lat2, lat0, lon0, x0, y0]: [f64; 6]| {
        projcs(
            name,
            &geog.wkt(),
            "Lambert_Conformal_Conic_2SP",
            &[
                ("standard_parallel_1", lat1),
                ("standard_parallel_2", lat2),
                ("latitude_of_origin", lat0),
                ("central_meridian", lon0),
                ("false_easting", x0),
                ("false_northing", y0),
            ],
            code,
        )
    };
    // The registry gives these systems northing first: written so, GDAL identifies
    // the WKT as the code (the data stay easting, northing, as every GIS reads them).
    let northing_first = |wkt: String| {
        wkt.replace(
            r#"AXIS["Easting",EAST],AXIS["Northing",NORTH]"#,
            r#"AXIS["Northing",NORTH],AXIS["Easting",EAST]"#,
        )
    };
    // 10°20′ E, 13°20′ E and 16°20′ E, the Austrian meridians (28°, 31°, 34° E of Ferro).
    let (m28, m31, m34) = (10.0 + 1.0 / 3.0, 13.0 + 1.0 / 3.0, 16.0 + 1.0 / 3.0);
    let wkt = Some(match code {
        4326 => wgs84.to_owned(),
        32601..=32660 => utm(wgs84, "WGS 84", code - 32600, false),
        32701..=32760 => utm(wgs84, "WGS 84", code - 32700, true),
        25828..=25838 => utm(&ETRS89.wkt(), "ETRS89", code - 25800, false),
        26901..=26923 => utm(&NAD83.wkt(), "NAD83", code - 26900, false),
        3035 => projcs(
            "ETRS89-extended / LAEA Europe",
            &ETRS89.wkt(),
            "Lambert_Azimuthal_Equal_Area",
            &[
                ("latitude_of_center", 52.0),
                ("longitude_of_center", 10.0),
                ("false_easting", 4_321_000.0),
                ("false_northing", 3_210_000.0),
            ],
            code,
        ),
        2056 => swiss("CH1903+ / LV95", &CH1903P, 2_600_000.0, 1_200_000.0, code),
        21781 => swiss("CH1903 / LV03", &CH1903, 600_000.0, 200_000.0, code),
        31254 => mgi_gk("West", m28, 0.0),
        31255 => mgi_gk("Central", m31, 0.0),
        31256 => mgi_gk("East", m34, 0.0),
        31257 => mgi_gk("M28", m28, 150_000.0),
        31258 => mgi_gk("M31", m31, 450_000.0),
        31259 => mgi_gk("M34", m34, 750_000.0),
        31287 => lcc(
            "MGI / Austria Lambert",
            &MGI,
            [49.0, 46.0, 47.5, m31, 400_000.0, 400_000.0],
        ),
        2154 => lcc(
            "RGF93 v1 / Lambert-93",
            &RGF93,
            [49.0, 44.0, 46.5, 3.0, 700_000.0, 6_600_000.0],
        ),
        31466..=31469 => {
            let zone = code - 31464;
            projcs(
                &format!("DHDN / 3-degree Gauss-Kruger zone {zone}"),
                &DHDN.wkt(),
                "Transverse_Mercator",
                &tm(
                    0.0,
                    3.0 * zone as f64,
                    1.0,
                    zone as f64 * 1e6 + 500_000.0,
                    0.0,
                ),
                code,
            )
        }
        3003 => projcs(
            "Monte Mario / Italy zone 1",
            &MONTE_MARIO.wkt(),
            "Transverse_Mercator",
            &tm(0.0, 9.0, 0.9996, 1_500_000.0, 0.0),
            code,
        ),
        3004 => projcs(
            "Monte Mario / Italy zone 2",
            &MONTE_MARIO.wkt(),
            "Transverse_Mercator",
            &tm(0.0, 15.0, 0.9996, 2_520_000.0, 0.0),
            code,
        ),
        28992 => projcs(
            "Amersfoort / RD New",
            &AMERSFOORT.wkt(),
            "Oblique_Stereographic",
            &[
                ("latitude_of_origin", 52.1561605555556),
                ("central_meridian", 5.38763888888889),
                ("scale_factor", 0.9999079),
                ("false_easting", 155_000.0),
                ("false_northing", 463_000.0),
            ],
            code,
        ),
        _ => return None,
    });
    wkt.map(|wkt| match code {
        3035 | 31254..=31259 | 31287 | 31466..=31469 => northing_first(wkt),
        _ => wkt,
    })
}

/// The EPSG code of the root node's `AUTHORITY[...]` / `ID[...]` (depth 1).
fn root_epsg(wkt: &str) -> Option<u32> {
    let bytes = wkt.as_bytes();
    let mut depth = 0usize;
    let mut in_quote = false;
    let mut found = None;
    let mut i = 0;
    while i < bytes.len() {
        let c = bytes[i];
        if in_quote {
            if c == b'"' {
                in_quote = false;
            }
            i += 1;
            continue;
        }
        match c {
            b'"' => in_quote = true,
            b'[' | b'(' => depth += 1,
            b']' | b')' => depth = depth.saturating_sub(1),
            _ if depth == 1 && c.is_ascii_alphabetic() => {
                let start = i;
                while i < bytes.len() && (bytes[i].is_ascii_alphanumeric() || bytes[i] == b'_') {
                    i += 1;
                }
                let word = wkt[start..i].to_ascii_uppercase();
                if (word == "AUTHORITY" || word == "ID") && i < bytes.len() {
                    if let Some(code) = parse_authority(&wkt[i..]) {
                        found = Some(code);
                    }
                }
                continue;
            }
            _ => {}
        }
        i += 1;
    }
    found
}

/// `["EPSG","32632"]` or `["EPSG",32632]` → 32632.
fn parse_authority(rest: &str) -> Option<u32> {
    let rest = rest.trim_start().strip_prefix(['[', '('])?;
    let end = rest.find([']', ')'])?;
    let mut parts = rest[..end].split(',');
    let name = parts.next()?.trim().trim_matches('"');
    if !name.eq_ignore_ascii_case("EPSG") {
        return None;
    }
    parts.next()?.trim().trim_matches('"').parse().ok()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn root_authority_wins_over_nested_ones() {
        let wkt = r#"PROJCS["WGS 84 / UTM zone 32N",GEOGCS["WGS 84",DATUM["WGS_1984",SPHEROID["WGS 84",6378137,298.257223563,AUTHORITY["EPSG","7030"]],AUTHORITY["EPSG","6326"]],PRIMEM["Greenwich",0],UNIT["degree",0.0174532925199433],AUTHORITY["EPSG","4326"]],PROJECTION["Transverse_Mercator"],UNIT["metre",1,AUTHORITY["EPSG","9001"]],AUTHORITY["EPSG","32632"]]"#;
        let crs = Crs::from_wkt(wkt);
        assert_eq!(crs.epsg, Some(32632));
        assert!(!crs.is_geographic());
        let wkt2 = r#"GEOGCRS["WGS 84",DATUM["World Geodetic System 1984",ELLIPSOID["WGS 84",6378137,298.257223563]],ID["EPSG",4326]]"#;
        let crs = Crs::from_wkt(wkt2);
        assert_eq!(crs.epsg, Some(4326));
        assert!(crs.is_geographic());
        let local =
            r#"LOCAL_CS["unnamed",UNIT["Meter",1.0],AXIS["Easting",EAST],AXIS["Northing",NORTH]]"#;
        assert!(Crs::from_wkt(local).is_local() && !Crs::from_wkt(wkt).is_local());
        assert_eq!(
            Crs::from_wkt(local).to_string(),
            "\"unnamed\" (WKT without EPSG code)"
        );
        let esri = r#"PROJCS["WGS_1984_UTM_Zone_32N",GEOGCS["GCS_WGS_1984",DATUM["D_WGS_1984",SPHEROID["WGS_1984",6378137.0,298.257223563]]],PROJECTION["Transverse_Mercator"]]"#;
        assert_eq!(Crs::from_wkt(esri).epsg, None);
    }

    #[test]
    fn wkt_made_from_a_code_names_that_code_at_its_root() {
        for code in [
            4326, 32632, 32719, 25833, 26911, 3035, 2056, 21781, 31254, 31259, 31287, 2154, 31467,
            3003, 3004, 28992,
        ] {
            let wkt = wkt_of_epsg(code).unwrap();
            let crs = Crs::from_wkt(&wkt);
            assert_eq!(crs.epsg, Some(code), "{wkt}");
            assert_eq!(crs.is_geographic(), code == 4326, "{wkt}");
        }
        let wkt = wkt_of_epsg(32632).unwrap();
        assert!(wkt.contains(r#"PARAMETER["central_meridian",9]"#), "{wkt}");
        let wkt = wkt_of_epsg(32719).unwrap();
        assert!(
            wkt.contains(r#"PARAMETER["central_meridian",-69]"#),
            "{wkt}"
        );
        assert!(
            wkt.contains(r#"PARAMETER["false_northing",10000000]"#),
            "{wkt}"
        );
        // DHDN zone 3: 9° E, 3 500 000 m false easting, northing first as registered.
        let wkt = wkt_of_epsg(31467).unwrap();
        assert!(wkt.contains(r#"PARAMETER["central_meridian",9]"#), "{wkt}");
        assert!(
            wkt.contains(r#"PARAMETER["false_easting",3500000]"#),
            "{wkt}"
        );
        assert!(wkt.contains(r#"AXIS["Northing",NORTH],AXIS["Easting",EAST]"#));
        // The parameters themselves are checked against GDAL's registry by
        // tests/python/test_prj_epsg.py.
        assert_eq!(wkt_of_epsg(5514), None);
        assert_eq!(Crs::from_epsg(5514).wkt_text(), None);
        assert!(Crs::from_epsg(32632).wkt_text().is_some());
    }

    #[test]
    fn mismatch_only_between_known_codes() {
        let a = Crs::from_epsg(32632);
        assert!(a.check_same("a", &Crs::from_epsg(32632), "b").is_ok());
        assert!(a.check_same("a", &Crs::unknown(), "b").is_ok());
        let err = a
            .check_same("the DEM", &Crs::from_epsg(2056), "the release")
            .unwrap_err();
        assert!(err.to_string().contains("EPSG:32632"), "{err}");
        assert!(err.to_string().contains("EPSG:2056"), "{err}");
    }
}
