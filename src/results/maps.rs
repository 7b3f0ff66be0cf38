//! `granflow maps SWEEP_DIR [--threshold H] [--observed FILE]`: the maps of a sweep's
//! ensemble of raster runs ([`super::ensemble`]) as rasters with the runs'
//! georeferencing, one row per run in `runs.csv` and, against an observed
//! footprint, each run's skill and rank ([`super::skill`]).
//!
//! The runs are those of `SWEEP_DIR/sweep-plan.toml` that are done (the sweep's own
//! rule, `docs/sweeps.md`: a result file with an ok status whose HDF5 file agrees); a
//! sweep with runs not done is refused unless `--partial`. Every run must be on the
//! same grid. Written into `SWEEP_DIR/maps` (or `--output`): `pft_probability`,
//! `pft_mean`, `pft_max`, `pfv_mean`, `pfv_max` (`.tif` or `.asc`), `runs.csv` and
//! `ensemble.toml` (the threshold, the runs used, the observed file).

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use super::args::MapsArgs;
use super::ensemble::Ensemble;
use super::publish::{Owner, Publish};
use super::run_file::{north_up, RunFile};
use super::skill::{skill, Skill};
use super::{write_raster, ResultsError};
use crate::gis::release::{self, CoverageRule, ThicknessSource};
use crate::gis::{asc, geotiff, Raster};
use crate::sweep::naming::format_float;
use crate::sweep::plan::Plan;
use crate::sweep::record;
use crate::sweep::summary::csv_field;

/// One run of the ensemble.
#[derive(Debug, Clone)]
pub struct RunRow {
    pub index: usize,
    pub name: String,
    pub values: Vec<String>,
    /// Area where pft exceeds the threshold (map units squared).
    pub area: f64,
    /// Against the observed footprint, when given.
    pub skill: Option<Skill>,
    /// 1 = closest to the perfect ROC point.
    pub rank: Option<usize>,
}

/// What `granflow maps` did.
#[derive(Debug, Clone)]
pub struct MapsReport {
    pub dir: PathBuf,
    pub threshold: f64,
    pub runs: Vec<RunRow>,
    /// Runs of the sweep left out (not done), with `--partial`.
    pub left_out: Vec<String>,
    pub files: Vec<PathBuf>,
    /// Areas where P(pft > h*) > 0, ≥ ½ and = 1.
    pub areas: [f64; 3],
}

/// The cells of `grid` (north row first) covered by the observed footprint `path`.
pub fn observed_cells(path: &Path, grid: &Raster) -> Result<Vec<bool>, ResultsError> {
    let bad =
        |reason: String| ResultsError::input(format!("--observed {}: {reason}", path.display()));
    let ext = path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    let cells: Vec<bool> = match ext.as_str() {
        "geojson" | "json" | "shp" => {
            let areas = release::read(path, ThicknessSource::Uniform(1.0))
                .map_err(|e| bad(e.to_string()))?;
            grid.crs
                .check_same("the runs", &areas.crs, "the observed footprint")
                .map_err(|e| bad(e.to_string()))?;
            let polygons: Vec<_> = areas
                .features
                .iter()
                .flat_map(|f| f.polygons.iter().cloned())
                .collect();
            release::coverage(&polygons, grid, CoverageRule::CellCentre)
                .iter()
                .map(|&c| c > 0.5)
                .collect()
        }
        "tif" | "tiff" | "asc" => {
            let r = if ext == "asc" {
                asc::read(path)
            } else {
                geotiff::read(path)
            }
            .map_err(|e| bad(e.to_string()))?;
            r.check_same_grid(grid)
                .map_err(|e| bad(format!("not on the runs' grid: {e}")))?;
            r.values
                .iter()
                .map(|&v| !r.is_nodata(v) && v > 0.0)
                .collect()
        }
        _ => {
            return Err(bad(
                "unknown kind of file: polygons (.geojson, .json, .shp) or a raster (.tif, \
                 .asc) expected"
                    .into(),
            ))
        }
    };
    if !cells.contains(&true) {
        return Err(bad("the footprint covers no cell of the runs' grid".into()));
    }
    Ok(cells)
}

/// The grid every run of `done` shares, with the CRS they state: each run must be on
/// the first run's grid, and every CRS known by an EPSG code must be the same one
/// (compared across all runs, not only with the first: a first run without a CRS
/// would otherwise let any two others mix). Runs without a CRS are not compared.
fn common_grid<R>(done: &[(R, PathBuf)]) -> Result<Raster, ResultsError> {
    let mut grid = RunFile::open(&done[0].1)?.grid().clone();
    let mut known: Option<(&Path, crate::gis::Crs)> = None;
    for (_, h5) in done {
        let file = RunFile::open(h5)?;
        let other = file.grid();
        let mut unplaced = other.clone();
        unplaced.crs = grid.crs.clone();
        unplaced.check_same_grid(&grid).map_err(|e| {
            ResultsError::input(format!(
                "{}: not on the grid of {}: {e}",
                h5.display(),
                done[0].1.display()
            ))
        })?;
        if other.crs.epsg.is_none() {
            continue;
        }
        match &known {
            Some((first, crs)) => crs
                .check_same(
                    &first.display().to_string(),
                    &other.crs,
                    &h5.display().to_string(),
                )
                .map_err(|e| ResultsError::input(e.to_string()))?,
            None => known = Some((h5.as_path(), other.crs.clone())),
        }
    }
    if let Some((_, crs)) = known {
        grid.crs = crs;
    }
    Ok(grid)
}

