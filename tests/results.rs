//! `granflow export` and `granflow maps` from the outside: the files they write read
//! back with granflow's GIS readers (origin, cell size, CRS and values against the
//! run's HDF5 file), their exit codes on bad input, and the probability maps of
//! small ensembles (identical runs: 0 or 1 only; two runs: ½ exactly where one
//! reaches).

use std::fs;
use std::path::{Path, PathBuf};
use std::process::Command;

use assert_cmd::prelude::*;
use granflow::gis::geotiff::{self, WriteOptions};
use granflow::gis::{asc, Crs, Raster};
use rust_hdf5::H5File;

use crate::common::assert_success;

fn granflow() -> Command {
    Command::cargo_bin("granflow").unwrap()
}

/// A cylinder collapsing on a flat bed, 24 × 16 square cells of 0.1 m.
const RADIAL: &str = r#"[domain]
x_min = -1.2
x_max = 1.2
y_min = -0.8
y_max = 0.8
cells = [24, 16]
coordinates = "cartesian"

[rheology]
law = "coulomb"
mu_deg = 27.0

[initial]
h = "if(x^2 + y^2 < 0.3^2, 0.4, 0)"

[time]
t_end = 0.5

[output]
every = 0.1
"#;

fn run(dir: &Path, name: &str, scenario: &str, args: &[&str]) -> PathBuf {
    let file = dir.join(format!("{name}.toml"));
    fs::write(&file, scenario).unwrap();
    let h5 = dir.join(format!("{name}.h5"));
    let out = granflow()
        .arg("run")
        .arg(&file)
        .args(["--quiet", "--output"])
        .arg(&h5)
        .args(args)
        .output()
        .unwrap();
    assert_success(&out);
    h5
}

fn read(h5: &Path, name: &str) -> (Vec<usize>, Vec<f64>) {
    let file = H5File::open(h5).unwrap();
    let ds = file.dataset(name).unwrap();
    (ds.shape(), ds.read_raw::<f64>().unwrap())
}

/// A (ny, nx) field of the HDF5 file (row 0 south) as a raster's values (row 0 north).
fn north_up(values: &[f64], nx: usize) -> Vec<f64> {
    values.chunks(nx).rev().flatten().copied().collect()
}

fn export(args: &[&str]) -> std::process::Output {
    granflow().arg("export").args(args).output().unwrap()
}

/// Writes `dir/dem.tif` and returns its raster: a GeoTIFF DEM of `nx` × `ny` cells of `cell` m whose top-left corner is
/// (`x_left`, `y_top`), in the CRS of EPSG code `epsg`, an inclined plane falling from
/// `top` by `drop` per column eastwards.
fn inclined_dem(
    dir: &Path,
    (nx, ny): (usize, usize),
    (x_left, y_top, cell): (f64, f64, f64),
    epsg: u32,
    (top, drop): (f64, f64),
) -> Raster {
    let mut dem = Raster::filled(nx, ny, x_left, y_top, cell, 0.0);
    for row in 0..ny {
        for col in 0..nx {
            let i = dem.index(col, row);
            dem.values[i] = top - drop * col as f64;
        }
    }
    dem.crs = Crs::from_epsg(epsg);
    geotiff::write(&dem, &dir.join("dem.tif"), WriteOptions::default()).unwrap();
    dem
}

/// A DEM in map coordinates (UTM 32N): an inclined plane of 20 × 14 cells of 10 m,
/// as a GeoTIFF with its EPSG code, and a scenario on its grid.
fn georeferenced_run(dir: &Path) -> PathBuf {
    inclined_dem(
        dir,
        (20, 14),
        (600_000.0, 5_200_140.0, 10.0),
        32632,
        (1000.0, 4.0),
    );
    let scenario = r#"[domain]
coordinates = "cartesian"

[bed]
b = { raster = "dem.tif" }

[rheology]
law = "coulomb"
mu_deg = 15.0

[initial]
h = "if((x - 600045)^2 + (y - 5200070)^2 < 25^2, 3, 0)"

[time]
t_end = 4

[output]
every = 1
"#;
    run(dir, "slope", scenario, &[])
}

