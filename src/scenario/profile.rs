//! Spatial profiles: `bed.b`, `initial.h`, `initial.u`, `initial.v`, `initial.w`.
//!
//! A profile is written in the scenario as a number, as an expression in `x` (and `y`
//! on a raster domain) (a string), as a CSV table along x (`{ table = "file.csv" }`)
//! or as a raster file (`{ raster = "dem.asc" }`, ESRI ASCII grid or GeoTIFF, read by
//! [`crate::gis`] and interpolated bilinearly between its cell centres). Expressions
//! are parsed once with `evalexpr` and evaluated per point through a small fixed
//! context: the variables `x`, `y`, `b` (bed elevation, only where allowed), the
//! constants `pi` and `deg`, and a fixed set of functions (see [`FUNCTIONS`]). Integer
//! literals are turned into floats right after parsing, so `1/2` is 0.5.

use std::fmt;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use evalexpr::error::EvalexprResultValue;
use evalexpr::{
    build_operator_tree, Context, DefaultNumericTypes, EvalexprError, EvalexprResult, Node,
    Operator, Value,
};

use super::compiled::Compiled;
use super::error::ScenarioError;
use crate::gis::short_number;

/// Function names an expression may call.
pub(crate) const FUNCTIONS: &[&str] = &[
    "exp", "ln", "log10", "sqrt", "abs", "sin", "cos", "tan", "asin", "acos", "atan", "atan2",
    "sinh", "cosh", "tanh", "erf", "min", "max", "floor", "ceil", "round", "pow", "if", "noise",
];

/// A function of position: constant, expression or interpolated table.
///
/// Cheap to clone (expressions and tables are shared).
#[derive(Debug, Clone)]
pub struct Profile {
    kind: Kind,
}

#[derive(Debug, Clone)]
enum Kind {
    Constant(f64),
    Expr(Arc<Expression>),
    Table(Arc<Table>),
    Raster(Arc<RasterProfile>),
    Function(Function),
}

/// A profile given as Rust code (tests and library users), f(x, b).
#[derive(Clone)]
struct Function(Arc<dyn Fn(f64, f64) -> f64 + Send + Sync>);

impl fmt::Debug for Function {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("Function")
    }
}

impl Profile {
    /// The same value everywhere.
    pub fn constant(v: f64) -> Profile {
        Profile {
            kind: Kind::Constant(v),
        }
    }

    /// A profile computed by `f(x, b)`, for library users and tests that build a
    /// [`Scenario`](super::Scenario) without a file.
    pub fn function(f: impl Fn(f64, f64) -> f64 + Send + Sync + 'static) -> Profile {
        Profile {
            kind: Kind::Function(Function(Arc::new(f))),
        }
    }

    /// Compiles an expression in `x` that may also use the bed elevation `b`.
    ///
    /// Mostly for tests and tools; scenario files go through the loader, which also names
    /// the key in its errors.
    pub fn expression(source: &str) -> Result<Profile, ScenarioError> {
        Expression::compile(source, true)
            .map(|e| Profile {
                kind: Kind::Expr(Arc::new(e)),
            })
            .map_err(ScenarioError::new)
    }

    /// Value at position `x`, where the bed elevation is `b` (ignored unless the profile is
    /// an expression using `b`).
    ///
    /// Returns NaN if the expression fails to evaluate there; a loaded scenario has been
    /// checked to give finite values at every cell centre.
    pub fn eval(&self, x: f64, b: f64) -> f64 {
        self.try_eval(x, b).unwrap_or(f64::NAN)
    }

    /// Value at the point (x, y) of a raster domain, where the bed elevation is `b`
    /// (NaN where it cannot be computed, as [`Profile::eval`]).
    pub fn eval_xy(&self, x: f64, y: f64, b: f64) -> f64 {
        self.try_eval_xy(x, y, b).unwrap_or(f64::NAN)
    }

    /// Whether the profile depends on y (an expression using `y`, or a raster): such a
    /// profile needs a raster domain.
    pub fn uses_y(&self) -> bool {
        match &self.kind {
            Kind::Expr(e) => e.uses_y,
            Kind::Raster(_) => true,
            _ => false,
        }
    }

    /// The raster behind a `{ raster = "…" }` profile.
    pub fn raster(&self) -> Option<&crate::gis::Raster> {
        match &self.kind {
            Kind::Raster(r) => Some(&r.raster),
            _ => None,
        }
    }

    /// A raster profile of `raster` (read from `path`, named in messages).
    pub(crate) fn from_raster(path: &Path, raster: crate::gis::Raster) -> Profile {
        Profile {
            kind: Kind::Raster(Arc::new(RasterProfile {
                path: path.to_owned(),
                raster,
            })),
        }
    }

    /// The file of a raster profile, as written in the scenario.
    pub(crate) fn raster_path(&self) -> Option<&Path> {
        match &self.kind {
            Kind::Raster(r) => Some(&r.path),
            _ => None,
        }
    }

    /// `Some(v)` for a constant profile.
    pub fn as_constant(&self) -> Option<f64> {
        match self.kind {
            Kind::Constant(v) => Some(v),
            _ => None,
        }
    }

    /// A short human description: `0.14`, `expression "max(0, 1 - x)"`,
    /// `table "h.csv" (12 rows, x in [0, 1.1])`.
    pub fn describe(&self) -> String {
        match &self.kind {
            Kind::Constant(v) => format!("{v}"),
            Kind::Expr(e) => format!("expression \"{}\"", e.source),
            Kind::Table(t) => format!(
                "table \"{}\" ({} row{}, x in [{}, {}])",
                t.path.display(),
                t.xs.len(),
                if t.xs.len() == 1 { "" } else { "s" },
                t.xs[0],
                t.xs[t.xs.len() - 1]
            ),
            Kind::Raster(r) => format!(
                "raster \"{}\" ({} × {} cells of {} m)",
                r.path.display(),
                r.raster.nx,
                r.raster.ny,
                r.raster.cell_size
            ),
            Kind::Function(_) => "function".to_string(),
        }
    }

    /// Value at `x`, or a description of why it cannot be computed.
    pub(crate) fn try_eval(&self, x: f64, b: f64) -> Result<f64, String> {
        self.try_eval_xy(x, 0.0, b)
    }

    /// Value at (x, y), or a description of why it cannot be computed.
    pub(crate) fn try_eval_xy(&self, x: f64, y: f64, b: f64) -> Result<f64, String> {
        match &self.kind {
            Kind::Constant(v) => Ok(*v),
            Kind::Expr(e) => e.eval(x, y, b),
            Kind::Table(t) => Ok(t.eval(x)),
            Kind::Raster(r) => r.eval(x, y),
            Kind::Function(f) => Ok((f.0)(x, b)),
        }
    }

