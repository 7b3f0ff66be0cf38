//! What a run gathers over all its steps, beyond the per-step diagnostics: the maps of
//! a raster run (largest thickness and speed, arrival time, deposit) and the numbers
//! derived from them (area reached, runout, travel angle). The run loop hands a
//! [`Tracker`] every accepted state and, once before the sink is finished, lets it
//! write what it gathered ([`crate::output::RunMaps`]); with every snapshot it also
//! writes the maps as they stand, so that a run killed later keeps them.

use crate::output::{OutputError, OutputSink};

/// Gathers over a run; `observe` is called with the initial state and after every
/// accepted step, in the order of the step records.
pub trait Tracker<G, S>: Send {
    /// Takes the state at time `t` into account.
    fn observe(&mut self, grid: &G, state: &S, t: f64);
    /// Hands what was gathered to `sink` ([`OutputSink::maps`]); `state` is the final
    /// one (the last accepted state, as the run ended).
    fn write(&self, grid: &G, state: &S, sink: &mut dyn OutputSink) -> Result<(), OutputError>;
    /// The end-of-run numbers derived from what was gathered (`/summary` scalars such
    /// as `runout_length`), `state` being the final one. The default has none.
    fn scalars(&self, _grid: &G, _state: &S) -> Vec<(&'static str, f64)> {
        Vec::new()
    }
    /// Hands the maps as they stand to `sink` ([`OutputSink::maps_so_far`]); called
    /// with every snapshot, `state` being the snapshot's. The default writes nothing.
    fn write_so_far(
        &self,
        _grid: &G,
        _state: &S,
        _sink: &mut dyn OutputSink,
    ) -> Result<(), OutputError> {
        Ok(())
    }
}