#[test]
fn exported_maps_have_the_runs_grid_crs_and_values() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let h5 = georeferenced_run(d);
    let out = d.join("out");
    let o = out.to_str().unwrap();
    let run = h5.to_str().unwrap();
    let listed = assert_success(&export(&[run, "--float64", "-o", o]));
    assert_eq!(listed.lines().count(), 5, "{listed}");
    assert_success(&export(&[run, "--format", "asc", "-o", o]));
    let (shape, x) = read(&h5, "grid/x");
    assert_eq!(shape, [20]);
    assert_eq!(x[0], 600_005.0);
    for (field, dataset) in [
        ("pft", "h_max"),
        ("pfv", "speed_max"),
        ("ppr", "ppr"),
        ("deposit", "deposit"),
        ("arrival_time", "arrival_time"),
    ] {
        let (shape, values) = read(&h5, &format!("maps/{dataset}"));
        assert_eq!(shape, [14, 20]);
        let want = north_up(&values, 20);
        let tif = geotiff::read(&out.join(format!("slope_{field}.tif"))).unwrap();
        let grid = asc::read(&out.join(format!("slope_{field}.asc"))).unwrap();
        for r in [&tif, &grid] {
            assert_eq!((r.nx, r.ny, r.cell_size), (20, 14, 10.0), "{field}");
            assert_eq!((r.x_left, r.y_top), (600_000.0, 5_200_140.0), "{field}");
            assert_eq!(r.nodata, Some(-9999.0));
            for (k, (&got, &want)) in r.values.iter().zip(&want).enumerate() {
                if want.is_nan() {
                    assert_eq!(got, -9999.0, "{field} cell {k}");
                } else {
                    assert_eq!(got, want, "{field} cell {k}");
                }
            }
        }
        assert_eq!(tif.crs.epsg, Some(32632), "{field}");
    }
    // The run moved: pft is not the release alone, and ppr = ρ pfv² with ρ = φ_s ρ_s.
    let (_, pfv) = read(&h5, "maps/speed_max");
    let (_, ppr) = read(&h5, "maps/ppr");
    let k = (0..pfv.len())
        .max_by(|&a, &b| pfv[a].total_cmp(&pfv[b]))
        .unwrap();
    assert!(pfv[k] > 1.0, "{}", pfv[k]);
    assert_eq!(ppr[k], 0.62 * 2500.0 * pfv[k] * pfv[k]);
}

/// A DEM whose origin and cell size are not binary fractions (CH1903+ / LV95): the
/// run's `/grid` attributes record its grid and CRS exactly, and the GeoTIFF and ESRI
/// ASCII grids exported from the run are on that very grid (the ASCII grid as the
/// DEM itself is in that format).
#[test]
fn the_grid_goes_unchanged_from_the_dem_to_the_file_and_the_exports() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (x_left, y_top, cell) = (2_600_123.37, 1_200_456.91, 0.3);
    let dem = inclined_dem(d, (13, 9), (x_left, y_top, cell), 2056, (500.0, 0.1));
    let scenario = r#"[domain]
coordinates = "cartesian"

[bed]
b = { raster = "dem.tif" }

[rheology]
law = "coulomb"
mu_deg = 15.0

[initial]
h = "if((x - 2600125.3)^2 + (y - 1200455.5)^2 < 0.7^2, 0.3, 0)"

[time]
t_end = 0.5

[output]
every = 0.25
"#;
    let h5 = run(d, "lv95", scenario, &[]);
    let file = H5File::open(&h5).unwrap();
    let grid = file.root_group().group("grid").unwrap();
    assert_eq!(grid.attr_string("kind").unwrap(), "raster");
    assert_eq!(grid.attr_string("crs").unwrap(), "EPSG:2056");
    let spec = grid.attr_string("spec").unwrap();
    let words: Vec<&str> = spec.split_whitespace().collect();
    assert_eq!(words[..2], ["13", "9"], "{spec}");
    let numbers: Vec<f64> = words[2..].iter().map(|w| w.parse().unwrap()).collect();
    assert_eq!(numbers[0], x_left, "{spec}");
    assert_eq!(numbers[3], y_top, "{spec}");
    assert_eq!(numbers[4..], [cell, cell], "{spec}");
    drop(file);

    let out = d.join("out");
    let (o, r) = (out.to_str().unwrap(), h5.to_str().unwrap());
    assert_success(&export(&[r, "-o", o]));
    assert_success(&export(&[r, "--format", "asc", "-o", o]));
    let tif = geotiff::read(&out.join("lv95_pft.tif")).unwrap();
    assert_eq!((tif.nx, tif.ny), (13, 9));
    assert_eq!(
        (tif.x_left, tif.y_top, tif.cell_size),
        (x_left, y_top, cell)
    );
    assert_eq!(tif.crs.epsg, Some(2056));
    asc::write(&dem, &d.join("dem.asc")).unwrap();
    let want = asc::read(&d.join("dem.asc")).unwrap();
    let grid = asc::read(&out.join("lv95_pft.asc")).unwrap();
    assert_eq!((grid.nx, grid.ny), (13, 9));
    assert_eq!(
        (grid.x_left, grid.y_top, grid.cell_size),
        (want.x_left, want.y_top, want.cell_size)
    );
    assert_eq!(grid.crs.epsg, Some(2056));
}

