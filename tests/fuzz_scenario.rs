//! Fuzzing the scenario loader, the sweep-file loader and the run setup: any byte
//! string, any edit of a real scenario or sweep file and any combination of schema keys
//! of every model (granular, multilayer, non-hydrostatic, dilatant, submarine) with
//! hostile values must give
//! a scenario or a `ScenarioError` (exit 0 or 2), never a panic, an abort (stack
//! overflow, out of memory) or a hang. The GIS and result inputs are fuzzed the same
//! way: crafted GeoTIFF headers, ESRI grids and side-car CRS files, release polygons,
//! run files for `export` and its arguments, sweep plans for `maps` and its
//! arguments, and signals sent to a 2-D run.
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

// ------------------------------------------------------------- GIS and result files

/// Numbers that have broken GIS headers: round-off, overflow, NaN, signs.
const HOSTILE_F64: &[f64] = &[
    0.0,
    -0.0,
    1.0,
    -1.0,
    5.0,
    1e-300,
    5e-324,
    1e17,
    1e300,
    -1e300,
    1.7e308,
    f64::NAN,
    f64::INFINITY,
    f64::NEG_INFINITY,
    2_600_000.0,
    0.5,
];

/// Texts of the same numbers, and some that are not numbers, for text headers.
const HOSTILE_TEXT: &[&str] = &[
    "0",
    "1",
    "2",
    "3",
    "-1",
    "5",
    "1e-300",
    "1e17",
    "1e300",
    "-1e308",
    "nan",
    "inf",
    "99999999999",
    "1e3",
    "x",
    "",
    "2600000",
    "0.5",
];

/// WKT texts for side-car `.prj` files: projected, geographic, without code, junk.
const WKTS: &[&str] = &[
    r#"PROJCS["CH1903+ / LV95",AUTHORITY["EPSG","2056"]]"#,
    r#"GEOGCS["WGS 84",AUTHORITY["EPSG","4326"]]"#,
    r#"PROJCS["no code"]"#,
    "\u{feff}",
    "[[[[",
];

/// Sizes for crafted headers: ordinary, degenerate and far beyond any run.
const SIZES: &[u32] = &[0, 1, 2, 3, 17, 1000, 40_000, 65_535, u32::MAX];

/// One crafted GIS or result input.
#[derive(Debug, Clone)]
enum GisInput {
    Tiff {
        spec: Box<crate::common::crafted::Tiff>,
    },
    Asc {
        header: Vec<(String, String)>,
        bom: bool,
        values: usize,
        prj: Option<usize>,
    },
    GeoJson {
        rings: Vec<Vec<[f64; 2]>>,
        crs: Option<u32>,
    },
    Shapefile {
        records: Vec<Vec<Vec<[f64; 2]>>>,
    },
    Export {
        nx: usize,
        ny: usize,
        maps: Option<(usize, usize)>,
        times: usize,
        args: Vec<String>,
    },
    Maps {
        plan: String,
        args: Vec<String>,
    },
}

fn hostile_f64() -> impl Strategy<Value = f64> {
    prop_oneof![
        (0..HOSTILE_F64.len()).prop_map(|k| HOSTILE_F64[k]),
        -1e3..1e3f64,
    ]
}

