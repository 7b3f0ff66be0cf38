//! The generic run loop: stop rules decide how a run ends, and the sink is finished
//! whatever ends it (also an output error).

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
