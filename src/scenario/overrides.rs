//! `--set key=value` overrides, applied to the TOML document before deserialising.
//!
//! The key is a dotted path (`domain.slope_deg`); the value is read as a TOML value
//! (`16`, `true`, `"text"`, `[1, 2]`, `{ table = "f.csv" }`) and, when it is not one, taken
//! as a bare string (`rheology.law=coulomb`). Edits go through `toml_edit`, so comments and
//! layout of the file survive in `Scenario::source_toml`. Whether the key exists in the
//! schema is decided afterwards by deserialisation (unknown keys are rejected there and
//! reported as coming from `--set`), so the schema is written down only once, in `raw`.

use toml_edit::{DocumentMut, InlineTable, Item, Table, Value};

use super::error::ScenarioError;

/// One parsed `key=value`.
#[derive(Debug, Clone)]
pub(crate) struct Override {
    /// The dotted key as normalised (`domain.slope_deg`).
    pub key: String,
    parts: Vec<String>,
    value: Value,
}

impl Override {
    pub(crate) fn parse(text: &str) -> Result<Override, ScenarioError> {
        let Some((key, value)) = text.split_once('=') else {
            return Err(ScenarioError::new(format!(
                "--set '{text}': expected key=value, e.g. domain.slope_deg=20"
            )));
        };
        let parts: Vec<String> = key.split('.').map(|p| p.trim().to_owned()).collect();
        if let Some(bad) = parts.iter().find(|p| {
            p.is_empty()
                || !p
                    .chars()
                    .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-')
        }) {
            let why = if bad.is_empty() {
                "empty key part".to_owned()
            } else {
                format!("invalid key part '{bad}'")
            };
            return Err(ScenarioError::new(format!(
                "--set '{text}': {why} (expected a dotted key such as domain.slope_deg)"
            )));
        }
        let key = parts.join(".");
        let value_text = value.trim();
        let mut value = match value_text.parse::<Value>() {
            Ok(v) => v,
            Err(_) if looks_numeric(value_text) => {
                return Err(ScenarioError::at(
                    key,
                    format!(
                        "{value_text} is out of range for a number (floats up to ±1.8e308, integers up to ±9.2e18)"
                    ),
                )
                .mark_from_set())
            }
            Err(_) => Value::from(value_text),
        };
        value.decor_mut().clear();
        Ok(Override { key, parts, value })
    }

    /// Sets the value in `doc`, creating missing tables on the way.
    pub(crate) fn apply(&self, doc: &mut DocumentMut) -> Result<(), ScenarioError> {
        let (leaf, parents) = self.parts.split_last().expect("at least one part");
        let mut table: &mut dyn toml_edit::TableLike = doc.as_table_mut();
        for (depth, part) in parents.iter().enumerate() {
            match table.get_mut(part) {
                Some(item) if item.is_table_like() => {}
                Some(Item::Value(old)) => {
                    // A value where a table is needed: `--set initial.h.table=f.csv` over
                    // `h = 0.1` turns the profile into a table. Whether the result is
                    // allowed is for deserialisation to say.
                    let mut fresh = Value::InlineTable(InlineTable::new());
                    *fresh.decor_mut() = old.decor().clone();
                    *old = fresh;
                }
                Some(_) => {
                    return Err(ScenarioError::at(
                        self.key.clone(),
                        format!(
                            "cannot set it: '{}' is not a table",
                            self.parts[..=depth].join(".")
                        ),
                    )
                    .mark_from_set())
                }
                None => {
                    // A new top-level section becomes a `[section]` at the end of the
                    // file; anything deeper an inline table.
                    let fresh = if depth == 0 {
                        Item::Table(Table::new())
                    } else {
                        Item::Value(Value::InlineTable(InlineTable::new()))
                    };
                    table.insert(part, fresh);
                }
            }
            let item = table.get_mut(part).expect("just ensured");
            table = item.as_table_like_mut().expect("just ensured");
        }
        let mut value = self.value.clone();
        match table.get_mut(leaf) {
            Some(Item::Value(old)) => {
                // Keep the spacing and any trailing comment of the replaced value.
                *value.decor_mut() = old.decor().clone();
                *old = value;
            }
            _ => {
                table.insert(leaf, Item::Value(value));
            }
        }
        Ok(())
    }
}