/// A domain given by its keys: the exported raster's corner is (x_min, y_max) of the
/// scenario and its cell size (x_max − x_min)/nx, as the run computed them (not
/// rebuilt from the cell centres).
#[test]
fn a_domain_of_keys_is_exported_on_the_scenarios_edges() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let h5 = run(d, "radial", RADIAL, &[]);
    let out = d.join("out");
    let (o, r) = (out.to_str().unwrap(), h5.to_str().unwrap());
    assert_success(&export(&[r, "-o", o]));
    let tif = geotiff::read(&out.join("radial_pft.tif")).unwrap();
    assert_eq!((tif.nx, tif.ny), (24, 16));
    assert_eq!((tif.x_left, tif.y_top), (-1.2, 0.8));
    assert_eq!(tif.cell_size, (1.2 - -1.2) / 24.0);
}

/// The GDAL_METADATA tag (42112) of a GeoTIFF, if it has one.
fn gdal_metadata(path: &Path) -> Option<String> {
    let file = std::io::BufReader::new(fs::File::open(path).unwrap());
    let mut dec = tiff::decoder::Decoder::new(file).unwrap();
    dec.find_tag(tiff::tags::Tag::Unknown(42112))
        .unwrap()
        .map(|v| v.into_string().unwrap())
}

/// Every map of the run file says what it is and in which units (`description` and
/// `units` attributes; `ppr` names its density), and the exported GeoTIFFs carry the
/// same as the band's description and units, where GDAL and QGIS read them.
#[test]
fn maps_and_exported_bands_say_what_they_are_and_their_units() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let h5 = georeferenced_run(d);
    let out = d.join("out");
    assert_success(&export(&[
        h5.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
    ]));
    let file = H5File::open(&h5).unwrap();
    let attr = |ds: &str, name: &str| -> String {
        file.dataset(ds)
            .unwrap()
            .attr(name)
            .unwrap_or_else(|e| panic!("{ds} has no {name}: {e}"))
            .read_string()
            .unwrap()
    };
    for (field, dataset, units, words) in [
        ("pft", "h_max", "m", "normal to the bed"),
        ("pfv", "speed_max", "m/s", "along the bed surface"),
        ("ppr", "ppr", "Pa", "rho = 1550 kg/m^3"),
        ("deposit", "deposit", "m", "end of the run"),
        ("arrival_time", "arrival_time", "s", "first exceeded"),
    ] {
        let ds = format!("maps/{dataset}");
        assert_eq!(attr(&ds, "units"), units, "{ds}");
        let description = attr(&ds, "description");
        assert!(description.contains(words), "{ds}: {description}");
        let xml = gdal_metadata(&out.join(format!("slope_{field}.tif")))
            .unwrap_or_else(|| panic!("{field}: no GDAL_METADATA"));
        assert!(
            xml.contains(&format!(
                r#"<Item name="DESCRIPTION" sample="0" role="description">{description}</Item>"#
            )),
            "{field}: {xml}"
        );
        assert!(
            xml.contains(&format!(
                r#"<Item name="UNITTYPE" sample="0" role="unittype">{units}</Item>"#
            )),
            "{field}: {xml}"
        );
    }
}

#[test]
fn a_snapshot_is_exported_at_the_nearest_time() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let h5 = run(d, "radial", RADIAL, &["--threads", "1"]);
    let run = h5.to_str().unwrap();
    let o = d.to_str().unwrap();
    // Snapshots at 0, 0.1, …, 0.5: 0.23 is nearest 0.2 (frame 2).
    let listed = assert_success(&export(&[
        run,
        "--time",
        "0.23",
        "--float64",
        "--fields",
        "h,u,v,speed",
        "-o",
        o,
    ]));
    assert!(listed.contains("radial_h_t0.2.tif"), "{listed}");
    let (shape, h) = read(&h5, "snapshots/h");
    assert_eq!(shape, [6, 16, 24]);
    let (_, u) = read(&h5, "snapshots/u");
    let (_, v) = read(&h5, "snapshots/v");
    let frame = 2 * 16 * 24..3 * 16 * 24;
    let got = |f: &str| geotiff::read(&d.join(format!("radial_{f}_t0.2.tif"))).unwrap();
    assert_eq!(got("h").values, north_up(&h[frame.clone()], 24));
    let speed: Vec<f64> = u[frame.clone()]
        .iter()
        .zip(&v[frame.clone()])
        .map(|(u, v)| u.hypot(*v))
        .collect();
    assert_eq!(got("speed").values, north_up(&speed, 24));
    assert!(speed.iter().any(|&s| s > 0.1));
    // Every snapshot as a NetCDF time series, and the maps.
    let listed = assert_success(&export(&[run, "--format", "netcdf", "-o", o]));
    assert!(listed.contains("radial_snapshots.nc") && listed.contains("radial_maps.nc"));
    let nc = fs::read(d.join("radial_snapshots.nc")).unwrap();
    assert_eq!(&nc[..4], b"CDF\x02");
    assert_eq!(
        u32::from_be_bytes(nc[4..8].try_into().unwrap()),
        6,
        "records"
    );
}