/// The first words of `ensemble.toml`, which tell granflow's from a user's file.
const MAPS_HEAD: &str = "# Written by `granflow maps`";

/// Runs `granflow maps`.
pub fn maps(args: &MapsArgs) -> Result<MapsReport, ResultsError> {
    if !(args.threshold.is_finite() && args.threshold >= 0.0) {
        return Err(ResultsError::input(format!(
            "--threshold {}: must be a finite number ≥ 0 (m)",
            crate::gis::short_number(args.threshold)
        )));
    }
    let plan = Plan::read(&args.dir).map_err(ResultsError::input)?;
    let mut done = Vec::new();
    let mut left_out = Vec::new();
    for run in &plan.runs {
        match record::done(&args.dir, &run.name, &run.scenario_hash) {
            Some(rec) => done.push((run, args.dir.join(&rec.h5))),
            None => left_out.push(run.name.clone()),
        }
    }
    if done.is_empty() {
        return Err(ResultsError::failure(format!(
            "{}: no run of the sweep is done",
            args.dir.display()
        )));
    }
    if !left_out.is_empty() && !args.partial {
        let shown: Vec<&str> = left_out.iter().take(5).map(String::as_str).collect();
        return Err(ResultsError::failure(format!(
            "{} of {} runs of {} are not done (failed, missing or still running): {}{}; run \
             the sweep again to finish them, or pass --partial to map the {} done",
            left_out.len(),
            plan.runs.len(),
            args.dir.display(),
            shown.join(", "),
            if left_out.len() > 5 { ", …" } else { "" },
            done.len()
        )));
    }
    let grid = common_grid(&done)?;
    let (nx, ny) = (grid.nx, grid.ny);
    // File order (south row first), as the runs' maps.
    let observed = match &args.observed {
        Some(path) => Some(north_up(&observed_cells(path, &grid)?, nx, ny)),
        None => None,
    };
    let mut ensemble = Ensemble::new(nx * ny, args.threshold);
    let mut rows = Vec::new();
    let mut reached = vec![false; nx * ny];
    for (run, h5) in &done {
        let file = RunFile::open(h5)?;
        let pft = file.map("h_max")?;
        let pfv = file.map("speed_max")?;
        ensemble.add(&pft, &pfv);
        for (r, &p) in reached.iter_mut().zip(&pft) {
            *r = p > args.threshold;
        }
        let count = reached.iter().filter(|&&r| r).count();
        rows.push(RunRow {
            index: run.index,
            name: run.name.clone(),
            values: run.values.clone(),
            area: count as f64 * grid.cell_area(),
            // Wall (nodata) cells, NaN in pft, are no cells of the domain: counted,
            // they would be true negatives, and FPR would depend on how much of the
            // DEM is nodata.
            skill: observed.as_ref().map(|o| {
                let (sim, obs): (Vec<bool>, Vec<bool>) = pft
                    .iter()
                    .zip(reached.iter().zip(o))
                    .filter(|(p, _)| !p.is_nan())
                    .map(|(_, (&s, &o))| (s, o))
                    .unzip();
                skill(&sim, &obs, grid.cell_area())
            }),
            rank: None,
        });
    }
    if observed.is_some() {
        let mut order: Vec<usize> = (0..rows.len()).collect();
        order.sort_by(|&a, &b| {
            let d = |k: usize| rows[k].skill.map_or(f64::INFINITY, |s| s.distance);
            d(a).total_cmp(&d(b))
                .then(rows[a].index.cmp(&rows[b].index))
        });
        for (rank, k) in order.into_iter().enumerate() {
            rows[k].rank = Some(rank + 1);
        }
    }
    let out = args.output.clone().unwrap_or_else(|| args.dir.join("maps"));
    std::fs::create_dir_all(&out)
        .map_err(|e| ResultsError::failure(format!("cannot create {}: {e}", out.display())))?;
    let probability = ensemble.probability();
    let area = |keep: &dyn Fn(f64) -> bool| {
        probability.iter().filter(|&&p| keep(p)).count() as f64 * grid.cell_area()
    };
    let areas = [area(&|p| p > 0.0), area(&|p| p >= 0.5), area(&|p| p >= 1.0)];
    let mut publish = Publish::new(args.force);
    for (name, values) in ensemble.maps() {
        let path = out.join(format!("{name}.{}", args.format.extension()));
        write_raster(
            &mut publish,
            &grid,
            north_up(&values, nx, ny),
            args.format,
            args.float64,
            &path,
        )?;
    }
    if let Some(o) = &observed {
        // The footprint as the runs' cells see it (1 observed, 0 not), for plots.
        let path = out.join(format!("observed.{}", args.format.extension()));
        let cells = o
            .iter()
            .map(|&c| f64::from(u8::from(c)))
            .collect::<Vec<_>>();
        write_raster(
            &mut publish,
            &grid,
            north_up(&cells, nx, ny),
            args.format,
            false,
            &path,
        )?;
    }
    let mut write = |name: &str, head: &'static str, text: String| {
        let path = out.join(name);
        publish.write(&path, &Owner::TextHead(head), |tmp| {
            std::fs::write(tmp, text)
                .map_err(|e| ResultsError::failure(format!("cannot write {}: {e}", tmp.display())))
        })
    };
    write("runs.csv", "index,run,", runs_csv(&plan.axes, &rows))?;
    let mut meta = format!("{MAPS_HEAD}: what the maps in this directory are.\n");
    let _ = writeln!(meta, "sweep = {:?}", args.dir.display().to_string());
    let _ = writeln!(meta, "threshold = {}", format_float(args.threshold));
    let _ = writeln!(meta, "runs = {}", rows.len());
    let _ = writeln!(meta, "runs_left_out = {}", left_out.len());
    if let Some(o) = &args.observed {
        let _ = writeln!(meta, "observed = {:?}", o.display().to_string());
    }
    write("ensemble.toml", MAPS_HEAD, meta)?;
    let files = publish.commit()?;
    Ok(MapsReport {
        dir: out,
        threshold: args.threshold,
        runs: rows,
        left_out,
        files,
        areas,
    })
}

