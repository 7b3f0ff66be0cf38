//! Cost of progressive HDF5 output: times each `snapshot()` of a synthetic run.
//!
//!     cargo run --release --example output_bench -- [--nx 10000] [--layers 1] \
//!         [--snapshots 200] [--steps-per-snapshot 5000] [--out DIR]
//!
//! Prints the time of the first snapshot, of snapshot 101 (after 100 on disk) and of
//! the last, the mean, and the file size.

use std::time::{Duration, Instant};

use granflow::grid::{GridSpec, LineGeometry};
use granflow::output::{
    GridData, Hdf5Sink, OutputSink, RunInfo, RunSummary, SnapshotView, StepRecord,
};

fn option(name: &str, default: usize) -> usize {
    let args: Vec<String> = std::env::args().collect();
    args.iter()
        .position(|a| a == name)
        .and_then(|i| args.get(i + 1))
        .map_or(default, |v| v.parse().expect("integer option"))
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let (nx, nl) = (option("--nx", 10_000), option("--layers", 1));
    let (snapshots, per) = (
        option("--snapshots", 200),
        option("--steps-per-snapshot", 5000),
    );
    let args: Vec<String> = std::env::args().collect();
    let dir = match args.iter().position(|a| a == "--out") {
        Some(i) => std::path::PathBuf::from(&args[i + 1]),
        None => std::env::temp_dir(),
    };
    let path = dir.join(format!("granflow_output_bench_{}.h5", std::process::id()));

    let x: Vec<f64> = (0..nx).map(|i| i as f64 * 0.01).collect();
    let zeros = vec![0.0; nx];
    let info = RunInfo {
        granflow_version: env!("CARGO_PKG_VERSION").into(),
        model: "granular".into(),
        pressure: "hydrostatic".into(),
        layers: nl,
        coordinates: "local".into(),
        slope_deg: 30.0,
        scenario_toml: String::new(),
        front_threshold: 1e-3,
        raster: None,
    };
    let mut sink = Hdf5Sink::create(&path)?;
    sink.begin(
        &info,
        &GridData {
            spec: &GridSpec::Line(LineGeometry::of_extent(
                nx,
                -0.005,
                (nx as f64 - 0.5) * 0.01,
            )),
            x: &x,
            y: None,
            shape: None,
            b: &zeros,
            h_bed: &zeros,
        },
    )?;
    let mut times = Vec::with_capacity(snapshots);
    let mut step = 0u64;
    for s in 0..snapshots {
        for _ in 0..per {
            let t = step as f64 * 1e-3;
            sink.step(&StepRecord {
                t,
                dt: 1e-3,
                mass: 1.0,
                kinetic_energy: 0.5,
                max_speed: 1.0,
                front_x: t,
            })?;
            step += 1;
        }
        let h: Vec<f64> = (0..nx).map(|i| 1.0 + (i + s) as f64 * 1e-6).collect();
        let u = vec![s as f64; nl * nx];
        let start = Instant::now();
        sink.snapshot(&SnapshotView {
            t: step as f64 * 1e-3,
            h: &h,
            u: &u,
            v: None,
            shape: None,
            w: None,
            p_nh: None,
            layers: nl,
            extra: &[],
            layer_uv: None,
        })?;
        times.push(start.elapsed());
    }
    let start = Instant::now();
    sink.finish(&RunSummary {
        runout: 0.0,
        stop_time: f64::NAN,
        settled_time: f64::NAN,
        settle_fraction: 1e-6,
        h_max_final: 1.0,
        t_end: step as f64 * 1e-3,
        steps: step,
        wall_time_s: 0.0,
        status: "completed".into(),
        max_wave_amplitude: None,
        wet: None,
        spread: None,
        outflowed_fraction: 0.0,
        front_at_end_time: f64::NAN,
        max_speed_final: 0.0,
        stage_times: Vec::new(),
    })?;
    let finish = start.elapsed();
    let ms = |d: Duration| d.as_secs_f64() * 1e3;
    let mean = times.iter().map(|&d| ms(d)).sum::<f64>() / times.len() as f64;
    let at = |k: usize| times.get(k).map_or(f64::NAN, |&d| ms(d));
    println!(
        "nx={nx} nl={nl} snapshots={snapshots} steps/snapshot={per}: snapshot #1 {:.2} ms, #101 {:.2} ms, \
         last {:.2} ms, mean {mean:.2} ms, max {:.2} ms; finish {:.2} ms; file {:.1} MB",
        at(0),
        at(100),
        at(snapshots - 1),
        times.iter().map(|&d| ms(d)).fold(0.0, f64::max),
        ms(finish),
        std::fs::metadata(&path)?.len() as f64 / 1e6,
    );
    std::fs::remove_file(&path)?;
    Ok(())
}
