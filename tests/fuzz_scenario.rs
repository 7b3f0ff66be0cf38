//! Fuzzing the scenario loader, the sweep-file loader and the run setup: any byte
//! string, any edit of a real scenario or sweep file and any combination of schema keys
//! of every model (granular, multilayer, non-hydrostatic, dilatant, submarine) with
//! hostile values must give
//! a scenario or a `ScenarioError` (exit 0 or 2), never a panic, an abort (stack
//! overflow, out of memory) or a hang.
//!
//! By default a fixed number of cases runs (deterministic, about a second). CI runs it
//! for a time budget: `GRANFLOW_FUZZ_SECONDS=60 cargo test --release --test main
//! fuzz_scenario::`. A failing input is printed (proptest shrinks it first).

use std::path::Path;
use std::time::{Duration, Instant};

use proptest::prelude::*;
use proptest::test_runner::{Config, TestCaseError, TestRunner};

/// Longest a single input may take to load and set up. Far above the few milliseconds
/// an input takes: this catches hangs, not slowness.
const PER_INPUT: Duration = Duration::from_secs(20);

/// Rounds of 256 inputs when no time budget is given.
const DEFAULT_ROUNDS: u32 = 8;

fn scenarios() -> Vec<String> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios");
    let mut texts: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .filter_map(|e| e.ok())
        .map(|e| e.path())
        .filter(|p| p.extension().is_some_and(|x| x == "toml"))
        .map(|p| std::fs::read_to_string(p).unwrap())
        .collect();
    texts.sort();
    texts
}

/// Values that have broken parsers and validators before, or might.
const NASTY: &[&str] = &[
    "0",
    "-0",
    "1",
    "-1",
    "1e400",
    "-1e400",
    "1e-400",
    "nan",
    "inf",
    "-inf",
    "1e308",
    "5e-324",
    "9223372036854775807",
    "-9223372036854775808",
    "99999999999999999999",
    "0x10",
    "1_000",
    "\"\"",
    "\" \"",
    "\"x\"",
    "\"1/0\"",
    "\"0/0\"",
    "\"ln(x)\"",
    "\"((((\"",
    "\"x +\"",
    "\"a = 1\"",
    "\"b\"",
    "\"if(x, 1, 2)\"",
    "\"noise(x, 1)\"",
    "\"sqrt(-1)\"",
    "\"pow(10, 400)\"",
    "\"max()\"",
    "\"tuple(1, 2)\"",
    "\"x; 1\"",
    "\"---------x\"",
    "true",
    "false",
    "[]",
    "[1, 2]",
    "{}",
    "{ table = \"/dev/null\" }",
    "{ table = \"nowhere.csv\" }",
    "{ table = \"\" }",
    "{ table = 1 }",
    "{ other = 1 }",
    "\"coulomb\"",
    "\"mu_i\"",
    "\"wall\"",
    "\"outflow\"",
    "\"cartesian\"",
    "\"local\"",
    "\"nonhydrostatic\"",
    "\"hydrostatic\"",
    "\"jop\"",
    "\"layer\"",
    "\"no_slip\"",
    "\"bound\"",
    "\"dilatant\"",
    "\"submarine\"",
    "\"granular\"",
    "\"split\"",
    "\"appendix_b\"",
    "\"implicit\"",
    "\"exponential\"",
    "\"f0\"",
    "\"f2\"",
    "\"submerged\"",
    "[1e300, 1e300, 1e300]",
    "[2, 2, 5]",
    "[1e-300, 1]",
    "[0.5, 0.5]",
    "[40, 40]",
    "[0, 40]",
    "[100000, 100000]",
    "[40, 40, 40]",
    "[[0.5, 0.5], [1e300, 0]]",
    "{ raster = \"missing.asc\" }",
    "{ raster = \"\" }",
    "1e300",
    "1e-300",
    "1e6",
    "2",
    "20",
    "1000",
    "1001",
    "100000",
    "1e-12",
    "0.5",
    "89.999999",
    "90",
    "-90",
    "1e20",
    "1.0000000000001e20",
    "2024-01-01",
    "\"\\u0000\"",
    "'''x'''",
];

