//! Command-line interface (clap): `granflow run | check | sweep`.

use std::path::PathBuf;

use clap::{Args, Parser, Subcommand};

/// Exit code of a solver or output failure (a run, or a sweep or merge with failures).
pub const EXIT_FAILURE: u8 = 1;
/// Exit code for bad input: scenario, sweep file, options.
pub const EXIT_BAD_INPUT: u8 = 2;

#[derive(Debug, Parser)]
#[command(
    name = "granflow",
    version,
    about = "Shallow-layer simulator for dry granular flows (Savage–Hutter μ(I) family)",
    propagate_version = true
)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
}

#[derive(Debug, Subcommand)]
pub enum Command {
    /// Run a scenario: writes the HDF5 file and the front-position CSV.
    Run(RunArgs),
    /// Validate a scenario without running it.
    Check(ScenarioArgs),
    /// Run a parameter sweep in parallel (see docs/sweeps.md), or `sweep merge DIR`.
    Sweep(crate::sweep::SweepArgs),
}

#[derive(Debug, Args)]
pub struct ScenarioArgs {
    /// Scenario file (TOML, see docs/scenario-format.md).
    pub scenario: PathBuf,
    /// Override a scenario key, e.g. --set domain.slope_deg=16 (repeatable).
    #[arg(long = "set", value_name = "KEY=VALUE")]
    pub set: Vec<String>,
}

#[derive(Debug, Args)]
pub struct RunArgs {
    #[command(flatten)]
    pub scenario: ScenarioArgs,
    /// Output HDF5 file (overrides output.file).
    #[arg(long, short)]
    pub output: Option<PathBuf>,
    /// No progress bar and no summary.
    #[arg(long, short)]
    pub quiet: bool,
}
