//! granflow: shallow-layer simulator for dry granular flows.
//!
//! Architecture (see `docs/numerics.md`): a validated [`scenario::Scenario`] builds a
//! [`mesh::Mesh`], a layered [`state::State`] and a [`pipeline`] of sub-steps
//! (hyperbolic → friction/viscous → projection, seed 000 §3 and seed 003 §4) that
//! [`simulation::Simulation`] advances in time, reporting to an [`output::OutputSink`].

pub mod cli;
pub mod diagnostics;
pub mod mesh;
pub mod numerics;
pub mod output;
pub mod physics;
pub mod pipeline;
pub mod profiles;
pub mod runner;
pub mod scenario;
pub mod setup;
pub mod simulation;
pub mod state;
pub mod sweep;