/// Values built at run time: deep and long expressions, long numbers.
fn huge_values() -> Vec<String> {
    vec![
        format!("\"{}x\"", "-".repeat(100_000)),
        format!("\"{}x{}\"", "(".repeat(20_000), ")".repeat(20_000)),
        format!("\"{}\"", vec!["x"; 4000].join("+")),
        format!("\"{}x{}\"", "sin(".repeat(600), ")".repeat(600)),
        format!("\"{}\"", vec!["0.01*exp(-x^2)"; 60].join("+")),
        "9".repeat(400),
        format!("[{}]", vec!["0.1"; 2000].join(", ")),
    ]
}

/// A hostile value: one of [`NASTY`] or of [`huge_values`].
fn nasty(i: usize) -> String {
    if i < NASTY.len() {
        NASTY[i].to_owned()
    } else {
        let h = huge_values();
        h[(i - NASTY.len()) % h.len()].clone()
    }
}

const N_NASTY: usize = NASTY.len() + 7;

/// Keys of the schema (and some that are not).
const KEYS: &[&str] = &[
    "domain.x_min",
    "domain.x_max",
    "domain.cells",
    "domain.slope_deg",
    "domain.coordinates",
    "domain.y_min",
    "domain.y_max",
    "bed.b",
    "material.rho_s",
    "material.phi",
    "material.d_s",
    "rheology.law",
    "rheology.mu",
    "rheology.mu_deg",
    "rheology.mu_s",
    "rheology.mu_s_deg",
    "rheology.mu_2",
    "rheology.mu_2_deg",
    "rheology.i0",
    "rheology.xi",
    "rheology.monolayer_shear",
    "rheology.basal",
    "rheology.regularization",
    "rheology.delta",
    "rheology.c_msm",
    "rheology.mu_w",
    "rheology.mu_w_deg",
    "rheology.width",
    "rheology.channel_width",
    "rheology.sidewall",
    "rheology.viscosity",
    "rheology.viscosity_tolerance",
    "rheology.viscosity_iterations",
    "model.kind",
    "model.pressure",
    "model.layers",
    "model.layer_fractions",
    "initial.h",
    "initial.u",
    "initial.v",
    "initial.w",
    "initial.erodible_bed",
    "initial.eta",
    "initial.phi",
    "dilatancy.k",
    "dilatancy.k_tilde",
    "dilatancy.phi_stat",
    "dilatancy.phi_eq",
    "dilatancy.n",
    "dilatancy.update",
    "dilatancy.alpha",
    "dilatancy.lambda",
    "dilatancy.xi",
    "dilatancy.scheme",
    "dilatancy.thin_layer_grains",
    "submarine.r",
    "submarine.k",
    "submarine.lambda1",
    "submarine.lambda2",
    "submarine.k_in",
    "submarine.buoyancy",
    "submarine.water_pressure",
    "submarine.water_layers",
    "boundary.left",
    "boundary.right",
    "boundary.west",
    "boundary.east",
    "boundary.south",
    "boundary.north",
    "time.t_end",
    "time.cfl",
    "time.stop_at_rest",
    "time.settle_fraction",
    "time.stop_when_settled",
    "output.file",
    "output.every",
    "output.front_threshold",
    "output.static_threshold",
    "output.gauges",
    "output.gauge_every",
    "domain",
    "x",
    "domain.x_min.y",
    "a.b.c.d",
];

/// Inputs refused and accepted.
static COUNTS: [std::sync::atomic::AtomicUsize; 2] = [
    std::sync::atomic::AtomicUsize::new(0),
    std::sync::atomic::AtomicUsize::new(0),
];

/// Loads `text` (with `sets`) and, when it is valid and small, builds the run.
fn exercise(text: &str, sets: &[String]) -> Result<(), TestCaseError> {
    let dir = std::env::temp_dir();
    let start = Instant::now();
    let loaded = granflow::scenario::load_str(text, &dir, sets);
    COUNTS[usize::from(loaded.is_ok())].fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    if let Ok(scn) = loaded {
        // Setup allocates per cell and layer; validation bounds that product, but the
        // largest scenarios would take gigabytes here, which is not what is tested.
        if scn.domain.cell_count() * scn.model.layers <= 200_000 {
            let _ = granflow::runner::check(&scn);
        }
    }
    let took = start.elapsed();
    prop_assert!(took < PER_INPUT, "took {took:?}");
    Ok(())
}

