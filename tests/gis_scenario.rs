//! GIS inputs of a raster (2-D) run, from the scenario and the command line: release
//! polygons (released volume by the area-fraction and cell-centre rules, thickness
//! normal to the slope on a 30° plane), nodata cells of the DEM as walls (mass
//! conserved, nothing enters, the same flow as at a wall side of the domain),
//! `domain.crop` and `domain.coarsen`, and bad inputs through `granflow check` and
//! `granflow run` (exit 2, an error naming the file and the reason).

use std::fs;
use std::path::Path;
use std::process::Command;

use assert_cmd::prelude::*;

use crate::common::{fails_at, load_in, python_with_h5py};

fn granflow() -> Command {
    Command::cargo_bin("granflow").unwrap()
}

/// An ESRI ASCII grid of `ncols` × `nrows` cells of `d` m, lower-left corner
/// (`x0`, `y0`), nodata −9999, with value(col, row from the top).
fn write_dem(
    path: &Path,
    (ncols, nrows, d): (usize, usize, f64),
    (x0, y0): (f64, f64),
    value: impl Fn(usize, usize) -> f64,
) {
    let mut text = format!(
        "ncols {ncols}\nnrows {nrows}\nxllcorner {x0}\nyllcorner {y0}\ncellsize {d}\nNODATA_value -9999\n"
    );
    for row in 0..nrows {
        let line: Vec<String> = (0..ncols).map(|c| format!("{}", value(c, row))).collect();
        text.push_str(&line.join(" "));
        text.push('\n');
    }
    fs::write(path, text).unwrap();
}

/// A GeoJSON FeatureCollection of one polygon (the ring closed here), with the
/// property `d` = 2 and, when given, the old-style `crs` member.
fn write_polygon(path: &Path, ring: &[[f64; 2]], epsg: Option<u32>) {
    let mut pts: Vec<String> = ring
        .iter()
        .map(|p| format!("[{}, {}]", p[0], p[1]))
        .collect();
    pts.push(pts[0].clone());
    let crs = epsg.map_or(String::new(), |c| {
        format!(
            r#""crs": {{"type": "name", "properties": {{"name": "urn:ogc:def:crs:EPSG::{c}"}}}},"#
        )
    });
    let text = format!(
        r#"{{"type": "FeatureCollection", {crs} "features": [{{"type": "Feature", "properties": {{"d": 2.0}}, "geometry": {{"type": "Polygon", "coordinates": [[{}]]}}}}]}}"#,
        pts.join(", ")
    );
    fs::write(path, text).unwrap();
}

/// A scenario on the grid of `dem.asc` with `initial.h` = `h` (a TOML value).
fn scenario(h: &str, extra: &str) -> String {
    format!(
        r#"[domain]
coordinates = "cartesian"
{extra}
[bed]
b = {{ raster = "dem.asc" }}

[rheology]
law = "coulomb"
mu_deg = 30.0

[initial]
h = {h}

[time]
t_end = 1.0
"#
    )
}

/// A quadrilateral not aligned with the cells: area by the shoelace formula.
const QUAD: [[f64; 2]; 4] = [[13.3, 11.7], [41.9, 14.2], [38.6, 36.1], [16.2, 31.4]];

fn shoelace(ring: &[[f64; 2]]) -> f64 {
    let n = ring.len();
    0.5 * (0..n)
        .map(|i| {
            let (a, b) = (ring[i], ring[(i + 1) % n]);
            a[0] * b[1] - b[0] * a[1]
        })
        .sum::<f64>()
        .abs()
}

/// By the area-fraction rule the released volume is area × thickness on any grid (to
/// rounding); by the cell-centre rule it converges to it as the cells shrink.
#[test]
fn a_release_polygon_releases_its_area_times_its_thickness() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write_polygon(&d.join("release.geojson"), &QUAD, None);
    let exact = shoelace(&QUAD) * 1.5;
    let h = |rule: &str| {
        format!(
            r#"{{ polygon = "release.geojson", thickness = 1.5, thickness_is = "vertical", rule = "{rule}" }}"#
        )
    };
    let mut centre_errors = Vec::new();
    for n in [10, 20, 40, 80] {
        let cell = 50.0 / n as f64;
        write_dem(&d.join("dem.asc"), (n, n, cell), (0.0, 0.0), |_, _| 0.0);
        let scn = load_in(&scenario(&h("area_fraction"), ""), d).unwrap();
        let release = scn.release.as_ref().unwrap();
        assert!(
            (release.volume - exact).abs() < 1e-12 * exact,
            "{n} cells: {} against {exact}",
            release.volume
        );
        // The state holds that volume.
        let held: f64 = scn.sampled.h.iter().sum::<f64>() * cell * cell;
        assert!((held - exact).abs() < 1e-12 * exact);
        assert!((release.area - shoelace(&QUAD)).abs() < 1e-12 * exact);
        assert_eq!(release.volume_on_walls, 0.0);
        let scn = load_in(&scenario(&h("cell_centre"), ""), d).unwrap();
        let v = scn.release.unwrap().volume;
        // Whole cells only.
        assert!(scn.sampled.h.iter().all(|&h| h == 0.0 || h == 1.5));
        centre_errors.push((v - exact).abs() / exact);
    }
    // The cell-centre error is O(perimeter × cell size / area): it falls with the
    // cells, below 2 % on the finest grid.
    assert!(centre_errors[3] < 0.02, "{centre_errors:?}");
    assert!(
        centre_errors[3] < centre_errors[0],
        "no convergence: {centre_errors:?}"
    );
}

