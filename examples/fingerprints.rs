//! Fingerprints of every bundled scenario (and law/model variants), for refactors
//! that must keep results bit-for-bit: FNV-1a over every snapshot field and step
//! record of a run with t_end capped, for any model.
//!
//!   cargo run --release --example fingerprints -- 0.3 scenarios/*.toml > before.txt
use granflow::output::memory::MemorySink;
use std::path::Path;

fn fnv(h: &mut u64, v: f64) {
    for b in v.to_bits().to_le_bytes() {
        *h ^= b as u64;
        *h = h.wrapping_mul(0x100_0000_01b3);
    }
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let Some(cap) = args.first().and_then(|a| a.parse::<f64>().ok()) else {
        eprintln!("usage: fingerprints T_END_CAP SCENARIO.toml ... (e.g. 0.3 scenarios/*.toml)");
        std::process::exit(2);
    };
    let variants: &[&[&str]] = &[
        &[],
        &["rheology.law=\"coulomb\""],
        &["model.pressure=\"nonhydrostatic\""],
        &["model.layers=4"],
    ];
    for file in &args[1..] {
        for v in variants {
            let mut sets: Vec<String> = v.iter().map(|s| s.to_string()).collect();
            sets.push(format!("time.t_end={cap}"));
            let scn = match granflow::scenario::load_file(Path::new(file), &sets) {
                Ok(s) => s,
                Err(_) => continue,
            };
            let mut sim = granflow::setup::build(&scn);
            let mut sink = MemorySink::default();
            let res = sim.run(&mut sink, &mut |_| {});
            let mut h = 0xcbf2_9ce4_8422_2325u64;
            for s in &sink.snapshots {
                fnv(&mut h, s.t);
                for x in s.h.iter().chain(&s.u) {
                    fnv(&mut h, *x)
                }
                for x in s.w.iter().flatten().chain(s.p_nh.iter().flatten()) {
                    fnv(&mut h, *x)
                }
                for (_, f) in &s.extra {
                    for x in f {
                        fnv(&mut h, *x)
                    }
                }
            }
            for r in &sink.steps {
                for x in [r.t, r.dt, r.mass, r.kinetic_energy, r.max_speed, r.front_x] {
                    fnv(&mut h, x)
                }
            }
            let sum = sink.summary.as_ref().unwrap();
            println!(
                "{file} {:?}: steps {} status {} ok {} runout {:.12e} stop {:.12e} hash {:#018x}",
                v,
                sum.steps,
                sum.status.split(':').next().unwrap(),
                res.is_ok(),
                sum.runout,
                sum.stop_time,
                h
            );
        }
    }
}
