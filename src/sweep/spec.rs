//! The sweep file: a base scenario, base overrides and the axes to vary.
//!
//! ```toml
//! scenario = "../collapse.toml"      # required, relative to this file
//! output = "out/slopes"              # optional, relative to the current directory
//! set = ["domain.cells=320"]         # optional, applied to every run
//!
//! [axes]                             # full product of these…
//! domain.slope_deg = [0, 9.78, 16]
//!
//! [[zip]]                            # …and of each zipped group (values taken together)
//! "initial.erodible_bed" = [0, 1.4e-3]
//! "rheology.mu_s_deg" = [25.5, 26]
//! ```
//!
//! Axis keys are the dotted scenario keys of `--set`, written either as TOML dotted keys
//! (`domain.slope_deg = …`) or quoted (`"domain.slope_deg" = …`); their values are
//! arrays. The file is read with `toml_edit` so that every error names its line.

use std::path::{Path, PathBuf};

use toml_edit::{Item, TableLike, Value};

use super::error::SweepError;
use super::naming::canonical_value;

/// One value of an axis.
#[derive(Debug, Clone, PartialEq)]
pub struct AxisValue {
    /// Inline TOML, as given to the scenario override (`9.78`, `"coulomb"`).
    pub toml: String,
    /// Canonical text for run names and the summary (`9.78`, `0.0014`, `coulomb`).
    pub display: String,
}

/// One scenario key varied by the sweep.
#[derive(Debug, Clone, PartialEq)]
pub struct Axis {
    /// Dotted scenario key (`domain.slope_deg`).
    pub key: String,
    /// Line of the key in the sweep file.
    pub line: Option<usize>,
    pub values: Vec<AxisValue>,
}

/// One factor of the product: a single axis, or a zipped group whose axes advance
/// together (all of the same length).
#[derive(Debug, Clone, PartialEq)]
pub struct Dimension {
    pub axes: Vec<Axis>,
    pub zipped: bool,
}