/// On a 30° plane a thickness h given normal to the slope becomes the vertical
/// thickness h / cos 30° in every released cell, and the volume grows by 1 / cos 30°.
#[test]
fn a_normal_thickness_on_a_30_degree_plane_is_h_over_cos_theta() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let tan = 30f64.to_radians().tan();
    // b = 100 − x tan 30°, cells of 2 m, x from 0 to 60.
    write_dem(&d.join("dem.asc"), (30, 20, 2.0), (0.0, 0.0), |c, _| {
        100.0 - (c as f64 + 0.5) * 2.0 * tan
    });
    let square = [[10.0, 10.0], [30.0, 10.0], [30.0, 30.0], [10.0, 30.0]];
    write_polygon(&d.join("release.geojson"), &square, None);
    let h = |is: &str| {
        format!(r#"{{ polygon = "release.geojson", thickness = 2.0, thickness_is = "{is}" }}"#)
    };
    let vertical = load_in(&scenario(&h("vertical"), ""), d).unwrap();
    let normal = load_in(&scenario(&h("normal"), ""), d).unwrap();
    let cos = 30f64.to_radians().cos();
    let mut released = 0;
    for (&hv, &hn) in vertical.sampled.h.iter().zip(&normal.sampled.h) {
        if hv > 0.0 {
            released += 1;
            assert!((hn - hv / cos).abs() < 1e-12, "{hn} against {}", hv / cos);
        } else {
            assert_eq!(hn, 0.0);
        }
    }
    assert_eq!(released, 100, "a 20 m square on 2 m cells");
    let (v0, v1) = (
        vertical.release.unwrap().volume,
        normal.release.unwrap().volume,
    );
    assert!((v0 - 800.0).abs() < 1e-9);
    assert!((v1 - 800.0 / cos).abs() < 1e-9, "{v1}");
}

#[test]
fn release_keys_are_checked_by_name() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write_dem(&d.join("dem.asc"), (10, 10, 5.0), (0.0, 0.0), |_, _| 0.0);
    write_polygon(
        &d.join("release.geojson"),
        &[[10.0, 10.0], [20.0, 10.0], [20.0, 20.0]],
        None,
    );
    let base = r#"polygon = "release.geojson", thickness_is = "vertical""#;
    let cases = [
        (
            format!("{{ {base} }}"),
            "initial.h.thickness",
            "thickness_attribute",
        ),
        (
            format!("{{ {base}, thickness = 1, thickness_attribute = \"d\" }}"),
            "initial.h.thickness_attribute",
            "not both",
        ),
        (
            format!("{{ {base}, thickness = -1 }}"),
            "initial.h.thickness",
            "at least 0",
        ),
        (
            r#"{ polygon = "release.geojson", thickness = 1 }"#.to_owned(),
            "initial.h.thickness_is",
            "normal",
        ),
        (
            format!("{{ {base}, thickness = 1, rule = \"centre\" }}"),
            "initial.h.rule",
            "cell_centre",
        ),
        (
            format!("{{ {base}, thickness = 1, colour = 1 }}"),
            "initial.h.colour",
            "allowed",
        ),
        (
            format!("{{ {base}, thickness_attribute = \"depth\" }}"),
            "initial.h.polygon",
            "attributes: d",
        ),
        (
            r#"{ polygon = "missing.geojson", thickness = 1, thickness_is = "vertical" }"#
                .to_owned(),
            "initial.h.polygon",
            "missing.geojson",
        ),
    ];
    for (h, key, words) in cases {
        let message = fails_at(&scenario(&h, ""), d, key);
        assert!(message.contains(words), "{key}: {message}");
    }
    // A thickness attribute: the feature's `d` = 2.
    let scn = load_in(
        &scenario(&format!("{{ {base}, thickness_attribute = \"d\" }}"), ""),
        d,
    )
    .unwrap();
    assert!((scn.release.unwrap().volume - 2.0 * 50.0).abs() < 1e-9);
    // A line domain has no polygons.
    let line = r#"[domain]
x_min = 0.0
x_max = 1.0
cells = 10

[rheology]
law = "coulomb"
mu = 0.5

[initial]
h = { polygon = "release.geojson", thickness = 1, thickness_is = "vertical" }

[time]
t_end = 1.0
"#;
    let message = fails_at(line, d, "initial.h.polygon");
    assert!(message.contains("raster"), "{message}");
}

