//! `granflow export --layout avaframe`: a run's peak maps as AvaFrame's com1DFA writes
//! them, so that AvaFrame's AIMEC (Fischer 2013) and its other analysis tools read them
//! as they are.
//!
//! AvaFrame finds peak files in `<avalanche dir>/Outputs/com1DFA/peakFiles/` and reads
//! the simulation and the result type from the file name,
//! `<release>_<simHash>_C_<simType>_<modelType>_<resType>` (its parser splits on `_`):
//! here `<release>` is the run file's stem with everything but ASCII letters and digits
//! removed (AvaFrame's release name holds no `_`), `<simHash>` ten hexadecimal digits of
//! the FNV-1a hash of the stem (distinct runs of a sweep stay apart), `C` the default
//! configuration, `null` the simulation type (no entrainment, no resistance, as
//! AvaFrame names it) and `dfa` the model type. The result types are `pft` (m), `pfv`
//! (m/s) and `ppr` in **kPa**, AvaFrame's units (granflow's `/maps/ppr` is in Pa).

use std::path::{Path, PathBuf};

use super::export::{Field, MAP_FIELDS};
use super::ResultsError;

/// The fields AvaFrame's tools read.
pub const PEAK_FIELDS: [&str; 3] = ["pft", "pfv", "ppr"];

/// The directory of the peak files under the avalanche directory `dir`.
pub fn peak_dir(dir: &Path) -> PathBuf {
    dir.join("Outputs").join("com1DFA").join("peakFiles")
}

/// The peak file's name (without extension) of field `res` of the run `stem`.
pub fn peak_name(stem: &str, res: &str) -> String {
    let mut release: String = stem.chars().filter(char::is_ascii_alphanumeric).collect();
    release.truncate(40);
    if release.is_empty() {
        release.push_str("granflow");
    }
    // FNV-1a, 64 bits: stable across versions and machines.
    let hash = stem.bytes().fold(0xcbf2_9ce4_8422_2325u64, |h, b| {
        (h ^ u64::from(b)).wrapping_mul(0x0000_0100_0000_01b3)
    });
    format!("{release}_{:010x}_C_null_dfa_{res}", hash >> 24)
}

/// The maps to export in AvaFrame's layout: `fields` among pft, pfv, ppr (all three
/// by default), with AvaFrame's units; an error for anything else.
pub fn fields(maps: &[Field], asked: bool) -> Result<Vec<Field>, ResultsError> {
    let chosen: Vec<Field> = if asked {
        maps.to_vec()
    } else {
        MAP_FIELDS
            .iter()
            .filter(|f| PEAK_FIELDS.contains(&f.name))
            .copied()
            .collect()
    };
    if let Some(f) = chosen.iter().find(|f| !PEAK_FIELDS.contains(&f.name)) {
        return Err(ResultsError::input(format!(
            "--fields {}: --layout avaframe writes AvaFrame's peak files pft, pfv and ppr only",
            f.name
        )));
    }
    Ok(chosen
        .into_iter()
        .map(|f| match f.name {
            "ppr" => Field {
                units: "kPa",
                long_name: "peak pressure rho |u|^2 in kPa",
                ..f
            },
            _ => f,
        })
        .collect())
}

/// Values in AvaFrame's units: ppr from Pa to kPa.
pub fn in_units(field: &Field, values: Vec<f64>) -> Vec<f64> {
    if field.name == "ppr" {
        values.into_iter().map(|v| v / 1000.0).collect()
    } else {
        values
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_parse_as_avaframe_parses_them() {
        let n = peak_name("mu_deg=21.5__thickness=1.4", "ppr");
        let parts: Vec<&str> = n.split('_').collect();
        assert_eq!(parts.len(), 6, "{n}");
        assert_eq!(parts[0], "mudeg215thickness14");
        assert_eq!(parts[1].len(), 10);
        assert!(parts[1].chars().all(|c| c.is_ascii_hexdigit()));
        assert_eq!(parts[2..], ["C", "null", "dfa", "ppr"]);
        assert_ne!(
            peak_name("a=1", "pft").split('_').nth(1),
            peak_name("a_1", "pft").split('_').nth(1)
        );
        assert!(peak_name("__", "pft").starts_with("granflow_"));
    }
}
