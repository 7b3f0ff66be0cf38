//! Shared test helpers: runs built from plain closures without scenario files, and
//! scenario texts loaded or refused at a key.
#![allow(dead_code)]

pub mod crafted;

use granflow::grid::LineSpec;
use granflow::model::granular::Granular;
use granflow::output::memory::MemorySink;
use granflow::output::RunSummary;
use granflow::scenario::{
    BasalCondition, Boundaries, BoundaryKind, Coordinates, Domain, FrictionLaw, Initial, Material,
    ModelKind, ModelSpec, MultilayerSpec, Numerics, OutputSpec, Pressure, Profile, Regularization,
    Sampled, Scenario, TimeSpec, ViscosityTime,
};
use granflow::setup::build_granular;
use granflow::simulation::Simulation;

pub struct Case {
    pub mesh: LineSpec,
    pub law: FrictionLaw,
    pub cfl: f64,
    pub t_end: f64,
    pub every: f64,
    pub stop_at_rest: bool,
    /// `[numerics]` (order 1 by default).
    pub numerics: Numerics,
    /// `model.layers` (1 by default; equal fractions).
    pub layers: usize,
    /// `model.pressure` (hydrostatic by default).
    pub pressure: Pressure,
}

impl Case {
    pub fn new(x_min: f64, x_max: f64, cells: usize) -> Case {
        Case {
            mesh: LineSpec {
                x_min,
                x_max,
                cells,
                slope_deg: 0.0,
                coordinates: Coordinates::Local,
                left: BoundaryKind::Wall,
                right: BoundaryKind::Wall,
            },
            law: FrictionLaw::Coulomb { mu: 0.0 },
            cfl: 0.5,
            t_end: 1.0,
            every: 0.1,
            stop_at_rest: false,
            numerics: Numerics::default(),
            layers: 1,
            pressure: Pressure::Hydrostatic,
        }
    }

    pub fn beads_material() -> Material {
        Material {
            rho_s: 2500.0,
            phi: 0.62,
            d_s: 0.7e-3,
        }
    }

    /// Builds the run with bed `b(x)`, thickness `h(x, b)` and velocity `u(x)`, through
    /// the same set-up as a scenario file (`setup::build_granular`).
    pub fn build(
        &self,
        b: impl Fn(f64) -> f64 + Send + Sync + 'static,
        h: impl Fn(f64, f64) -> f64 + Send + Sync + 'static,
        u: impl Fn(f64) -> f64 + Send + Sync + 'static,
    ) -> Simulation<Granular> {
        let mut scn = Scenario {
            notes: Vec::new(),
            source_toml: String::new(),
            base_dir: ".".into(),
            domain: Domain {
                x_min: self.mesh.x_min,
                x_max: self.mesh.x_max,
                cells: self.mesh.cells,
                slope_deg: self.mesh.slope_deg,
                coordinates: self.mesh.coordinates,
                curvature: true,
                plane: None,
            },
            bed: Profile::function(move |x, _| b(x)),
            material: Self::beads_material(),
            friction: self.law,
            friction_zones: None,
            model: ModelSpec {
                kind: ModelKind::Granular,
                pressure: self.pressure,
                layers: self.layers,
            },
            multilayer: MultilayerSpec {
                layer_fractions: vec![1.0 / self.layers as f64; self.layers],
                basal: BasalCondition::Coulomb,
                regularization: Regularization::Delta { delta: 1e-5 },
                sidewall: None,
                c_msm: false,
                viscosity: ViscosityTime::Frozen,
                static_threshold: 1e-3,
            },
            dilatancy: None,
            release: None,
            initial: Initial {
                h: Profile::function(h),
                u: Profile::function(move |x, _| u(x)),
                v: Profile::constant(0.0),
                w: Profile::constant(0.0),
                erodible_bed: Profile::constant(0.0),
                eta: None,
                phi: None,
            },
            boundary: Boundaries {
                left: self.mesh.left,
                right: self.mesh.right,
                south: BoundaryKind::Wall,
                north: BoundaryKind::Wall,
            },
            time: TimeSpec {
                t_end: self.t_end,
                cfl: self.cfl,
                stop_at_rest: self.stop_at_rest,
                settle_fraction: 1e-6,
                stop_when_settled: false,
                film_thickness: 0.0,
            },
            output: OutputSpec {
                file: "test.h5".into(),
                every: self.every,
                front_threshold: 1e-3,
                gauges: Vec::new(),
                gauges_y: Vec::new(),
                gauge_every: None,
                path: None,
            },
            submarine: None,
            sampled: Sampled::default(),
            numerics: self.numerics,
        };
        scn.sampled = Sampled::of(&scn.domain, &scn.bed, &scn.initial);
        build_granular(&scn)
    }
}

/// Runs to the end, keeping everything in memory.
pub fn run(sim: &mut Simulation<Granular>) -> (MemorySink, RunSummary) {
    let mut sink = MemorySink::default();
    let summary = sim.run(&mut sink, &mut |_| {}).expect("run succeeds");
    (sink, summary)
}