/// Runs `granflow ARGS` in `dir`; returns (exit code, stderr).
fn granflow_in(dir: &Path, args: &[&str]) -> (Option<i32>, String) {
    let out = granflow().current_dir(dir).args(args).output().unwrap();
    (
        out.status.code(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// Bad inputs through the command line: `check` and `run` both exit with 2 and an
/// error that names the file and says what is wrong with it.
#[test]
fn bad_gis_inputs_exit_2_naming_the_file_and_the_reason() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let polygon = r#"{ polygon = "release.geojson", thickness = 1, thickness_is = "vertical" }"#;
    fs::write(d.join("s.toml"), scenario(polygon, "")).unwrap();
    let good_dem = |d: &Path| write_dem(&d.join("dem.asc"), (10, 8, 5.0), (0.0, 0.0), |_, _| 0.0);
    let inside = [[10.0, 10.0], [20.0, 10.0], [20.0, 20.0]];
    type Case<'a> = (&'a str, Box<dyn Fn(&Path) + 'a>, Vec<&'a str>);
    let cases: Vec<Case> = vec![
        (
            "a DEM whose header lies about its size",
            Box::new(|d: &Path| {
                good_dem(d);
                let text = fs::read_to_string(d.join("dem.asc")).unwrap();
                fs::write(d.join("dem.asc"), text.replace("nrows 8", "nrows 9")).unwrap();
                write_polygon(&d.join("release.geojson"), &inside, None);
            }),
            vec!["dem.asc", "promises 90 values", "only 80"],
        ),
        (
            "a polygon outside the DEM",
            Box::new(|d: &Path| {
                good_dem(d);
                let far = [[500.0, 500.0], [510.0, 500.0], [510.0, 510.0]];
                write_polygon(&d.join("release.geojson"), &far, None);
            }),
            vec!["release.geojson", "outside the raster"],
        ),
        (
            "a CRS mismatch between the DEM and the release",
            Box::new(|d: &Path| {
                good_dem(d);
                fs::write(
                    d.join("dem.prj"),
                    r#"PROJCS["CH1903+ / LV95",AUTHORITY["EPSG","2056"]]"#,
                )
                .unwrap();
                write_polygon(&d.join("release.geojson"), &inside, Some(21781));
            }),
            vec!["dem.asc", "release.geojson", "EPSG:2056", "EPSG:21781"],
        ),
        (
            "a 0-byte DEM",
            Box::new(|d: &Path| {
                fs::write(d.join("dem.asc"), "").unwrap();
                write_polygon(&d.join("release.geojson"), &inside, None);
            }),
            vec!["dem.asc", "empty (0 bytes)"],
        ),
        (
            "a 0-byte release file",
            Box::new(|d: &Path| {
                good_dem(d);
                fs::write(d.join("release.geojson"), "").unwrap();
            }),
            vec!["release.geojson", "empty (0 bytes)"],
        ),
        (
            "a huge DEM",
            Box::new(|d: &Path| {
                // A sparse file of 2 GiB: refused by its size, never read.
                let f = fs::File::create(d.join("dem.asc")).unwrap();
                f.set_len(2 << 30).unwrap();
                write_polygon(&d.join("release.geojson"), &inside, None);
            }),
            vec!["dem.asc", "2.0 GiB", "crop"],
        ),
        (
            "a huge release file",
            Box::new(|d: &Path| {
                good_dem(d);
                let f = fs::File::create(d.join("release.geojson")).unwrap();
                f.set_len(1 << 30).unwrap();
            }),
            vec!["release.geojson", "1024 MiB"],
        ),
    ];
    for (what, make, words) in cases {
        for f in ["dem.asc", "dem.prj", "release.geojson"] {
            let _ = fs::remove_file(d.join(f));
        }
        make(d);
        for command in ["check", "run"] {
            let (code, stderr) = granflow_in(d, &[command, "s.toml"]);
            assert_eq!(code, Some(2), "{what} ({command}): {stderr}");
            for w in &words {
                assert!(
                    stderr.contains(w),
                    "{what} ({command}): no `{w}` in {stderr}"
                );
            }
            assert!(!stderr.contains("panicked"), "{stderr}");
        }
    }
}

/// `check` prints the released volume (and the volume dropped on nodata cells); `run`
/// stores it in `/summary`.
#[test]
fn the_released_volume_is_printed_and_stored() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // A hole of nodata under part of the release: 2 × 2 cells of 25 m².
    write_dem(&d.join("dem.asc"), (12, 10, 5.0), (0.0, 0.0), |c, r| {
        if (3..5).contains(&c) && (4..6).contains(&r) {
            -9999.0
        } else {
            0.0
        }
    });
    write_polygon(
        &d.join("release.geojson"),
        &[[10.0, 10.0], [30.0, 10.0], [30.0, 40.0], [10.0, 40.0]],
        None,
    );
    let h = r#"{ polygon = "release.geojson", thickness = 1, thickness_is = "vertical" }"#;
    fs::write(d.join("s.toml"), scenario(h, "")).unwrap();
    let (code, stderr) = granflow_in(d, &["check", "s.toml"]);
    assert_eq!(code, Some(0), "{stderr}");
    // 600 m² × 1 m, of which 100 m² on the hole.
    assert!(
        stderr.contains("released volume 5.000000e2 m³")
            && stderr.contains("1.000000e2 m³ on wall (nodata) cells"),
        "{stderr}"
    );
    let (code, stderr) = granflow_in(d, &["run", "s.toml", "--quiet"]);
    assert_eq!(code, Some(0), "{stderr}");
    let Some(py) = python_with_h5py() else {
        return;
    };
    let out = Command::new(py)
        .arg("-c")
        .arg(
            "import h5py, numpy, sys\n\
             f = h5py.File(sys.argv[1])\n\
             s = f['summary'].attrs\n\
             h = f['snapshots/h'][0]\n\
             print(s['release_volume'], s['release_volume_on_walls'], s['wall_cells'], \
             int(numpy.isnan(h).sum()), int(numpy.isnan(f['maps/h_max'][:]).sum()))",
        )
        .arg(d.join("s.h5"))
        .output()
        .unwrap();
    let text = crate::common::assert_success(&out);
    let v: Vec<f64> = text
        .split_whitespace()
        .map(|w| w.parse().unwrap())
        .collect();
    assert!(
        (v[0] - 500.0).abs() < 1e-9 && (v[1] - 100.0).abs() < 1e-9,
        "{text}"
    );
    assert_eq!(&v[2..], &[4.0, 4.0, 4.0], "{text}");
}

