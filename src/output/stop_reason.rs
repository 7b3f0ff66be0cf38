//! Why a run ended, in words: the reason the report's status line gives after the
//! status, and `/summary` `stop_reason` (docs/output-format.md). One text for both, so
//! the file says what the terminal said.
//!
//! A run ends at `time.t_end` (`completed`), when a stop rule ends it (`settled`: the
//! kinetic energy fell to `time.settle_fraction` × its peak, the practice of hazard
//! runs; `stopped_at_rest`, `outflowed`, `no_mass`), on Ctrl-C (`interrupted`) or when
//! the solver or the output fails (`failed: …`, whose reason is the failure's).

use super::RunSummary;

/// A speed at or below this (m/s) is rest to round-off: a lake at rest keeps speeds
/// of order 1e-15 m/s from the rounding of its fluxes.
pub const ROUND_OFF_SPEED: f64 = 1e-10;

/// Why the run of `s` ended (empty for an unknown status): the text after the status
/// in the report's first line, with the state of motion at the end when the status
/// does not say it.
pub fn stop_reason(s: &RunSummary) -> String {
    let fraction = fraction(s.settle_fraction);
    let motion = || -> String {
        if !s.stop_time.is_nan() {
            format!("at rest since t = {} s", sig(s.stop_time))
        } else if s.max_speed_final <= ROUND_OFF_SPEED {
            format!(
                "at rest to round-off (largest speed {} m/s)",
                sig(s.max_speed_final)
            )
        } else if !s.settled_time.is_nan() {
            format!(
                "settled since t = {} s (kinetic energy at most {fraction} × its peak, \
                 time.settle_fraction), largest speed {} m/s",
                sig(s.settled_time),
                sig(s.max_speed_final)
            )
        } else {
            format!(
                "still moving (largest speed {} m/s)",
                sig(s.max_speed_final)
            )
        }
    };
    match s.status.as_str() {
        "completed" => format!("reached time.t_end; {}", motion()),
        "stopped_at_rest" => {
            "every speed is zero (time.stop_at_rest ends the run at rest)".to_owned()
        }
        "settled" => format!(
            "the kinetic energy fell to {fraction} × its peak (time.settle_fraction, \
             time.stop_when_settled); largest speed {} m/s",
            sig(s.max_speed_final)
        ),
        "outflowed" => "all the mass left through an outflow boundary".to_owned(),
        "no_mass" => "the initial state holds no mass".to_owned(),
        "interrupted" => format!("stopped by Ctrl-C or SIGTERM; {}", motion()),
        failed if failed.starts_with("failed: ") => failed["failed: ".len()..].to_owned(),
        _ => String::new(),
    }
}

/// A settle fraction as written in a scenario: `0.01`, `1e-6` (NaN: `NaN`).
fn fraction(f: f64) -> String {
    if f.is_finite() && f != 0.0 && f.abs() < 1e-3 {
        format!("{f:e}")
    } else {
        format!("{f}")
    }
}

/// `v` with four significant digits: plain decimals between 1e-3 and 1e5, exponent
/// form outside (so t_end = 1e-5 s is not printed as 0.0000).
pub fn sig(v: f64) -> String {
    if !v.is_finite() {
        return format!("{v}");
    }
    if v == 0.0 {
        return "0".to_owned();
    }
    let a = v.abs();
    if (1e-3..1e5).contains(&a) {
        let decimals = (3 - a.log10().floor() as i32).max(0) as usize;
        format!("{v:.decimals$}")
    } else {
        format!("{v:.3e}")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fractions_read_as_in_a_scenario() {
        assert_eq!(fraction(0.01), "0.01");
        assert_eq!(fraction(1e-6), "1e-6");
        assert_eq!(fraction(0.05), "0.05");
    }
}
