//! `granflow export RUN.h5 --format geotiff|asc|netcdf [--time T] [--fields …]`: a
//! raster run's maps, or one of its snapshots, as files a GIS opens, with the run's
//! georeferencing (the grid of `/grid/x`, `/grid/y`) and CRS.
//!
//! The maps take the names of the avalanche-hazard literature (as in AvaFrame,
//! Tonnel et al. 2023): `pft` the peak flow thickness (`/maps/h_max`), `pfv` the peak
//! flow velocity (`/maps/speed_max`), `ppr` the peak pressure ρ|u|² (`/maps/ppr`),
//! `deposit` and `arrival_time`. A snapshot gives `h`, `u`, `v` and
//! `speed` = √(u² + v²). GeoTIFF and ESRI ASCII grids get one file per field,
//! `RUN_<field>.tif` (a snapshot: `RUN_<field>_t<time>.tif`); NetCDF gets the
//! snapshots as one CF time series, `RUN_snapshots.nc`, and the maps as one record at
//! the time of the last snapshot, `RUN_maps.nc` (a chosen snapshot: `RUN_t<time>.nc`).

use std::path::{Path, PathBuf};

use super::args::{ExportArgs, ExportFormat, Layout, RasterFormat};
use super::avaframe;
use super::publish::{Owner, Publish};
use super::run_file::{north_up, RunFile};
use super::{write_raster_band, ResultsError};
use crate::gis::geotiff::Band;
use crate::gis::netcdf::{FieldSpec, NetCdfWriter};
use crate::output::maps::{MapKind, MAPS};
use crate::sweep::naming::format_float;

/// A field that can be exported: its name, where it comes from, units, long name.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Field {
    pub name: &'static str,
    /// The `/maps` dataset of a map; for a snapshot field, its `/snapshots` dataset
    /// (`speed` is computed from `u` and `v`).
    pub source: &'static str,
    pub units: &'static str,
    pub long_name: &'static str,
}

/// The maps, in their default order (the peak fields first, then the deposit and the
/// arrival time), as the table of `output::maps` names them.
pub const MAP_FIELDS: [Field; 5] = [
    map_field(&MAPS[0]),
    map_field(&MAPS[1]),
    map_field(&MAPS[2]),
    map_field(&MAPS[4]),
    map_field(&MAPS[3]),
];

/// The export field of a map.
const fn map_field(m: &MapKind) -> Field {
    Field {
        name: m.short,
        source: m.dataset,
        units: m.units,
        long_name: m.long_name,
    }
}

/// The snapshot fields.
pub const SNAPSHOT_FIELDS: [Field; 4] = [
    Field {
        name: "h",
        source: "h",
        units: "m",
        long_name: "flow thickness normal to the bed",
    },
    Field {
        name: "u",
        source: "u",
        units: "m/s",
        long_name: "velocity along x",
    },
    Field {
        name: "v",
        source: "v",
        units: "m/s",
        long_name: "velocity along y",
    },
    Field {
        name: "speed",
        source: "speed",
        units: "m/s",
        long_name: "flow speed",
    },
];

/// A GeoTIFF band's description: the run file's `description` attribute of the map
/// when it has one, else the field's name and long name.
fn band_description(f: &Field, stored: Option<&str>) -> String {
    stored.map_or_else(|| format!("{}: {}", f.name, f.long_name), str::to_owned)
}

/// What a GIS will not know of the files' CRS: none at all, or (ESRI ASCII grids,
/// whose `.prj` is WKT) a code whose WKT granflow cannot make.
pub fn crs_warning(crs: &crate::gis::Crs, format: ExportFormat) -> Option<String> {
    if crs.is_unknown() || crs.is_local() {
        return Some(
            "the run has no CRS (its DEM stated none, and no release file gave one): the files are written without one; give the DEM its .prj and run again"
                .to_owned(),
        );
    }
    match (format, crs.epsg) {
        (ExportFormat::Asc, Some(code)) if crs.wkt_text().is_none() => Some(format!(
            "the run's CRS is EPSG:{code}, known by its code alone: an ESRI ASCII grid keeps a CRS only as WKT in its .prj, which granflow makes only for the codes listed in docs/gis.md (WGS 84 and UTM, ETRS89 UTM and LAEA, NAD83 UTM, the Swiss, Austrian, German, French, Italian and Dutch national grids), so the .asc files have no .prj; export as GeoTIFF (the default), or copy the DEM's .prj beside each .asc"
        )),
        _ => None,
    }
}

