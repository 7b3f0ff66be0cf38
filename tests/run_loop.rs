//! The generic run loop: stop rules decide how a run ends, and the sink is finished
//! whatever ends it (also an output error).

use std::path::Path;

use crate::common::Case;
use granflow::model::granular::Granular;
use granflow::output::{
    GridData, OutputError, OutputSink, RunInfo, RunSummary, SnapshotView, StepRecord,
};
use granflow::simulation::{RunError, Simulation};
use granflow::stop::{StepContext, StopRule, Verdict};

fn collapse() -> Simulation<Granular> {
    let mut case = Case::new(-0.2, 1.0, 120);
    case.mesh.slope_deg = 22.0;
    case.law = granflow::scenario::FrictionLaw::Coulomb { mu: 0.4 };
    case.t_end = 1.0;
    case.every = 0.1;
    case.build(|_| 0.0, |x, _| if x < 0.0 { 0.14 } else { 0.0 }, |_| 0.0)
}

/// Fails its `fail_at`-th snapshot; remembers whether it was finished, and with what.
#[derive(Default)]
struct FlakySink {
    snapshots: usize,
    fail_at: usize,
    finished: Option<String>,
}

impl OutputSink for FlakySink {
    fn begin(&mut self, _: &RunInfo, _: &GridData) -> Result<(), OutputError> {
        Ok(())
    }
    fn snapshot(&mut self, _: &SnapshotView) -> Result<(), OutputError> {
        self.snapshots += 1;
        if self.snapshots == self.fail_at {
            return Err(OutputError::Io {
                path: "flaky".into(),
                message: "disk full".into(),
            });
        }
        Ok(())
    }
    fn step(&mut self, _: &StepRecord) -> Result<(), OutputError> {
        Ok(())
    }
    fn finish(&mut self, summary: &RunSummary) -> Result<(), OutputError> {
        self.finished = Some(summary.status.clone());
        Ok(())
    }
}

#[test]
fn an_output_error_still_finishes_the_sink() {
    let mut sim = collapse();
    let mut sink = FlakySink {
        fail_at: 3,
        ..Default::default()
    };
    let err = sim.run(&mut sink, &mut |_| {}).unwrap_err();
    assert!(matches!(err, RunError::Output(_)), "{err}");
    let status = sink.finished.expect("finish was called");
    assert!(
        status.starts_with("failed: ") && status.contains("disk full"),
        "{status}"
    );
    assert_eq!(sink.snapshots, 3);
}

/// Ends the run after a number of steps with its own status.
struct StepBudget(u64);

impl StopRule for StepBudget {
    fn check(&mut self, ctx: &StepContext) -> Verdict {
        if ctx.steps >= self.0 {
            Verdict::Stop("step_budget")
        } else {
            Verdict::Continue
        }
    }
}

#[test]
fn a_stop_rule_ends_the_run_with_its_status() {
    let mut sim = collapse();
    sim.add_rule(Box::new(StepBudget(7)));
    let (sink, summary) = crate::common::run(&mut sim);
    assert_eq!(summary.status, "step_budget");
    assert_eq!(summary.steps, 7);
    assert_eq!(sink.steps.len(), 8, "t = 0 and seven steps");
    // The state at the stop is written as a snapshot.
    assert_eq!(sink.snapshots.last().unwrap().t, summary.t_end);
}

/// A run that fails its speed bound names the fastest cell by its x (the rule sees
/// only the largest speed).
#[test]
fn a_speed_bound_failure_names_the_fastest_cell() {
    let mut sim = collapse();
    sim.add_rule(Box::new(granflow::stop::SpeedBound { bound: 0.05 }));
    let mut sink = granflow::output::memory::MemorySink::default();
    let Err(RunError::Solver(failure)) = sim.run(&mut sink, &mut |_| {}) else {
        panic!("the run fails its speed bound");
    };
    let s = &sim.state;
    let speed = |i: usize| granflow::physics::shallow::velocity(s.h[i + 1], s.hu[i + 1]).abs();
    // The first cell of the largest speed.
    let fastest = (0..s.nx).fold(0, |m, i| if speed(i) > speed(m) { i } else { m });
    assert!(speed(fastest) > 0.05);
    let x = sim.grid.x[fastest];
    assert_eq!((failure.x, failure.y), (Some(x), None), "{failure}");
    let message = failure.to_string();
    assert!(message.contains(&format!("at x = {x} m")), "{message}");
}

