//! Command-line interface (clap): `granflow run | check | sweep | scenarios | init |
//! export | maps | completions`.

use std::path::PathBuf;

use clap::{Args, Parser, Subcommand, ValueEnum};

/// Shown by `granflow --help` (not `-h`): the first hour of a new user.
const LONG_ABOUT: &str = "\
Shallow-layer simulator for dry granular flows (Savage–Hutter μ(I) family), in two
settings:

- along a 1-D slope profile: column collapses, avalanches and landslides on rigid or
  erodible beds, with five model families: the Savage–Hutter monolayer (Coulomb or
  μ(I) friction), the multilayer μ(I) model, the weakly non-hydrostatic model
  (monolayer or multilayer), the two-layer submarine-avalanche model (water over
  grains, and the waves it raises) and the compressible μ(I)–φ model with dilatancy;
- in 2-D over terrain: the Savage–Hutter monolayer (Coulomb, Voellmy or μ(I)) on a
  DEM (GeoTIFF or ESRI ASCII grid), released from polygons (shapefile or GeoJSON),
  with the hazard maps of the run (peak flow thickness pft, peak flow velocity pfv,
  peak pressure ppr, deposit, arrival time), its runout along the flow and travel
  angle, exported to GeoTIFF, ESRI ASCII or NetCDF for a GIS.

One TOML file per scenario; results in HDF5 (plus a CSV of the front position).";

const AFTER_LONG_HELP: &str = "\
Getting started:
  granflow scenarios                      list the bundled paper cases
  granflow init my_flow                   write my_flow.toml, a commented starter
  granflow init my_collapse --from collapse
  granflow run my_flow.toml               writes my_flow.h5 and my_flow_front.csv
  granflow run my_flow.toml --set domain.slope_deg=16 --output out/s16.h5
  granflow check my_flow.toml             validate without running
  granflow sweep slopes.toml --jobs 2     parameter sweep (docs/sweeps.md)
  granflow init dem --from dem_release    a 2-D run on a DEM from a release polygon
                                          (then: granflow run dem.toml)
  granflow export my_2d_run.h5            pft, pfv, ppr, … as GeoTIFF (docs/gis.md)
  granflow maps my_sweep/                 probability maps of a sweep (docs/gis.md)

Exit codes: 0 success, 1 solver or output failure (partial results are kept),
2 bad input (the message names the key and its line).

Shell completion: granflow completions bash > ~/.local/share/bash-completion/completions/granflow
(zsh, fish, elvish and powershell too; see `granflow completions --help`).
Documentation: README.md and docs/ in the source repository.";

#[derive(Debug, Parser)]
#[command(
    name = "granflow",
    version,
    about = "Shallow-layer simulator for dry granular flows (Savage–Hutter μ(I) family)",
    long_about = LONG_ABOUT,
    after_long_help = AFTER_LONG_HELP,
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
    /// List the scenarios bundled in this binary, with one line on each.
    Scenarios(ScenariosArgs),
    /// Write a commented starter scenario, or a copy of a bundled one (--from).
    Init(InitArgs),
    /// Export a raster run's maps (pft, pfv, ppr, deposit, arrival time) or a snapshot
    /// as GeoTIFF, ESRI ASCII grids or CF NetCDF (docs/gis.md).
    Export(crate::results::ExportArgs),
    /// Maps of a sweep's ensemble: P(pft > threshold), mean and max pft and pfv, and
    /// each run's skill against an observed footprint (docs/gis.md).
    Maps(crate::results::MapsArgs),
    /// Print a shell completion script to stdout.
    #[command(long_about = "Print a shell completion script to stdout.\n\n\
                      bash:  granflow completions bash > ~/.local/share/bash-completion/completions/granflow\n\
                      zsh:   granflow completions zsh > ~/.zfunc/_granflow   (with fpath+=~/.zfunc in ~/.zshrc)\n\
                      fish:  granflow completions fish > ~/.config/fish/completions/granflow.fish")]
    Completions(CompletionsArgs),
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
    /// No progress display and no summary.
    #[arg(long, short)]
    pub quiet: bool,
    /// Progress display on stderr: a bar on a terminal, else a line every
    /// --progress-every seconds (auto); or force one of them, or none.
    #[arg(long, value_enum, default_value_t = ProgressMode::Auto, value_name = "MODE")]
    pub progress: ProgressMode,
    /// Seconds between two progress lines (--progress lines, or auto in a pipe); 0 for
    /// a line after every step, at most 1e6.
    #[arg(long, default_value_t = 10.0, value_name = "SECONDS", value_parser = progress_interval)]
    pub progress_every: f64,
    /// Replace the output files even when they are not granflow outputs (or are the
    /// scenario itself).
    #[arg(long)]
    pub force: bool,
    /// When another granflow process writes the same output file, wait for it instead
    /// of failing.
    #[arg(long)]
    pub wait: bool,
    /// Threads of a raster (2-D) run; default, and at most: the threads the machine
    /// runs at once. The results are the same bits whatever the count. 1-D runs use
    /// one thread.
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u16).range(1..))]
    pub threads: Option<u16>,
}

/// The default of `--threads`: the machine's cores.
pub fn default_threads() -> usize {
    std::thread::available_parallelism().map_or(1, usize::from)
}

/// The threads a run uses for `--threads asked` on a machine that runs `available`
/// threads at once: more would only slow the run down (each step waits for every
/// thread) and delay a Ctrl-C while the pool starts, so the count is bounded, with a
/// note saying so.
pub fn bounded_threads(asked: Option<u16>, available: usize) -> (usize, Option<String>) {
    let available = available.max(1);
    match asked.map(usize::from) {
        None => (available, None),
        Some(n) if n <= available => (n, None),
        Some(n) => (
            available,
            Some(format!(
                "note: --threads {n} is more than the {available} threads this machine runs at once; using {available}"
            )),
        ),
    }
}

/// The largest `--progress-every` (s): about 11.6 days, beyond any run that shows
/// progress; `--progress none` shows none.
const PROGRESS_EVERY_MAX: f64 = 1e6;

/// Parses `--progress-every`: a finite number of seconds in [0, 1e6].
fn progress_interval(text: &str) -> Result<f64, String> {
    let v: f64 = text
        .trim()
        .parse()
        .map_err(|_| "not a number of seconds".to_owned())?;
    if !(0.0..=PROGRESS_EVERY_MAX).contains(&v) {
        return Err(format!(
            "must be between 0 (a line after every step) and {PROGRESS_EVERY_MAX} seconds; --progress none shows no progress"
        ));
    }
    Ok(v)
}

/// How `granflow run` shows its progress.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum ProgressMode {
    /// A bar when stderr is a terminal, lines otherwise.
    Auto,
    Bar,
    Lines,
    None,
}

#[derive(Debug, Args)]
pub struct ScenariosArgs {
    /// Print this bundled scenario's TOML instead of the list.
    #[arg(long, value_name = "NAME")]
    pub show: Option<String>,
}

#[derive(Debug, Args)]
pub struct InitArgs {
    /// Scenario to write: NAME.toml (or NAME itself if it ends in .toml).
    #[arg(value_name = "NAME")]
    pub name: PathBuf,
    /// Start from this bundled scenario (see `granflow scenarios`); its CSV tables are
    /// written under data/ next to it.
    #[arg(long, value_name = "SCENARIO")]
    pub from: Option<String>,
    /// Overwrite existing files.
    #[arg(long)]
    pub force: bool,
}

#[derive(Debug, Args)]
pub struct CompletionsArgs {
    /// The shell to complete for.
    #[arg(value_enum)]
    pub shell: clap_complete::Shell,
}