    /// Reads a profile from its TOML form. `key` is the dotted key (for errors), `base_dir`
    /// resolves table paths, `allow_b` says whether expressions may use the variable `b`.
    pub(crate) fn from_toml(
        key: &str,
        value: &toml::Value,
        base_dir: &Path,
        allow_b: bool,
    ) -> Result<Profile, ScenarioError> {
        match value {
            toml::Value::Integer(i) => Ok(Profile::constant(*i as f64)),
            toml::Value::Float(v) if v.is_finite() => Ok(Profile::constant(*v)),
            toml::Value::Float(v) => Err(ScenarioError::at(
                key,
                format!("must be finite, got {v}"),
            )),
            toml::Value::String(s) => Expression::compile(s, allow_b)
                .map(|e| Profile {
                    kind: Kind::Expr(Arc::new(e)),
                })
                .map_err(|m| ScenarioError::at(key, m)),
            toml::Value::Table(t) => {
                if let Some(other) = t.keys().find(|k| k.as_str() != "table" && k.as_str() != "raster") {
                    return Err(ScenarioError::at(
                        format!("{key}.{other}"),
                        format!("unknown key '{other}' in a table profile (only 'table' or 'raster' is allowed)"),
                    ));
                }
                if t.contains_key("raster") {
                    if t.contains_key("table") {
                        return Err(ScenarioError::at(
                            format!("{key}.raster"),
                            "give either table (a CSV along x) or raster (a grid file), not both",
                        ));
                    }
                    return match t.get("raster") {
                        Some(toml::Value::String(file)) => {
                            RasterProfile::load(Path::new(file), base_dir)
                                .map(|r| Profile {
                                    kind: Kind::Raster(Arc::new(r)),
                                })
                                .map_err(|m| ScenarioError::at(key, m))
                        }
                        Some(other) => Err(ScenarioError::at(
                            format!("{key}.raster"),
                            format!(
                                "must be a file name (a string), found {}",
                                other.type_str()
                            ),
                        )),
                        None => unreachable!("checked above"),
                    };
                }
                match t.get("table") {
                    Some(toml::Value::String(file)) => Table::load(Path::new(file), base_dir, key)
                        .map(|t| Profile {
                            kind: Kind::Table(Arc::new(t)),
                        })
                        .map_err(|m| ScenarioError::at(key, m)),
                    Some(other) => Err(ScenarioError::at(
                        format!("{key}.table"),
                        format!(
                            "must be a file name (a string), found {}",
                            other.type_str()
                        ),
                    )),
                    None => Err(ScenarioError::at(
                        key,
                        "a table profile needs a file: { table = \"file.csv\" }",
                    )),
                }
            }
            other => Err(ScenarioError::at(
                key,
                format!(
                    "must be a number, an expression in x (a string), {{ table = \"file.csv\" }} or {{ raster = \"file.asc\" }}, found {}",
                    other.type_str()
                ),
            )),
        }
    }
}

// ---------------------------------------------------------------------------------------
// Expressions

struct Expression {
    source: String,
    node: Node<DefaultNumericTypes>,
    /// The typed tree evaluated per point, when the expression has one
    /// ([`super::compiled`]); `evalexpr` evaluates the others.
    compiled: Option<Compiled>,
    allow_b: bool,
    /// Whether it reads `y`.
    uses_y: bool,
}

impl fmt::Debug for Expression {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Expression")
            .field("source", &self.source)
            .field("allow_b", &self.allow_b)
            .finish_non_exhaustive()
    }
}

impl Expression {
    /// Parses `source`; errors are messages (the caller adds the key).
    fn compile(source: &str, allow_b: bool) -> Result<Expression, String> {
        if source.trim().is_empty() {
            return Err("empty expression".into());
        }
        check_size(source)?;
        let mut node = build_operator_tree::<DefaultNumericTypes>(source)
            .map_err(|e| format!("cannot parse expression \"{source}\": {}", eval_message(&e)))?;
        for op in node.iter_operators_mut() {
            if let Operator::Const { value } = op {
                if let Value::Int(i) = *value {
                    *value = Value::Float(i as f64);
                }
            }
        }
        if let Some(w) = node.iter_write_variable_identifiers().next() {
            return Err(format!(
                "expression \"{source}\" assigns to '{w}'; assignments are not allowed"
            ));
        }
        let mut uses_y = false;
        for var in node.iter_read_variable_identifiers() {
            match var {
                "x" | "pi" | "deg" => {}
                "y" => uses_y = true,
                "b" if allow_b => {}
                "b" => {
                    return Err(format!(
                        "expression \"{source}\" uses the bed elevation b, which is only available in initial profiles"
                    ))
                }
                _ => {
                    return Err(format!(
                        "unknown variable '{var}' in expression \"{source}\" (available: x, y, {}pi, deg)",
                        if allow_b { "b, " } else { "" }
                    ))
                }
            }
        }
        for fun in node.iter_function_identifiers() {
            if !FUNCTIONS.contains(&fun) {
                return Err(format!(
                    "unknown function '{fun}' in expression \"{source}\" (available: {})",
                    FUNCTIONS.join(", ")
                ));
            }
        }
        let expr = Expression {
            source: source.to_owned(),
            compiled: Compiled::new(&node, allow_b),
            node,
            allow_b,
            uses_y,
        };
        // Some malformed input (`x +`, `sin(x, 1)`, `x < 1`) only shows when evaluated;
        // one trial evaluation catches it here. Functions give NaN, not errors, outside
        // their domain, so this does not reject e.g. `ln(x)`.
        match expr
            .node
            .eval_with_context(&ExprContext::new(0.0, 0.0, 0.0, allow_b))
        {
            Ok(Value::Float(_)) | Ok(Value::Int(_)) => Ok(expr),
            Ok(other) => Err(format!(
                "expression \"{source}\" gives {other}, not a number"
            )),
            Err(e) => Err(format!(
                "invalid expression \"{source}\": {}",
                eval_message(&e)
            )),
        }
    }

    fn eval(&self, x: f64, y: f64, b: f64) -> Result<f64, String> {
        if let Some(c) = &self.compiled {
            return c
                .eval(x, y, b)
                .map_err(|m| format!("expression \"{}\" fails: {m}", self.source));
        }
        self.eval_tree(x, y, b)
    }

    /// The value by `evalexpr`'s evaluation of the operator tree.
    fn eval_tree(&self, x: f64, y: f64, b: f64) -> Result<f64, String> {
        match self
            .node
            .eval_with_context(&ExprContext::new(x, y, b, self.allow_b))
        {
            Ok(Value::Float(v)) => Ok(v),
            Ok(Value::Int(i)) => Ok(i as f64),
            Ok(other) => Err(format!(
                "expression \"{}\" gives {other}, not a number",
                self.source
            )),
            Err(e) => Err(format!(
                "expression \"{}\" fails: {}",
                self.source,
                eval_message(&e)
            )),
        }
    }
}

