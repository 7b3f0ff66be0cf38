//! Command line of `granflow sweep` (clap), kept here so that `cli.rs` only names it.

use std::path::PathBuf;

use clap::{Args, Subcommand};

use super::expand::Shard;

/// `granflow sweep SWEEP.toml [options]` or `granflow sweep merge DIR`.
#[derive(Debug, Args)]
#[command(args_conflicts_with_subcommands = true, subcommand_negates_reqs = true)]
pub struct SweepArgs {
    #[command(subcommand)]
    pub command: Option<SweepCommand>,
    /// Sweep file (TOML, see docs/sweeps.md).
    #[arg(required = true, value_name = "SWEEP.toml")]
    pub sweep: Option<PathBuf>,
    /// Runs at once (default: the number of available cores). Each run is single-threaded.
    #[arg(long, short, value_name = "N", value_parser = clap::value_parser!(u32).range(1..))]
    pub jobs: Option<u32>,
    /// Output directory (default: the sweep file's `output`, else the sweep file's stem).
    #[arg(long, short, value_name = "DIR")]
    pub output: Option<PathBuf>,
    /// Re-run runs that are already done.
    #[arg(long)]
    pub force: bool,
    /// Run only the runs whose index is K modulo N (0 <= K < N), e.g. for a job array.
    #[arg(long, value_name = "K/N")]
    pub shard: Option<Shard>,
    /// Override a scenario key in every run, e.g. --set domain.cells=100 (repeatable).
    #[arg(long = "set", value_name = "KEY=VALUE")]
    pub set: Vec<String>,
    /// No progress display and no table.
    #[arg(long, short)]
    pub quiet: bool,
    /// When another sweep (or the same shard) writes into the output directory, wait
    /// for it instead of failing.
    #[arg(long)]
    pub wait: bool,
}

#[derive(Debug, Subcommand)]
pub enum SweepCommand {
    /// Rebuild DIR/summary.csv from the results of all shards of a sweep.
    Merge(MergeArgs),
}

#[derive(Debug, Args)]
pub struct MergeArgs {
    /// Output directory of the sweep (holding sweep-plan.toml).
    #[arg(value_name = "DIR")]
    pub dir: PathBuf,
    /// Do not print the table.
    #[arg(long, short)]
    pub quiet: bool,
}