fn tiff_input() -> impl Strategy<Value = GisInput> {
    let sizes = (0..SIZES.len(), 0..SIZES.len());
    let sample = (
        prop::sample::select(vec![1u16, 7, 8, 16, 32, 64]),
        0u16..5,
        prop::sample::select(vec![1u16, 5, 7, 8, 32773]),
    );
    let strip = (
        prop::collection::vec(any::<u8>(), 0..256),
        prop::option::of(prop::sample::select(vec![0u32, 1, 7, u32::MAX])),
    );
    let georef = (
        prop::option::of(prop::array::uniform3(hostile_f64())),
        prop::option::of(prop::array::uniform6(hostile_f64())),
        prop::option::of(prop::collection::vec(hostile_f64(), 16)),
        prop::option::of((
            prop::sample::select(vec![1024u16, 1025, 2048, 3072, 4096]),
            prop::sample::select(vec![0u16, 1, 2, 2056, 4326, 21781, 32632, 32767]),
        )),
    );
    (sizes, sample, strip, georef).prop_map(
        |((w, h), (bits, format, compression), (bytes, count), (scale, tie, transform, key))| {
            let (width, height) = (SIZES[w], SIZES[h]);
            let mut spec = crate::common::crafted::Tiff::float32(1, 1);
            (spec.width, spec.height) = (width, height);
            (spec.bits, spec.sample_format, spec.compression) = (bits, format, compression);
            // A complete uncompressed strip when it is small, else the random bytes.
            let full = u64::from(width)
                .saturating_mul(u64::from(height))
                .saturating_mul(u64::from(bits / 8));
            spec.strip = if compression == 1 && full <= 4096 {
                vec![0; full as usize]
            } else {
                bytes
            };
            spec.strip_byte_count = count;
            spec.scale = scale;
            spec.tiepoint = tie;
            spec.transform = transform.map(|m| m.try_into().unwrap());
            if let Some((k, code)) = key {
                spec = spec.with_epsg(k, code);
            }
            GisInput::Tiff {
                spec: Box::new(spec),
            }
        },
    )
}

fn asc_input() -> impl Strategy<Value = GisInput> {
    let keys = prop::sample::select(vec![
        "ncols",
        "nrows",
        "xllcorner",
        "yllcorner",
        "xllcenter",
        "cellsize",
        "dx",
        "dy",
        "NODATA_value",
        "bogus",
    ]);
    let good: Vec<(String, String)> = [
        ("ncols", "4"),
        ("nrows", "3"),
        ("xllcorner", "0"),
        ("yllcorner", "0"),
        ("cellsize", "5"),
    ]
    .iter()
    .map(|(k, v)| (k.to_string(), v.to_string()))
    .collect();
    (
        prop::collection::vec((keys, 0..HOSTILE_TEXT.len()), 0..4),
        any::<bool>(),
        0usize..30,
        prop::option::of(0..WKTS.len()),
    )
        .prop_map(move |(edits, bom, values, prj)| {
            let mut header = good.clone();
            for (key, v) in edits {
                let value = HOSTILE_TEXT[v].to_string();
                match header.iter_mut().find(|(k, _)| k == key) {
                    Some(entry) => entry.1 = value,
                    None => header.push((key.to_string(), value)),
                }
            }
            GisInput::Asc {
                header,
                bom,
                values,
                prj,
            }
        })
}

fn ring() -> impl Strategy<Value = Vec<[f64; 2]>> {
    prop::collection::vec(
        prop_oneof![
            (0.0..20.0f64, 0.0..15.0f64).prop_map(|(x, y)| [x, y]),
            (hostile_f64(), hostile_f64()).prop_map(|(x, y)| [x, y]),
        ],
        0..8,
    )
}

fn polygon_input() -> impl Strategy<Value = GisInput> {
    prop_oneof![
        (
            prop::collection::vec(ring(), 1..4),
            prop::option::of(prop::sample::select(vec![2056u32, 4326, 21781])),
        )
            .prop_map(|(rings, crs)| GisInput::GeoJson { rings, crs }),
        prop::collection::vec(prop::collection::vec(ring(), 1..3), 1..3)
            .prop_map(|records| GisInput::Shapefile { records }),
    ]
}

fn result_input() -> impl Strategy<Value = GisInput> {
    let counts = prop::sample::select(vec![0usize, 1, 2, 5]);
    let export_args = prop::collection::vec(
        prop::sample::select(vec![
            "--format=geotiff",
            "--format=asc",
            "--format=netcdf",
            "--format=png",
            "--time=-1",
            "--time=0",
            "--time=nan",
            "--time=1e300",
            "--time=-inf",
            "--fields=pft",
            "--fields=h,speed",
            "--fields=",
            "--fields=bogus",
            "--fields=pft,pft",
            "--float64",
            "--quiet",
        ]),
        0..4,
    );
    let maps_args = prop::collection::vec(
        prop::sample::select(vec![
            "--threshold=-1",
            "--threshold=nan",
            "--threshold=1e300",
            "--threshold=0",
            "--observed=missing.geojson",
            "--observed=plan.toml",
            "--partial",
            "--format=asc",
        ]),
        0..4,
    );
    prop_oneof![
        (
            counts.clone(),
            counts.clone(),
            prop::option::of((counts.clone(), counts.clone())),
            counts,
            export_args,
        )
            .prop_map(|(nx, ny, maps, times, args)| GisInput::Export {
                nx,
                ny,
                maps,
                times,
                args: args.into_iter().map(str::to_owned).collect(),
            }),
        (any::<Vec<u8>>(), maps_args).prop_map(|(plan, args)| GisInput::Maps {
            plan: String::from_utf8_lossy(&plan).into_owned(),
            args: args.into_iter().map(str::to_owned).collect(),
        }),
    ]
}