/// The maps and snapshot fields asked for by `--fields` (or the defaults), checked
/// against `--time` and the format.
pub fn choose_fields(
    names: &[String],
    time: bool,
    format: ExportFormat,
) -> Result<(Vec<Field>, Vec<Field>), ResultsError> {
    let netcdf = format == ExportFormat::Netcdf;
    if names.is_empty() {
        return Ok(match (time, netcdf) {
            (true, _) => (Vec::new(), vec![SNAPSHOT_FIELDS[0], SNAPSHOT_FIELDS[3]]),
            (false, false) => (MAP_FIELDS.to_vec(), Vec::new()),
            (false, true) => (MAP_FIELDS.to_vec(), SNAPSHOT_FIELDS.to_vec()),
        });
    }
    let (mut maps, mut snaps) = (Vec::new(), Vec::new());
    let all = || {
        MAP_FIELDS
            .iter()
            .chain(&SNAPSHOT_FIELDS)
            .map(|f| f.name)
            .collect::<Vec<_>>()
            .join(", ")
    };
    for name in names {
        let name = name.trim();
        if let Some(f) = MAP_FIELDS.iter().find(|f| f.name == name) {
            if time {
                return Err(ResultsError::input(format!(
                    "--fields {name}: a map over the whole run has no time; with --time \
                     export the snapshot fields h, u, v, speed"
                )));
            }
            if !maps.contains(f) {
                maps.push(*f);
            }
        } else if let Some(f) = SNAPSHOT_FIELDS.iter().find(|f| f.name == name) {
            if !time && !netcdf {
                return Err(ResultsError::input(format!(
                    "--fields {name}: a snapshot field needs --time T (or --format netcdf for \
                     every snapshot)"
                )));
            }
            if !snaps.contains(f) {
                snaps.push(*f);
            }
        } else {
            return Err(ResultsError::input(format!(
                "--fields: unknown field `{name}` (fields: {})",
                all()
            )));
        }
    }
    Ok((maps, snaps))
}

/// The index of the snapshot nearest `t` (the earlier of two equally near), or an
/// error when `t` lies outside [t_first, t_last] (beyond a relative 10⁻⁹).
pub fn nearest_snapshot(times: &[f64], t: f64) -> Result<usize, ResultsError> {
    let (Some(&first), Some(&last)) = (times.first(), times.last()) else {
        return Err(ResultsError::input("the run has no snapshot"));
    };
    let tol = 1e-9 * first.abs().max(last.abs()).max(1.0);
    if !t.is_finite() || t < first - tol || t > last + tol {
        return Err(ResultsError::input(format!(
            "--time {}: outside the snapshots' times [{}, {}] s ({} snapshots)",
            crate::gis::short_number(t),
            format_float(first),
            format_float(last),
            times.len()
        )));
    }
    let mut best = 0;
    for (k, &tk) in times.iter().enumerate() {
        if (tk - t).abs() < (times[best] - t).abs() {
            best = k;
        }
    }
    Ok(best)
}

/// A snapshot field's values at frame `k`, in the file's order.
fn snapshot_values(run: &RunFile, field: &Field, k: usize) -> Result<Vec<f64>, ResultsError> {
    if field.name == "speed" {
        let u = run.frame("u", k)?;
        let v = run.frame("v", k)?;
        return Ok(u.iter().zip(&v).map(|(u, v)| u.hypot(*v)).collect());
    }
    run.frame(field.source, k)
}

/// What `granflow export` wrote, and what to warn about.
#[derive(Debug)]
pub struct Exported {
    pub files: Vec<PathBuf>,
    /// Set when the run did not end normally: its maps are those of the part it ran.
    pub warning: Option<String>,
}

