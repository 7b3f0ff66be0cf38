//! The diagnostics of a raster model formed band by band (`Raster2d::bands`) on the
//! run's threads: each band's sums and extrema ([`BandSums`]), then their total added
//! in band order ([`combine`]), so that the numbers do not depend on the threads.

use crate::model::Diagnostics;

/// One band's part of the diagnostics (sums and extrema over its cells).
#[derive(Debug, Clone, Copy)]
pub(crate) struct BandSums {
    /// Σ h.
    pub mass: f64,
    /// Σ h |u|² (twice the kinetic energy per unit area).
    pub ke: f64,
    /// Σ of the discharges, whose finiteness stands for the state's.
    pub q_sum: f64,
    /// The largest speed, squared.
    pub max_speed2: f64,
    /// The largest signal speed of the CFL step.
    pub signal: f64,
    pub h_max: f64,
    /// The largest x of a cell that counts for the front (−∞: none).
    pub front: f64,
    /// Cells with h > H_DRY.
    pub wet: usize,
}

impl BandSums {
    /// The part of a band with no cell.
    pub fn empty() -> BandSums {
        BandSums {
            mass: 0.0,
            ke: 0.0,
            q_sum: 0.0,
            max_speed2: 0.0,
            signal: 0.0,
            h_max: 0.0,
            front: f64::NEG_INFINITY,
            wet: 0,
        }
    }
}

/// The diagnostics from the bands' parts `bands`, added in band order, on cells of
/// area `cell_area`; `non_finite` finds the first cell with a non-finite value, asked
/// only when the sums are not finite.
pub(crate) fn combine(
    bands: &[BandSums],
    cell_area: f64,
    non_finite: impl FnOnce() -> Option<usize>,
) -> Diagnostics {
    let mut total = BandSums::empty();
    for b in bands {
        total.mass += b.mass;
        total.ke += b.ke;
        total.q_sum += b.q_sum;
        total.max_speed2 = total.max_speed2.max(b.max_speed2);
        total.signal = total.signal.max(b.signal);
        total.h_max = total.h_max.max(b.h_max);
        total.front = total.front.max(b.front);
        total.wet += b.wet;
    }
    let non_finite_at = if (total.mass + total.q_sum).is_finite() {
        None
    } else {
        non_finite().or(Some(0))
    };
    Diagnostics {
        mass: total.mass * cell_area,
        kinetic_energy: 0.5 * total.ke * cell_area,
        max_speed: total.max_speed2.sqrt(),
        signal_speed: total.signal,
        front_x: if total.front.is_finite() {
            total.front
        } else {
            f64::NAN
        },
        h_max: total.h_max,
        non_finite_at,
        wet_cells: Some(total.wet),
    }
}