#[test]
fn bad_inputs_exit_with_2_and_say_why() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let h5 = run(d, "radial", RADIAL, &["--threads", "1"]);
    let run = h5.to_str().unwrap();
    let one_d = d.join("line.h5");
    let collapse = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/collapse.toml");
    assert_success(
        &granflow()
            .arg("run")
            .arg(&collapse)
            .args(["--quiet", "--set", "time.t_end=0.01", "--output"])
            .arg(&one_d)
            .output()
            .unwrap(),
    );
    let missing = d.join("missing.h5");
    let cases: [(Vec<&str>, &str); 6] = [
        (vec![one_d.to_str().unwrap()], "a 1-D run"),
        (vec![missing.to_str().unwrap()], "no such file"),
        (
            vec![run, "--time", "0.6"],
            "outside the snapshots' times [0, 0.5]",
        ),
        (vec![run, "--time=-1"], "outside"),
        (vec![run, "--fields", "pft,pfd"], "unknown field `pfd`"),
        (vec![run, "--fields", "h"], "needs --time"),
    ];
    for (args, message) in cases {
        let out = export(&args);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.contains(message), "{args:?}: {err}");
    }
    // Not square cells.
    let stretched = RADIAL.replace("cells = [24, 16]", "cells = [24, 10]");
    let h5 = self::run(d, "stretched", &stretched, &[]);
    let out = export(&[h5.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("not square"));
}

/// Runs a sweep of the radial collapse in `dir` over `axis` and maps it.
fn sweep(dir: &Path, axis: &str) -> PathBuf {
    let base = dir.join("radial.toml");
    fs::write(&base, RADIAL).unwrap();
    let file = dir.join("ensemble.toml");
    fs::write(
        &file,
        format!("scenario = \"radial.toml\"\n\n[axes]\n{axis}\n"),
    )
    .unwrap();
    let out = dir.join("runs");
    assert_success(
        &granflow()
            .arg("sweep")
            .arg(&file)
            .args(["--quiet", "--jobs", "1", "--output"])
            .arg(&out)
            .output()
            .unwrap(),
    );
    out
}

fn probability(out: &Path) -> Vec<f64> {
    geotiff::read(&out.join("maps/pft_probability.tif"))
        .unwrap()
        .values
}

#[test]
fn identical_runs_give_probabilities_zero_or_one() {
    let dir = tempfile::tempdir().unwrap();
    // The grain diameter plays no part in Coulomb friction: the runs are identical.
    let out = sweep(dir.path(), "material.d_s = [1e-3, 2e-3, 3e-3]");
    let o = out.to_str().unwrap();
    let table = assert_success(
        &granflow()
            .args(["maps", o, "--threshold", "0.02"])
            .output()
            .unwrap(),
    );
    assert!(table.contains("maps: 3 runs"), "{table}");
    let p = probability(&out);
    let (_, pft) = read(&out.join("d_s=0.001.h5"), "maps/h_max");
    let reached: Vec<f64> = north_up(&pft, 24)
        .iter()
        .map(|&h| if h > 0.02 { 1.0 } else { 0.0 })
        .collect();
    assert_eq!(p, reached);
    assert!(p.contains(&0.0) && p.contains(&1.0));
}