/// A dam break towards a band of nodata cells across the whole DEM is the same flow,
/// to round-off, as the one on the DEM cut at the band with a wall side: the nodata
/// cells reflect it, hold nothing and the volume is conserved.
#[test]
fn nodata_cells_reflect_the_flow_like_a_wall_side() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let bed = |c: usize, r: usize| 0.01 * (c as f64) + 0.002 * (r as f64);
    // 40 × 12 cells; columns 30.. are nodata. The cut DEM is columns 0..30.
    write_dem(&d.join("dem.asc"), (40, 12, 1.0), (0.0, 0.0), |c, r| {
        if c >= 30 {
            -9999.0
        } else {
            bed(c, r)
        }
    });
    let sub = d.join("cut");
    fs::create_dir(&sub).unwrap();
    write_dem(&sub.join("dem.asc"), (30, 12, 1.0), (0.0, 0.0), bed);
    let text =
        scenario("\"if(x > 18 && y > 3, 1.0, 0.1)\"", "").replace("mu_deg = 30.0", "mu = 0.05");
    let holed = load_in(&text, d).unwrap();
    let cut = load_in(&text, &sub).unwrap();
    let mut a = granflow::setup::build_granular_2d(&holed, 1);
    let mut b = granflow::setup::build_granular_2d(&cut, 1);
    let m0 = a.diagnostics().mass;
    assert!((m0 - b.diagnostics().mass).abs() < 1e-12 * m0);
    let (nx, ny) = (40, 12);
    let mut moved_back = false;
    for _ in 0..200 {
        let dt_a = a.step(f64::INFINITY).unwrap();
        let dt_b = b.step(f64::INFINITY).unwrap();
        assert_eq!(dt_a, dt_b);
        for j in 0..ny {
            for i in 0..nx {
                let k = j * nx + i;
                if i >= 30 {
                    assert_eq!(a.state.h[k], 0.0, "mass in the wall cell ({i}, {j})");
                    assert_eq!((a.state.hu[k], a.state.hv[k]), (0.0, 0.0));
                } else {
                    let kb = j * 30 + i;
                    assert!((a.state.h[k] - b.state.h[kb]).abs() < 1e-12);
                    assert!((a.state.hu[k] - b.state.hu[kb]).abs() < 1e-12);
                    assert!((a.state.hv[k] - b.state.hv[kb]).abs() < 1e-12);
                }
            }
        }
        let m = a.diagnostics().mass;
        assert!((m - m0).abs() < 1e-13 * m0, "volume {m} against {m0}");
        // Reflected: the cells against the wall flow back (u < 0) at some point.
        moved_back |= (0..ny).any(|j| a.state.hu[j * nx + 29] < -1e-3);
    }
    assert!(moved_back, "the flow never reflected off the nodata cells");
}