/// Largest accepted table file (bytes): about a million rows. A bound, so that a path
/// such as `/dev/zero` is refused instead of read until memory runs out.
pub(crate) const MAX_TABLE_BYTES: u64 = 64 << 20;

/// Reads a UTF-8 text file of at most `limit` bytes.
pub(crate) fn read_bounded(path: &Path, limit: u64) -> std::io::Result<String> {
    use std::io::Read;
    // A FIFO would block the open (or the read) forever, a device may never end: only
    // regular files are read.
    let kind = std::fs::metadata(path)?.file_type();
    if !kind.is_file() {
        let what = if kind.is_dir() {
            "a directory"
        } else {
            "a FIFO, socket or device"
        };
        return Err(std::io::Error::other(format!(
            "not a regular file (it is {what})"
        )));
    }
    let mut text = String::new();
    std::fs::File::open(path)?
        .take(limit + 1)
        .read_to_string(&mut text)?;
    if text.len() as u64 > limit {
        return Err(std::io::Error::other(format!(
            "the file is larger than {} MiB",
            limit >> 20
        )));
    }
    Ok(text)
}

/// Longest accepted expression (bytes): ample for a profile written by hand or by a
/// script (thirty Gaussian bumps take about 900), small enough to parse in microseconds.
pub(crate) const MAX_EXPR_BYTES: usize = 10_000;

/// Largest accepted nesting weight, see [`nesting_weight`].
pub(crate) const MAX_EXPR_NESTING: usize = 1000;

/// An upper bound on the depth of the operator tree `evalexpr` builds for `source`:
/// every operator character counts 1 (a chain `x+x+…+x` of n terms is a tree n deep,
/// and so is n-fold unary minus) and every opening parenthesis 2 (the group and a
/// possible function call). Parsing, evaluating and dropping the tree all recurse
/// over it, so a deep tree overflows the stack and aborts the process; a weight of
/// 1000 stays well inside the 2 MiB stack of a worker thread even in a debug build
/// (measured: 2000-deep trees overflow there, 1000-deep ones do not).
fn nesting_weight(source: &str) -> usize {
    source
        .bytes()
        .map(|c| match c {
            b'(' => 2,
            b'+' | b'-' | b'*' | b'/' | b'%' | b'^' | b'<' | b'>' | b'=' | b'!' | b'&' | b'|'
            | b',' | b';' => 1,
            _ => 0,
        })
        .sum()
}

/// Refuses expressions too long or too deeply nested to handle safely, before parsing.
/// The message does not quote the expression (it may be megabytes).
fn check_size(source: &str) -> Result<(), String> {
    if source.len() > MAX_EXPR_BYTES {
        return Err(format!(
            "expression is too long: {} bytes (at most {MAX_EXPR_BYTES}; use a table file for long profiles)",
            source.len()
        ));
    }
    let weight = nesting_weight(source);
    if weight > MAX_EXPR_NESTING {
        return Err(format!(
            "expression is too deep: {weight} operators and parentheses (each parenthesis counts 2; at most {MAX_EXPR_NESTING}); split it or use a table file"
        ));
    }
    Ok(())
}

/// evalexpr prefixes custom messages with "Error: "; drop it.
fn eval_message(e: &EvalexprError<DefaultNumericTypes>) -> String {
    match e {
        EvalexprError::CustomMessage(m) => m.clone(),
        other => other.to_string(),
    }
}

const PI: Value<DefaultNumericTypes> = Value::Float(std::f64::consts::PI);
const DEG: Value<DefaultNumericTypes> = Value::Float(std::f64::consts::PI / 180.0);

/// The evaluation context: position, bed elevation, constants and our functions only
/// (evalexpr's own builtins are disabled).
struct ExprContext {
    x: Value<DefaultNumericTypes>,
    y: Value<DefaultNumericTypes>,
    b: Value<DefaultNumericTypes>,
    allow_b: bool,
}

impl ExprContext {
    fn new(x: f64, y: f64, b: f64, allow_b: bool) -> Self {
        ExprContext {
            x: Value::Float(x),
            y: Value::Float(y),
            b: Value::Float(b),
            allow_b,
        }
    }
}

impl Context for ExprContext {
    type NumericTypes = DefaultNumericTypes;

    fn get_value(&self, identifier: &str) -> Option<&Value<DefaultNumericTypes>> {
        match identifier {
            "x" => Some(&self.x),
            "y" => Some(&self.y),
            "b" if self.allow_b => Some(&self.b),
            "pi" => Some(&PI),
            "deg" => Some(&DEG),
            _ => None,
        }
    }

    fn call_function(
        &self,
        identifier: &str,
        argument: &Value<DefaultNumericTypes>,
    ) -> EvalexprResultValue<DefaultNumericTypes> {
        call_function(identifier, argument)
    }

    fn are_builtin_functions_disabled(&self) -> bool {
        true
    }

    fn set_builtin_functions_disabled(&mut self, _disabled: bool) -> EvalexprResult<()> {
        Err(EvalexprError::CustomMessage(
            "builtin functions cannot be enabled".into(),
        ))
    }
}

fn custom<T>(message: String) -> EvalexprResult<T> {
    Err(EvalexprError::CustomMessage(message))
}

/// The arguments of a call, as a slice (one argument is not wrapped in a tuple).
fn arguments(argument: &Value<DefaultNumericTypes>) -> &[Value<DefaultNumericTypes>] {
    match argument {
        Value::Tuple(items) => items,
        Value::Empty => &[],
        single => std::slice::from_ref(single),
    }
}

fn number(function: &str, v: &Value<DefaultNumericTypes>) -> EvalexprResult<f64> {
    match v {
        Value::Float(f) => Ok(*f),
        Value::Int(i) => Ok(*i as f64),
        other => custom(format!("{function}: expected a number, got {other}")),
    }
}

fn numbers<const N: usize>(
    function: &str,
    argument: &Value<DefaultNumericTypes>,
) -> EvalexprResult<[f64; N]> {
    let args = arguments(argument);
    if args.len() != N {
        return custom(format!(
            "{function} takes {N} argument{}, got {}",
            if N == 1 { "" } else { "s" },
            args.len()
        ));
    }
    let mut out = [0.0; N];
    for (o, a) in out.iter_mut().zip(args) {
        *o = number(function, a)?;
    }
    Ok(out)
}

