//! granflow: shallow-layer simulator for dry granular flows.
//!
//! Architecture (see `docs/architecture.md`): a validated [`scenario::Scenario`] names
//! a [`model::Model`]; [`setup`] builds its grid (the [`grid`] floor: a
//! [`grid::Line`] or a [`grid::CurvedLine`]), its state ([`state`]) and its
//! [`pipeline`] of sub-steps (hyperbolic → friction/viscous → projection, Garres-Díaz et al. 2021, §3
//! and Escalante et al. 2023, §4), which the generic [`simulation::Simulation`] advances in time,
//! consulting its [`stop`] rules and reporting to an [`output::OutputSink`].

pub mod catalog;
pub mod cli;
pub mod discover;
pub mod gauges;
pub mod gis;
pub mod grid;
pub mod interrupt;
pub mod lock;
pub mod model;
pub mod numerics;
pub mod output;
pub mod overwrite;
pub mod physics;
pub mod pipeline;
pub mod progress;
pub mod results;
pub mod runner;
pub mod scenario;
pub mod setup;
pub mod simulation;
pub mod state;
pub mod stop;
pub mod sweep;
pub mod terminal;