/// A release next to a square nodata hole inside the DEM: the volume is conserved,
/// the hole stays empty, and mass flows around it.
#[test]
fn a_nodata_hole_stays_empty_and_the_volume_is_conserved() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let tan = 30f64.to_radians().tan();
    write_dem(&d.join("dem.asc"), (40, 30, 1.0), (0.0, 0.0), |c, r| {
        if (20..25).contains(&c) && (12..17).contains(&r) {
            -9999.0
        } else {
            40.0 - c as f64 * tan
        }
    });
    write_polygon(
        &d.join("release.geojson"),
        &[[8.0, 10.0], [18.0, 10.0], [18.0, 20.0], [8.0, 20.0]],
        None,
    );
    let h = r#"{ polygon = "release.geojson", thickness = 1, thickness_is = "vertical" }"#;
    let scn = load_in(
        &scenario(h, "").replace("mu_deg = 30.0", "mu_deg = 15.0"),
        d,
    )
    .unwrap();
    assert_eq!(scn.sampled.wall.iter().filter(|&&w| w).count(), 25);
    let mut sim = granflow::setup::build_granular_2d(&scn, 1);
    let m0 = sim.diagnostics().mass;
    assert!((m0 - 100.0).abs() < 1e-9);
    for _ in 0..300 {
        sim.step(f64::INFINITY).unwrap();
        for (k, &w) in scn.sampled.wall.iter().enumerate() {
            if w {
                assert_eq!(sim.state.h[k], 0.0);
            }
        }
    }
    let m = sim.diagnostics().mass;
    assert!((m - m0).abs() < 1e-13 * m0, "volume {m} against {m0}");
    // Mass went past the hole: some cell beyond it (column ≥ 25) is wet.
    let nx = 40;
    assert!((0..sim.state.h.len()).any(|k| k % nx >= 25 && sim.state.h[k] > 1e-3));
}

/// `domain.crop` and `domain.coarsen`: the grid of the cropped and coarsened DEM, the
/// same released volume (area fraction), a thickness raster coarsened by block means
/// (its volume kept), a block all nodata becomes a wall.
#[test]
fn a_cropped_and_coarsened_run_has_its_grid_and_its_volume() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // 40 × 30 cells of 5 m from (1000, 2000); one nodata cell and a 2 × 2 nodata block.
    write_dem(
        &d.join("dem.asc"),
        (40, 30, 5.0),
        (1000.0, 2000.0),
        |c, r| {
            if (c, r) == (10, 10) || ((20..22).contains(&c) && (4..6).contains(&r)) {
                -9999.0
            } else {
                c as f64 + 0.1 * r as f64
            }
        },
    );
    write_polygon(
        &d.join("release.geojson"),
        &QUAD.map(|p| [p[0] + 1040.0, p[1] + 2040.0]),
        None,
    );
    let h = r#"{ polygon = "release.geojson", thickness = 1.5, thickness_is = "vertical" }"#;
    let exact = shoelace(&QUAD) * 1.5;
    let fine = load_in(&scenario(h, ""), d).unwrap();
    assert_eq!(
        (fine.domain.cells, fine.domain.plane.as_ref().unwrap().ny),
        (40, 30)
    );
    // Crop to the centres in x ∈ [1012, 1163], y ∈ [2021, 2140]: columns 2..32 (31),
    // rows from the top 2..25 (24); coarsened by 2: the last column is left out.
    let extra = "crop = [1012.0, 1163.0, 2021.0, 2140.0]\ncoarsen = 2\n";
    let coarse = load_in(&scenario(h, extra), d).unwrap();
    let plane = coarse.domain.plane.as_ref().unwrap();
    assert_eq!((coarse.domain.cells, plane.ny), (15, 12));
    assert_eq!((coarse.domain.x_min, coarse.domain.x_max), (1010.0, 1160.0));
    assert_eq!((plane.y_min, plane.y_max), (2020.0, 2140.0));
    assert!(
        coarse.notes.iter().any(|n| n.contains("left out")),
        "{:?}",
        coarse.notes
    );
    for scn in [&fine, &coarse] {
        let v = scn.release.as_ref().unwrap().volume;
        assert!((v - exact).abs() < 1e-12 * exact, "{v} against {exact}");
    }
    // Bed: block means of the valid cells; the all-nodata block (columns 20, 21,
    // rows from the top 4, 5) is a wall: coarse column 9, row from the top 1, i.e.
    // row from the south 10.
    let wall: Vec<usize> = (0..coarse.sampled.wall.len())
        .filter(|&k| coarse.sampled.wall[k])
        .collect();
    assert_eq!(wall, vec![10 * 15 + 9]);
    // Coarse cell (column 4, row from the top 4) holds fine columns 10, 11 and rows
    // 10, 11 from the top, one of them nodata.
    let k = (12 - 1 - 4) * 15 + 4;
    let expected = ((11.0 + 1.0) + (10.0 + 1.1) + (11.0 + 1.1)) / 3.0;
    assert!(
        (coarse.sampled.b[k] - expected).abs() < 1e-12,
        "{}",
        coarse.sampled.b[k]
    );
    // A thickness raster on the DEM's grid is cut and coarsened with it: block means
    // keep the volume inside the crop.
    write_dem(&d.join("h.asc"), (40, 30, 5.0), (1000.0, 2000.0), |c, r| {
        if (8..14).contains(&c) && (6..16).contains(&r) {
            0.5 + 0.01 * c as f64
        } else {
            0.0
        }
    });
    let raster_h = load_in(&scenario(r#"{ raster = "h.asc" }"#, extra), d).unwrap();
    let volume: f64 = raster_h.sampled.h.iter().sum::<f64>() * 100.0;
    let fine_volume: f64 = (8..14)
        .flat_map(|c| (6..16).map(move |_| (0.5 + 0.01 * c as f64) * 25.0))
        .sum();
    assert!(
        (volume - fine_volume).abs() < 1e-9,
        "{volume} against {fine_volume}"
    );
    // The keys are checked.
    for (extra, key, words) in [
        ("crop = [1.0, 2.0]\n", "domain.crop", "four numbers"),
        (
            "crop = [1100.0, 1000.0, 2000.0, 2100.0]\n",
            "domain.crop",
            "x_min < x_max",
        ),
        (
            "crop = [0.0, 10.0, 0.0, 10.0]\n",
            "domain.crop",
            "no cell centre",
        ),
        ("coarsen = 0\n", "domain.coarsen", "at least 1"),
        ("coarsen = 50\n", "domain.coarsen", "50 × 50"),
    ] {
        let message = fails_at(&scenario(h, extra), d, key);
        assert!(message.contains(words), "{key}: {message}");
    }
    let keyed = scenario(h, "x_min = 1000.0\nx_max = 1200.0\ny_min = 2000.0\ny_max = 2150.0\ncells = [40, 30]\ncoarsen = 2\n");
    let message = fails_at(&keyed, d, "domain.coarsen");
    assert!(message.contains("grid of a raster bed"), "{message}");
}

/// A DEM in a geographic CRS has coordinates in degrees, which the run would take as
/// metres: refused naming the file, and so is a release polygon in one.
#[test]
fn inputs_in_a_geographic_crs_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write_dem(&d.join("dem.asc"), (10, 8, 5.0), (0.0, 0.0), |_, _| 0.0);
    fs::write(
        d.join("dem.prj"),
        r#"GEOGCS["WGS 84",DATUM["WGS_1984",SPHEROID["WGS 84",6378137,298.257223563]],PRIMEM["Greenwich",0],UNIT["degree",0.0174532925199433],AUTHORITY["EPSG","4326"]]"#,
    )
    .unwrap();
    let message = fails_at(&scenario("0.5", ""), d, "bed.b");
    assert!(message.contains("dem.asc"), "{message}");
    assert!(message.contains("geographic CRS (EPSG:4326)"), "{message}");
    fs::remove_file(d.join("dem.prj")).unwrap();
    write_polygon(
        &d.join("release.geojson"),
        &[[10.0, 10.0], [20.0, 10.0], [20.0, 20.0]],
        Some(4326),
    );
    let polygon = r#"{ polygon = "release.geojson", thickness = 1, thickness_is = "vertical" }"#;
    let message = fails_at(&scenario(polygon, ""), d, "initial.h.polygon");
    assert!(message.contains("release.geojson"), "{message}");
    assert!(message.contains("geographic CRS"), "{message}");
}