/// The one-argument functions of profile expressions (shared by the evaluation here
/// and the compiled tree of `compiled.rs`, so that both give the same bits).
pub(super) fn unary_function(name: &str) -> Option<fn(f64) -> f64> {
    Some(match name {
        "exp" => f64::exp,
        "ln" => f64::ln,
        "log10" => f64::log10,
        "sqrt" => f64::sqrt,
        "abs" => f64::abs,
        "sin" => f64::sin,
        "cos" => f64::cos,
        "tan" => f64::tan,
        "asin" => f64::asin,
        "acos" => f64::acos,
        "atan" => f64::atan,
        "sinh" => f64::sinh,
        "cosh" => f64::cosh,
        "tanh" => f64::tanh,
        "erf" => erf,
        "floor" => f64::floor,
        "ceil" => f64::ceil,
        "round" => f64::round,
        _ => return None,
    })
}

fn call_function(
    name: &str,
    argument: &Value<DefaultNumericTypes>,
) -> EvalexprResultValue<DefaultNumericTypes> {
    let unary = |f: fn(f64) -> f64| -> EvalexprResultValue<DefaultNumericTypes> {
        let [a] = numbers::<1>(name, argument)?;
        Ok(Value::Float(f(a)))
    };
    if let Some(f) = unary_function(name) {
        return unary(f);
    }
    match name {
        "pow" => {
            let [a, p] = numbers::<2>(name, argument)?;
            Ok(Value::Float(a.powf(p)))
        }
        "atan2" => {
            let [y, x] = numbers::<2>(name, argument)?;
            Ok(Value::Float(y.atan2(x)))
        }
        "min" | "max" => {
            let args = arguments(argument);
            if args.is_empty() {
                return custom(format!("{name} needs at least one argument"));
            }
            let mut acc = number(name, &args[0])?;
            for a in &args[1..] {
                let v = number(name, a)?;
                acc = if name == "min" {
                    acc.min(v)
                } else {
                    acc.max(v)
                };
            }
            Ok(Value::Float(acc))
        }
        "if" => {
            let args = arguments(argument);
            if args.len() != 3 {
                return custom(format!(
                    "if takes 3 arguments (condition, then, else), got {}",
                    args.len()
                ));
            }
            match &args[0] {
                Value::Boolean(true) => Ok(args[1].clone()),
                Value::Boolean(false) => Ok(args[2].clone()),
                other => custom(format!(
                    "if: the condition must be a comparison such as x < 1, got {other}"
                )),
            }
        }
        "noise" => {
            let [x, seed] = numbers::<2>(name, argument)?;
            if !seed.is_finite() || seed.fract() != 0.0 {
                return custom(format!("noise: the seed must be an integer, got {seed}"));
            }
            Ok(Value::Float(noise(x, seed as i64)))
        }
        _ => Err(EvalexprError::FunctionIdentifierNotFound(name.to_owned())),
    }
}