#[test]
fn two_runs_give_one_half_exactly_where_one_reaches() {
    let dir = tempfile::tempdir().unwrap();
    let out = sweep(dir.path(), "rheology.mu_deg = [20, 35]");
    let o = out.to_str().unwrap();
    // The observed footprint: a disc of radius 0.5 m.
    let ring: Vec<String> = (0..64)
        .map(|k| {
            let a = std::f64::consts::TAU * k as f64 / 64.0;
            format!("[{}, {}]", 0.5 * a.cos(), 0.5 * a.sin())
        })
        .collect();
    let observed = dir.path().join("observed.geojson");
    fs::write(
        &observed,
        format!(
            r#"{{"type": "Polygon", "coordinates": [[{}, {}]]}}"#,
            ring.join(", "),
            ring[0]
        ),
    )
    .unwrap();
    let table = assert_success(
        &granflow()
            .args(["maps", o, "--threshold", "0.02", "--observed"])
            .arg(&observed)
            .output()
            .unwrap(),
    );
    let p = probability(&out);
    let reach = |name: &str| -> Vec<bool> {
        let (_, pft) = read(&out.join(format!("{name}.h5")), "maps/h_max");
        north_up(&pft, 24).iter().map(|&h| h > 0.02).collect()
    };
    let (a, b) = (reach("mu_deg=20"), reach("mu_deg=35"));
    let mut halves = 0;
    for k in 0..p.len() {
        let want = match (a[k], b[k]) {
            (true, true) => 1.0,
            (false, false) => 0.0,
            _ => 0.5,
        };
        assert_eq!(p[k], want, "cell {k}");
        halves += usize::from(want == 0.5);
    }
    assert!(halves > 0, "the two runs reach the same cells");
    // The skill: TP + FN is the observed area for every run, and the ranks 1 and 2.
    let csv = fs::read_to_string(out.join("maps/runs.csv")).unwrap();
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
    let rows: Vec<Vec<String>> = lines
        .map(|l| l.split(',').map(String::from).collect())
        .collect();
    assert_eq!(rows.len(), 2);
    let num = |r: &[String], c: &str| r[col(c)].parse::<f64>().unwrap();
    let observed_area = num(&rows[0], "tp_area") + num(&rows[0], "fn_area");
    let total = 2.4 * 1.6;
    for r in &rows {
        let sum = num(r, "tp_area") + num(r, "fp_area") + num(r, "fn_area") + num(r, "tn_area");
        assert!((sum - total).abs() < 1e-9, "{sum}");
        assert!((num(r, "tp_area") + num(r, "fn_area") - observed_area).abs() < 1e-12);
        let (tpr, fpr) = (num(r, "tpr"), num(r, "fpr"));
        assert!((num(r, "roc_distance") - (1.0 - tpr).hypot(fpr)).abs() < 1e-15);
    }
    let mut ranks: Vec<String> = rows.iter().map(|r| r[col("rank")].clone()).collect();
    ranks.sort();
    assert_eq!(ranks, ["1", "2"]);
    assert!(table.contains("rank"), "{table}");

    // A run scored against its own footprint (its pft exported as a raster, cells
    // above 0 observed; simulated: pft above 0) is perfect and ranks first.
    let own = out.join("mu_deg=35.h5");
    let gis = dir.path().join("gis");
    assert_success(&export(&[
        own.to_str().unwrap(),
        "--fields",
        "pft",
        "--format",
        "asc",
        "-o",
        gis.to_str().unwrap(),
    ]));
    assert_success(
        &granflow()
            .args([
                "maps",
                o,
                "--threshold",
                "0",
                "--format",
                "asc",
                "--observed",
            ])
            .arg(gis.join("mu_deg=35_pft.asc"))
            .output()
            .unwrap(),
    );
    let csv = fs::read_to_string(out.join("maps/runs.csv")).unwrap();
    let own_row = csv.lines().find(|l| l.contains(",mu_deg=35,")).unwrap();
    let fields: Vec<&str> = own_row.split(',').collect();
    let at = |c: &str| fields[col(c)];
    assert_eq!(
        (at("fp_area"), at("fn_area"), at("tpr"), at("fpr")),
        ("0", "0", "1", "0")
    );
    assert_eq!((at("roc_distance"), at("rank")), ("0", "1"));
}

/// The skill of `granflow maps --observed` counts the domain's cells with data only:
/// the wall cells of a DEM (nodata, here 6 rows added north of the grid) are no true
/// negatives, so TP + FP + FN + TN is the area with data, and the same flow (walls
/// there either way) has the same FPR on both DEMs.
#[test]
fn the_roc_leaves_the_wall_cells_out() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let fpr_of = |name: &str, extra_rows: usize| -> (f64, f64) {
        let sub = d.join(name);
        fs::create_dir_all(&sub).unwrap();
        let top = 0.8 + 0.1 * extra_rows as f64;
        let mut dem = Raster::filled(24, 16 + extra_rows, -1.2, top, 0.1, 0.0);
        dem.nodata = Some(-9999.0);
        for v in &mut dem.values[..24 * extra_rows] {
            *v = -9999.0;
        }
        asc::write(&dem, &sub.join("dem.asc")).unwrap();
        let scenario = RADIAL
            .replace(
                "x_min = -1.2\nx_max = 1.2\ny_min = -0.8\ny_max = 0.8\ncells = [24, 16]\n",
                "",
            )
            .replace(
                "[rheology]",
                "[bed]\nb = { raster = \"dem.asc\" }\n\n[rheology]",
            );
        fs::write(sub.join("radial.toml"), scenario).unwrap();
        fs::write(
            sub.join("ensemble.toml"),
            "scenario = \"radial.toml\"\n\n[axes]\nrheology.mu_deg = [20]\n",
        )
        .unwrap();
        fs::write(
            sub.join("observed.geojson"),
            r#"{"type": "Polygon", "coordinates": [[[-0.5, -0.5], [0.5, -0.5], [0.5, 0.5], [-0.5, 0.5], [-0.5, -0.5]]]}"#,
        )
        .unwrap();
        assert_success(
            &granflow()
                .current_dir(&sub)
                .args(["sweep", "ensemble.toml", "--quiet", "--output", "runs"])
                .output()
                .unwrap(),
        );
        assert_success(
            &granflow()
                .current_dir(&sub)
                .args([
                    "maps",
                    "runs",
                    "--threshold",
                    "0.02",
                    "--observed",
                    "observed.geojson",
                ])
                .output()
                .unwrap(),
        );
        let csv = fs::read_to_string(sub.join("runs/maps/runs.csv")).unwrap();
        let mut lines = csv.lines();
        let header: Vec<&str> = lines.next().unwrap().split(',').collect();
        let row: Vec<&str> = lines.next().unwrap().split(',').collect();
        let num = |c: &str| -> f64 {
            row[header.iter().position(|h| *h == c).unwrap()]
                .parse()
                .unwrap()
        };
        let total = num("tp_area") + num("fp_area") + num("fn_area") + num("tn_area");
        (total, num("fpr"))
    };
    let (plain, fpr_plain) = fpr_of("plain", 0);
    let (walled, fpr_walled) = fpr_of("walled", 6);
    let cell = 0.1 * 0.1;
    assert!((plain - 384.0 * cell).abs() < 1e-9, "{plain}");
    assert!((walled - 384.0 * cell).abs() < 1e-9, "{walled}");
    assert!(
        fpr_plain > 0.0,
        "the run reaches beyond the observed square"
    );
    assert!(
        (fpr_walled - fpr_plain).abs() < 1e-12,
        "{fpr_walled} against {fpr_plain}"
    );
}