pub fn tan_deg(deg: f64) -> f64 {
    deg.to_radians().tan()
}

/// L1 norm of a − b times dx.
pub fn l1(a: &[f64], b: &[f64], dx: f64) -> f64 {
    a.iter().zip(b).map(|(a, b)| (a - b).abs()).sum::<f64>() * dx
}

/// Least-squares slope of log(err) against log(dx): the observed order.
pub fn observed_order(dx: &[f64], err: &[f64]) -> f64 {
    let n = dx.len() as f64;
    let lx: Vec<f64> = dx.iter().map(|v| v.ln()).collect();
    let ly: Vec<f64> = err.iter().map(|v| v.ln()).collect();
    let mx = lx.iter().sum::<f64>() / n;
    let my = ly.iter().sum::<f64>() / n;
    let sxy: f64 = lx.iter().zip(&ly).map(|(x, y)| (x - mx) * (y - my)).sum();
    let sxx: f64 = lx.iter().map(|x| (x - mx) * (x - mx)).sum();
    sxy / sxx
}

/// A float dataset of an HDF5 file, flattened.
pub fn read_h5(f: &rust_hdf5::H5File, name: &str) -> Vec<f64> {
    f.dataset(name).unwrap().read_raw::<f64>().unwrap()
}

/// Asserts that a finished command succeeded, showing its stderr otherwise; returns
/// its stdout.
pub fn assert_success(out: &std::process::Output) -> String {
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout).into_owned()
}

fn has_h5py(python: &str) -> bool {
    std::process::Command::new(python)
        .args(["-c", "import h5py, numpy"])
        .output()
        .is_ok_and(|o| o.status.success())
}

/// What a test that needs h5py does without it: under CI (the variable `CI` set, as
/// on every CI service) it fails, since a skipped check would count as passed; on a
/// developer's machine it is skipped with a message.
pub fn without_h5py(ci: Option<std::ffi::OsString>) -> Result<(), String> {
    match ci {
        Some(v) if !v.is_empty() && v != "0" && v != "false" => Err(format!(
            "CI={} is set but no Python with h5py and numpy was found: set GRANFLOW_PYTHON \
             to one (a skipped check would count as passed)",
            v.to_string_lossy()
        )),
        _ => Ok(()),
    }
}

#[test]
fn tests_needing_h5py_fail_under_ci_without_it() {
    assert!(without_h5py(Some("true".into())).is_err());
    assert!(without_h5py(Some("1".into())).is_err());
    assert!(without_h5py(None).is_ok());
    assert!(without_h5py(Some("".into())).is_ok());
    assert!(without_h5py(Some("false".into())).is_ok());
}

/// A Python with h5py and numpy: the one `GRANFLOW_PYTHON` names (CI sets it; one that
/// cannot import them fails the test), else `python3` or `python` on PATH if it can.
/// Without one, the test fails when `CI` is set ([`without_h5py`]); otherwise `None`
/// after printing `SKIPPED: …` on the terminal: written to stderr directly, because
/// the test harness hides `eprintln!` of passing tests.
pub fn python_with_h5py() -> Option<String> {
    use std::io::Write;
    if let Ok(python) = std::env::var("GRANFLOW_PYTHON") {
        assert!(
            has_h5py(&python),
            "GRANFLOW_PYTHON={python} cannot import h5py and numpy"
        );
        return Some(python);
    }
    if let Some(found) = ["python3", "python"].into_iter().find(|p| has_h5py(p)) {
        return Some(found.to_owned());
    }
    if let Err(message) = without_h5py(std::env::var_os("CI")) {
        panic!("{message}");
    }
    let _ = writeln!(
        std::io::stderr(),
        "SKIPPED: the h5py check of {} (no Python with h5py and numpy; set GRANFLOW_PYTHON)",
        std::thread::current().name().unwrap_or("a test")
    );
    None
}

/// Runs `scripts/check_output.py` on `h5` with the Python of [`python_with_h5py`]
/// (nothing when it is not set); returns the script's stdout.
pub fn check_output_with_h5py(h5: &std::path::Path, layers: usize) -> Option<String> {
    let python = python_with_h5py()?;
    let script = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scripts/check_output.py");
    let out = std::process::Command::new(python)
        .arg(script)
        .arg(h5)
        .args(["--expect-layers", &layers.to_string()])
        .output()
        .unwrap();
    Some(assert_success(&out))
}

/// FNV-1a over the exact bits of a sequence of numbers (frozen-result tests).
pub fn fingerprint<'a>(values: impl IntoIterator<Item = &'a f64>) -> u64 {
    let mut hash = 0xcbf2_9ce4_8422_2325u64;
    for v in values {
        for byte in v.to_bits().to_le_bytes() {
            hash ^= byte as u64;
            hash = hash.wrapping_mul(0x0100_0000_01b3);
        }
    }
    hash
}