/// An edit of a real scenario: a value replaced, a line dropped or doubled, bytes
/// inserted.
fn edited_scenario() -> impl Strategy<Value = String> {
    let texts = scenarios();
    (
        0..texts.len(),
        prop::collection::vec(
            (
                0u8..5,
                any::<prop::sample::Index>(),
                0..N_NASTY,
                any::<Vec<u8>>(),
            ),
            1..6,
        ),
    )
        .prop_map(move |(k, edits)| {
            let mut lines: Vec<String> = texts[k].lines().map(str::to_owned).collect();
            for (kind, at, value, bytes) in edits {
                if lines.is_empty() {
                    break;
                }
                let i = at.index(lines.len());
                match kind {
                    0 => {
                        if let Some((key, _)) = lines[i].split_once('=') {
                            lines[i] = format!("{key}= {}", nasty(value));
                        }
                    }
                    1 => {
                        lines.remove(i);
                    }
                    2 => {
                        let l = lines[i].clone();
                        lines.insert(i, l);
                    }
                    3 => {
                        let junk = String::from_utf8_lossy(&bytes).into_owned();
                        lines.insert(i, junk);
                    }
                    _ => {
                        let cut = (bytes.len() % (lines[i].len() + 1)).min(lines[i].len());
                        let cut = (0..=cut)
                            .rev()
                            .find(|&c| lines[i].is_char_boundary(c))
                            .unwrap_or(0);
                        lines[i].truncate(cut);
                    }
                }
            }
            lines.join("\n")
        })
}

/// A document built from schema keys and hostile values, as dotted keys.
fn generated_document() -> impl Strategy<Value = String> {
    prop::collection::vec((0..KEYS.len(), 0..N_NASTY), 0..30).prop_map(|pairs| {
        pairs
            .into_iter()
            .map(|(k, v)| format!("{} = {}\n", KEYS[k], nasty(v)))
            .collect()
    })
}

/// `--set` overrides built the same way.
fn overrides() -> impl Strategy<Value = Vec<String>> {
    prop::collection::vec((0..KEYS.len(), 0..N_NASTY, any::<String>()), 0..4).prop_map(|v| {
        v.into_iter()
            .map(|(k, n, junk)| {
                if junk.len() % 3 == 0 {
                    format!("{}={}", KEYS[k], nasty(n))
                } else {
                    junk
                }
            })
            .collect()
    })
}

/// A real scenario with the value of one profile (`h`, `u`, `w`, `b`) replaced: the
/// expressions are where deep input does harm, and they are only reached when the rest
/// of the file is valid.
fn profile_edit() -> impl Strategy<Value = String> {
    let texts = scenarios();
    (0..texts.len(), any::<prop::sample::Index>(), 0..N_NASTY).prop_map(move |(k, at, value)| {
        let mut lines: Vec<String> = texts[k].lines().map(str::to_owned).collect();
        let profiles: Vec<usize> = (0..lines.len())
            .filter(|&i| {
                let key = lines[i].split('=').next().unwrap_or("").trim();
                matches!(key, "h" | "u" | "w" | "b")
            })
            .collect();
        if !profiles.is_empty() {
            let i = profiles[at.index(profiles.len())];
            let key = lines[i].split('=').next().unwrap_or("").to_owned();
            lines[i] = format!("{key}= {}", nasty(value));
        }
        lines.join("\n")
    })
}

/// Sweep files: the bundled ones edited like scenarios (their `scenario` made
/// absolute), and generated ones whose axes take schema keys and hostile values.
fn sweep_text() -> impl Strategy<Value = String> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios");
    let mut texts: Vec<String> = std::fs::read_dir(dir.join("sweeps"))
        .unwrap()
        .filter_map(|e| e.ok())
        .map(|e| std::fs::read_to_string(e.path()).unwrap())
        .map(|t| {
            t.replace(
                "scenario = \"../",
                &format!("scenario = \"{}/", dir.display()),
            )
        })
        .collect();
    texts.sort();
    let bases: Vec<String> = scenarios_paths();
    let edited = (
        0..texts.len(),
        prop::collection::vec((any::<prop::sample::Index>(), 0..N_NASTY), 1..4),
    )
        .prop_map(move |(k, edits)| {
            let mut lines: Vec<String> = texts[k].lines().map(str::to_owned).collect();
            for (at, value) in edits {
                let i = at.index(lines.len());
                if let Some((key, _)) = lines[i].split_once('=') {
                    if key.trim() != "scenario" && key.trim() != "output" {
                        lines[i] = format!("{key}= {}", nasty(value));
                    }
                }
            }
            lines.join("\n")
        });
    let generated = (
        0..bases.len(),
        prop::collection::vec(
            (0..KEYS.len(), prop::collection::vec(0..N_NASTY, 0..4)),
            0..4,
        ),
        any::<bool>(),
    )
        .prop_map(move |(k, axes, zip)| {
            let mut text = format!("scenario = {:?}\nset = [\"domain.cells=20\"]\n", bases[k]);
            text.push_str(if zip { "[[zip]]\n" } else { "[axes]\n" });
            for (key, values) in axes {
                let values: Vec<String> = values.into_iter().map(nasty).collect();
                text.push_str(&format!("{} = [{}]\n", KEYS[key], values.join(", ")));
            }
            text
        });
    prop_oneof![edited, generated]
}