impl Dimension {
    /// Number of values along this dimension.
    pub fn len(&self) -> usize {
        self.axes.first().map_or(0, |a| a.values.len())
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// A parsed, checked sweep file.
#[derive(Debug, Clone)]
pub struct SweepSpec {
    /// The sweep file as given on the command line.
    pub path: PathBuf,
    /// Its text.
    pub text: String,
    /// The base scenario (the `scenario` key resolved against the sweep file's directory).
    pub scenario: PathBuf,
    /// Line of the `scenario` key.
    pub scenario_line: Option<usize>,
    /// Default output directory, when the file names one.
    pub output: Option<PathBuf>,
    /// Overrides applied to every run (`set = [...]`), before `--set` and the axes.
    pub set: Vec<String>,
    /// Line of the `set` key.
    pub set_line: Option<usize>,
    /// Factors of the product, outermost (slowest varying) first: the `[axes]` entries in
    /// file order, then the `[[zip]]` groups in file order.
    pub dims: Vec<Dimension>,
}

impl SweepSpec {
    /// Every axis, in column order.
    pub fn axes(&self) -> impl Iterator<Item = &Axis> {
        self.dims.iter().flat_map(|d| d.axes.iter())
    }

    /// The axis whose key is `key` or holds it (`initial.h` holds `initial.h.table`),
    /// or is held by it.
    pub fn axis_touching(&self, key: &str) -> Option<&Axis> {
        self.axes()
            .find(|a| is_under(key, &a.key) || is_under(&a.key, key))
    }

    /// Number of runs.
    pub fn run_count(&self) -> usize {
        self.dims.iter().map(Dimension::len).product()
    }
}

/// `path` is `ancestor` or below it in the dotted hierarchy.
pub(crate) fn is_under(path: &str, ancestor: &str) -> bool {
    path == ancestor
        || (path.len() > ancestor.len()
            && path.starts_with(ancestor)
            && path.as_bytes()[ancestor.len()] == b'.')
}

/// 1-based line of byte `offset` in `text`.
fn line_of(text: &str, offset: usize) -> usize {
    text.as_bytes()[..offset.min(text.len())]
        .iter()
        .filter(|&&c| c == b'\n')
        .count()
        + 1
}

const TOP_KEYS: &str = "scenario, output, set, axes, zip";

/// Reads and checks a sweep file.
pub fn load(path: &Path) -> Result<SweepSpec, SweepError> {
    let text =
        crate::scenario::read_bounded(path, crate::scenario::MAX_SCENARIO_BYTES).map_err(|e| {
            SweepError::file(path, None, None, format!("cannot read the sweep file: {e}"))
        })?;
    parse(path, &text)
}

/// Checks sweep-file `text`; `path` locates the base scenario and names the file in errors.
pub fn parse(path: &Path, text: &str) -> Result<SweepSpec, SweepError> {
    let doc = toml_edit::Document::parse(text).map_err(|e| {
        let line = e.span().map(|s| line_of(text, s.start));
        SweepError::file(
            path,
            line,
            None,
            format!("invalid TOML: {}", e.message().trim()),
        )
    })?;
    let p = Parser { path, text };
    let root = doc.as_table();

    let mut scenario = None;
    let mut output = None;
    let mut set = Vec::new();
    let mut set_line = None;
    let mut scenario_line = None;
    let mut product = Vec::new();
    let mut zips = Vec::new();
    for (name, item) in root.iter() {
        let line = p.key_line(root, name);
        match name {
            "scenario" => {
                scenario = Some(p.string(item, name, line)?);
                scenario_line = line;
            }
            "output" => output = Some(PathBuf::from(p.string(item, name, line)?)),
            "set" => {
                set = p.string_array(item, name, line)?;
                set_line = line;
            }
            "axes" => {
                let table = item.as_table_like().ok_or_else(|| {
                    p.err(
                        line,
                        name,
                        "must be a table: [axes] with one array per scenario key",
                    )
                })?;
                let mut axes = Vec::new();
                p.collect_axes(table, "", "axes", true, &mut axes)?;
                product.extend(axes.into_iter().map(|a| Dimension {
                    axes: vec![a],
                    zipped: false,
                }));
            }
            "zip" => {
                for (i, group) in p.zip_groups(item, line)?.into_iter().enumerate() {
                    let label = format!("zip[{i}]");
                    let mut axes = Vec::new();
                    p.collect_axes(group, "", &label, false, &mut axes)?;
                    if axes.is_empty() {
                        return Err(p.err(line, &label, "a [[zip]] group needs at least one axis"));
                    }
                    let first = &axes[0];
                    if let Some(bad) = axes.iter().find(|a| a.values.len() != first.values.len()) {
                        return Err(p.err(
                            bad.line,
                            &format!("{label}.{}", bad.key),
                            format!(
                                "zipped axes must have the same number of values: '{}' has {}, '{}' (line {}) has {}",
                                bad.key,
                                bad.values.len(),
                                first.key,
                                first.line.map_or("?".into(), |l| l.to_string()),
                                first.values.len()
                            ),
                        ));
                    }
                    zips.push(Dimension { axes, zipped: true });
                }
            }
            other => {
                return Err(p.err(
                    line,
                    other,
                    format!("unknown key '{other}' (allowed here: {TOP_KEYS})"),
                ))
            }
        }
    }
    let Some(scenario) = scenario else {
        return Err(p.err(
            None,
            "scenario",
            "missing required key: the base scenario file, e.g. scenario = \"../collapse.toml\"",
        ));
    };
    let dims: Vec<Dimension> = product.into_iter().chain(zips).collect();
    if dims.is_empty() {
        return Err(p.err(
            None,
            "axes",
            "no axes: add an [axes] table, e.g. domain.slope_deg = [16, 19, 22]",
        ));
    }
    // The same key (or a key and a table holding it) on two axes.
    let all: Vec<&Axis> = dims.iter().flat_map(|d| d.axes.iter()).collect();
    for (i, a) in all.iter().enumerate() {
        if let Some(b) = all[..i]
            .iter()
            .find(|b| is_under(&a.key, &b.key) || is_under(&b.key, &a.key))
        {
            return Err(p.err(
                a.line,
                &a.key,
                format!(
                    "'{}' is already varied by the axis '{}' (line {})",
                    a.key,
                    b.key,
                    b.line.map_or("?".into(), |l| l.to_string())
                ),
            ));
        }
    }
    let base_dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    };
    Ok(SweepSpec {
        path: path.to_path_buf(),
        text: text.to_owned(),
        scenario: base_dir.join(scenario),
        scenario_line,
        output,
        set,
        set_line,
        dims,
    })
}

struct Parser<'a> {
    path: &'a Path,
    text: &'a str,
}