/// A small valid scenario (a 14 cm column on 22°, μ(I), 60 cells, 0.05 s) for command-line
/// tests to edit.
pub const MINIMAL: &str = r#"[domain]
x_min = -0.2
x_max = 1.0
cells = 60
slope_deg = 22

[rheology]
law = "mu_i"
mu_s_deg = 25.5
mu_2_deg = 36
i0 = 0.279

[initial]
h = "if(x <= 0, 0.14, 0)"

[time]
t_end = 0.05
"#;

/// What a run with many snapshots needs to keep: the largest |p_nh| over all its
/// snapshots, the last snapshot's h, and the number of snapshots (a sink that does not
/// keep every frame in memory).
#[derive(Debug, Default)]
pub struct PressureWatch {
    pub max_p: f64,
    pub last_h: Vec<f64>,
    pub snapshots: usize,
}

impl granflow::output::OutputSink for PressureWatch {
    fn begin(
        &mut self,
        _info: &granflow::output::RunInfo,
        _grid: &granflow::output::GridData,
    ) -> Result<(), granflow::output::OutputError> {
        Ok(())
    }

    fn snapshot(
        &mut self,
        snap: &granflow::output::SnapshotView,
    ) -> Result<(), granflow::output::OutputError> {
        let p = snap.p_nh.expect("a non-hydrostatic run");
        self.max_p = p.iter().fold(self.max_p, |m, p| m.max(p.abs()));
        self.last_h.clear();
        self.last_h.extend_from_slice(snap.h);
        self.snapshots += 1;
        Ok(())
    }

    fn step(
        &mut self,
        _rec: &granflow::output::StepRecord,
    ) -> Result<(), granflow::output::OutputError> {
        Ok(())
    }

    fn finish(&mut self, _summary: &RunSummary) -> Result<(), granflow::output::OutputError> {
        Ok(())
    }
}

/// The bundled granular scenario `file` with the overrides `sets`, run to its end of
/// 10 s with snapshots every `every` s into a [`PressureWatch`].
pub fn watch_pressure(file: &str, sets: &[&str], every: &str) -> PressureWatch {
    let mut sets: Vec<String> = sets.iter().map(|s| s.to_string()).collect();
    sets.push(format!("output.every={every}"));
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("scenarios")
        .join(file);
    let scn = granflow::scenario::load_file(&path, &sets).expect("scenario loads");
    let mut sim = build_granular(&scn);
    let mut w = PressureWatch::default();
    let summary = sim
        .run(&mut w, &mut |_| {})
        .unwrap_or_else(|e| panic!("every {every}: the run fails: {e}"));
    assert_eq!(summary.t_end, 10.0, "every {every}");
    w
}

/// The check of a run with snapshots every 0.1 s (`coarse`) against the same run with
/// snapshots every 0.004 s (`fine`, many steps shortened to land on an output time):
/// the largest |p_nh| of the fine run's snapshots within twice the coarse run's (250
/// times as many snapshots see more of its peaks), and h at the end within 2 % in
/// relative L1 (the step lengths' own effect is 0.5–1 %).
pub fn assert_snapshot_times_agree(label: &str, coarse: &PressureWatch, fine: &PressureWatch) {
    let d = relative_l1(&coarse.last_h, &fine.last_h);
    println!(
        "{label}, snapshots every 0.1 / 0.004 s: largest |p_nh| {:.3e} / {:.3e}, h at t = 10 s {d:.2e} apart (relative L1)",
        coarse.max_p, fine.max_p
    );
    assert!(
        fine.max_p < 2.0 * coarse.max_p,
        "{} vs {}",
        fine.max_p,
        coarse.max_p
    );
    assert!(d < 0.02, "{d}");
}

/// Relative L1 distance Σ|a − b| / Σ|a|.
pub fn relative_l1(a: &[f64], b: &[f64]) -> f64 {
    let d: f64 = a.iter().zip(b).map(|(a, b)| (a - b).abs()).sum();
    d / a.iter().map(|a| a.abs()).sum::<f64>()
}

/// A scenario from its text, with `dir` for the files it names (no overrides).
pub fn load_in(
    text: &str,
    dir: &std::path::Path,
) -> Result<granflow::scenario::Scenario, granflow::scenario::ScenarioError> {
    granflow::scenario::load_str(text, dir, &[])
}

/// Loads `text` (files in `dir`), expects an error at `key` with its line, returns the
/// message.
#[track_caller]
pub fn fails_at(text: &str, dir: &std::path::Path, key: &str) -> String {
    match load_in(text, dir) {
        Ok(_) => panic!("expected an error at {key}, the scenario loaded"),
        Err(e) => {
            assert_eq!(e.key(), Some(key), "{e}");
            assert!(e.line().is_some(), "no line: {e}");
            e.message().to_owned()
        }
    }
}