#[test]
fn maps_refuses_a_sweep_with_runs_not_done_unless_partial() {
    let dir = tempfile::tempdir().unwrap();
    let out = sweep(dir.path(), "rheology.mu_deg = [20, 35]");
    fs::remove_file(out.join("mu_deg=35.result.toml")).unwrap();
    let o = out.to_str().unwrap();
    let refused = granflow().args(["maps", o]).output().unwrap();
    assert_eq!(refused.status.code(), Some(1));
    let err = String::from_utf8_lossy(&refused.stderr);
    assert!(
        err.contains("1 of 2 runs") && err.contains("--partial"),
        "{err}"
    );
    let table = assert_success(&granflow().args(["maps", o, "--partial"]).output().unwrap());
    assert!(
        table.contains("maps: 1 runs (1 not done, left out)"),
        "{table}"
    );
    let bad = granflow()
        .args(["maps", dir.path().to_str().unwrap()])
        .output()
        .unwrap();
    assert_eq!(bad.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&bad.stderr).contains("sweep-plan.toml"));
}

/// Forwards to the HDF5 sink and aborts the process once the maps of the third
/// snapshot are on disk, as a run killed then.
struct AbortAfterThirdSnapshot {
    inner: granflow::output::hdf5::Hdf5Sink,
    snapshots: usize,
}

impl granflow::output::OutputSink for AbortAfterThirdSnapshot {
    fn begin(
        &mut self,
        info: &granflow::output::RunInfo,
        grid: &granflow::output::GridData,
    ) -> Result<(), granflow::output::OutputError> {
        self.inner.begin(info, grid)
    }
    fn snapshot(
        &mut self,
        snap: &granflow::output::SnapshotView,
    ) -> Result<(), granflow::output::OutputError> {
        self.snapshots += 1;
        self.inner.snapshot(snap)
    }
    fn step(
        &mut self,
        rec: &granflow::output::StepRecord,
    ) -> Result<(), granflow::output::OutputError> {
        self.inner.step(rec)
    }
    fn finish(
        &mut self,
        summary: &granflow::output::RunSummary,
    ) -> Result<(), granflow::output::OutputError> {
        self.inner.finish(summary)
    }
    fn maps_so_far(
        &mut self,
        maps: &[granflow::output::CellField],
    ) -> Result<(), granflow::output::OutputError> {
        self.inner.maps_so_far(maps)?;
        if self.snapshots == 3 {
            std::process::abort();
        }
        Ok(())
    }
}

#[test]
fn a_killed_run_keeps_the_maps_of_its_last_snapshot() {
    if let Ok(path) = std::env::var("GRANFLOW_TEST_MAPS_ABORT_CHILD") {
        let dir = Path::new(&path).parent().unwrap();
        let scn = granflow::scenario::load_str(RADIAL, dir, &[]).unwrap();
        let mut run = granflow::setup::build(&scn);
        let mut sink = AbortAfterThirdSnapshot {
            inner: granflow::output::hdf5::Hdf5Sink::create(Path::new(&path)).unwrap(),
            snapshots: 0,
        };
        let _ = run.run(&mut sink, &mut |_| {});
        unreachable!("the sink aborts at the third snapshot");
    }
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("killed.h5");
    let child = Command::new(std::env::current_exe().unwrap())
        .args([
            "--exact",
            "results::a_killed_run_keeps_the_maps_of_its_last_snapshot",
            "--test-threads=1",
        ])
        .env("GRANFLOW_TEST_MAPS_ABORT_CHILD", &path)
        .output()
        .unwrap();
    assert!(!child.status.success(), "the child should have aborted");
    let (shape, h) = read(&path, "snapshots/h");
    assert_eq!(shape, [3, 16, 24]);
    let (_, h_max) = read(&path, "maps/h_max");
    let (_, deposit) = read(&path, "maps/deposit");
    let (_, ppr) = read(&path, "maps/ppr");
    let (_, speed) = read(&path, "maps/speed_max");
    let cells = 16 * 24;
    // The maps of t = 0.2 s: deposit is that snapshot's h, h_max at least every
    // snapshot's h and above the last one somewhere (the flow thinned since).
    assert_eq!(deposit, h[2 * cells..]);
    for k in 0..cells {
        for frame in 0..3 {
            assert!(h_max[k] >= h[frame * cells + k], "cell {k}");
        }
        assert_eq!(ppr[k], 0.62 * 2500.0 * speed[k] * speed[k]);
    }
    assert!((0..cells).any(|k| h_max[k] > deposit[k]));
    // The file is a run that did not finish, and export reads it.
    let out = export(&[path.to_str().unwrap(), "--fields", "pft", "--float64"]);
    assert_success(&out);
    let pft = geotiff::read(&dir.path().join("killed_pft.tif")).unwrap();
    assert_eq!(pft.values, north_up(&h_max, 24));
}