/// The warning for maps exported from a run that did not end normally (status
/// `unfinished`, `interrupted` or `failed: …`): they are not a final deposit.
fn status_warning(run: &RunFile) -> Option<String> {
    let status = run.status().unwrap_or_else(|| "unknown".to_owned());
    if crate::sweep::record::status_is_ok(&status) {
        return None;
    }
    let t = run
        .times()
        .last()
        .map_or_else(|| "?".to_owned(), |&t| format_float(t));
    let why = if status == crate::output::hdf5::UNFINISHED {
        "it is still running, or was killed".to_owned()
    } else {
        format!("its status is `{status}`")
    };
    Some(format!(
        "warning: {} did not end normally ({why}): what is exported is the state of the run up to its last snapshot (t = {t} s), not a final deposit",
        run.path().display()
    ))
}

/// Runs `granflow export`.
pub fn export(args: &ExportArgs) -> Result<Exported, ResultsError> {
    let (mut maps, snaps) = choose_fields(&args.fields, args.time.is_some(), args.format)?;
    let avaframe = args.layout == Layout::Avaframe;
    if avaframe {
        if args.time.is_some() || args.format == ExportFormat::Netcdf {
            return Err(ResultsError::input(
                "--layout avaframe writes AvaFrame's peak files (the maps, as .tif or .asc): not with --time or --format netcdf",
            ));
        }
        maps = avaframe::fields(&maps, !args.fields.is_empty())?;
    }
    let run = RunFile::open(&args.run)?;
    // A snapshot is what it says at its time; the maps of a run that stopped early
    // are not its final deposit.
    let warning = if maps.is_empty() {
        None
    } else {
        status_warning(&run)
    };
    let done = |files| Exported { files, warning };
    let frame = args
        .time
        .map(|t| nearest_snapshot(run.times(), t))
        .transpose()?;
    let mut dir = match &args.output {
        Some(d) => d.clone(),
        None => args.run.parent().map(Path::to_path_buf).unwrap_or_default(),
    };
    if avaframe {
        dir = avaframe::peak_dir(&dir);
    }
    if !dir.as_os_str().is_empty() {
        std::fs::create_dir_all(&dir)
            .map_err(|e| ResultsError::failure(format!("cannot create {}: {e}", dir.display())))?;
    }
    if let Some(w) = crs_warning(&run.grid().crs, args.format) {
        crate::terminal::print_err(&format!("warning: {w}\n"));
    }
    let stem = crate::output::run_stem(&args.run);
    let (nx, ny) = (run.grid().nx, run.grid().ny);
    let time_tag = |k: usize| format!("_t{}", format_float(run.times()[k]));
    let mut publish = Publish::new(args.force);
    let raster = match args.format {
        ExportFormat::Geotiff => Some(RasterFormat::Geotiff),
        ExportFormat::Asc => Some(RasterFormat::Asc),
        ExportFormat::Netcdf => None,
    };
    if let Some(format) = raster {
        let ext = format.extension();
        // One band: its file, values (north row first) and description.
        let mut band = |path: PathBuf, values: Vec<f64>, f: &Field, description: String| {
            let band = Band {
                description: &description,
                units: f.units,
            };
            let options = (format, args.float64);
            write_raster_band(&mut publish, run.grid(), values, options, &path, Some(band))
        };
        for f in &maps {
            let values = north_up(&run.map(f.source)?, nx, ny);
            // The run file's own description (it names ppr's density), else ours.
            let text = run.map_description(f.source);
            let mut description = band_description(f, text.as_deref());
            let (path, values) = if avaframe {
                if f.name == "ppr" {
                    description = description.replace("in Pa (1 kPa = 1000 Pa)", "in kPa");
                }
                let name = avaframe::peak_name(&stem, f.name);
                (
                    dir.join(format!("{name}.{ext}")),
                    avaframe::in_units(f, values),
                )
            } else {
                (dir.join(format!("{stem}_{}.{ext}", f.name)), values)
            };
            band(path, values, f, description)?;
        }
        if let Some(k) = frame {
            for f in &snaps {
                let path = dir.join(format!("{stem}_{}{}.{ext}", f.name, time_tag(k)));
                let values = north_up(&snapshot_values(&run, f, k)?, nx, ny);
                let t = format_float(run.times()[k]);
                band(
                    path,
                    values,
                    f,
                    format!("{} at t = {t} s", band_description(f, None)),
                )?;
            }
        }
        return publish.commit().map(done);
    }
    let title = format!("granflow run {}", args.run.display());
    let nc_err = |e: crate::gis::GisError| ResultsError::failure(e.to_string());
    let specs = |fields: &[Field]| -> Vec<FieldSpec> {
        fields
            .iter()
            .map(|f| FieldSpec::new(f.name, f.units, f.long_name))
            .collect()
    };
    if !snaps.is_empty() {
        let (path, frames) = match frame {
            Some(k) => (dir.join(format!("{stem}{}.nc", time_tag(k))), k..k + 1),
            None => (
                dir.join(format!("{stem}_snapshots.nc")),
                0..run.times().len(),
            ),
        };
        publish.write(&path, &Owner::NetCdf, |tmp| {
            let mut nc =
                NetCdfWriter::create(tmp, run.grid(), &specs(&snaps), &title).map_err(nc_err)?;
            for k in frames {
                let values = snaps
                    .iter()
                    .map(|f| Ok(north_up(&snapshot_values(&run, f, k)?, nx, ny)))
                    .collect::<Result<Vec<_>, ResultsError>>()?;
                let slabs: Vec<&[f64]> = values.iter().map(Vec::as_slice).collect();
                nc.write_frame(run.times()[k], &slabs).map_err(nc_err)?;
            }
            nc.finish().map_err(nc_err)
        })?;
    }
    if !maps.is_empty() {
        let path = dir.join(format!("{stem}_maps.nc"));
        publish.write(&path, &Owner::NetCdf, |tmp| {
            let mut nc =
                NetCdfWriter::create(tmp, run.grid(), &specs(&maps), &title).map_err(nc_err)?;
            let values = maps
                .iter()
                .map(|f| Ok(north_up(&run.map(f.source)?, nx, ny)))
                .collect::<Result<Vec<_>, ResultsError>>()?;
            let slabs: Vec<&[f64]> = values.iter().map(Vec::as_slice).collect();
            let t = run.times().last().copied().unwrap_or(0.0);
            nc.write_frame(t, &slabs).map_err(nc_err)?;
            nc.finish().map_err(nc_err)
        })?;
    }
    publish.commit().map(done)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_nearest_snapshot_is_chosen_and_ties_go_to_the_earlier() {
        let t = [0.0, 0.5, 1.0];
        assert_eq!(nearest_snapshot(&t, 0.0).unwrap(), 0);
        assert_eq!(nearest_snapshot(&t, 0.2).unwrap(), 0);
        assert_eq!(nearest_snapshot(&t, 0.25).unwrap(), 0);
        assert_eq!(nearest_snapshot(&t, 0.26).unwrap(), 1);
        assert_eq!(nearest_snapshot(&t, 1.0).unwrap(), 2);
        for bad in [-0.1, 1.1, f64::NAN] {
            let e = nearest_snapshot(&t, bad).unwrap_err();
            assert!(e.to_string().contains("outside"), "{e}");
            assert_eq!(e.exit_code(), 2);
        }
    }

    #[test]
    fn fields_are_checked_against_the_time_and_the_format() {
        let names = |s: &[&str]| s.iter().map(|s| s.to_string()).collect::<Vec<_>>();
        let (m, s) = choose_fields(&[], false, ExportFormat::Geotiff).unwrap();
        assert_eq!((m.len(), s.len()), (5, 0));
        let (m, s) = choose_fields(&[], true, ExportFormat::Asc).unwrap();
        assert_eq!(m.len(), 0);
        assert_eq!(s.iter().map(|f| f.name).collect::<Vec<_>>(), ["h", "speed"]);
        let (m, s) = choose_fields(&names(&["pft", "h"]), false, ExportFormat::Netcdf).unwrap();
        assert_eq!((m[0].name, s[0].name), ("pft", "h"));
        for (fields, time, message) in [
            (&["pft"][..], true, "has no time"),
            (&["h"][..], false, "needs --time"),
            (&["pfd"][..], false, "unknown field `pfd`"),
        ] {
            let e = choose_fields(&names(fields), time, ExportFormat::Geotiff).unwrap_err();
            assert!(e.to_string().contains(message), "{e}");
        }
    }
}
