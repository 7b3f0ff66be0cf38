//! Stop rules: small checks the run loop consults after every step (the shape of
//! Oceananigans' stop criteria and callbacks). Each rule sees the step just taken and
//! answers "go on", "stop with this status" or "fail with this reason"; the loop
//! itself only advances time and writes output.
//!
//! The default rules ([`default_rules`]): a non-finite value (or a total mass or
//! kinetic energy that overflows) fails the run, a CFL step that collapses fails it,
//! and so does one that would need more than [`MAX_STEPS`] steps to reach t_end in a run
//! no early-stop rule can end, Ctrl-C ends it (`interrupted`), an empty domain ends it
//! (`no_mass`, `outflowed`), a speed beyond the run's physical bound or a mass that
//! grows fails it, with `time.stop_at_rest` a mass at rest ends it and with
//! `time.stop_when_settled` a mass whose kinetic energy has fallen to
//! `time.settle_fraction` of its peak ends it (`settled`).
//! The end time is the loop's own condition.

use crate::model::Diagnostics;

/// What a rule sees after a step.
#[derive(Debug, Clone, Copy)]
pub struct StepContext<'a> {
    pub t: f64,
    pub t_end: f64,
    pub steps: u64,
    /// Diagnostics of the state after the step.
    pub diagnostics: &'a Diagnostics,
    /// The CFL time step the next step would take (∞ if nothing moves).
    pub next_dt: f64,
    /// Position (m) of cell `i`, for messages.
    pub x: &'a [f64],
    /// The y (m) of cell `i` on a raster (empty on a line).
    pub y: &'a [f64],
    /// Whether the whole mass is at rest (every speed ≤ the model's rest speed).
    pub at_rest: bool,
    /// The mass of the initial state (the same measure as `diagnostics.mass`).
    pub mass0: f64,
}

/// Why the solver gave up: the reason, where and when.
#[derive(Debug, Clone, PartialEq)]
pub struct SolverFailure {
    pub reason: FailureReason,
    /// Position (m) of the offending cell, when there is one.
    pub x: Option<f64>,
    /// Its y (m) on a raster.
    pub y: Option<f64>,
    pub t: f64,
    pub step: u64,
}

