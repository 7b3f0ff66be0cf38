//! The cost of a raster run that follows the flow (docs/performance.md, "Cost that
//! follows the flow"): runs a raster scenario to its end on the active tiles (the
//! default) or with every tile stepped (`--full`, the full sweep), and prints the
//! raster's size, the steps, the set-up and run times, the CPU time of the process,
//! the cell updates (in stepped tiles and of wet cells) with their rates, and an
//! FNV-1a hash of every snapshot and step record (the same for both ways and any
//! thread count).
//!
//!   cargo run --release --example flow_cost -- scenarios/hockey_channel.toml --threads 1
//!
//! Options: `--full`, `--threads N` (default 1), `--set KEY=VALUE` (repeatable, as
//! `granflow run --set`). Snapshots are kept in memory: give large rasters a long
//! `output.every`. CPU times are read from /proc/self/stat (Linux).
use granflow::output::memory::MemorySink;
use std::path::Path;
use std::time::Instant;

fn fnv(h: &mut u64, v: f64) {
    for b in v.to_bits().to_le_bytes() {
        *h ^= b as u64;
        *h = h.wrapping_mul(0x100_0000_01b3);
    }
}

/// User + system CPU seconds of this process so far (clock ticks of 1/100 s).
fn cpu_seconds() -> f64 {
    let stat = std::fs::read_to_string("/proc/self/stat").unwrap_or_default();
    // The fields after the command name (which is in parentheses): utime is the 12th
    // of them, stime the 13th.
    let rest = stat.rsplit(')').next().unwrap_or("");
    let f: Vec<f64> = rest
        .split_whitespace()
        .map(|x| x.parse().unwrap_or(0.0))
        .collect();
    if f.len() < 13 {
        return f64::NAN;
    }
    (f[11] + f[12]) / 100.0
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let Some(file) = args.first() else {
        eprintln!("usage: flow_cost SCENARIO.toml [--full] [--threads N] [--set KEY=VALUE ...]");
        std::process::exit(2);
    };
    let (mut full, mut threads, mut sets) = (false, 1usize, Vec::new());
    let mut rest = args[1..].iter();
    while let Some(a) = rest.next() {
        match a.as_str() {
            "--full" => full = true,
            "--threads" => threads = rest.next().and_then(|n| n.parse().ok()).unwrap_or(1),
            "--set" => sets.extend(rest.next().cloned()),
            other => {
                eprintln!("flow_cost: unknown argument {other}");
                std::process::exit(2);
            }
        }
    }
    let (wall0, cpu0) = (Instant::now(), cpu_seconds());
    let scn = granflow::scenario::load_file(Path::new(file), &sets).unwrap_or_else(|e| {
        eprintln!("{e}");
        std::process::exit(2)
    });
    let mut sim = granflow::setup::build_granular_2d(&scn, threads);
    if full {
        sim.state.tiles.step_every_tile();
    }
    let (setup_wall, setup_cpu) = (wall0.elapsed().as_secs_f64(), cpu_seconds() - cpu0);
    let (wall1, cpu1) = (Instant::now(), cpu_seconds());
    let mut sink = MemorySink::default();
    let result = sim.run(&mut sink, &mut |_| {});
    let (run_wall, run_cpu) = (wall1.elapsed().as_secs_f64(), cpu_seconds() - cpu1);
    let mut hash = 0xcbf2_9ce4_8422_2325u64;
    for s in &sink.snapshots {
        fnv(&mut hash, s.t);
        let extra = s.extra.iter().flat_map(|(_, f)| f);
        for x in s.h.iter().chain(&s.u).chain(extra) {
            fnv(&mut hash, *x);
        }
    }
    for r in &sink.steps {
        for x in [r.t, r.dt, r.mass, r.kinetic_energy, r.max_speed, r.front_x] {
            fnv(&mut hash, x);
        }
    }
    let cells = sim.state.h.len();
    let updates = sim.state.tiles.updates();
    let steps = sim.steps as f64;
    // The wet cells of every step, from the summary's mean wet fraction.
    let wet = sink
        .summary
        .as_ref()
        .and_then(|s| s.wet)
        .map_or(f64::NAN, |w| {
            (w.mean_fraction * steps * w.flow_cells as f64).round()
        });
    let status = sink
        .summary
        .as_ref()
        .map_or("-".into(), |s| s.status.clone());
    println!(
        "{file} {}: {cells} cells, {} steps, {status} (ok {}), threads {threads}",
        if full { "full sweep" } else { "active tiles" },
        sim.steps,
        result.is_ok()
    );
    println!("set-up {setup_wall:.2} s wall, {setup_cpu:.2} s CPU; run {run_wall:.2} s wall, {run_cpu:.2} s CPU");
    println!(
        "cell updates: stepped {updates} (mean fraction {:.4}), wet {wet} (mean fraction {:.4})",
        updates as f64 / (steps * cells as f64),
        wet / (steps * cells as f64),
    );
    println!(
        "rates: {:.3e} stepped and {:.3e} wet cell updates per second of the run's wall time",
        updates as f64 / run_wall,
        wet / run_wall
    );
    println!("hash {hash:#018x}");
}
