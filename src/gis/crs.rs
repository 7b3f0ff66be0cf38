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
            (None, Some(_)) => write!(f, "WKT without EPSG code"),
            (None, None) => write!(f, "unknown CRS"),
        }
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
        let esri = r#"PROJCS["WGS_1984_UTM_Zone_32N",GEOGCS["GCS_WGS_1984",DATUM["D_WGS_1984",SPHEROID["WGS_1984",6378137.0,298.257223563]]],PROJECTION["Transverse_Mercator"]]"#;
        assert_eq!(Crs::from_wkt(esri).epsg, None);
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