#[derive(Debug, Clone, PartialEq)]
pub enum FailureReason {
    /// A NaN or infinity in the state (before the first step: in the initial state).
    NonFinite,
    /// Every cell is finite but a total over the domain (its mass or kinetic energy)
    /// overflows to infinity: no budget or stop rule can be judged on it.
    TotalOverflow { quantity: &'static str },
    /// The thickness would become negative even with the smallest retried Δt.
    NegativeThickness { h: f64, dt: f64 },
    /// The CFL step fell below [`collapse_threshold`].
    DtCollapse { dt: f64, max_speed: f64 },
    /// At the CFL step `dt` the time left to t_end would take more than [`MAX_STEPS`]
    /// steps, in a run that no early-stop rule can end.
    TooManySteps { dt: f64, steps: f64, t_end: f64 },
    /// A stage left the model's admissible states (e.g. a volume fraction outside (0, 1)).
    Inadmissible { quantity: &'static str, value: f64 },
    /// The largest speed exceeds the run's physical bound ([`SpeedBound`]).
    SpeedBound { speed: f64, bound: f64 },
    /// The mass grew although nothing can add any ([`MassGain`]).
    MassGain { mass: f64, mass0: f64 },
}

impl std::fmt::Display for SolverFailure {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let x = self.x.unwrap_or(f64::NAN);
        // The cell: x on a line, the point (x, y) on a raster.
        let at = match self.y {
            None => format!("x = {x} m"),
            Some(y) => format!("(x, y) = ({x}, {y}) m"),
        };
        let (t, step) = (self.t, self.step);
        match &self.reason {
            FailureReason::NonFinite if step == 0 => {
                write!(f, "non-finite initial state at {at}")
            }
            FailureReason::NonFinite => {
                write!(f, "non-finite value at {at}, t = {t:.6e} s (step {step})")
            }
            FailureReason::TotalOverflow { quantity } => {
                let when = if step == 0 {
                    "of the initial state".to_string()
                } else {
                    format!("at t = {t:.6e} s (step {step})")
                };
                write!(
                    f,
                    "the total {quantity} {when} overflows (every cell is finite, their sum \
                     over the domain is not): the domain is too large for its thicknesses \
                     and speeds, or the scheme blew up"
                )
            }
            FailureReason::NegativeThickness { h, dt } => write!(
                f,
                "thickness would become negative ({h:.3e} m) at {at}, t = {t:.6e} s even with Δt = {dt:.3e} s"
            ),
            FailureReason::DtCollapse { dt, max_speed } => write!(
                f,
                "time step collapsed to {dt:.3e} s at t = {t:.6e} s (step {step}, max speed {max_speed:.3e} m/s)"
            ),
            FailureReason::TooManySteps {
                dt,
                steps,
                t_end,
            } => write!(
                f,
                "at the CFL step {dt:.3e} s the run would take {steps:.1e} more steps to reach \
                 time.t_end = {t_end:e} s (more than {MAX_STEPS:e}) at t = {t:.6e} s (step \
                 {step}): shorten time.t_end, or let the run end itself with \
                 time.stop_at_rest or time.stop_when_settled"
            ),
            FailureReason::Inadmissible { quantity, value } => write!(
                f,
                "{quantity} = {value:e} is outside its admissible range at {at}, t = {t:.6e} s (step {step})"
            ),
            FailureReason::SpeedBound { speed, bound } => write!(
                f,
                "the largest speed {speed:.3e} m/s{} exceeds the physical bound {bound:.3e} m/s \
                 ({SPEED_BOUND_FACTOR} × the speed of free fall over the bed's relief and the \
                 initial thickness, from the initial speed) at t = {t:.6e} s (step {step}): \
                 the scheme is unstable for these parameters",
                if self.x.is_some() {
                    format!(", at {at},")
                } else {
                    String::new()
                }
            ),
            FailureReason::MassGain { mass, mass0 } => write!(
                f,
                "the mass grew from {mass0:.6e} to {mass:.6e} (+{:.3e} %) by t = {t:.6e} s \
                 (step {step}) although nothing adds mass: material entered the domain \
                 (through an outflow end) or the scheme created it",
                100.0 * (mass / mass0 - 1.0)
            ),
        }
    }
}

/// What a rule decides.
#[derive(Debug, Clone, PartialEq)]
pub enum Verdict {
    Continue,
    /// End the run normally with this status (e.g. "stopped_at_rest").
    Stop(&'static str),
    Fail(SolverFailure),
}

/// A check consulted after every step.
pub trait StopRule: Send {
    fn check(&mut self, ctx: &StepContext) -> Verdict;
}

/// A non-finite value anywhere fails the run at the step that produced it, and so
/// does a total (mass, kinetic energy) that overflows although every cell is finite:
/// an infinite mass would otherwise count as "outflowed" or "at rest".
#[derive(Debug, Default)]
pub struct NonFinite;

impl StopRule for NonFinite {
    fn check(&mut self, ctx: &StepContext) -> Verdict {
        let d = ctx.diagnostics;
        let (reason, cell) = match (d.non_finite_at, total_overflow(d)) {
            (Some(i), _) => (FailureReason::NonFinite, Some(i)),
            (None, Some(quantity)) => (FailureReason::TotalOverflow { quantity }, None),
            (None, None) => return Verdict::Continue,
        };
        Verdict::Fail(SolverFailure {
            reason,
            x: cell.and_then(|i| ctx.x.get(i).copied()),
            y: cell.and_then(|i| ctx.y.get(i).copied()),
            t: ctx.t,
            step: ctx.steps,
        })
    }
}

/// The total of `d` that is not finite (mass first), if any.
pub fn total_overflow(d: &Diagnostics) -> Option<&'static str> {
    if !d.mass.is_finite() {
        Some("mass")
    } else if !d.kinetic_energy.is_finite() {
        Some("kinetic energy")
    } else {
        None
    }
}

/// A CFL step below this fraction of t_end (of [`COLLAPSE_REFERENCE_MAX`] for longer
/// runs) stops the run as a solver failure.
pub const MIN_DT_FRACTION: f64 = 1e-10;

/// The longest time (s) the collapse threshold is taken from: with t_end = 10¹⁰ s a
/// threshold of 10⁻¹⁰ t_end would be 1 s, above the ordinary CFL step of most runs. A
/// step below 10⁻¹⁰ of this (10⁻⁶ s) on a run of hours would take more than 10¹⁰
/// steps, so the capped threshold still catches every collapse that matters.
pub const COLLAPSE_REFERENCE_MAX: f64 = 1e4;

/// The Δt below which a run of end time `t_end` counts as collapsed.
pub fn collapse_threshold(t_end: f64) -> f64 {
    MIN_DT_FRACTION * t_end.min(COLLAPSE_REFERENCE_MAX)
}

/// A finite but absurd state (e.g. u = 1e154 m/s) would crawl on with Δt near zero,
/// filling memory with step records: fail it instead.
#[derive(Debug, Default)]
pub struct DtCollapse;

impl StopRule for DtCollapse {
    fn check(&mut self, ctx: &StepContext) -> Verdict {
        if ctx.next_dt >= collapse_threshold(ctx.t_end) {
            return Verdict::Continue;
        }
        Verdict::Fail(SolverFailure {
            reason: FailureReason::DtCollapse {
                dt: ctx.next_dt,
                max_speed: ctx.diagnostics.max_speed,
            },
            x: None,
            y: None,
            t: ctx.t,
            step: ctx.steps,
        })
    }
}

/// Most steps a run may still need at its current CFL step: a run of t_end = 10⁹ s at
/// Δt = 2·10⁻³ s (5·10¹¹ steps) would crawl on for years, filling the disk with step
/// records.
pub const MAX_STEPS: f64 = 1e10;

/// Fails a run whose remaining time would take more than [`MAX_STEPS`] steps at its
/// CFL step. Only in runs without `time.stop_at_rest` or `time.stop_when_settled`: a
/// run that may end itself (t_end is then only an upper bound) is never judged on a
/// forecast.
#[derive(Debug, Default)]
pub struct StepBudget;

impl StopRule for StepBudget {
    fn check(&mut self, ctx: &StepContext) -> Verdict {
        let steps = (ctx.t_end - ctx.t) / ctx.next_dt;
        if steps.is_nan() || steps <= MAX_STEPS {
            return Verdict::Continue;
        }
        Verdict::Fail(SolverFailure {
            reason: FailureReason::TooManySteps {
                dt: ctx.next_dt,
                steps,
                t_end: ctx.t_end,
            },
            x: None,
            y: None,
            t: ctx.t,
            step: ctx.steps,
        })
    }
}

/// Ends the run once the whole mass is at rest (`time.stop_at_rest`).
#[derive(Debug, Default)]
pub struct AtRest;

impl StopRule for AtRest {
    fn check(&mut self, ctx: &StepContext) -> Verdict {
        if ctx.at_rest {
            Verdict::Stop("stopped_at_rest")
        } else {
            Verdict::Continue
        }
    }
}

/// Fraction of the initial mass below which the domain counts as emptied: the dry-cell
/// film a shallow-water scheme leaves behind a departing mass (1e-10 m here and there)
/// is not a deposit.
pub const OUTFLOWED_FRACTION: f64 = 1e-6;

/// Ends a run with nothing left to simulate: `no_mass` when there was none to begin
/// with, `outflowed` when all of it (but [`OUTFLOWED_FRACTION`]) has left through an
/// outflow boundary. (Such runs
/// used to end "stopped_at_rest" with a NaN runout: an empty domain is at rest.)
/// Consulted before [`AtRest`], whose status it replaces.
#[derive(Debug, Default)]
pub struct MassGone;

impl StopRule for MassGone {
    fn check(&mut self, ctx: &StepContext) -> Verdict {
        let mass = ctx.diagnostics.mass;
        // An overflowing total is the NonFinite rule's failure, never an empty domain.
        if !(mass.is_finite() && ctx.mass0.is_finite()) {
            Verdict::Continue
        } else if ctx.mass0 <= 0.0 {
            Verdict::Stop("no_mass")
        } else if mass <= OUTFLOWED_FRACTION * ctx.mass0 {
            Verdict::Stop("outflowed")
        } else {
            Verdict::Continue
        }
    }
}

/// The speed bound of a run is this factor × √(u₀² + w₀² + 2 g (Δz + h₀)): the speed
/// of free fall over the bed's relief Δz (of the potential elevation z, the plane's
/// drop included in local coordinates) and the largest initial thickness h₀ (water
/// depth included), starting at the largest initial speed. Energy conservation bounds
/// a particle's speed by the free-fall one; pressure gradients drive the front of a
/// dam break to 2√(g h₀), √2 times it, so the factor leaves a wide margin for fronts
/// and thin cells while catching a blow-up (speeds of 1e4–1e8 m/s) in its first steps.
pub const SPEED_BOUND_FACTOR: f64 = 10.0;

/// Fails a run whose largest speed exceeds its physical bound (∞: no bound), the sign
/// of an unstable scheme that has not yet produced a NaN.
#[derive(Debug)]
pub struct SpeedBound {
    pub bound: f64,
}

impl StopRule for SpeedBound {
    fn check(&mut self, ctx: &StepContext) -> Verdict {
        let speed = ctx.diagnostics.max_speed;
        if speed <= self.bound {
            return Verdict::Continue;
        }
        Verdict::Fail(SolverFailure {
            reason: FailureReason::SpeedBound {
                speed,
                bound: self.bound,
            },
            x: None,
            y: None,
            t: ctx.t,
            step: ctx.steps,
        })
    }
}

/// Relative growth of the mass above which a run without mass sources fails. The
/// hydrostatic schemes conserve mass to round-off; the multilayer non-hydrostatic
/// scheme's wet/dry treatment gains up to about 1e-6 of it (measured on
/// `nh_multilayer_convergence.toml` and a mass below its repose slope); outflow ends
/// only remove mass. A tenth of a percent is far above both and far below an inflow
/// through an outflow end (a 7.6e4-fold growth in the unstable submarine run).
pub const MASS_GAIN_TOLERANCE: f64 = 1e-3;

/// Fails a run whose mass grows by more than [`MASS_GAIN_TOLERANCE`] of the initial
/// mass: the mass budget initial − outflowed = current has outflowed ≥ 0, so a gain
/// means material entered through an outflow end (the ghost state of an unstable run)
/// or the scheme created it. An erodible bed adds nothing to this measure: its grains
/// are part of the initial thickness (h = initial.h + h_i) and the friction law only
/// sets them moving, so the rule holds for every run.
#[derive(Debug, Default)]
pub struct MassGain;

impl StopRule for MassGain {
    fn check(&mut self, ctx: &StepContext) -> Verdict {
        let (mass, mass0) = (ctx.diagnostics.mass, ctx.mass0);
        if mass0.is_nan() || mass0 <= 0.0 || mass <= mass0 * (1.0 + MASS_GAIN_TOLERANCE) {
            return Verdict::Continue;
        }
        Verdict::Fail(SolverFailure {
            reason: FailureReason::MassGain { mass, mass0 },
            x: None,
            y: None,
            t: ctx.t,
            step: ctx.steps,
        })
    }
}

/// Ends the run after Ctrl-C or SIGTERM (see [`crate::interrupt`]).
#[derive(Debug, Default)]
pub struct Interrupted;

impl StopRule for Interrupted {
    fn check(&mut self, _ctx: &StepContext) -> Verdict {
        if crate::interrupt::requested() {
            Verdict::Stop("interrupted")
        } else {
            Verdict::Continue
        }
    }
}

/// Whether a kinetic energy `ke` counts as settled for the peak `peak` so far:
/// `ke` ≤ `fraction` × `peak` (a mass that never moved, ke = peak = 0, is settled).
#[inline]
pub fn settled(ke: f64, peak: f64, fraction: f64) -> bool {
    ke <= fraction * peak
}

/// Ends the run with status `settled` once the kinetic energy has fallen to
/// `time.settle_fraction` × its peak (`time.stop_when_settled`). For μ(I), whose
/// friction tends to μ_s as the speed vanishes, a released mass creeps long after it
/// has practically stopped (Bouchut et al. 2021, §4: 40 s to stop fully at 22°, under 1 mm/s from
/// 19 s), and the exact-rest time grows without bound under refinement
/// (docs/validation.md "Stop time and runout under refinement"); the settled time
/// converges. Consulted after [`AtRest`], whose status wins on the same step.
#[derive(Debug)]
pub struct Settled {
    fraction: f64,
    peak: f64,
}

impl Settled {
    pub fn new(fraction: f64) -> Settled {
        Settled {
            fraction,
            peak: 0.0,
        }
    }
}

impl StopRule for Settled {
    fn check(&mut self, ctx: &StepContext) -> Verdict {
        let ke = ctx.diagnostics.kinetic_energy;
        self.peak = self.peak.max(ke);
        if settled(ke, self.peak, self.fraction) {
            Verdict::Stop("settled")
        } else {
            Verdict::Continue
        }
    }
}

/// The optional rules of a run, as plain values (setup reads them from the scenario's
/// `[time]`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StopOptions {
    /// End the run (status `stopped_at_rest`) once the whole mass is at rest.
    pub at_rest: bool,
    /// End the run (status `settled`) once the kinetic energy is at or below this
    /// fraction of its peak.
    pub settled_fraction: Option<f64>,
    /// Fail the run once a speed exceeds this bound (m/s; ∞: never), [`SpeedBound`].
    pub speed_bound: f64,
}

