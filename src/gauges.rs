//! Gauges: time series of the free surface and the grain depth at fixed points, the
//! way tide gauges are recorded by tsunami codes (`output.gauges`, `output.gauge_every`).
//!
//! **In space**, a gauge at x between the cell centres x_i ≤ x ≤ x_{i+1} reads
//! v = (1 − w) v_i + w v_{i+1}, w = (x − x_i)/Δx, from the model's cell values
//! ([`Model::gauge_cell`]) with the cells and weights of [`Grid::locate`]; a gauge in
//! the outer half cell of the domain (x < x_0 or
//! x > x_{nx−1}) reads the boundary cell's value. So a gauge at a cell centre reads
//! exactly that cell, and the gauge series at a snapshot time is the snapshot's field
//! interpolated by [`interpolation`].
//!
//! **In time**, without `gauge_every` a record is taken at t = 0 and after every step.
//! With it, records are taken at t = k·gauge_every without touching the time step:
//! the values at t_k are interpolated linearly between the two steps around it
//! (t_n < t_k ≤ t_{n+1}), a t_k on a step end (to rounding, as for snapshots) takes
//! that step's values exactly; the last time of the run is recorded too when it is
//! not already.

use crate::grid::{Grid, Point, Stencil};
use crate::model::Model;
use crate::output::{GaugeRecord, OutputError, OutputSink};

pub use crate::grid::line::interpolate as interpolation;

/// The gauges of one run: positions, interpolation weights and the buffers of the
/// current and previous values (allocated once).
#[derive(Debug, Clone)]
pub struct Gauges {
    x: Vec<f64>,
    /// The y of each gauge on a raster, empty on a line.
    y: Vec<f64>,
    at: Vec<Stencil>,
    every: Option<f64>,
    /// Values after the current step: free surface, grain depth.
    eta: Vec<f64>,
    h: Vec<f64>,
    /// Values after the previous step, and its time (gauge_every only).
    prev_eta: Vec<f64>,
    prev_h: Vec<f64>,
    prev_t: f64,
    /// Scratch for time-interpolated rows.
    row_eta: Vec<f64>,
    row_h: Vec<f64>,
    /// Index k of the next record time k·gauge_every.
    next: u64,
    last_recorded: f64,
}

impl Gauges {
    /// Gauges at `x` (inside the grid; on a raster at the points (x, y), `y` empty on
    /// a line), recorded every step or every `every` seconds.
    pub fn new<G: Grid>(grid: &G, x: &[f64], y: &[f64], every: Option<f64>) -> Gauges {
        let n = x.len();
        Gauges {
            x: x.to_vec(),
            y: y.to_vec(),
            at: x
                .iter()
                .enumerate()
                .map(|(k, &x)| {
                    let y = y.get(k).copied().unwrap_or(0.0);
                    grid.locate(Point { x, y })
                })
                .collect(),
            every,
            eta: vec![0.0; n],
            h: vec![0.0; n],
            prev_eta: vec![0.0; n],
            prev_h: vec![0.0; n],
            prev_t: 0.0,
            row_eta: vec![0.0; n],
            row_h: vec![0.0; n],
            next: 0,
            last_recorded: f64::NEG_INFINITY,
        }
    }

    /// The positions (m).
    pub fn x(&self) -> &[f64] {
        &self.x
    }

    /// Reads the gauges of `state` into the current values; false if the model has no
    /// gauge values.
    fn read<M: Model>(&mut self, model: &M, grid: &M::Grid, state: &M::State) -> bool {
        std::mem::swap(&mut self.eta, &mut self.prev_eta);
        std::mem::swap(&mut self.h, &mut self.prev_h);
        for (k, stencil) in self.at.iter().enumerate() {
            let Some((eta, h)) = model.gauge_cell(grid, state, stencil.first()) else {
                return false;
            };
            if stencil.len() == 1 {
                (self.eta[k], self.h[k]) = (eta, h);
                continue;
            }
            // Σ w_k v_k, the first term from the values already read.
            let mut pairs = stencil.pairs();
            let (_, w0) = pairs.next().expect("a stencil has a cell");
            let (mut eta_sum, mut h_sum) = (w0 * eta, w0 * h);
            for (cell, w) in pairs {
                let (eta1, h1) = model
                    .gauge_cell(grid, state, cell)
                    .unwrap_or((f64::NAN, f64::NAN));
                eta_sum += w * eta1;
                h_sum += w * h1;
            }
            (self.eta[k], self.h[k]) = (eta_sum, h_sum);
        }
        true
    }