/// How a scenario's run ends: its status, or its failure's text.
fn outcome_of(text: &str, sets: &[&str]) -> Result<String, String> {
    let sets: Vec<String> = sets.iter().map(|s| s.to_string()).collect();
    let scn = granflow::scenario::load_str(text, Path::new("."), &sets).unwrap();
    let mut sink = granflow::output::memory::MemorySink::default();
    let result = if scn.domain.plane.is_some() {
        granflow::setup::build_granular_2d(&scn, 1).run(&mut sink, &mut |_| {})
    } else {
        granflow::setup::build_granular(&scn).run(&mut sink, &mut |_| {})
    };
    match result {
        Ok(summary) => Ok(summary.status),
        Err(RunError::Solver(f)) => Err(f.to_string()),
        Err(e) => panic!("{e}"),
    }
}

/// Material flowing in through an outflow end (u < 0 at the east end) grows the mass;
/// an erodible bed is part of the initial mass and adds none, so the run fails the
/// mass check with one as without one, on a line and on a raster.
#[test]
fn an_erodible_bed_does_not_switch_the_mass_check_off() {
    let line = r#"[domain]
x_min = 0
x_max = 10
cells = 50
coordinates = "cartesian"

[rheology]
law = "coulomb"
mu_deg = 0

[initial]
h = 1.0
u = -1.0

[boundary]
right = "outflow"

[time]
t_end = 5
"#;
    let raster = line
        .replace("cells = 50", "y_min = 0\ny_max = 2\ncells = [50, 10]")
        .replace("right = \"outflow\"", "east = \"outflow\"");
    for text in [line.to_string(), raster] {
        for bed in ["0", "0.1"] {
            let set = format!("initial.erodible_bed={bed}");
            let failure = outcome_of(&text, &[&set]).unwrap_err();
            assert!(failure.contains("the mass grew"), "{bed}: {failure}");
        }
    }
}

/// Cells that are each finite but whose total overflows (a domain of 10³⁰⁸ m holding
/// 10⁴ m of material) fail the run naming the total, instead of ending `outflowed`.
#[test]
fn an_overflowing_total_mass_fails_the_run() {
    let text = r#"[domain]
x_min = 0
x_max = 1.7e308
cells = 10

[rheology]
law = "coulomb"
mu_deg = 30

[initial]
h = 1e4

[time]
t_end = 1
"#;
    let failure = outcome_of(text, &[]).unwrap_err();
    assert!(
        failure.contains("the total mass of the initial state overflows"),
        "{failure}"
    );
}

/// An end time of 10¹⁰ s is only an upper bound for a run that stops at rest: it must
/// not fail as a "collapsed" time step (the threshold was 10⁻¹⁰ × t_end = 1 s, above
/// the ordinary CFL step).
#[test]
fn a_huge_end_time_is_no_time_step_collapse() {
    let text = r#"[domain]
x_min = 0
x_max = 4
cells = 40
coordinates = "cartesian"

[rheology]
law = "coulomb"
mu_deg = 35

[initial]
h = "if(x < 1, 0.2, 0)"

[time]
t_end = 1e10
stop_at_rest = true

[output]
every = 1e6
"#;
    let status = outcome_of(text, &[]).unwrap();
    assert_eq!(status, "stopped_at_rest");
    // Without a rule that may end it, the same run would take 10¹² steps: refused
    // at its first step as such, not as a collapse.
    let failure = outcome_of(text, &["time.stop_at_rest=false"]).unwrap_err();
    assert!(
        failure.contains("more steps to reach time.t_end"),
        "{failure}"
    );
    assert!(!failure.contains("collapsed"), "{failure}");
}
