//! The integration tests, one crate with a module per area (linked once).
//!
//! Run one area with `cargo test --test main AREA::`, e.g.
//! `cargo test --test main analytic::`.

mod common;

mod analytic;
mod architecture;
mod avaframe;
mod cli;
mod conservation;
mod dilatant;
mod fuzz_scenario;
mod gauges;
mod gis;
mod gis_scenario;
mod hostile;
mod hostile_outputs;
mod multilayer;
mod newcomer;
mod nh_multilayer;
mod nonhydrostatic;
mod output_hdf5;
mod properties;
mod results;
mod robustness;
mod run_loop;
mod run_output;
mod run_report;
mod scenarios;
mod second_order;
mod second_order_2d;
mod submarine;
mod submarine_paper;
mod sweep;
mod terrain_2d;
mod terrain_2d_bed_normal;
mod terrain_2d_io;
mod terrain_2d_reference;
mod terrain_2d_tiles;
mod terrain_2d_zones;
mod water_nh;
mod well_balanced;