    /// Starts the series: announces the positions to `sink` and records t = 0.
    pub fn begin<M: Model>(
        &mut self,
        model: &M,
        grid: &M::Grid,
        state: &M::State,
        sink: &mut dyn OutputSink,
    ) -> Result<(), OutputError> {
        if !self.read(model, grid, state) {
            return Err(OutputError::Io {
                path: "output.gauges".into(),
                message: format!("the {} model records no gauges", model.kind()),
            });
        }
        sink.begin_gauges(&self.x)?;
        if !self.y.is_empty() {
            sink.gauges_y(&self.y)?;
        }
        self.prev_t = 0.0;
        self.next = 1;
        self.emit_current(0.0, sink)
    }

    fn emit_current(&mut self, t: f64, sink: &mut dyn OutputSink) -> Result<(), OutputError> {
        self.last_recorded = t;
        sink.gauges(&GaugeRecord {
            t,
            eta: &self.eta,
            h_grains: &self.h,
        })
    }

    /// Records what falls in the step that ended at `t`.
    pub fn after_step<M: Model>(
        &mut self,
        model: &M,
        grid: &M::Grid,
        state: &M::State,
        t: f64,
        sink: &mut dyn OutputSink,
    ) -> Result<(), OutputError> {
        self.read(model, grid, state);
        let Some(every) = self.every else {
            return self.emit_current(t, sink);
        };
        loop {
            let tk = self.next as f64 * every;
            if tk >= t * (1.0 - 1e-14) {
                if tk <= t * (1.0 + 1e-14) {
                    self.next += 1;
                    self.emit_current(tk, sink)?;
                }
                break;
            }
            let w = (tk - self.prev_t) / (t - self.prev_t);
            for k in 0..self.x.len() {
                self.row_eta[k] = (1.0 - w) * self.prev_eta[k] + w * self.eta[k];
                self.row_h[k] = (1.0 - w) * self.prev_h[k] + w * self.h[k];
            }
            self.next += 1;
            self.last_recorded = tk;
            sink.gauges(&GaugeRecord {
                t: tk,
                eta: &self.row_eta,
                h_grains: &self.row_h,
            })?;
        }
        self.prev_t = t;
        Ok(())
    }

    /// Records the last state of the run at `t` unless it was just recorded.
    pub fn end(&mut self, t: f64, sink: &mut dyn OutputSink) -> Result<(), OutputError> {
        if self.last_recorded < t * (1.0 - 1e-14) {
            self.emit_current(t, sink)?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::interpolation;

    #[test]
    fn weights_between_centres() {
        let x = [0.5, 1.5, 2.5, 3.5];
        assert_eq!(interpolation(&x, 1.0, 0.0), (0, 0.0));
        assert_eq!(interpolation(&x, 1.0, 0.5), (0, 0.0));
        assert_eq!(interpolation(&x, 1.0, 1.5), (1, 0.0));
        assert_eq!(interpolation(&x, 1.0, 1.75), (1, 0.25));
        assert_eq!(interpolation(&x, 1.0, 3.5), (3, 0.0));
        assert_eq!(interpolation(&x, 1.0, 4.0), (3, 0.0));
        // Centres with rounding: 0.1·(i + ½).
        let x: Vec<f64> = (0..100).map(|i| 0.1 * (i as f64 + 0.5)).collect();
        for (i, &xi) in x.iter().enumerate() {
            assert_eq!(interpolation(&x, 0.1, xi), (i, 0.0));
        }
    }
}