/// The rules every run consults, in order.
pub fn default_rules(options: StopOptions) -> Vec<Box<dyn StopRule>> {
    let mut rules: Vec<Box<dyn StopRule>> = vec![
        Box::new(NonFinite),
        Box::new(DtCollapse),
        Box::new(SpeedBound {
            bound: options.speed_bound,
        }),
        Box::new(MassGain),
        Box::new(Interrupted),
        Box::new(MassGone),
    ];
    if !options.at_rest && options.settled_fraction.is_none() {
        rules.insert(2, Box::new(StepBudget));
    }
    if options.at_rest {
        rules.push(Box::new(AtRest));
    }
    if let Some(fraction) = options.settled_fraction {
        rules.push(Box::new(Settled::new(fraction)));
    }
    rules
}

#[cfg(test)]
mod tests {
    use super::*;

    fn verdicts(rule: &mut dyn StopRule, energies: &[f64]) -> Vec<Verdict> {
        energies
            .iter()
            .enumerate()
            .map(|(k, &ke)| {
                let d = Diagnostics {
                    mass: 1.0,
                    kinetic_energy: ke,
                    max_speed: ke.sqrt(),
                    signal_speed: 1.0,
                    front_x: 0.0,
                    h_max: 1.0,
                    non_finite_at: None,
                    wet_cells: None,
                };
                rule.check(&StepContext {
                    t: k as f64,
                    t_end: 100.0,
                    steps: k as u64,
                    diagnostics: &d,
                    next_dt: 1.0,
                    x: &[0.0],
                    y: &[],
                    at_rest: false,
                    mass0: 1.0,
                })
            })
            .collect()
    }