/// Rasters whose cells vanish in the round-off of their coordinates (cells of 5 m at
/// x = 10¹⁷, of 10⁻³⁰⁰ m at x = 1, a corner at 10³⁰⁰) are refused naming the file,
/// as a domain's keys are (they used to panic).
#[test]
fn rasters_whose_cells_vanish_in_round_off_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    for (cells, corner) in [
        ((10, 8, 5.0), (1e17, 0.0)),
        ((10, 8, 1e-300), (1.0, 0.0)),
        ((10, 8, 1.0), (0.0, 1e300)),
    ] {
        write_dem(&d.join("dem.asc"), cells, corner, |_, _| 0.0);
        let message = fails_at(&scenario("0.5", ""), d, "bed.b");
        assert!(message.contains("dem.asc"), "{message}");
        assert!(message.contains("round-off"), "{message}");
        // Numbers in exponent form, not the 300 digits of 1e300.
        assert!(!message.contains(&"0".repeat(20)), "{message}");
    }
}

/// A polygon whose ring has no area is refused as such (it used to be "outside the
/// raster", although it lay inside).
#[test]
fn a_zero_area_release_is_refused_as_such() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write_dem(&d.join("dem.asc"), (10, 8, 5.0), (0.0, 0.0), |_, _| 0.0);
    write_polygon(
        &d.join("release.geojson"),
        &[[10.0, 10.0], [20.0, 20.0], [30.0, 30.0]],
        None,
    );
    let polygon = r#"{ polygon = "release.geojson", thickness = 1, thickness_is = "vertical" }"#;
    let message = fails_at(&scenario(polygon, ""), d, "initial.h.polygon");
    assert!(message.contains("release.geojson"), "{message}");
    assert!(message.contains("feature 0"), "{message}");
    assert!(message.contains("encloses no area"), "{message}");
    assert!(!message.contains("outside the raster"), "{message}");
}