/// `maps` compares the CRS of every run, not only each with the first: a first run
/// without a CRS does not let runs in EPSG:2056 and EPSG:21781 mix into one map.
#[test]
fn maps_refuses_runs_in_two_crs_whatever_the_first_run_states() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let mut dem = Raster::filled(12, 8, 2_600_000.0, 1_200_080.0, 10.0, 0.0);
    for (i, v) in dem.values.iter_mut().enumerate() {
        *v = 100.0 - (i % 12) as f64;
    }
    let wkt = |code: u32| format!(r#"PROJCS["a projection",AUTHORITY["EPSG","{code}"]]"#);
    for (name, crs) in [("a", None), ("b", Some(2056)), ("c", Some(21781))] {
        asc::write(&dem, &d.join(format!("{name}.asc"))).unwrap();
        if let Some(code) = crs {
            fs::write(d.join(format!("{name}.prj")), wkt(code)).unwrap();
        }
    }
    let scenario = r#"[domain]
coordinates = "cartesian"

[bed]
b = { raster = "a.asc" }

[rheology]
law = "coulomb"
mu_deg = 15.0

[initial]
h = "if((x - 2600040)^2 + (y - 1200040)^2 < 15^2, 2, 0)"

[time]
t_end = 0.5

[output]
every = 0.25
"#;
    fs::write(d.join("dem.toml"), scenario).unwrap();
    fs::write(
        d.join("crs.toml"),
        "scenario = \"dem.toml\"\n\n[axes]\nbed.b = { raster = [\"a.asc\", \"b.asc\", \"c.asc\"] }\n",
    )
    .unwrap();
    let out = d.join("runs");
    assert_success(
        &granflow()
            .arg("sweep")
            .arg(d.join("crs.toml"))
            .args(["--quiet", "--jobs", "1", "--output"])
            .arg(&out)
            .output()
            .unwrap(),
    );
    let refused = granflow()
        .args(["maps", out.to_str().unwrap()])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&refused.stderr);
    assert_eq!(refused.status.code(), Some(2), "{err}");
    assert!(
        err.contains("EPSG:2056") && err.contains("EPSG:21781"),
        "{err}"
    );
}

#[test]
fn maps_replaces_only_its_own_files() {
    let dir = tempfile::tempdir().unwrap();
    let out = sweep(dir.path(), "material.d_s = [1e-3, 2e-3]");
    let o = out.to_str().unwrap();
    let maps = |extra: &[&str]| {
        granflow()
            .args(["maps", o, "-q"])
            .args(extra)
            .output()
            .unwrap()
    };
    fs::create_dir_all(out.join("maps")).unwrap();
    let mine = "my notes on these runs\n";
    fs::write(out.join("maps/runs.csv"), mine).unwrap();
    let refused = maps(&[]);
    let stderr = String::from_utf8_lossy(&refused.stderr);
    assert_eq!(refused.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("runs.csv") && stderr.contains("--force"),
        "{stderr}"
    );
    assert_eq!(fs::read_to_string(out.join("maps/runs.csv")).unwrap(), mine);
    // Nothing else was written either.
    assert_eq!(fs::read_dir(out.join("maps")).unwrap().count(), 1);
    assert_success(&maps(&["--force"]));
    // Its own files are replaced without --force, in both formats.
    assert_success(&maps(&[]));
    assert_success(&maps(&["--format", "asc"]));
    assert_success(&maps(&["--format", "asc"]));
}

