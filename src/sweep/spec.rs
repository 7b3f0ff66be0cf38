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
use super::sample;

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

const TOP_KEYS: &str = "scenario, output, set, axes, zip, sample";

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
            "sample" => zips.push(p.sample(item, line)?),
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

/// A dotted scenario key's parts are ASCII letters, digits, `_` and `-`.
fn check_key(key: &str) -> Result<(), String> {
    match key.split('.').find(|part| {
        part.is_empty()
            || !part
                .chars()
                .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-')
    }) {
        Some(bad) => Err(format!(
            "'{bad}' is not a valid scenario key part (expected a dotted key such as domain.slope_deg)"
        )),
        None => Ok(()),
    }
}

/// A distribution of `[sample]` (`sweep::sample`): `uniform = [a, b]`,
/// `normal = [mean, sd]` with optional `min`, `max`, or `ci95 = [value, half_width]`.
fn distribution(t: &dyn TableLike) -> Result<sample::Distribution, String> {
    use sample::Distribution;
    let number = |v: &Item| v.as_float().or_else(|| v.as_integer().map(|i| i as f64));
    let pair = |name: &str| -> Result<Option<(f64, f64)>, String> {
        let Some(v) = t.get(name) else {
            return Ok(None);
        };
        let a = v.as_array().filter(|a| a.len() == 2);
        let p = a.and_then(|a| {
            let x: Vec<f64> = a
                .iter()
                .filter_map(|v| v.as_float().or_else(|| v.as_integer().map(|i| i as f64)))
                .collect();
            (x.len() == 2 && x.iter().all(|x| x.is_finite())).then(|| (x[0], x[1]))
        });
        p.map(Some).ok_or_else(|| {
            format!(
                "{name} must be two finite numbers, found {}",
                v.to_string().trim()
            )
        })
    };
    let kinds: Vec<&str> = ["uniform", "normal", "ci95"]
        .into_iter()
        .filter(|k| t.contains_key(k))
        .collect();
    if kinds.len() > 1 {
        return Err(format!(
            "one distribution per key, found {}",
            kinds.join(" and ")
        ));
    }
    let allowed: &[&str] = match kinds[0] {
        "normal" => &["normal", "min", "max"],
        "uniform" => &["uniform"],
        _ => &["ci95"],
    };
    if let Some((other, _)) = t.iter().find(|(k, _)| !allowed.contains(k)) {
        return Err(format!(
            "unknown key '{other}' with {} (allowed: {})",
            kinds[0],
            allowed.join(", ")
        ));
    }
    let bound = |name: &str, default: f64| -> Result<f64, String> {
        match t.get(name) {
            None => Ok(default),
            Some(v) => number(v).filter(|x| x.is_finite()).ok_or_else(|| {
                format!(
                    "{name} must be a finite number, found {}",
                    v.to_string().trim()
                )
            }),
        }
    };
    let d = match kinds[0] {
        "uniform" => {
            let (lo, hi) = pair("uniform")?.unwrap_or_default();
            if lo >= hi {
                return Err(format!("uniform = [a, b] needs a < b, got [{lo}, {hi}]"));
            }
            Distribution::Uniform { lo, hi }
        }
        "ci95" => {
            let (v, c) = pair("ci95")?.unwrap_or_default();
            if c <= 0.0 {
                return Err(format!(
                    "ci95 = [value, half_width] needs a half-width > 0, got {c}"
                ));
            }
            Distribution::Uniform {
                lo: v - c,
                hi: v + c,
            }
        }
        _ => {
            let (mean, sd) = pair("normal")?.unwrap_or_default();
            if sd <= 0.0 {
                return Err(format!("normal = [mean, sd] needs sd > 0, got {sd}"));
            }
            let (lo, hi) = (
                bound("min", f64::NEG_INFINITY)?,
                bound("max", f64::INFINITY)?,
            );
            if lo >= hi {
                return Err(format!("min ({lo}) must be below max ({hi})"));
            }
            let d = Distribution::Normal { mean, sd, lo, hi };
            // Far in a tail the window holds no probability a double can resolve.
            if d.mass().is_nan() || d.mass() <= 1e-300 {
                return Err(format!(
                    "[min, max] = [{lo}, {hi}] holds no probability of normal = [{mean}, {sd}]"
                ));
            }
            d
        }
    };
    Ok(d)
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

    /// `[sample]`: `runs`, `seed` and one distribution per scenario key, drawn by a
    /// Latin hypercube into one zipped group of `runs` values (`sweep::sample`).
    fn sample(&self, item: &Item, line: Option<usize>) -> Result<Dimension, SweepError> {
        let table = item.as_table_like().ok_or_else(|| {
            self.err(
                line,
                "sample",
                "must be a table: [sample] with runs, seed and one distribution per key",
            )
        })?;
        let integer = |name: &str, min: i64| -> Result<Option<i64>, SweepError> {
            let Some(v) = table.get(name) else {
                return Ok(None);
            };
            match v.as_integer() {
                Some(i) if i >= min => Ok(Some(i)),
                _ => Err(self.err(
                    self.key_line(table, name),
                    &format!("sample.{name}"),
                    format!("must be an integer ≥ {min}, found {}", v.to_string().trim()),
                )),
            }
        };
        let runs = integer("runs", 1)?.ok_or_else(|| {
            self.err(
                line,
                "sample.runs",
                "missing: the number of runs to draw, e.g. runs = 40",
            )
        })? as usize;
        let seed = integer("seed", 0)?.unwrap_or(0) as u64;
        let mut leaves = Vec::new();
        for (name, item) in table.iter() {
            if name != "runs" && name != "seed" {
                self.distributions(table, name, item, name.to_owned(), &mut leaves)?;
            }
        }
        if leaves.is_empty() {
            return Err(self.err(
                line,
                "sample",
                "no distribution: add e.g. rheology.mu = { uniform = [0.12, 0.2] }",
            ));
        }
        let u = sample::latin_hypercube(runs, leaves.len(), seed);
        let axes = leaves
            .into_iter()
            .zip(u)
            .map(|((key, line, dist), u)| Axis {
                key,
                line,
                values: u
                    .into_iter()
                    .map(|u| {
                        let v = Value::from(dist.quantile(u));
                        AxisValue {
                            toml: v.to_string(),
                            display: canonical_value(&v),
                        }
                    })
                    .collect(),
            })
            .collect();
        Ok(Dimension { axes, zipped: true })
    }

    /// The distributions under `item` (key `key`): a table with `uniform`, `normal` or
    /// `ci95` is one; any other table holds more.
    fn distributions(
        &self,
        parent: &dyn TableLike,
        name: &str,
        item: &Item,
        key: String,
        out: &mut Vec<(String, Option<usize>, sample::Distribution)>,
    ) -> Result<(), SweepError> {
        let line = self.key_line(parent, name);
        let shown = format!("sample.{key}");
        check_key(&key).map_err(|m| self.err(line, &shown, m))?;
        let Some(t) = item.as_table_like() else {
            return Err(self.err(
                line,
                &shown,
                "must be a distribution: { uniform = [a, b] }, { normal = [mean, sd] } (with optional min, max) or { ci95 = [value, half_width] }",
            ));
        };
        if !["uniform", "normal", "ci95"]
            .iter()
            .any(|k| t.contains_key(k))
        {
            for (sub, item) in t.iter() {
                self.distributions(t, sub, item, format!("{key}.{sub}"), out)?;
            }
            return Ok(());
        }
        let d = distribution(t).map_err(|m| self.err(line, &shown, m))?;
        out.push((key, line, d));
        Ok(())
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

    #[test]
    fn a_sample_is_one_zipped_group_drawn_by_a_latin_hypercube() {
        let text = "scenario = \"c.toml\"\n[axes]\ndomain.slope_deg = [10, 20]\n[sample]\nruns = 8\nseed = 3\nrheology.mu = { uniform = [0.1, 0.3] }\ninitial.h = { thickness = { ci95 = [1.5, 0.3] } }\nrheology.xi = { normal = [2000, 400], min = 1500 }\n";
        let s = parse_ok(text);
        assert_eq!(s.run_count(), 2 * 8);
        let group = &s.dims[1];
        assert!(group.zipped);
        let keys: Vec<&str> = group.axes.iter().map(|a| a.key.as_str()).collect();
        // In the order of the TOML tables (rheology's keys together).
        assert_eq!(keys, ["rheology.mu", "rheology.xi", "initial.h.thickness"]);
        assert_eq!(group.axes[0].line, Some(7));
        let values =
            |a: &Axis| -> Vec<f64> { a.values.iter().map(|v| v.toml.parse().unwrap()).collect() };
        // Every stratum of each axis once: the uniform's and the ci95's by their
        // bounds, the normal's through its CDF.
        let strata = |x: &[f64], cdf: &dyn Fn(f64) -> f64| {
            let mut k: Vec<usize> = x.iter().map(|&x| (cdf(x) * 8.0) as usize).collect();
            k.sort();
            k
        };
        let all: Vec<usize> = (0..8).collect();
        assert_eq!(strata(&values(&group.axes[0]), &|x| (x - 0.1) / 0.2), all);
        assert_eq!(strata(&values(&group.axes[2]), &|x| (x - 1.2) / 0.6), all);
        let phi = sample::phi;
        let lo = phi(-1.25);
        let normal = |x: f64| (phi((x - 2000.0) / 400.0) - lo) / (1.0 - lo);
        assert_eq!(strata(&values(&group.axes[1]), &normal), all);
        assert!(values(&group.axes[1]).iter().all(|&x| x >= 1500.0));
        // The same seed, the same runs; another, others.
        assert_eq!(parse_ok(text).dims, s.dims);
        assert_ne!(parse_ok(&text.replace("seed = 3", "seed = 4")).dims, s.dims);
    }

    #[test]
    fn bad_samples_name_their_key_and_line() {
        let base = "scenario = \"c\"\n[sample]\n";
        for (body, key, line, needle) in [
            (
                "seed = 1\na = { uniform = [0, 1] }\n",
                "sample.runs",
                Some(2),
                "missing",
            ),
            (
                "runs = 0\na = { uniform = [0, 1] }\n",
                "sample.runs",
                Some(3),
                "integer ≥ 1",
            ),
            (
                "runs = 4\nseed = -1\na = { uniform = [0, 1] }\n",
                "sample.seed",
                Some(4),
                "integer ≥ 0",
            ),
            ("runs = 4\n", "sample", Some(2), "no distribution"),
            (
                "runs = 4\na.b = { uniform = [1, 0] }\n",
                "sample.a.b",
                Some(4),
                "a < b",
            ),
            (
                "runs = 4\na = { uniform = [0] }\n",
                "sample.a",
                Some(4),
                "two finite numbers",
            ),
            (
                "runs = 4\na = { normal = [0, 0] }\n",
                "sample.a",
                Some(4),
                "sd > 0",
            ),
            (
                "runs = 4\na = { normal = [0, 1], min = 2, max = 1 }\n",
                "sample.a",
                Some(4),
                "below max",
            ),
            (
                "runs = 4\na = { normal = [0, 1], min = 50 }\n",
                "sample.a",
                Some(4),
                "no probability",
            ),
            (
                "runs = 4\na = { ci95 = [1, -0.1] }\n",
                "sample.a",
                Some(4),
                "half-width > 0",
            ),
            (
                "runs = 4\na = { uniform = [0, 1], min = 0 }\n",
                "sample.a",
                Some(4),
                "unknown key 'min'",
            ),
            (
                "runs = 4\na = { uniform = [0, 1], ci95 = [1, 1] }\n",
                "sample.a",
                Some(4),
                "one distribution",
            ),
            (
                "runs = 4\na = 3\n",
                "sample.a",
                Some(4),
                "must be a distribution",
            ),
        ] {
            fails(&format!("{base}{body}"), key, line, needle);
        }
    }
}