fn gis_input() -> impl Strategy<Value = GisInput> {
    prop_oneof![tiff_input(), asc_input(), polygon_input(), result_input()]
}

/// A scenario on the raster bed `bed` with the thickness `h` (a TOML value).
fn raster_scenario(bed: &str, h: &str) -> String {
    format!(
        "[domain]\ncoordinates = \"cartesian\"\n[bed]\nb = {{ raster = \"{bed}\" }}\n[rheology]\nlaw = \"coulomb\"\nmu_deg = 30\n[initial]\nh = {h}\n[time]\nt_end = 0.1\n"
    )
}

/// Loads a scenario of `dir` and builds its run when it is small.
fn load_and_check(text: &str, dir: &Path) {
    if let Ok(scn) = granflow::scenario::load_str(text, dir, &[]) {
        if scn.domain.cell_count() <= 200_000 {
            let _ = granflow::runner::check(&scn);
        }
    }
}

/// The export and maps command lines as `granflow` parses them.
#[derive(clap::Parser, Debug)]
struct ExportLine {
    #[command(flatten)]
    args: granflow::results::ExportArgs,
}

#[derive(clap::Parser, Debug)]
struct MapsLine {
    #[command(flatten)]
    args: granflow::results::MapsArgs,
}

/// A run file with the given axes, maps and snapshot times (and nothing else a run
/// writes), for `export` to read.
fn crafted_run(path: &Path, nx: usize, ny: usize, maps: Option<(usize, usize)>, times: usize) {
    let Ok(f) = rust_hdf5::H5File::create(path) else {
        return;
    };
    let _ = f.set_attr_string("granflow_version", "0");
    let _ = f.set_attr_string("grid", "raster");
    let axis = |n: usize| (0..n).map(|i| i as f64 + 0.5).collect::<Vec<f64>>();
    if let Ok(g) = f.create_group("grid") {
        for (name, n) in [("x", nx), ("y", ny)] {
            if let Ok(ds) = g.new_dataset::<f64>().shape([n]).create(name) {
                let _ = ds.write_raw(&axis(n));
            }
        }
    }
    if let Ok(s) = f.create_group("snapshots") {
        if let Ok(ds) = s.new_dataset::<f64>().shape([times]).create("t") {
            let _ = ds.write_raw(&axis(times));
        }
    }
    if let (Some((rows, cols)), Ok(m)) = (maps, f.create_group("maps")) {
        for name in ["h_max", "speed_max", "ppr", "arrival_time", "deposit"] {
            if let Ok(ds) = m.new_dataset::<f64>().shape([rows, cols]).create(name) {
                let _ = ds.write_raw(&vec![0.25; rows * cols]);
            }
        }
    }
}