/// A raster run of one row records its cell sizes (dy is no NaN), and `export` places
/// it by them: square cells export where they are, cells taller than wide are refused
/// (a GeoTIFF needs square cells) instead of exported as squares in the wrong place.
#[test]
fn a_run_of_one_row_exports_where_it_is_or_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let text = |y_max: f64| {
        format!(
            "[domain]\nx_min = 0\nx_max = 10\ny_min = 0\ny_max = {y_max}\ncells = [10, 1]\ncoordinates = \"cartesian\"\n\n[rheology]\nlaw = \"coulomb\"\nmu_deg = 30\n\n[initial]\nh = \"if(x < 3, 1, 0)\"\n\n[time]\nt_end = 0.2\n\n[output]\nevery = 0.1\n"
        )
    };
    fs::write(d.join("square.toml"), text(1.0)).unwrap();
    fs::write(d.join("tall.toml"), text(2.0)).unwrap();
    for name in ["square", "tall"] {
        let (code, stderr) = granflow_in(d, &["run", &format!("{name}.toml"), "--quiet"]);
        assert_eq!(code, Some(0), "{stderr}");
        let f = rust_hdf5::H5File::open(d.join(format!("{name}.h5"))).unwrap();
        let y = f.dataset("grid/y").unwrap();
        let spacing: f64 = y.attr("spacing").unwrap().read_numeric().unwrap();
        assert_eq!(spacing, if name == "square" { 1.0 } else { 2.0 });
    }
    let (code, stderr) = granflow_in(d, &["export", "square.h5", "--fields", "pft"]);
    assert_eq!(code, Some(0), "{stderr}");
    let r = granflow::gis::geotiff::read(&d.join("square_pft.tif")).unwrap();
    assert_eq!((r.nx, r.ny, r.cell_size), (10, 1, 1.0));
    assert_eq!((r.x_left, r.y_top), (0.0, 1.0));
    let (code, stderr) = granflow_in(d, &["export", "tall.h5", "--fields", "pft"]);
    assert_eq!(code, Some(2), "{stderr}");
    assert!(stderr.contains("not square"), "{stderr}");
    assert!(stderr.contains("dy = 2"), "{stderr}");
    // A negative time is granflow's to refuse (the argument parser took `-1` for an
    // option).
    let (code, stderr) = granflow_in(d, &["export", "square.h5", "--time", "-1"]);
    assert_eq!(code, Some(2), "{stderr}");
    assert!(
        stderr.contains("--time -1: outside the snapshots' times [0, 0.2] s"),
        "{stderr}"
    );
}

/// `scripts/check_output.py` accepts a run with wall cells (NaN by design in
/// `/grid/b`, the snapshots and the maps): the bundled DEM scenario, coarsened.
#[test]
fn check_output_accepts_a_run_with_nodata_walls() {
    let Some(python) = python_with_h5py() else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let h5 = dir.path().join("walls.h5");
    let scn = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/dem_release.toml");
    let out = granflow()
        .arg("run")
        .arg(&scn)
        .args(["--quiet", "--set", "domain.coarsen=2"])
        .args(["--set", "time.t_end=2", "--set", "output.every=1", "-o"])
        .arg(&h5)
        .output()
        .unwrap();
    crate::common::assert_success(&out);
    let f = rust_hdf5::H5File::open(&h5).unwrap();
    let walls: i64 = f
        .dataset("grid/b")
        .unwrap()
        .read_raw::<f64>()
        .unwrap()
        .iter()
        .filter(|v| v.is_nan())
        .count() as i64;
    assert!(walls > 0, "the scenario has no wall cell");
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("scripts/check_output.py");
    let out = Command::new(python).arg(script).arg(&h5).output().unwrap();
    let stdout = crate::common::assert_success(&out);
    assert!(stdout.starts_with("OK"), "{stdout}");
}

/// `domain.coarsen` on a DEM whose cell size is not round (4.9977 m, corner at
/// 1.8e5 m, as real survey grids are): the grid is trimmed to a multiple of each
/// factor 2–6 by whole cells and coarsened, never a lost row and a panic. `check`
/// exits 0 and names the coarse grid.
#[test]
fn coarsening_a_grid_of_non_round_cell_size_trims_whole_cells() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let cell = 4.9977;
    write_dem(
        &d.join("dem.asc"),
        (37, 29, cell),
        (180_123.4, 101_987.6),
        |c, r| 0.3 * c as f64 + 0.1 * r as f64,
    );
    let h = r#"{ polygon = "release.geojson", thickness = 1.0, thickness_is = "vertical" }"#;
    write_polygon(
        &d.join("release.geojson"),
        &[
            [180_150.0, 102_050.0],
            [180_220.0, 102_050.0],
            [180_220.0, 102_100.0],
            [180_150.0, 102_100.0],
        ],
        None,
    );
    for k in 2..=6usize {
        let text = scenario(h, &format!("coarsen = {k}\n"));
        let scn = load_in(&text, d).unwrap_or_else(|e| panic!("coarsen = {k}: {e}"));
        let plane = scn.domain.plane.as_ref().unwrap();
        assert_eq!((scn.domain.cells, plane.ny), (37 / k, 29 / k), "k = {k}");
        // The top-left corner is kept and the cells are k times as wide.
        let dx = (scn.domain.x_max - scn.domain.x_min) / (37 / k) as f64;
        assert!((dx - k as f64 * cell).abs() < 1e-9, "k = {k}: {dx}");
        assert!((scn.domain.x_min - 180_123.4).abs() < 1e-6, "k = {k}");
        assert!(
            (plane.y_max - (101_987.6 + 29.0 * cell)).abs() < 1e-6,
            "k = {k}"
        );
        fs::write(d.join("s.toml"), &text).unwrap();
        let (code, stderr) = granflow_in(d, &["check", "s.toml"]);
        assert_eq!(code, Some(0), "coarsen = {k}: {stderr}");
        assert!(!stderr.contains("panicked"), "{stderr}");
    }
}