/// Text that is meant as a number (a digit first, after an optional sign or point) but
/// that TOML did not take as one: too large (`1e400`, twenty-digit integers).
/// Other words (`coulomb`, `infinity`, `run 1.h5`) stay bare strings.
fn looks_numeric(text: &str) -> bool {
    let body = text.trim_start_matches(['+', '-']).trim_start_matches('.');
    body.starts_with(|c: char| c.is_ascii_digit()) && text.replace('_', "").parse::<f64>().is_ok()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn apply(text: &str, sets: &[&str]) -> String {
        let mut doc: DocumentMut = text.parse().unwrap();
        for s in sets {
            Override::parse(s).unwrap().apply(&mut doc).unwrap();
        }
        doc.to_string()
    }

    #[test]
    fn replaces_value_keeping_comment() {
        let out = apply(
            "[domain]\nslope_deg = 20 # degrees\ncells = 10\n",
            &["domain.slope_deg=16"],
        );
        assert_eq!(out, "[domain]\nslope_deg = 16 # degrees\ncells = 10\n");
    }

    #[test]
    fn bare_words_are_strings_and_toml_values_are_parsed() {
        let out = apply("[rheology]\nlaw = \"mu_i\"\n", &["rheology.law=coulomb"]);
        assert_eq!(out, "[rheology]\nlaw = \"coulomb\"\n");
        let out = apply("[time]\nt_end = 1\n", &["time.stop_at_rest = true"]);
        assert_eq!(out, "[time]\nt_end = 1\nstop_at_rest = true\n");
        let out = apply("[output]\n", &["output.file=run 1.h5"]);
        assert_eq!(out, "[output]\nfile = \"run 1.h5\"\n");
        let out = apply("[initial]\nh = 0.1\n", &["initial.h={ table = \"f.csv\" }"]);
        assert_eq!(out, "[initial]\nh = { table = \"f.csv\" }\n");
        let out = apply("[bed]\nb = 0\n", &["bed.b=\"0.1*x\""]);
        assert_eq!(out, "[bed]\nb = \"0.1*x\"\n");
    }

    #[test]
    fn adds_missing_keys_and_sections() {
        let out = apply(
            "[domain]\ncells = 10\n\n[time]\nt_end = 1\n",
            &["initial.erodible_bed=0.01", "domain.x_min=0"],
        );
        assert_eq!(
            out,
            "[domain]\ncells = 10\nx_min = 0\n\n[time]\nt_end = 1\n\n[initial]\nerodible_bed = 0.01\n"
        );
        let out = apply("[initial]\n", &["initial.h.table=f.csv"]);
        assert_eq!(out, "[initial]\nh = { table = \"f.csv\" }\n");
    }

    #[test]
    fn dotted_keys_in_the_file() {
        let out = apply("domain.x_min = 0\n[time]\nt_end = 1\n", &["domain.cells=3"]);
        let back: toml::Table = toml::from_str(&out).unwrap();
        assert_eq!(back["domain"]["cells"].as_integer(), Some(3), "{out}");
        assert_eq!(back["domain"]["x_min"].as_integer(), Some(0), "{out}");
    }

    #[test]
    fn value_becomes_table_when_a_subkey_is_set() {
        let out = apply("[initial]\nh = 0.1 # m\n", &["initial.h.table=f.csv"]);
        assert_eq!(out, "[initial]\nh = { table = \"f.csv\" } # m\n");
    }

    #[test]
    fn errors() {
        assert!(Override::parse("domain.cells").is_err());
        assert!(Override::parse("domain..cells=1").is_err());
        assert!(Override::parse("=1").is_err());
        assert!(Override::parse("domain.a b=1").is_err());
        let mut doc: DocumentMut = "[[domain]]\ncells = 10\n".parse().unwrap();
        let e = Override::parse("domain.cells=1")
            .unwrap()
            .apply(&mut doc)
            .unwrap_err();
        assert_eq!(e.key(), Some("domain.cells"));
        assert!(e.is_from_set());
        assert!(e.message().contains("'domain' is not a table"), "{e}");
    }
}