fn scenarios_paths() -> Vec<String> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios");
    let mut paths: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .filter_map(|e| e.ok())
        .map(|e| e.path())
        .filter(|p| p.extension().is_some_and(|x| x == "toml"))
        .map(|p| p.display().to_string())
        .collect();
    paths.sort();
    paths
}

/// Parses a sweep file, expands it when it is small, and loads and builds the first
/// runs' scenarios as `granflow sweep` would.
fn exercise_sweep(text: &str) -> Result<(), TestCaseError> {
    let start = Instant::now();
    let path = std::env::temp_dir().join("granflow-fuzz-sweep.toml");
    if let Ok(spec) = granflow::sweep::spec::parse(&path, text) {
        if spec.run_count() <= 64 {
            if let Ok(points) = granflow::sweep::expand::expand_spec(&spec) {
                let base = std::fs::read_to_string(&spec.scenario).unwrap_or_default();
                let dir = spec
                    .scenario
                    .parent()
                    .unwrap_or(Path::new("."))
                    .to_path_buf();
                for point in points.iter().take(4) {
                    let sets = point.overrides();
                    if let Ok(scn) = granflow::scenario::load_str(&base, &dir, &sets) {
                        if scn.domain.cell_count() * scn.model.layers <= 200_000 {
                            let _ = granflow::runner::check(&scn);
                        }
                    }
                }
            }
        }
    }
    let took = start.elapsed();
    prop_assert!(took < PER_INPUT, "took {took:?}");
    Ok(())
}

fn input() -> impl Strategy<Value = (String, Vec<String>)> {
    prop_oneof![
        any::<Vec<u8>>().prop_map(|b| String::from_utf8_lossy(&b).into_owned()),
        edited_scenario(),
        edited_scenario(),
        profile_edit(),
        profile_edit(),
        generated_document(),
    ]
    .prop_flat_map(|text| (Just(text), overrides()))
}

#[test]
fn any_input_loads_or_is_refused_without_panic_or_hang() {
    let budget = std::env::var("GRANFLOW_FUZZ_SECONDS")
        .ok()
        .and_then(|s| s.parse::<f64>().ok());
    let start = Instant::now();
    let mut round = 0u32;
    loop {
        // Each round a new deterministic seed, so a budgeted run keeps finding new cases.
        let config = Config {
            cases: 256,
            failure_persistence: None,
            rng_algorithm: proptest::test_runner::RngAlgorithm::ChaCha,
            ..Config::default()
        };
        let seed = [round as u8; 32];
        let rng = proptest::test_runner::TestRng::from_seed(
            proptest::test_runner::RngAlgorithm::ChaCha,
            &seed,
        );
        let mut runner = TestRunner::new_with_rng(config, rng);
        let result = runner.run(&input(), |(text, sets)| exercise(&text, &sets));
        if let Err(e) = result {
            panic!("{e}");
        }
        let result = runner.run(&sweep_text(), |text| exercise_sweep(&text));
        if let Err(e) = result {
            panic!("sweep file: {e}");
        }
        round += 1;
        // Without a budget: a fixed number of rounds (about a second in a debug build).
        match budget {
            Some(seconds) if start.elapsed().as_secs_f64() < seconds => continue,
            None if round < DEFAULT_ROUNDS => continue,
            _ => break,
        }
    }
    let [refused, accepted] = &COUNTS;
    eprintln!(
        "fuzz: {round} rounds, {} inputs refused and {} accepted, in {:.1} s",
        refused.load(std::sync::atomic::Ordering::Relaxed),
        accepted.load(std::sync::atomic::Ordering::Relaxed),
        start.elapsed().as_secs_f64()
    );
}