/// Reads (or refuses) one crafted input through the library and a scenario, as
/// `granflow check`, `export` and `maps` would.
fn exercise_gis(input: &GisInput) -> Result<(), TestCaseError> {
    use clap::Parser;
    let start = Instant::now();
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    match input {
        GisInput::Tiff { spec } => {
            let p = d.join("dem.tif");
            std::fs::write(&p, spec.bytes()).unwrap();
            let _ = granflow::gis::geotiff::read(&p);
            load_and_check(&raster_scenario("dem.tif", "0.5"), d);
        }
        GisInput::Asc {
            header,
            bom,
            values,
            prj,
        } => {
            let mut text = if *bom {
                "\u{feff}".to_string()
            } else {
                String::new()
            };
            for (k, v) in header {
                text.push_str(&format!("{k} {v}\n"));
            }
            let row: Vec<&str> = vec!["1.5"; *values];
            text.push_str(&row.join(" "));
            let p = d.join("dem.asc");
            std::fs::write(&p, text).unwrap();
            if let Some(k) = prj {
                std::fs::write(d.join("dem.prj"), WKTS[*k]).unwrap();
            }
            let _ = granflow::gis::asc::read(&p);
            load_and_check(&raster_scenario("dem.asc", "0.5"), d);
        }
        GisInput::GeoJson { .. } | GisInput::Shapefile { .. } => {
            let dem = "ncols 4\nnrows 3\nxllcorner 0\nyllcorner 0\ncellsize 5\n0 0 0 0\n0 0 0 0\n0 0 0 0\n";
            std::fs::write(d.join("dem.asc"), dem).unwrap();
            let file = match input {
                GisInput::GeoJson { rings, crs } => {
                    let ring_text = |r: &Vec<[f64; 2]>| {
                        let pts: Vec<String> = r
                            .iter()
                            .map(|p| format!("[{:?}, {:?}]", p[0], p[1]))
                            .collect();
                        format!("[{}]", pts.join(", "))
                    };
                    let rings: Vec<String> = rings.iter().map(ring_text).collect();
                    let crs = crs.map_or(String::new(), |c| {
                        format!(
                            r#""crs": {{"type": "name", "properties": {{"name": "EPSG:{c}"}}}},"#
                        )
                    });
                    let text = format!(
                        r#"{{"type": "FeatureCollection", {crs} "features": [{{"type": "Feature", "properties": {{}}, "geometry": {{"type": "Polygon", "coordinates": [{}]}}}}]}}"#,
                        rings.join(", ")
                    );
                    // NaN and infinity are no JSON numbers: such a file is refused as
                    // JSON, which is a case too.
                    std::fs::write(d.join("r.geojson"), text).unwrap();
                    "r.geojson"
                }
                GisInput::Shapefile { records } => {
                    std::fs::write(
                        d.join("r.shp"),
                        crate::common::crafted::polygon_shp(records),
                    )
                    .unwrap();
                    "r.shp"
                }
                _ => unreachable!(),
            };
            let _ = granflow::gis::release::read(
                &d.join(file),
                granflow::gis::release::ThicknessSource::Uniform(1.0),
            );
            let h =
                format!("{{ polygon = \"{file}\", thickness = 1, thickness_is = \"vertical\" }}");
            load_and_check(&raster_scenario("dem.asc", &h), d);
        }
        GisInput::Export {
            nx,
            ny,
            maps,
            times,
            args,
        } => {
            let run = d.join("run.h5");
            crafted_run(&run, *nx, *ny, *maps, *times);
            let out = d.join("out");
            let mut line = vec![
                "export".to_string(),
                run.display().to_string(),
                format!("--output={}", out.display()),
            ];
            line.extend(args.iter().cloned());
            if let Ok(parsed) = ExportLine::try_parse_from(&line) {
                let _ = std::fs::create_dir_all(&out);
                let _ = granflow::results::export::export(&parsed.args);
            }
        }
        GisInput::Maps { plan, args } => {
            std::fs::write(d.join("sweep-plan.toml"), plan).unwrap();
            std::fs::write(d.join("plan.toml"), plan).unwrap();
            let mut line = vec!["maps".to_string(), d.display().to_string()];
            line.extend(args.iter().cloned());
            if let Ok(parsed) = MapsLine::try_parse_from(&line) {
                let _ = granflow::results::maps::maps(&parsed.args);
            }
        }
    }
    let took = start.elapsed();
    prop_assert!(took < PER_INPUT, "took {took:?}");
    Ok(())
}