/// `runs.csv`: one row per run in sweep order, with its skill and rank when an
/// observed footprint was given.
pub fn runs_csv(axes: &[String], rows: &[RunRow]) -> String {
    let skills = rows.iter().any(|r| r.skill.is_some());
    let mut header: Vec<String> = vec!["index".into(), "run".into()];
    header.extend(axes.iter().map(|a| csv_field(a)));
    header.push("area_reached".into());
    if skills {
        for h in [
            "tp_area",
            "fp_area",
            "fn_area",
            "tn_area",
            "tpr",
            "fpr",
            "roc_distance",
            "rank",
        ] {
            header.push(h.into());
        }
    }
    let mut out = header.join(",") + "\n";
    for r in rows {
        let mut fields = vec![r.index.to_string(), csv_field(&r.name)];
        fields.extend(r.values.iter().map(|v| csv_field(v)));
        fields.push(format_float(r.area));
        if let Some(s) = r.skill {
            for v in [s.tp, s.fp, s.fn_, s.tn, s.tpr, s.fpr, s.distance] {
                fields.push(format_float(v));
            }
            fields.push(r.rank.map_or_else(String::new, |k| k.to_string()));
        }
        out.push_str(&fields.join(","));
        out.push('\n');
    }
    out
}

impl MapsReport {
    /// The table printed at the end: the runs (ranked, with an observed footprint)
    /// and the files.
    pub fn table(&self) -> String {
        let mut out = String::new();
        let skills = self.runs.iter().any(|r| r.skill.is_some());
        let mut rows: Vec<&RunRow> = self.runs.iter().collect();
        if skills {
            rows.sort_by_key(|r| r.rank);
            let _ = writeln!(
                out,
                "rank  {:<40}  {:>10}  {:>6}  {:>6}  {:>6}",
                "run", "area_m2", "TPR", "FPR", "d_ROC"
            );
        } else {
            let _ = writeln!(out, "{:<40}  {:>10}", "run", "area_m2");
        }
        for r in rows {
            match (r.skill, r.rank) {
                (Some(s), Some(k)) => {
                    let _ = writeln!(
                        out,
                        "{k:>4}  {:<40}  {:>10.4}  {:>6.3}  {:>6.3}  {:>6.3}",
                        r.name, r.area, s.tpr, s.fpr, s.distance
                    );
                }
                _ => {
                    let _ = writeln!(out, "{:<40}  {:>10.4}", r.name, r.area);
                }
            }
        }
        let h = format_float(self.threshold);
        let _ = writeln!(
            out,
            "maps: {} runs{}, P(pft > {h} m) > 0 on {:.4} m², ≥ 0.5 on {:.4} m², = 1 on {:.4} \
             m²; written to {}",
            self.runs.len(),
            if self.left_out.is_empty() {
                String::new()
            } else {
                format!(" ({} not done, left out)", self.left_out.len())
            },
            self.areas[0],
            self.areas[1],
            self.areas[2],
            self.dir.display()
        );
        out
    }
}