/// One SplitMix64 step (a strong 64-bit mixer).
fn splitmix64(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// Deterministic pseudo-random number in [0, 1) from the bits of `x` and a seed.
pub(crate) fn noise(x: f64, seed: i64) -> f64 {
    // +0.0 and -0.0 are the same position.
    let x = if x == 0.0 { 0.0 } else { x };
    let h = splitmix64(x.to_bits() ^ splitmix64(seed as u64));
    // Top 53 bits → a double in [0, 1).
    (h >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
}

/// The error function erf(x) = 2/√π ∫₀ˣ e^(−t²) dt, to a few units in the last place.
///
/// The standard library has none. Summed as e^(−x²) · 2/√π · Σₙ (2x²)ⁿ x / (1·3·…·(2n+1))
/// (Abramowitz & Stegun 7.1.6): every term is positive, so nothing cancels and the
/// relative error stays at round-off for any x; beyond |x| = 6 the sum would only add
/// terms below half an ulp of 1 (erfc(6) ≈ 2e-17), so the value is ±1. It serves
/// the normal distribution's CDF Φ(z) = ½(1 + erf(z/√2)) of topographies written with
/// it (the channels of AvaFrame's generated DEMs).
pub(crate) fn erf(x: f64) -> f64 {
    if x.is_nan() {
        return x;
    }
    let a = x.abs();
    if a >= 6.0 {
        return 1.0f64.copysign(x);
    }
    let two_a2 = 2.0 * a * a;
    let (mut term, mut sum) = (a, a);
    let mut n = 0.0;
    // The terms grow while 2n + 1 < 2x² and then fall faster than geometrically; at
    // |x| < 6 they are below 1e-17 of the sum within 200 terms.
    while term > 1e-17 * sum {
        n += 1.0;
        term *= two_a2 / (2.0 * n + 1.0);
        sum += term;
    }
    let value = sum * (-a * a).exp() * std::f64::consts::FRAC_2_SQRT_PI;
    value.min(1.0).copysign(x)
}

// ---------------------------------------------------------------------------------------
// Tables

#[derive(Debug)]
struct Table {
    /// The path as written in the scenario (for messages).
    path: PathBuf,
    xs: Vec<f64>,
    vs: Vec<f64>,
}

impl Table {
    /// Reads a CSV table for the profile `key` (e.g. `bed.b`); errors are messages naming
    /// the file (the caller adds the key).
    fn load(path: &Path, base_dir: &Path, key: &str) -> Result<Table, String> {
        let full = base_dir.join(path);
        let text = read_bounded(&full, MAX_TABLE_BYTES)
            .map_err(|e| format!("cannot read table file '{}': {e}", full.display()))?;
        Table::parse(&text, path, key).map_err(|m| format!("table file '{}': {m}", full.display()))
    }

    /// Parses a table for the profile `key`. Its columns are found by name: `x`, and
    /// the values in the column named `value` or after the key's last part (`b` for
    /// `bed.b`, `h` for `initial.h`), or in the one other column of a two-column
    /// header. A file without a header (its first line is numbers) must have exactly
    /// two columns, x and the value. Anything else is refused, naming the columns
    /// found: a guess would read the wrong column without a word.
    fn parse(text: &str, path: &Path, key: &str) -> Result<Table, String> {
        let mut lines = text
            .lines()
            .enumerate()
            .map(|(i, l)| (i + 1, l.trim()))
            .filter(|(_, l)| !l.is_empty() && !l.starts_with('#'));
        let split = |l: &str| -> Vec<String> {
            l.split(',')
                .map(|f| f.trim().trim_matches('"').trim().to_owned())
                .collect()
        };
        let leaf = key.rsplit('.').next().unwrap_or(key);
        let wanted = if leaf.eq_ignore_ascii_case("value") {
            "`x,value`".to_owned()
        } else {
            format!("`x,{leaf}` or `x,value`")
        };
        let Some((header_line, header)) = lines.next() else {
            return Err(format!(
                "empty file (expected a header line {wanted} and at least one row)"
            ));
        };
        let names = split(header);
        let numeric = |s: &String| s.parse::<f64>().is_ok();
        // Column names are quoted only when they look like names: errors never echo
        // other content of the file (it may not be a table at all).
        let found = || {
            let list: Vec<String> = names
                .iter()
                .enumerate()
                .map(|(k, n)| {
                    let plain = !n.is_empty()
                        && n.len() <= 32
                        && n.chars()
                            .all(|c| c.is_alphanumeric() || "_- ().".contains(c));
                    if plain {
                        format!("'{n}'")
                    } else {
                        format!("column {} (not a plain name)", k + 1)
                    }
                })
                .collect();
            list.join(", ")
        };
        let (ix, iv, first_row) = if names.iter().any(numeric) {
            // No header: the first line is already data, x and the value.
            if names.len() != 2 || !names.iter().all(numeric) {
                return Err(format!(
                    "line {header_line}: no header line and {} columns: name the columns in a first line {wanted}",
                    names.len()
                ));
            }
            (0, 1, Some((header_line, header)))
        } else {
            let find = |want: &str| names.iter().position(|n| n.eq_ignore_ascii_case(want));
            let Some(ix) = find("x") else {
                return Err(format!(
                    "line {header_line}: no column named 'x' (columns found: {}); the header must be {wanted}",
                    found()
                ));
            };
            let iv = find("value")
                .or_else(|| find(leaf))
                .or_else(|| (names.len() == 2).then_some(1 - ix));
            let Some(iv) = iv else {
                return Err(format!(
                    "line {header_line}: cannot tell which column holds {key} (columns found: {}); name it '{leaf}' or 'value'",
                    found()
                ));
            };
            (ix, iv, None)
        };
        let mut xs = Vec::new();
        let mut vs = Vec::new();
        for (line, row) in first_row.into_iter().chain(lines) {
            let fields = split(row);
            let field = |i: usize, what: &str| -> Result<f64, String> {
                let s = fields
                    .get(i)
                    .ok_or_else(|| {
                        format!(
                            "line {line}: missing the {what} column (column {} of a row with {} column{})",
                            i + 1,
                            fields.len(),
                            if fields.len() == 1 { "" } else { "s" }
                        )
                    })?;
                let v: f64 = s.parse().map_err(|_| {
                    format!("line {line}: the {what} (column {}) is not a number", i + 1)
                })?;
                if v.is_finite() {
                    Ok(v)
                } else {
                    Err(format!(
                        "line {line}: the {what} (column {}) must be finite",
                        i + 1
                    ))
                }
            };
            let x = field(ix, "x")?;
            let v = field(iv, "value")?;
            if let Some(&last) = xs.last() {
                if x <= last {
                    return Err(format!(
                        "line {line}: x must be strictly increasing ({x} after {last})"
                    ));
                }
            }
            xs.push(x);
            vs.push(v);
        }
        if xs.is_empty() {
            return Err(
                "no data rows (expected at least one row `x,value` after the header)".into(),
            );
        }
        Ok(Table {
            path: path.to_owned(),
            xs,
            vs,
        })
    }

    /// Linear interpolation, constant beyond the ends.
    fn eval(&self, x: f64) -> f64 {
        let n = self.xs.len();
        if x.is_nan() {
            return f64::NAN;
        }
        if x <= self.xs[0] {
            return self.vs[0];
        }
        if x >= self.xs[n - 1] {
            return self.vs[n - 1];
        }
        // First index with xs[k] > x; 1 <= k <= n-1 here.
        let k = self.xs.partition_point(|&xk| xk <= x);
        let (x0, x1) = (self.xs[k - 1], self.xs[k]);
        let (v0, v1) = (self.vs[k - 1], self.vs[k]);
        v0 + (v1 - v0) * (x - x0) / (x1 - x0)
    }
}

// ---------------------------------------------------------------------------------------
// Rasters

/// Largest accepted raster file (bytes): an ESRI ASCII grid of about 5·10⁷ cells, a
/// Float32 GeoTIFF of 2.5·10⁸; a bound so that a wrong path (a disk image, `/dev/zero`)
/// is refused at once instead of read until memory runs out.
pub(crate) const MAX_RASTER_BYTES: u64 = 1 << 30;

/// A raster file as a profile: bilinear interpolation between the cell centres,
/// constant beyond the outer centres (up to the raster's edge), no value outside the
/// raster or where a neighbouring cell is nodata.
#[derive(Debug)]
struct RasterProfile {
    /// The path as written in the scenario (for messages).
    path: PathBuf,
    raster: crate::gis::Raster,
}

/// Refuses a raster whose cells vanish in the round-off of its coordinates (a cell of
/// 5 m at x = 10¹⁷, of 10⁻³⁰⁰ m anywhere but next to 0) or whose far edges overflow:
/// cell centres would not be distinct, and the grid built on them would not be the
/// raster's. The bound is the one of a domain's keys ([`MIN_RELATIVE_DX`]).
///
/// [`MIN_RELATIVE_DX`]: super::validate::MIN_RELATIVE_DX
fn check_round_off(r: &crate::gis::Raster) -> Result<(), String> {
    let b = r.bbox();
    let corners = [b.x_min, b.x_max, b.y_min, b.y_max];
    if corners.iter().any(|v| !v.is_finite()) {
        return Err(format!(
            "its extent overflows (left edge {}, {} columns of {}; top edge {}, {} rows)",
            short_number(r.x_left),
            r.nx,
            short_number(r.cell_size),
            short_number(r.y_top),
            r.ny
        ));
    }
    let scale = corners.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    if r.cell_size < super::validate::MIN_RELATIVE_DX * scale {
        return Err(format!(
            "cells of {} are at the round-off of its coordinates (up to {}): cell \
             centres would not be distinct; check the header's cell size and corner (a \
             corner in the wrong units?)",
            short_number(r.cell_size),
            short_number(scale)
        ));
    }
    Ok(())
}

impl RasterProfile {
    /// Reads an ESRI ASCII grid (`.asc`) or a GeoTIFF (`.tif`, `.tiff`); errors are
    /// messages naming the file (the caller adds the key).
    fn load(path: &Path, base_dir: &Path) -> Result<RasterProfile, String> {
        let full = base_dir.join(path);
        if let Ok(meta) = std::fs::metadata(&full) {
            if !meta.is_file() {
                return Err(format!(
                    "raster file '{}' is not a regular file",
                    full.display()
                ));
            }
            if meta.len() > MAX_RASTER_BYTES {
                return Err(format!(
                    "raster file '{}' is {:.1} GiB, more than the {} GiB a raster input may be: crop it to the area of the run first (e.g. gdal_translate -projwin)",
                    full.display(),
                    meta.len() as f64 / (1u64 << 30) as f64,
                    MAX_RASTER_BYTES >> 30
                ));
            }
        }
        let ext = full
            .extension()
            .map(|e| e.to_string_lossy().to_ascii_lowercase())
            .unwrap_or_default();
        let raster = match ext.as_str() {
            "asc" => crate::gis::asc::read(&full),
            "tif" | "tiff" => crate::gis::geotiff::read(&full),
            _ => {
                return Err(format!(
                    "raster file '{}': unknown format (expected an ESRI ASCII grid .asc or a GeoTIFF .tif)",
                    full.display()
                ))
            }
        }
        .map_err(|e| format!("cannot read raster file: {e}"))?;
        check_round_off(&raster)
            .map_err(|reason| format!("raster file '{}': {reason}", full.display()))?;
        Ok(RasterProfile {
            path: path.to_owned(),
            raster,
        })
    }

    /// The bilinear interpolation at (x, y) of the values at the cell centres.
    fn eval(&self, x: f64, y: f64) -> Result<f64, String> {
        let r = &self.raster;
        let b = r.bbox();
        if !(x >= b.x_min && x <= b.x_max && y >= b.y_min && y <= b.y_max) {
            return Err(format!(
                "raster \"{}\" covers x in [{}, {}], y in [{}, {}], not the point",
                self.path.display(),
                short_number(b.x_min),
                short_number(b.x_max),
                short_number(b.y_min),
                short_number(b.y_max)
            ));
        }
        // Fractional column and row of the point, counted from the first centre; a
        // centre (up to round-off of its coordinates) reads its own cell exactly.
        let snap = |f: f64| {
            if (f - f.round()).abs() < 1e-9 {
                f.round()
            } else {
                f
            }
        };
        let fc = snap((x - r.x_left) / r.cell_size - 0.5).clamp(0.0, (r.nx - 1) as f64);
        let fr = snap((r.y_top - y) / r.cell_size - 0.5).clamp(0.0, (r.ny - 1) as f64);
        let (c0, r0) = (fc.floor() as usize, fr.floor() as usize);
        let (c1, r1) = ((c0 + 1).min(r.nx - 1), (r0 + 1).min(r.ny - 1));
        let (wc, wr) = (fc - c0 as f64, fr - r0 as f64);
        let mut v = 0.0;
        for (col, row, w) in [
            (c0, r0, (1.0 - wc) * (1.0 - wr)),
            (c1, r0, wc * (1.0 - wr)),
            (c0, r1, (1.0 - wc) * wr),
            (c1, r1, wc * wr),
        ] {
            if w == 0.0 {
                continue;
            }
            match r.get(col, row) {
                Some(value) => v += w * value,
                None => {
                    let (cx, cy) = r.cell_centre(col, row);
                    return Err(format!(
                        "raster \"{}\" has no value (nodata) in its cell centred at ({}, {})",
                        self.path.display(),
                        short_number(cx),
                        short_number(cy)
                    ));
                }
            }
        }
        Ok(v)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn expr(s: &str) -> Profile {
        Profile::expression(s).unwrap_or_else(|e| panic!("{s}: {e}"))
    }

    /// The bits of the compiled evaluation and of `evalexpr`'s, or both errors' texts.
    fn both_ways(
        e: &Expression,
        x: f64,
        y: f64,
        b: f64,
    ) -> (Result<u64, String>, Result<u64, String>) {
        let compiled = e.eval(x, y, b).map(f64::to_bits);
        let tree = e.eval_tree(x, y, b).map(f64::to_bits);
        (compiled, tree)
    }

    #[test]
    fn compiled_expressions_give_the_bits_of_the_operator_tree() {
        let sources = [
            "if(x < 3210.9, 2200 - tan(34*deg)*x, if(x < 3322.8, 200 - sqrt(max(0, 200^2 - (x - 3322.8)^2)), 0)) + 100*min((y/200)^2, 1)",
            "if(((x - 500)/200)^2 + (y/120)^2 < 1, 2, 0)",
            "0.5*exp(-((x - 1)^2 + y^2)/0.1) - b % 0.3 + ln(abs(x) + 1) * log10(2 + y*y)",
            "atan2(y, x) + pow(abs(x), 1/3) + floor(x) - ceil(y) + round(x*y) + -x",
            "sin(x)*cos(y)*tan(0.1*x) + asin(0.5) + acos(0.1) + atan(x) + sinh(0.1*y) + cosh(0.2) + tanh(x)",
            "min(x, y, 1, -2*b) + max(x) + if(x >= 1 && !(y <= 0) || x == y, 1, 0) + if(x != 0 == true, 2, 3)",
            "noise(x, 7) + noise(y, -3)",
            "erf(x) + erf(y/250) - erf(-3*b)",
            "noise(x, x)",
            "1/x + x/0 - 0/0",
        ];
        let points = [
            -2.5,
            -1.0,
            -0.0,
            0.0,
            0.3,
            1.0,
            1.5,
            600.0,
            3300.0,
            1e9,
            f64::NAN,
        ];
        for source in sources {
            let e = Expression::compile(source, true).unwrap_or_else(|m| panic!("{m}"));
            assert!(e.compiled.is_some(), "{source} has a compiled form");
            for &x in &points {
                for &y in &points {
                    for b in [0.0, 0.7] {
                        let (compiled, tree) = both_ways(&e, x, y, b);
                        assert_eq!(compiled, tree, "{source} at ({x}, {y}, {b})");
                    }
                }
            }
        }
        // A failing noise seed fails both ways with the same message.
        let e = Expression::compile("noise(x, x)", false).unwrap();
        assert!(e.eval(0.5, 0.0, 0.0).is_err());
        // What does not type-check as a number keeps the operator tree.
        for source in ["x; 2", "if(x < 1, x < 2, 3) * 0 + 1"] {
            if let Ok(e) = Expression::compile(source, false) {
                assert!(e.compiled.is_none(), "{source}");
            }
        }
    }

    #[test]
    fn profile_is_send_sync_clone_debug() {
        fn check<T: Send + Sync + Clone + fmt::Debug>() {}
        check::<Profile>();
    }

    #[test]
    fn integer_division_is_real_division() {
        assert_eq!(expr("1/2").eval(0.0, 0.0), 0.5);
        assert_eq!(expr("7/2*2").eval(0.0, 0.0), 7.0);
        assert_eq!(expr("2^-1").eval(0.0, 0.0), 0.5);
        assert_eq!(expr("x/4").eval(1.0, 0.0), 0.25);
        assert_eq!(expr("1e-3*x").eval(1000.0, 0.0), 1.0);
        assert_eq!(expr("2.5e1 + 1E2").eval(0.0, 0.0), 125.0);
        assert_eq!(expr("3 % 2 / 4").eval(0.0, 0.0), 0.25);
    }

    #[test]
    fn functions_and_constants() {
        let t = expr("tan(20*deg)").eval(0.0, 0.0);
        assert!((t - 20f64.to_radians().tan()).abs() < 1e-15);
        assert!((expr("cos(pi)").eval(0.0, 0.0) + 1.0).abs() < 1e-15);
        let m = expr("max(0, 0.14 - x)");
        assert!((m.eval(0.04, 0.0) - 0.10).abs() < 1e-15);
        assert_eq!(m.eval(0.5, 0.0), 0.0);
        let e = expr("0.3*exp(-10*(x-1)^2)");
        assert!((e.eval(1.0, 0.0) - 0.3).abs() < 1e-15);
        assert!((e.eval(1.5, 0.0) - 0.3 * (-2.5f64).exp()).abs() < 1e-15);
        assert_eq!(expr("-x^2").eval(3.0, 0.0), -9.0);
        assert_eq!(expr("min(3, x, 5)").eval(1.0, 0.0), 1.0);
        assert_eq!(expr("pow(2, 10)").eval(0.0, 0.0), 1024.0);
        assert_eq!(
            expr("sqrt(abs(-16)) + floor(1.7) + ceil(0.2)").eval(0.0, 0.0),
            6.0
        );
        assert!((expr("ln(exp(2)) + log10(100)").eval(0.0, 0.0) - 4.0).abs() < 1e-14);
    }

    #[test]
    fn if_with_comparisons() {
        let p = expr("if(x <= 0, 0.14, 0)");
        assert_eq!(p.eval(-1.0, 0.0), 0.14);
        assert_eq!(p.eval(0.0, 0.0), 0.14);
        assert_eq!(p.eval(0.1, 0.0), 0.0);
        let r = expr("if(!(x < 1) || x == -1, 1, 0)");
        assert_eq!(r.eval(0.5, 0.0), 0.0);
        assert_eq!(r.eval(1.0, 0.0), 1.0);
        assert_eq!(r.eval(-1.0, 0.0), 1.0);
        assert_eq!(expr("x % 1").eval(2.25, 0.0), 0.25);
        let q = expr("if(x > 1 && x < 2, 1, 0)");
        assert_eq!(q.eval(1.5, 0.0), 1.0);
        assert_eq!(q.eval(2.5, 0.0), 0.0);
        // A condition that is not a comparison is an evaluation error.
        assert!(Expression::compile("if(x, 1, 0)", true).is_err());
    }

    #[test]
    fn erf_matches_reference_values_to_round_off() {
        // erf at these points to 16-17 digits, as the C library's erf prints them
        // (Python's math.erf); Abramowitz & Stegun Table 7.1 agrees where it has them.
        let cases = [
            (0.0, 0.0),
            (1e-10, 1.1283791670955126e-10),
            (0.1, 0.1124629160182849),
            (0.5, 0.5204998778130465),
            (1.0, 0.8427007929497149),
            (1.5, 0.9661051464753108),
            (2.0, 0.9953222650189527),
            (3.0, 0.9999779095030014),
            (4.5, 0.9999999998033839),
            (5.9, 0.9999999999999999),
            (7.0, 1.0),
        ];
        for (x, want) in cases {
            for (x, want) in [(x, want), (-x, -want)] {
                let got = expr("erf(x)").eval(x, 0.0);
                assert!(
                    (got - want).abs() <= 4.0 * f64::EPSILON * want.abs().max(1e-300),
                    "erf({x}) = {got:e}, want {want:e}"
                );
            }
        }
        assert!(erf(f64::NAN).is_nan());
        // The normal CDF written with it, as AvaFrame's channel topographies use it.
        let phi = expr("0.5*(1 + erf((x - 652.32)/(250*sqrt(2))))");
        assert!((phi.eval(652.32, 0.0) - 0.5).abs() < 1e-16);
    }

    #[test]
    fn noise_is_deterministic_in_unit_interval_and_varies() {
        let p = expr("noise(x, 7)");
        let a = p.eval(0.25, 0.0);
        assert_eq!(a, p.eval(0.25, 0.0));
        assert_eq!(a, noise(0.25, 7));
        assert_ne!(a, p.eval(0.26, 0.0));
        assert_ne!(a, expr("noise(x, 8)").eval(0.25, 0.0));
        let mut sum = 0.0;
        let n = 10_000;
        for i in 0..n {
            let v = p.eval(i as f64 * 1e-3, 0.0);
            assert!((0.0..1.0).contains(&v), "{v}");
            sum += v;
        }
        let mean = sum / n as f64;
        assert!((mean - 0.5).abs() < 0.02, "mean {mean}");
        assert!(Expression::compile("noise(x, 1.5)", true).is_err());
    }

    #[test]
    fn bed_variable_in_initial_profiles() {
        let p = expr("max(0, 0.5 - b)");
        assert_eq!(p.eval(0.0, 0.2), 0.3);
        assert_eq!(p.eval(0.0, 0.7), 0.0);
    }

    #[test]
    fn compile_errors() {
        assert!(Expression::compile("x +", true).is_err());
        assert!(Expression::compile("", true).is_err());
        let e = Expression::compile("z * 2", true).unwrap_err();
        assert!(e.contains("unknown variable 'z'"), "{e}");
        // y is a variable (of raster domains), which the profile records.
        let y = Expression::compile("y * 2", true).unwrap();
        assert!(y.uses_y && !Expression::compile("x * 2", true).unwrap().uses_y);
        assert_eq!(y.eval(0.0, 1.5, 0.0), Ok(3.0));
        let e = Expression::compile("b + 1", false).unwrap_err();
        assert!(e.contains("bed elevation b"), "{e}");
        let e = Expression::compile("math::sin(x)", true).unwrap_err();
        assert!(e.contains("unknown function 'math::sin'"), "{e}");
        let e = Expression::compile("a = 2; a*x", true).unwrap_err();
        assert!(e.contains("assign"), "{e}");
    }

    #[test]
    fn evaluation_errors() {
        let e = Expression::compile("sin(x, 1)", true).unwrap_err();
        assert!(e.contains("sin takes 1 argument, got 2"), "{e}");
        let e = Expression::compile("x < 1", true).unwrap_err();
        assert!(e.contains("not a number"), "{e}");
        // Outside a function's domain: NaN, found later when sampling, not a compile error.
        assert!(expr("ln(x)").eval(-1.0, 0.0).is_nan());
        // An error that depends on x.
        let p = expr("if(x < 1, 0, 1 < 2)");
        assert_eq!(p.try_eval(0.5, 0.0), Ok(0.0));
        assert!(p.try_eval(1.5, 0.0).is_err());
        assert!(p.eval(1.5, 0.0).is_nan());
    }

    #[test]
    fn describe_forms() {
        assert_eq!(Profile::constant(0.14).describe(), "0.14");
        assert_eq!(expr("1 - x").describe(), "expression \"1 - x\"");
        let t = Table::parse("x,value\n0,1\n1,2\n", Path::new("h.csv"), "initial.h").unwrap();
        let p = Profile {
            kind: Kind::Table(Arc::new(t)),
        };
        assert_eq!(p.describe(), "table \"h.csv\" (2 rows, x in [0, 1])");
    }

    #[test]
    fn table_interpolates_and_extrapolates_constantly() {
        let t = Table::parse(
            "x,value\n0.0, 1.0\n1.0, 3.0\n# comment\n\n3.0, -1.0\n",
            Path::new("t.csv"),
            "initial.h",
        )
        .unwrap();
        assert_eq!(t.eval(-5.0), 1.0);
        assert_eq!(t.eval(0.0), 1.0);
        assert_eq!(t.eval(0.5), 2.0);
        assert_eq!(t.eval(1.0), 3.0);
        assert_eq!(t.eval(2.0), 1.0);
        assert_eq!(t.eval(3.0), -1.0);
        assert_eq!(t.eval(10.0), -1.0);
    }

    #[test]
    fn table_columns_by_name_or_position() {
        let t = Table::parse("value,x\n5,0\n7,1\n", Path::new("t.csv"), "initial.h").unwrap();
        assert_eq!(t.eval(0.5), 6.0);
        // The column named after the key, among others.
        let t = Table::parse(
            "x,h,comment\n0,1,a\n2,3,b\n",
            Path::new("t.csv"),
            "initial.h",
        )
        .unwrap();
        assert_eq!(t.eval(1.0), 2.0);
        // Two columns, one of them x: the other holds the values, whatever its name.
        let t = Table::parse("x,b\n0,1\n2,3\n", Path::new("t.csv"), "initial.h").unwrap();
        assert_eq!(t.eval(1.0), 2.0);
        // A single row is a constant.
        let t = Table::parse("x,value\n0.3,0.1\n", Path::new("t.csv"), "initial.h").unwrap();
        assert_eq!(t.eval(-1.0), 0.1);
        assert_eq!(t.eval(1.0), 0.1);
        // Without a header line, the first line is data.
        let t = Table::parse("0,1\n1,2\n", Path::new("t.csv"), "initial.h").unwrap();
        assert_eq!(t.eval(0.5), 1.5);
    }

    #[test]
    fn table_columns_must_be_named() {
        // Three columns and none named after the key: no guess.
        let e = Table::parse("x,y,z\n0,1,2\n1,2,3\n", Path::new("t.csv"), "bed.b").unwrap_err();
        assert!(
            e.contains("cannot tell which column holds bed.b")
                && e.contains("'x', 'y', 'z'")
                && e.contains("'b' or 'value'"),
            "{e}"
        );
        let t = Table::parse("x,y,b\n0,1,2\n1,2,3\n", Path::new("t.csv"), "bed.b").unwrap();
        assert_eq!(t.eval(0.5), 2.5);
        // No x column.
        let e = Table::parse("pos,h\n0,1\n", Path::new("t.csv"), "initial.h").unwrap_err();
        assert!(
            e.contains("no column named 'x'") && e.contains("'pos', 'h'"),
            "{e}"
        );
        // No header and three columns.
        let e = Table::parse("0,1,2\n1,2,3\n", Path::new("t.csv"), "bed.b").unwrap_err();
        assert!(e.contains("no header line and 3 columns"), "{e}");
        // A header with a number in it is not a header either.
        let e = Table::parse("x,1\n0,1\n", Path::new("t.csv"), "bed.b").unwrap_err();
        assert!(e.contains("no header line"), "{e}");
    }

    #[test]
    fn table_errors_name_the_line() {
        let e =
            Table::parse("x,value\n0,1\n1,oops\n", Path::new("t.csv"), "initial.h").unwrap_err();
        assert!(
            e.contains("line 3") && e.contains("value (column 2)"),
            "{e}"
        );
        assert!(!e.contains("oops"), "file content quoted: {e}");
        let e = Table::parse("x,value\n0,1\n0,2\n", Path::new("t.csv"), "initial.h").unwrap_err();
        assert!(
            e.contains("line 3") && e.contains("strictly increasing"),
            "{e}"
        );
        let e = Table::parse("x,value\n", Path::new("t.csv"), "initial.h").unwrap_err();
        assert!(e.contains("no data rows"), "{e}");
        let e = Table::parse("x,value\n0\n", Path::new("t.csv"), "initial.h").unwrap_err();
        assert!(e.contains("line 2") && e.contains("value column"), "{e}");
        let e = Table::parse("x,value\n0,nan\n", Path::new("t.csv"), "initial.h").unwrap_err();
        assert!(e.contains("finite"), "{e}");
    }

    #[test]
    fn from_toml_forms() {
        let dir = Path::new(".");
        let p = Profile::from_toml("initial.h", &toml::Value::Float(0.14), dir, true).unwrap();
        assert_eq!(p.as_constant(), Some(0.14));
        let p = Profile::from_toml("initial.h", &toml::Value::Integer(2), dir, true).unwrap();
        assert_eq!(p.as_constant(), Some(2.0));
        let p =
            Profile::from_toml("bed.b", &toml::Value::String("2*x".into()), dir, false).unwrap();
        assert_eq!(p.eval(1.5, 0.0), 3.0);
        let e =
            Profile::from_toml("bed.b", &toml::Value::String("b".into()), dir, false).unwrap_err();
        assert_eq!(e.key(), Some("bed.b"));
        let e =
            Profile::from_toml("initial.u", &toml::Value::Boolean(true), dir, true).unwrap_err();
        assert_eq!(e.key(), Some("initial.u"));
        let e =
            Profile::from_toml("initial.h", &toml::Value::Float(f64::NAN), dir, true).unwrap_err();
        assert_eq!(e.key(), Some("initial.h"));
        let mut t = toml::Table::new();
        t.insert("tabel".into(), toml::Value::String("a.csv".into()));
        let e = Profile::from_toml("initial.h", &toml::Value::Table(t), dir, true).unwrap_err();
        assert_eq!(e.key(), Some("initial.h.tabel"));
        let mut t = toml::Table::new();
        t.insert(
            "table".into(),
            toml::Value::String("does-not-exist-5f2c.csv".into()),
        );
        let e = Profile::from_toml("initial.h", &toml::Value::Table(t), dir, true).unwrap_err();
        assert_eq!(e.key(), Some("initial.h"));
        assert!(e.message().contains("does-not-exist-5f2c.csv"), "{e}");
    }
}