/// Whether a GeoTIFF has a GeoKey directory (34735).
fn has_geo_keys(path: &Path) -> bool {
    let file = std::io::BufReader::new(fs::File::open(path).unwrap());
    let mut dec = tiff::decoder::Decoder::new(file).unwrap();
    dec.find_tag(tiff::tags::Tag::GeoKeyDirectoryTag)
        .unwrap()
        .is_some()
}

/// The CRS of the inputs reaches the outputs, or the user is told: a DEM `.asc`
/// without its `.prj` under a release that states EPSG:32632 runs in EPSG:32632 (a
/// note says so) and its exports carry it (a GeoTIFF key, a `.prj` made from the
/// code, NetCDF `crs_wkt`); without any CRS the GeoTIFF has no GeoKey directory
/// (GDAL reads "no CRS", not a LOCAL_CS that `rio info` fails on) and `export` warns.
/// The exported grid is the DEM's exactly (corner and cell size as read, in doubles),
/// also for a cell size that is not round.
#[test]
fn the_crs_and_the_grid_of_the_inputs_reach_the_exports() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (x0, y0, cell) = (612_345.67, 5_123_456.7, 4.9977);
    write_dem(&d.join("dem.asc"), (30, 20, cell), (x0, y0), |c, _| {
        100.0 - 0.5 * c as f64
    });
    let ring =
        [[20.0, 40.0], [45.0, 40.0], [45.0, 65.0], [20.0, 65.0]].map(|p| [p[0] + x0, p[1] + y0]);
    write_polygon(&d.join("release.geojson"), &ring, Some(32632));
    let h = r#"{ polygon = "release.geojson", thickness = 1.0, thickness_is = "vertical" }"#;
    let text = scenario(h, "").replace("t_end = 1.0", "t_end = 0.5");
    fs::write(d.join("s.toml"), &text).unwrap();
    let (code, stderr) = granflow_in(d, &["check", "s.toml"]);
    assert_eq!(code, Some(0), "{stderr}");
    assert!(
        stderr.contains("states no CRS") && stderr.contains("EPSG:32632"),
        "{stderr}"
    );
    let (code, stderr) = granflow_in(d, &["run", "s.toml", "--quiet", "--output", "r.h5"]);
    assert_eq!(code, Some(0), "{stderr}");
    for format in ["geotiff", "asc", "netcdf"] {
        let (code, stderr) = granflow_in(
            d,
            &["export", "r.h5", "--format", format, "-o", "out", "--quiet"],
        );
        assert_eq!(code, Some(0), "{format}: {stderr}");
        assert!(!stderr.contains("warning"), "{format}: {stderr}");
    }
    let tif = granflow::gis::geotiff::read(&d.join("out/r_pft.tif")).unwrap();
    assert_eq!(tif.crs.epsg, Some(32632));
    assert_eq!(
        (tif.x_left, tif.y_top, tif.cell_size),
        (x0, y0 + 20.0 * cell, cell)
    );
    let dem = granflow::gis::asc::read(&d.join("dem.asc")).unwrap();
    assert_eq!(
        (tif.x_left, tif.y_top, tif.cell_size),
        (dem.x_left, dem.y_top, dem.cell_size)
    );
    let asc = granflow::gis::asc::read(&d.join("out/r_pft.asc")).unwrap();
    assert_eq!(asc.crs.epsg, Some(32632), "no .prj made from the code");
    assert_eq!(
        (asc.x_left, asc.y_top, asc.cell_size),
        (dem.x_left, dem.y_top, dem.cell_size)
    );
    let nc = fs::read(d.join("out/r_maps.nc")).unwrap();
    let nc = String::from_utf8_lossy(&nc);
    assert!(nc.contains("crs_wkt") && nc.contains(r#"AUTHORITY["EPSG","32632"]"#));

    // No CRS anywhere: no GeoKey directory, and a warning.
    write_polygon(&d.join("release.geojson"), &ring, None);
    let (code, stderr) = granflow_in(d, &["run", "s.toml", "--quiet", "--output", "u.h5"]);
    assert_eq!(code, Some(0), "{stderr}");
    let (code, stderr) = granflow_in(d, &["export", "u.h5", "-o", "out", "--quiet"]);
    assert_eq!(code, Some(0), "{stderr}");
    assert!(stderr.contains("warning: the run has no CRS"), "{stderr}");
    assert!(!has_geo_keys(&d.join("out/u_pft.tif")));
    assert!(has_geo_keys(&d.join("out/r_pft.tif")));
}