    /// The non-finite rule's failure for cell 1 of a grid with centres `x` and `y`.
    fn non_finite(x: &[f64], y: &[f64]) -> String {
        let d = Diagnostics {
            mass: f64::NAN,
            kinetic_energy: 0.0,
            max_speed: 0.0,
            signal_speed: 1.0,
            front_x: 0.0,
            h_max: 1.0,
            non_finite_at: Some(1),
            wet_cells: None,
        };
        let ctx = StepContext {
            t: 0.5,
            t_end: 1.0,
            steps: 7,
            diagnostics: &d,
            next_dt: 1.0,
            x,
            y,
            at_rest: false,
            mass0: 1.0,
        };
        match NonFinite.check(&ctx) {
            Verdict::Fail(failure) => failure.to_string(),
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn failures_name_the_cell_by_x_on_a_line_and_by_x_and_y_on_a_raster() {
        let line = non_finite(&[0.5, 1.5], &[]);
        assert!(line.contains("at x = 1.5 m, t = "), "{line}");
        let raster = non_finite(&[0.5, 1.5], &[-2.25, -2.25]);
        assert!(
            raster.contains("at (x, y) = (1.5, -2.25) m, t = "),
            "{raster}"
        );
        let failure = SolverFailure {
            reason: FailureReason::NegativeThickness { h: -1.0, dt: 0.1 },
            x: Some(3.0),
            y: Some(4.0),
            t: 1.0,
            step: 2,
        };
        assert!(
            failure.to_string().contains("at (x, y) = (3, 4) m"),
            "{failure}"
        );
    }

    #[test]
    fn settled_rule_stops_once_the_energy_falls_to_the_fraction_of_its_peak() {
        let mut rule = Settled::new(1e-3);
        let v = verdicts(&mut rule, &[1.0, 4.0, 1e-2, 4.1e-3, 4e-3, 1e-9]);
        // Growth and decay above 1e-3 × peak (4e-3) go on; 4e-3 itself is settled.
        assert_eq!(v[..4], vec![Verdict::Continue; 4][..]);
        assert_eq!(v[4], Verdict::Stop("settled"));
        assert_eq!(v[5], Verdict::Stop("settled"));
        // The peak is the running one: a slow start is not "settled".
        let mut rule = Settled::new(1e-3);
        let v = verdicts(&mut rule, &[1e-12, 1e-6, 1.0]);
        assert!(v.iter().all(|v| *v == Verdict::Continue), "{v:?}");
        assert!(settled(0.0, 0.0, 1e-6) && !settled(1e-9, 0.0, 1e-6));
    }

    /// The context of one step with these diagnostics and Δt.
    fn judge(
        rule: &mut dyn StopRule,
        d: &Diagnostics,
        t_end: f64,
        next_dt: f64,
        mass0: f64,
    ) -> Verdict {
        rule.check(&StepContext {
            t: 1.0,
            t_end,
            steps: 1,
            diagnostics: d,
            next_dt,
            x: &[0.0],
            y: &[],
            at_rest: false,
            mass0,
        })
    }

    fn diagnostics(mass: f64, kinetic_energy: f64) -> Diagnostics {
        Diagnostics {
            mass,
            kinetic_energy,
            max_speed: 1.0,
            signal_speed: 1.0,
            front_x: 0.0,
            h_max: 1.0,
            non_finite_at: None,
            wet_cells: None,
        }
    }

    #[test]
    fn the_collapse_threshold_is_capped_for_huge_end_times() {
        let d = diagnostics(1.0, 1.0);
        let fails = |t_end: f64, dt: f64| {
            matches!(judge(&mut DtCollapse, &d, t_end, dt, 1.0), Verdict::Fail(_))
        };
        assert!(fails(1.0, 0.9e-10) && !fails(1.0, 1e-10));
        // t_end = 1e10: an ordinary step of 0.5 s is no collapse (it was below 1 s).
        assert!(!fails(1e10, 0.5));
        assert!(fails(1e10, 0.9e-6) && !fails(1e10, 1e-6));
    }

    #[test]
    fn a_run_that_cannot_end_itself_is_refused_beyond_its_step_budget() {
        let d = diagnostics(1.0, 1.0);
        let v = judge(&mut StepBudget, &d, 1e9, 2e-3, 1.0);
        let Verdict::Fail(f) = v else { panic!("{v:?}") };
        assert!(f.to_string().contains("5.0e11 more steps"), "{f}");
        assert_eq!(
            judge(&mut StepBudget, &d, 10.0, 2e-3, 1.0),
            Verdict::Continue
        );
        assert_eq!(
            judge(&mut StepBudget, &d, 1e9, f64::INFINITY, 1.0),
            Verdict::Continue
        );
        // Only in runs without an early-stop rule.
        let mut options = StopOptions {
            at_rest: false,
            settled_fraction: None,
            speed_bound: f64::INFINITY,
        };
        let budget = |o: StopOptions| {
            default_rules(o)
                .iter_mut()
                .any(|r| matches!(judge(r.as_mut(), &d, 1e9, 2e-3, 1.0), Verdict::Fail(ref f) if matches!(f.reason, FailureReason::TooManySteps { .. })))
        };
        assert!(budget(options));
        options.at_rest = true;
        assert!(!budget(options));
        options.at_rest = false;
        options.settled_fraction = Some(1e-3);
        assert!(!budget(options));
    }

    #[test]
    fn an_overflowing_total_fails_and_is_never_outflowed() {
        for (mass, ke, name) in [
            (f64::INFINITY, 1.0, "mass"),
            (1.0, f64::INFINITY, "kinetic energy"),
        ] {
            let d = diagnostics(mass, ke);
            let v = judge(&mut NonFinite, &d, 1.0, 1.0, 1.0);
            let Verdict::Fail(f) = v else { panic!("{v:?}") };
            assert!(
                f.to_string().contains(&format!("the total {name} at t")),
                "{f}"
            );
        }
        let d = diagnostics(f64::INFINITY, 1.0);
        assert_eq!(
            judge(&mut MassGone, &d, 1.0, 1.0, f64::INFINITY),
            Verdict::Continue
        );
    }

    #[test]
    fn settled_rule_is_only_in_the_rules_when_asked_for() {
        // With stop_at_rest, so that the step budget is out of the rules either way.
        let mut options = StopOptions {
            at_rest: true,
            settled_fraction: None,
            speed_bound: f64::INFINITY,
        };
        let n = default_rules(options).len();
        options.settled_fraction = Some(1e-6);
        assert_eq!(default_rules(options).len(), n + 1);
    }
}
