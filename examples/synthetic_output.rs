//! Writes a small synthetic granflow run through the real sinks, for checking the
//! file with an external reader (CI runs `scripts/check_output.py` on it):
//!
//!     cargo run --example synthetic_output -- out/synthetic.h5 [--hydrostatic] [--nx N] [--layers N]
//!
//! Fields are smooth closed-form profiles; `mass` is exactly Σh·dx of the state at
//! each step, so the checker's mass test applies.

use std::path::PathBuf;

use granflow::grid::{GridSpec, LineGeometry};
use granflow::output::{
    create_run_sinks, GridData, OutputSink, RunInfo, RunSummary, SnapshotView, StepRecord,
};

struct Args {
    path: PathBuf,
    nx: usize,
    layers: usize,
    nonhydrostatic: bool,
}

fn parse() -> Result<Args, String> {
    let mut args = Args {
        path: PathBuf::new(),
        nx: 50,
        layers: 2,
        nonhydrostatic: true,
    };
    let mut it = std::env::args().skip(1);
    while let Some(arg) = it.next() {
        let mut number = |name: &str| -> Result<usize, String> {
            it.next()
                .and_then(|v| v.parse().ok())
                .filter(|&n| n > 0)
                .ok_or(format!("{name} needs a positive integer"))
        };
        match arg.as_str() {
            "--hydrostatic" => args.nonhydrostatic = false,
            "--nx" => args.nx = number("--nx")?,
            "--layers" => args.layers = number("--layers")?,
            _ if arg.starts_with("--") => return Err(format!("unknown option {arg}")),
            _ => args.path = PathBuf::from(arg),
        }
    }
    if args.path.as_os_str().is_empty() {
        return Err("usage: synthetic_output OUT.h5 [--hydrostatic] [--nx N] [--layers N]".into());
    }
    Ok(args)
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args = parse()?;
    let (nx, nl) = (args.nx, args.layers);
    let dx = 10.0 / nx as f64;
    let x: Vec<f64> = (0..nx).map(|i| (i as f64 + 0.5) * dx).collect();
    let b: Vec<f64> = x.iter().map(|x| -0.1 * x).collect();
    let h_bed = vec![0.0; nx];
    let h_at = |t: f64| -> Vec<f64> {
        x.iter()
            .map(|&x| (1.0 - ((x - 2.0 - t) / 1.5).powi(2)).max(0.0))
            .collect()
    };
    let layered = |t: f64, rows: usize, cols: usize, scale: f64| -> Vec<f64> {
        (0..rows * cols)
            .map(|k| scale * (1.0 + (k / cols) as f64) * (t + (k % cols) as f64 / cols as f64))
            .collect()
    };
    let info = RunInfo {
        granflow_version: env!("CARGO_PKG_VERSION").to_string(),
        model: "granular".into(),
        pressure: if args.nonhydrostatic {
            "nonhydrostatic"
        } else {
            "hydrostatic"
        }
        .into(),
        layers: nl,
        coordinates: "local".into(),
        slope_deg: 30.0,
        scenario_toml: "# synthetic run written by examples/synthetic_output.rs\n".into(),
        front_threshold: 1e-3,
        raster: None,
    };

    let mut sink = create_run_sinks(&args.path)?;
    sink.begin(
        &info,
        &GridData {
            spec: &GridSpec::Line(LineGeometry::of_extent(nx, 0.0, nx as f64 * dx)),
            x: &x,
            y: None,
            shape: None,
            b: &b,
            h_bed: &h_bed,
        },
    )?;
    let (dt, steps, every) = (0.05, 40, 10);
    for k in 0..=steps {
        let t = k as f64 * dt;
        let h = h_at(t);
        let front = x.iter().zip(&h).rfind(|(_, &h)| h > info.front_threshold);
        sink.step(&StepRecord {
            t,
            dt,
            mass: h.iter().sum::<f64>() * dx,
            kinetic_energy: 0.5 * h.iter().sum::<f64>() * dx,
            max_speed: 1.0,
            front_x: front.map_or(f64::NAN, |(&x, _)| x),
        })?;
        if k % every == 0 {
            let u = layered(t, nl, nx, 1.0);
            let w = layered(t, nl, nx, -0.01);
            let p = layered(t, nl + 1, nx + 1, 5.0);
            let nh = args.nonhydrostatic;
            sink.snapshot(&SnapshotView {
                t,
                h: &h,
                u: &u,
                v: None,
                shape: None,
                w: nh.then_some(&w[..]),
                p_nh: nh.then_some(&p[..]),
                layers: nl,
                extra: &[],
                layer_uv: None,
            })?;
        }
    }
    sink.finish(&RunSummary {
        runout: steps as f64 * dt,
        stop_time: f64::NAN,
        settled_time: f64::NAN,
        settle_fraction: 1e-6,
        h_max_final: 1.0,
        t_end: steps as f64 * dt,
        steps: steps as u64,
        wall_time_s: 0.0,
        status: "completed".into(),
        max_wave_amplitude: None,
        wet: None,
        spread: None,
        outflowed_fraction: 0.0,
        front_at_end_time: f64::NAN,
        max_speed_final: 0.0,
        stage_times: vec![("hyperbolic".into(), 0.0), ("friction".into(), 0.0)],
    })?;
    println!("wrote {}", args.path.display());
    Ok(())
}