impl Parser<'_> {
    fn err(&self, line: Option<usize>, key: &str, message: impl Into<String>) -> SweepError {
        SweepError::file(self.path, line, Some(key), message)
    }

    fn key_line(&self, table: &dyn TableLike, name: &str) -> Option<usize> {
        let (key, item) = table.get_key_value(name)?;
        key.span()
            .or_else(|| item.span())
            .map(|s| line_of(self.text, s.start))
    }

    fn string(&self, item: &Item, key: &str, line: Option<usize>) -> Result<String, SweepError> {
        match item.as_str() {
            Some(s) if !s.trim().is_empty() => Ok(s.to_owned()),
            Some(_) => Err(self.err(line, key, "must not be empty")),
            None => Err(self.err(line, key, "must be a string (in quotes)")),
        }
    }

    fn string_array(
        &self,
        item: &Item,
        key: &str,
        line: Option<usize>,
    ) -> Result<Vec<String>, SweepError> {
        let wrong = || {
            self.err(
                line,
                key,
                "must be an array of \"key=value\" strings, e.g. [\"domain.cells=320\"]",
            )
        };
        let array = item.as_array().ok_or_else(wrong)?;
        array
            .iter()
            .map(|v| v.as_str().map(str::to_owned).ok_or_else(wrong))
            .collect()
    }

    /// The tables of `zip`: `[[zip]]`, a single `[zip]`, or an array of inline tables.
    fn zip_groups<'i>(
        &self,
        item: &'i Item,
        line: Option<usize>,
    ) -> Result<Vec<&'i dyn TableLike>, SweepError> {
        let wrong = || {
            self.err(
                line,
                "zip",
                "must be one or more [[zip]] tables, each with arrays of equal length",
            )
        };
        match item {
            Item::ArrayOfTables(tables) => Ok(tables.iter().map(|t| t as &dyn TableLike).collect()),
            Item::Table(t) => Ok(vec![t as &dyn TableLike]),
            Item::Value(Value::Array(a)) => a
                .iter()
                .map(|v| match v {
                    Value::InlineTable(t) => Ok(t as &dyn TableLike),
                    _ => Err(wrong()),
                })
                .collect(),
            _ => Err(wrong()),
        }
    }

    /// Flattens `table` into axes: every array is an axis named by its dotted path.
    /// With `unique`, a value may not repeat (product axes; in a zipped group values
    /// repeat legitimately and only whole tuples must differ, which run names check).
    fn collect_axes(
        &self,
        table: &dyn TableLike,
        prefix: &str,
        label: &str,
        unique: bool,
        out: &mut Vec<Axis>,
    ) -> Result<(), SweepError> {
        for (name, item) in table.iter() {
            let key = if prefix.is_empty() {
                name.to_owned()
            } else {
                format!("{prefix}.{name}")
            };
            let line = self.key_line(table, name);
            let shown = format!("{label}.{key}");
            if let Some(bad) = key.split('.').find(|part| {
                part.is_empty()
                    || !part
                        .chars()
                        .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-')
            }) {
                return Err(self.err(
                    line,
                    &shown,
                    format!("'{bad}' is not a valid scenario key part (expected a dotted key such as domain.slope_deg)"),
                ));
            }
            match item {
                Item::Value(Value::Array(values)) => {
                    if values.is_empty() {
                        return Err(self.err(line, &shown, "needs at least one value"));
                    }
                    let values: Vec<AxisValue> = values
                        .iter()
                        .map(|v| {
                            let mut v = v.clone();
                            v.decor_mut().clear();
                            AxisValue {
                                toml: v.to_string(),
                                display: canonical_value(&v),
                            }
                        })
                        .collect();
                    for (i, v) in values.iter().enumerate().filter(|_| unique) {
                        if values[..i].iter().any(|w| w.display == v.display) {
                            return Err(self.err(
                                line,
                                &shown,
                                format!("the value {} is listed twice", v.toml),
                            ));
                        }
                    }
                    out.push(Axis { key, line, values });
                }
                _ => {
                    match item.as_table_like() {
                        Some(sub) => self.collect_axes(sub, &key, label, unique, out)?,
                        None => return Err(self.err(
                            line,
                            &shown,
                            "axis values must be an array, e.g. domain.slope_deg = [16, 19, 22]",
                        )),
                    }
                }
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse_ok(text: &str) -> SweepSpec {
        parse(Path::new("dir/s.toml"), text).unwrap_or_else(|e| panic!("{e}"))
    }

    #[track_caller]
    fn fails(text: &str, key: &str, line: Option<usize>, needle: &str) {
        match parse(Path::new("s.toml"), text) {
            Ok(_) => panic!("expected an error at {key}"),
            Err(e) => {
                assert_eq!(e.key(), Some(key), "{e}");
                assert_eq!(e.line(), line, "{e}");
                assert!(e.to_string().contains(needle), "{e}");
                assert_eq!(e.exit_code(), 2);
            }
        }
    }

    #[test]
    fn axes_zip_set_and_output() {
        let s = parse_ok(
            "scenario = \"../c.toml\"\noutput = \"out\"\nset = [\"domain.cells=100\"]\n\n[axes]\ndomain.slope_deg = [0, 9.78, 16]\n\"time.cfl\" = [0.5]\n\n[[zip]]\n\"initial.erodible_bed\" = [0, 1.4e-3]\nrheology.mu_s_deg = [25.5, 26]\n",
        );
        assert_eq!(s.scenario, Path::new("dir/../c.toml"));
        assert_eq!(s.output, Some(PathBuf::from("out")));
        assert_eq!(s.set, vec!["domain.cells=100".to_string()]);
        assert_eq!(s.set_line, Some(3));
        let keys: Vec<&str> = s.axes().map(|a| a.key.as_str()).collect();
        assert_eq!(
            keys,
            [
                "domain.slope_deg",
                "time.cfl",
                "initial.erodible_bed",
                "rheology.mu_s_deg"
            ]
        );
        assert_eq!(s.dims.len(), 3);
        assert!(s.dims[2].zipped && !s.dims[0].zipped);
        assert_eq!(s.run_count(), 3 * 2);
        let slope = &s.dims[0].axes[0];
        assert_eq!(slope.line, Some(6));
        assert_eq!(slope.values[1].toml, "9.78");
        let bed = &s.dims[2].axes[0];
        assert_eq!(bed.values[1].toml, "0.0014");
        assert_eq!(bed.values[1].display, "0.0014");
        assert!(s.axis_touching("domain.slope_deg").is_some());
        assert!(s.axis_touching("domain").is_some());
        assert!(s.axis_touching("domain.cells").is_none());
    }

    #[test]
    fn zip_forms_and_inline_tables() {
        let s = parse_ok(
            "scenario = \"c.toml\"\nzip = [{ a.x = [1, 2], b = [3, 4] }]\n[axes]\ninitial.h = { table = [\"a.csv\", \"b.csv\"] }\n",
        );
        let keys: Vec<&str> = s.axes().map(|a| a.key.as_str()).collect();
        assert_eq!(keys, ["initial.h.table", "a.x", "b"]);
        assert_eq!(s.run_count(), 4);
        let s = parse_ok("scenario = \"c.toml\"\n[zip]\na = [1, 2]\nb = [3, 4]\n");
        assert_eq!(s.dims.len(), 1);
        assert_eq!(s.run_count(), 2);
    }

    #[test]
    fn errors_name_key_and_line() {
        fails(
            "[axes]\na = [1]\n",
            "scenario",
            None,
            "missing required key",
        );
        fails("scenario = \"c\"\n", "axes", None, "no axes");
        fails(
            "scenario = \"c\"\nfoo = 1\n[axes]\na = [1]\n",
            "foo",
            Some(2),
            "unknown key 'foo'",
        );
        fails(
            "scenario = 3\n[axes]\na = [1]\n",
            "scenario",
            Some(1),
            "string",
        );
        fails(
            "scenario = \"c\"\n[axes]\na.b = 3\n",
            "axes.a.b",
            Some(3),
            "must be an array",
        );
        fails(
            "scenario = \"c\"\n[axes]\n\na.b = []\n",
            "axes.a.b",
            Some(4),
            "at least one value",
        );
        fails(
            "scenario = \"c\"\n[axes]\na = [1, 2, 1.0]\n",
            "axes.a",
            Some(3),
            "listed twice",
        );
        fails(
            "scenario = \"c\"\n[axes]\n\"a b\" = [1]\n",
            "axes.a b",
            Some(3),
            "not a valid scenario key part",
        );
        fails(
            "scenario = \"c\"\n[[zip]]\nx.a = [1, 2]\n\nx.b = [1, 2, 3]\n",
            "zip[0].x.b",
            Some(5),
            "same number of values: 'x.b' has 3, 'x.a' (line 3) has 2",
        );
        fails(
            "scenario = \"c\"\n[axes]\ninitial.h = [1]\n[[zip]]\ninitial.h.table = [\"a\"]\n",
            "initial.h.table",
            Some(5),
            "already varied by the axis 'initial.h'",
        );
        fails(
            "scenario = \"c\"\nset = \"a=1\"\n[axes]\na = [1]\n",
            "set",
            Some(2),
            "array",
        );
        let e = parse(Path::new("s.toml"), "scenario = \n").unwrap_err();
        assert_eq!(e.line(), Some(1), "{e}");
        assert!(e.to_string().contains("invalid TOML"), "{e}");
    }
}