/// A sweep whose axes are sampled (`[sample]`, a seeded Latin hypercube): each of the
/// n strata of every axis holds one run, the same seed draws the same runs (their
/// names and parameters in `summary.csv`), and `granflow maps` maps them as any sweep.
#[test]
fn a_sampled_sweep_is_stratified_reproducible_and_mapped() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    fs::write(d.join("radial.toml"), RADIAL).unwrap();
    let text = "scenario = \"radial.toml\"\n\n[sample]\nruns = 4\nseed = 11\nrheology.mu_deg = { uniform = [20, 32] }\ntime.t_end = { normal = [0.5, 0.05], min = 0.4 }\n";
    fs::write(d.join("lhs.toml"), text).unwrap();
    let sweep = |out: &str| {
        assert_success(
            &granflow()
                .args([
                    "sweep", "lhs.toml", "--quiet", "--jobs", "1", "--output", out,
                ])
                .current_dir(d)
                .output()
                .unwrap(),
        );
        fs::read_to_string(d.join(out).join("summary.csv")).unwrap()
    };
    let csv = sweep("a");
    let header: Vec<&str> = csv.lines().next().unwrap().split(',').collect();
    assert_eq!(header[2..4], ["rheology.mu_deg", "time.t_end"], "{csv}");
    let column = |c: usize| -> Vec<f64> {
        csv.lines()
            .skip(1)
            .map(|l| l.split(',').nth(c).unwrap().parse().unwrap())
            .collect()
    };
    let mut strata: Vec<usize> = column(2)
        .iter()
        .map(|mu| ((mu - 20.0) / 12.0 * 4.0) as usize)
        .collect();
    strata.sort();
    assert_eq!(strata, [0, 1, 2, 3], "{csv}");
    assert!(column(3).iter().all(|&t| t >= 0.4), "{csv}");
    // The same seed: the same runs; the rows name the same parameters.
    let again = sweep("b");
    let params = |csv: &str| -> Vec<String> {
        csv.lines()
            .map(|l| l.split(',').take(4).collect::<Vec<_>>().join(","))
            .collect()
    };
    assert_eq!(params(&again), params(&csv));
    let table = assert_success(
        &granflow()
            .args(["maps", "a", "--threshold", "0.02"])
            .current_dir(d)
            .output()
            .unwrap(),
    );
    assert!(table.contains("maps: 4 runs"), "{table}");
    assert!(d.join("a/maps/pft_probability.tif").is_file());
    // A bad distribution: exit 2, naming the key.
    fs::write(
        d.join("bad.toml"),
        text.replace("uniform = [20, 32]", "uniform = [32, 20]"),
    )
    .unwrap();
    let out = granflow()
        .args(["sweep", "bad.toml", "--output", "c"])
        .current_dir(d)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("sample.rheology.mu_deg") && err.contains("line 6"),
        "{err}"
    );
    assert!(!d.join("c").join("summary.csv").exists());
}

/// `--layout avaframe`: AvaFrame's peak files (`Outputs/com1DFA/peakFiles`, names
/// `<release>_<hash>_C_null_dfa_<res>`, ppr in kPa), on the run's grid; other maps,
/// snapshots and NetCDF are refused with exit code 2.
#[test]
fn the_avaframe_layout_writes_peak_files_in_avaframes_names_and_units() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let h5 = georeferenced_run(d);
    let (run, ava) = (h5.to_str().unwrap(), d.join("avaSlope"));
    let listed = assert_success(&export(&[
        run,
        "--layout",
        "avaframe",
        "--format",
        "asc",
        "-o",
        ava.to_str().unwrap(),
    ]));
    let peak = ava.join("Outputs/com1DFA/peakFiles");
    let mut names: Vec<String> = fs::read_dir(&peak)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(".asc"))
        .collect();
    names.sort();
    assert_eq!(names.len(), 3, "{listed}");
    for (name, (res, dataset, scale)) in names.iter().zip([
        ("pft", "h_max", 1.0),
        ("pfv", "speed_max", 1.0),
        ("ppr", "ppr", 1000.0),
    ]) {
        let parts: Vec<&str> = name.trim_end_matches(".asc").split('_').collect();
        assert_eq!(parts[0], "slope", "{name}");
        assert_eq!(parts[2..], ["C", "null", "dfa", res], "{name}");
        let grid = asc::read(&peak.join(name)).unwrap();
        let (_, values) = read(&h5, &format!("maps/{dataset}"));
        let want: Vec<f64> = north_up(&values, 20).iter().map(|v| v / scale).collect();
        assert_eq!(
            (grid.x_left, grid.y_top, grid.cell_size),
            (600_000.0, 5_200_140.0, 10.0)
        );
        assert_eq!(grid.values, want, "{name}");
    }
    for (args, needle) in [
        (
            &["--format", "netcdf"][..],
            "not with --time or --format netcdf",
        ),
        (&["--time", "1"][..], "not with --time"),
        (&["--fields", "deposit"][..], "pft, pfv and ppr only"),
    ] {
        let mut all = vec![run, "--layout", "avaframe"];
        all.extend(args);
        let out = export(&all);
        assert_eq!(out.status.code(), Some(2), "{args:?}");
        assert!(
            String::from_utf8_lossy(&out.stderr).contains(needle),
            "{args:?}"
        );
    }
}
