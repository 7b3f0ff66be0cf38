//! The cost of handing a pass of tiles to the run's threads (docs/performance.md,
//! "Cost that follows the flow"): `Workers::tiles` over 53 tiles of a fixed busy-wait
//! each, passes separated by a serial gap (the run loop's work between two passes),
//! from a caller outside the pool (as the run loop was) and from a thread of the pool
//! (`Workers::install`, as the run loop is). Prints the wall time per pass and its
//! overhead over the ideal (gap + tiles × work / threads).
//!
//!   cargo run --release --example fork_join_cost -- 2 20 2
//!
//! Arguments: threads, serial gap (µs), work per tile (µs).
use granflow::numerics::workers::Workers;
use std::time::Instant;

fn busy(us: f64) {
    let t = Instant::now();
    while t.elapsed().as_secs_f64() < us * 1e-6 {
        std::hint::spin_loop();
    }
}

fn main() {
    let arg = |k: usize, default: f64| {
        std::env::args()
            .nth(k)
            .and_then(|a| a.parse().ok())
            .unwrap_or(default)
    };
    let (threads, gap, work) = (arg(1, 2.0) as usize, arg(2, 20.0), arg(3, 2.0));
    let workers = Workers::new(threads).expect("a pool");
    let tiles: Vec<u32> = (0..53).collect();
    let passes = 3000;
    let run = || {
        let start = Instant::now();
        for _ in 0..passes {
            workers.tiles(&tiles, |_, _| busy(work));
            busy(gap);
        }
        start.elapsed().as_secs_f64() / passes as f64 * 1e6
    };
    let ideal = gap + tiles.len() as f64 * work / threads as f64;
    let outside = run();
    let inside = workers.install(run);
    println!(
        "{threads} threads, gap {gap} µs, {work} µs per tile: per pass {outside:.1} µs from outside the pool \
         (overhead {:.1}), {inside:.1} µs from a thread of the pool (overhead {:.1})",
        outside - ideal,
        inside - ideal
    );
}
