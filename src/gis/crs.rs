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

/// ETRS89 (EPSG:4258) as WKT 1.
const ETRS89_GEOGCS: &str = r#"GEOGCS["ETRS89",DATUM["European_Terrestrial_Reference_System_1989",SPHEROID["GRS 1980",6378137,298.257222101,AUTHORITY["EPSG","7019"]],AUTHORITY["EPSG","6258"]],PRIMEM["Greenwich",0,AUTHORITY["EPSG","8901"]],UNIT["degree",0.0174532925199433,AUTHORITY["EPSG","9122"]],AUTHORITY["EPSG","4258"]]"#;

/// WKT 1 for an EPSG code without a database: WGS 84 (4326), its UTM zones (32601–
/// 32660 north, 32701–32760 south) and ETRS89's (25828–25838), the systems a DEM
/// known only by its code (a GeoTIFF's key) is most often in. `None` for the others:
/// their parameters would need the EPSG registry.
pub fn wkt_of_epsg(code: u32) -> Option<String> {
    let utm = |geogcs: &str, base: &str, zone: u32, south: bool| {
        let central = 6 * zone as i32 - 183;
        let hemisphere = if south { 'S' } else { 'N' };
        let false_northing = if south { 10_000_000 } else { 0 };
        format!(
            r#"PROJCS["{base} / UTM zone {zone}{hemisphere}",{geogcs},PROJECTION["Transverse_Mercator"],PARAMETER["latitude_of_origin",0],PARAMETER["central_meridian",{central}],PARAMETER["scale_factor",0.9996],PARAMETER["false_easting",500000],PARAMETER["false_northing",{false_northing}],UNIT["metre",1,AUTHORITY["EPSG","9001"]],AXIS["Easting",EAST],AXIS["Northing",NORTH],AUTHORITY["EPSG","{code}"]]"#
        )
    };
    match code {
        4326 => Some(WGS84_GEOGCS.to_owned()),
        32601..=32660 => Some(utm(WGS84_GEOGCS, "WGS 84", code - 32600, false)),
        32701..=32760 => Some(utm(WGS84_GEOGCS, "WGS 84", code - 32700, true)),
        25828..=25838 => Some(utm(ETRS89_GEOGCS, "ETRS89", code - 25800, false)),
        _ => None,
    }
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
        for code in [4326, 32632, 32719, 25833] {
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
        assert_eq!(wkt_of_epsg(2056), None);
        assert_eq!(Crs::from_epsg(2056).wkt_text(), None);
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