/// A 2-D run (the radial collapse on 40 × 40 cells) sent SIGINT or SIGKILL `delay_ms`
/// after its file appeared: it ends without a panic, and its file opens with a status that says
/// how it ended (`interrupted` or `unfinished` when the signal came first).
fn signal_a_raster_run(delay_ms: u64, kill: bool) {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("radial.h5");
    let scn = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/radial_collapse.toml");
    let mut child = std::process::Command::new(assert_cmd::cargo::cargo_bin("granflow"))
        .arg("run")
        .arg(&scn)
        .args(["--quiet", "--set", "domain.cells=[40,40]", "-o"])
        .arg(&out)
        .stdin(std::process::Stdio::null())
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    // From the moment the file exists (a kill while it is being created is the
    // output tests' case, not this one's).
    let start = Instant::now();
    while !out.exists() && start.elapsed() < PER_INPUT {
        if child.try_wait().unwrap().is_some() {
            break;
        }
        std::thread::sleep(Duration::from_millis(2));
    }
    std::thread::sleep(Duration::from_millis(delay_ms));
    let signal = if kill { "-KILL" } else { "-INT" };
    let _ = std::process::Command::new("kill")
        .args([signal, &child.id().to_string()])
        .status();
    let start = Instant::now();
    let status = loop {
        if let Some(status) = child.try_wait().unwrap() {
            break status;
        }
        if start.elapsed() > PER_INPUT {
            let _ = child.kill();
            panic!("a 2-D run still going {PER_INPUT:?} after SIG{signal}");
        }
        std::thread::sleep(Duration::from_millis(10));
    };
    let mut stderr = String::new();
    std::io::Read::read_to_string(&mut child.stderr.take().unwrap(), &mut stderr).unwrap();
    assert!(!stderr.contains("panicked"), "{stderr}");
    if !out.exists() {
        // Killed before the file was created.
        return;
    }
    let file = rust_hdf5::H5File::options()
        .no_locking()
        .open(&out)
        .unwrap_or_else(|e| panic!("SIG{signal} after {delay_ms} ms ({status}): {e}"));
    let ended = file
        .root_group()
        .group("summary")
        .and_then(|g| g.attr_string("status"))
        .unwrap_or_else(|e| panic!("SIG{signal} after {delay_ms} ms ({status}): {e}"));
    assert!(
        [
            "completed",
            "interrupted",
            "unfinished",
            "stopped_at_rest",
            "settled"
        ]
        .contains(&ended.as_str()),
        "SIG{signal} after {delay_ms} ms: status {ended}"
    );
}

/// Crafted GeoTIFFs, ESRI grids (with side-car `.prj`), release polygons (GeoJSON and
/// shapefiles), run files for `export` and sweep plans for `maps`, with their command
/// lines: each is read or refused, never a panic, an abort or a hang; and each round
/// a 2-D run interrupted or killed at a moment of its own. The same time budget as
/// the scenario fuzzing (`GRANFLOW_FUZZ_SECONDS`).
#[test]
fn gis_and_result_inputs_are_read_or_refused_without_panic_or_hang() {
    let budget = std::env::var("GRANFLOW_FUZZ_SECONDS")
        .ok()
        .and_then(|s| s.parse::<f64>().ok());
    let start = Instant::now();
    let mut round = 0u32;
    loop {
        let config = Config {
            cases: 64,
            failure_persistence: None,
            rng_algorithm: proptest::test_runner::RngAlgorithm::ChaCha,
            ..Config::default()
        };
        let seed = [round.wrapping_add(101) as u8; 32];
        let rng = proptest::test_runner::TestRng::from_seed(
            proptest::test_runner::RngAlgorithm::ChaCha,
            &seed,
        );
        let mut runner = TestRunner::new_with_rng(config, rng);
        if let Err(e) = runner.run(&gis_input(), |input| exercise_gis(&input)) {
            panic!("{e}");
        }
        // A moment in the first second of the run (start-up, the first snapshots, the
        // steps between them), from the round number.
        let moment = u64::from(round).wrapping_mul(0x9e37_79b9) % 1000;
        signal_a_raster_run(moment, round % 3 == 2);
        round += 1;
        match budget {
            Some(seconds) if start.elapsed().as_secs_f64() < seconds => continue,
            None if round < 2 => continue,
            _ => break,
        }
    }
    eprintln!(
        "fuzz (GIS and results): {round} rounds of 64 inputs in {:.1} s",
        start.elapsed().as_secs_f64()
    );
}
