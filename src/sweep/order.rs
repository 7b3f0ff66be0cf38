//! The order in which a sweep hands its runs to the workers: the expected-longest
//! first, so that with several jobs the longest run does not start last while the
//! other workers sit idle (longest-processing-time-first scheduling). Only the order
//! of execution changes: results, their names and the summary's row order do not.
//!
//! The expected cost of a run is its number of cell updates: cells × layers × the
//! CFL steps to t_end, the steps estimated from a speed of its initial state,
//!
//!   steps ≈ t_end · v / (CFL · Δx),   v = s₀ + g sin θ · √(h₀ / g),
//!
//! s₀ the signal speed of the initial state (the wave speed √(g h) plus |u|), h₀ its
//! largest thickness and θ the slope: v is the speed the thickest part of the mass
//! reaches along the slope after its free-fall time, a proxy for how fast (and, with
//! stop rules, how long) it flows. Non-hydrostatic runs count 3× for their pressure
//! solve (docs/performance.md). Runs that stop early on a rule are not foreseen; the
//! estimate only has to rank runs, and it ranks a sweep over slopes, cells, layers or
//! t_end in the order of their wall times.

use super::exec::Prepared;
use crate::scenario::Scenario;

const G: f64 = 9.81;

/// The expected cost of a run of `scn` (arbitrary units, comparable within a sweep).
pub fn expected_cost(scn: &Scenario) -> f64 {
    let sim = crate::setup::build(scn);
    let d = sim.diagnostics();
    let cells = sim.cells() as f64;
    let dx = (scn.domain.x_max - scn.domain.x_min) / cells;
    let sin = scn.domain.slope_deg.to_radians().sin().max(0.0);
    let h0 = d.h_max.max(0.0);
    let v = d.signal_speed.max(0.0) + G * sin * (h0 / G).sqrt();
    let steps = (scn.time.t_end * v / (scn.time.cfl * dx)).max(1.0);
    let info = sim.info();
    let pressure = if info.pressure == "nonhydrostatic" {
        3.0
    } else {
        1.0
    };
    let cost = steps * cells * info.layers.max(1) as f64 * pressure;
    if cost.is_finite() {
        cost
    } else {
        0.0
    }
}

/// `todo` (indices into `runs`) sorted by decreasing expected cost; ties keep their
/// sweep order.
pub fn longest_first(runs: &[&Prepared], todo: &[usize]) -> Vec<usize> {
    let mut keyed: Vec<(f64, usize)> = todo
        .iter()
        .map(|&slot| (expected_cost(&runs[slot].scenario), slot))
        .collect();
    keyed.sort_by(|a, b| b.0.total_cmp(&a.0));
    keyed.into_iter().map(|(_, slot)| slot).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;

    fn cost(sets: &[&str]) -> f64 {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/collapse.toml");
        let sets: Vec<String> = sets.iter().map(|s| s.to_string()).collect();
        expected_cost(&crate::scenario::load_file(&path, &sets).unwrap())
    }

    /// The slopes sweep (its wall times grow with the slope: 0.07 … 0.33 s) and the
    /// obvious factors rank in the order of their run times.
    #[test]
    fn costs_rank_runs_by_their_expected_work() {
        let slopes: Vec<f64> = [0.0, 9.78, 16.0, 19.0, 22.0]
            .iter()
            .map(|s| cost(&[&format!("domain.slope_deg={s}")]))
            .collect();
        assert!(slopes.windows(2).all(|w| w[0] < w[1]), "{slopes:?}");
        let base = cost(&[]);
        assert!(cost(&["domain.cells=1280"]) > 3.0 * base);
        assert!(cost(&["model.layers=4"]) > 3.0 * base);
        assert!(cost(&["time.t_end=20"]) > 1.5 * base);
        assert!(cost(&["model.pressure=\"nonhydrostatic\""]) > 2.0 * base);
    }
}
