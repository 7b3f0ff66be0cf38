//! Stable text for parameter values and the file name of each run.
//!
//! A run is named from its parameters, `slope_deg=16__erodible_bed=0.0014`: one
//! `name=value` part per axis in axis order, joined by `__`. The name of a key is its last
//! component unless two axes share it, then the whole dotted key. Numbers are written the
//! same way whatever their spelling in the sweep file (`16`, `16.0` → `16`; `1.4e-3` →
//! `0.0014`; `1e-7` → `1e-7`): the shortest text that reads back as the same f64, plain
//! decimal between 1e-4 and 1e15, exponent form outside. Characters other than ASCII
//! letters, digits and `. _ - + =` become `_`; over-long names are cut and end in a hash
//! of the full name.

use toml_edit::Value;

/// Longest run name kept as is (bytes); longer ones are cut and hashed.
const MAX_NAME: usize = 150;

/// Canonical text of a float: shortest round-trip representation, exponent form for very
/// small or large magnitudes, no trailing `.0`, no negative zero.
pub fn format_float(v: f64) -> String {
    if v.is_nan() {
        return "nan".into();
    }
    if v.is_infinite() {
        return if v > 0.0 { "inf" } else { "-inf" }.into();
    }
    if v == 0.0 {
        return "0".into();
    }
    let a = v.abs();
    if !(1e-4..1e15).contains(&a) {
        format!("{v:e}")
    } else {
        // `Display` of f64 is the shortest decimal that round-trips, without exponent.
        format!("{v}")
    }
}

/// Canonical text of an axis value (for names and the summary).
pub fn canonical_value(v: &Value) -> String {
    match v {
        Value::Integer(i) => i.value().to_string(),
        Value::Float(f) => format_float(*f.value()),
        Value::String(s) => s.value().clone(),
        Value::Boolean(b) => b.value().to_string(),
        other => {
            let mut v = other.clone();
            v.decor_mut().clear();
            v.to_string()
        }
    }
}

/// Short names of the axis keys: the last component, or the whole key when that is shared.
pub fn short_names(keys: &[&str]) -> Vec<String> {
    let leaf = |k: &str| k.rsplit('.').next().unwrap_or(k).to_owned();
    keys.iter()
        .map(|k| {
            let l = leaf(k);
            if keys.iter().filter(|o| leaf(o) == l).count() > 1 {
                (*k).to_owned()
            } else {
                l
            }
        })
        .collect()
}

/// Replaces every character not safe in a file name on common file systems.
pub fn sanitize(text: &str) -> String {
    text.chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || matches!(c, '.' | '_' | '-' | '+' | '=') {
                c
            } else {
                '_'
            }
        })
        .collect()
}

/// The run name from `(short name, value text)` pairs.
pub fn run_name(parts: &[(&str, &str)]) -> String {
    let full: String = parts
        .iter()
        .map(|(k, v)| format!("{k}={v}"))
        .collect::<Vec<_>>()
        .join("__");
    let mut name = sanitize(&full);
    if name.starts_with('.') {
        name.replace_range(0..1, "_");
    }
    if name.len() > MAX_NAME {
        name.truncate(MAX_NAME - 18);
        name.push('~');
        name.push_str(&format!("{:016x}", fnv1a(full.as_bytes())));
    }
    name
}

/// 64-bit FNV-1a: a small hash whose value is fixed forever (unlike `DefaultHasher`),
/// so it can be stored in files.
pub fn fnv1a(bytes: &[u8]) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for &b in bytes {
        h ^= u64::from(b);
        h = h.wrapping_mul(0x0000_0100_0000_01b3);
    }
    h
}

#[cfg(test)]
mod tests {
    use super::*;

    fn value(text: &str) -> Value {
        text.parse().unwrap()
    }

    #[test]
    fn floats_are_stable_and_exact() {
        assert_eq!(format_float(16.0), "16");
        assert_eq!(format_float(9.78), "9.78");
        assert_eq!(format_float(1.4e-3), "0.0014");
        assert_eq!(format_float(1e-7), "1e-7");
        assert_eq!(format_float(2.5e300), "2.5e300");
        assert_eq!(format_float(-0.0), "0");
        assert_eq!(format_float(-22.5), "-22.5");
        assert_eq!(format_float(f64::NAN), "nan");
        for v in [0.1 + 0.2, 1.0 / 3.0, 1.82e-3, 23.7, 1e-5, 123456.789e10] {
            assert_eq!(format_float(v).parse::<f64>().unwrap(), v);
        }
    }

    #[test]
    fn canonical_values_ignore_spelling() {
        assert_eq!(canonical_value(&value("16")), "16");
        assert_eq!(canonical_value(&value("16.0")), "16");
        assert_eq!(canonical_value(&value("1.4e-3")), "0.0014");
        assert_eq!(canonical_value(&value("\"coulomb\"")), "coulomb");
        assert_eq!(canonical_value(&value("true")), "true");
        assert_eq!(
            canonical_value(&value("{ table = \"a.csv\" }")),
            "{ table = \"a.csv\" }"
        );
    }

    #[test]
    fn names() {
        assert_eq!(
            short_names(&["domain.slope_deg", "initial.erodible_bed"]),
            ["slope_deg", "erodible_bed"]
        );
        assert_eq!(short_names(&["a.mu", "b.mu", "c.x"]), ["a.mu", "b.mu", "x"]);
        assert_eq!(
            run_name(&[("slope_deg", "16"), ("erodible_bed", "0.0014")]),
            "slope_deg=16__erodible_bed=0.0014"
        );
        assert_eq!(
            run_name(&[("h", "if(x <= 0, 0.14, 0)")]),
            "h=if_x__=_0__0.14__0_"
        );
        assert_eq!(run_name(&[("a/b", "..")]), "a_b=..");
        let long = "x".repeat(400);
        let n = run_name(&[("h", &long)]);
        assert_eq!(n.len(), MAX_NAME - 1);
        assert_ne!(n, run_name(&[("h", &format!("{long}y"))]));
        assert_eq!(fnv1a(b""), 0xcbf2_9ce4_8422_2325);
        assert_eq!(fnv1a(b"a"), 0xaf63_dc4c_8601_ec8c);
    }
}
