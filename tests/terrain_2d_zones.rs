//! Zones of a raster run: the friction coefficients μ and ξ as fields (raster files or
//! expressions in x, y), the erodible bed as a number, an expression or a raster (a
//! layer of grains at rest added under the flow, Fernández-Nieto et al. 2016, §4.2),
//! and gauges that would read a wall (nodata) cell.

use std::fs;
use std::path::Path;
use std::process::Command;

use assert_cmd::prelude::*;
use granflow::output::memory::MemorySink;
use granflow::scenario::Scenario;

use crate::common::{fails_at, load_in};
use granflow::setup::{build_granular, build_granular_2d};

/// An ESRI ASCII grid of `ncols` × `nrows` cells of `d` m, lower-left corner (0, 0),
/// nodata −9999, with value(x, y) at the cell centres.
fn write_asc(path: &Path, (ncols, nrows, d): (usize, usize, f64), value: impl Fn(f64, f64) -> f64) {
    let mut text = format!(
        "ncols {ncols}\nnrows {nrows}\nxllcorner 0\nyllcorner 0\ncellsize {d}\nNODATA_value -9999\n"
    );
    for row in 0..nrows {
        let y = (nrows - 1 - row) as f64 * d + 0.5 * d;
        let line: Vec<String> = (0..ncols)
            .map(|c| format!("{}", value(c as f64 * d + 0.5 * d, y)))
            .collect();
        text.push_str(&line.join(" "));
        text.push('\n');
    }
    fs::write(path, text).unwrap();
}

/// A raster domain [0, 4] × [0, 1] of 80 × 20 cells of 5 cm, a Cartesian plane falling
/// along x with slope 0.2, walls all round; `rheology` and `initial` are the tables'
/// bodies.
fn plane(rheology: &str, initial: &str) -> String {
    format!(
        r#"[domain]
x_min = 0.0
x_max = 4.0
y_min = 0.0
y_max = 1.0
cells = [80, 20]
coordinates = "cartesian"

[bed]
b = "-0.2 * x"

[rheology]
{rheology}

[initial]
{initial}

[time]
t_end = 2.0
"#
    )
}

/// Two cones of slope 0.3 and height 0.1 on the plane, one in each half; the first
/// reaches down to x = 1.983, its last wet cells against the line x = 2.
const TWO_CONES: &str =
    "h = \"max(0, 0.1 - 0.3 * sqrt((x - 1.65)^2 + (y - 0.5)^2)) + max(0, 0.1 - 0.3 * sqrt((x - 3)^2 + (y - 0.5)^2))\"";

/// Steps both runs `steps` times and asserts that their states are the same bits.
fn same_bits(a: &Scenario, b: &Scenario, steps: usize) {
    let (mut a, mut b) = (build_granular_2d(a, 1), build_granular_2d(b, 1));
    for step in 0..steps {
        let (dt_a, dt_b) = (
            a.step(f64::INFINITY).unwrap(),
            b.step(f64::INFINITY).unwrap(),
        );
        assert_eq!(dt_a, dt_b, "step {step}");
        assert_eq!(a.state.h, b.state.h, "h, step {step}");
        assert_eq!(a.state.hu, b.state.hu, "hu, step {step}");
        assert_eq!(a.state.hv, b.state.hv, "hv, step {step}");
    }
    assert!(a.state.hu.iter().any(|&q| q != 0.0), "the case must flow");
}

/// A μ (and ξ) raster of one value everywhere, on the domain's grid, gives the bits of
/// the number: the per-cell laws are the uniform law in every cell.
#[test]
fn a_uniform_friction_raster_gives_the_bits_of_the_number() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write_asc(&d.join("mu.asc"), (80, 20, 0.05), |_, _| 0.15);
    write_asc(&d.join("xi.asc"), (80, 20, 0.05), |_, _| 400.0);
    let coulomb = |mu: &str| plane(&format!("law = \"coulomb\"\nmu = {mu}"), TWO_CONES);
    let number = load_in(&coulomb("0.15"), d).unwrap();
    let raster = load_in(&coulomb("{ raster = \"mu.asc\" }"), d).unwrap();
    assert!(raster.friction_zones.is_some());
    same_bits(&number, &raster, 60);
    let voellmy = |mu: &str, xi: &str| {
        plane(
            &format!("law = \"voellmy\"\nmu = {mu}\nxi = {xi}"),
            TWO_CONES,
        )
    };
    let number = load_in(&voellmy("0.15", "400"), d).unwrap();
    let raster = load_in(
        &voellmy("{ raster = \"mu.asc\" }", "{ raster = \"xi.asc\" }"),
        d,
    )
    .unwrap();
    same_bits(&number, &raster, 60);
    // An expression of one value is a field too.
    let expression = load_in(&voellmy("\"0.15 + 0*x\"", "400"), d).unwrap();
    same_bits(&number, &expression, 60);
}

/// Two friction zones on the plane of slope 0.2: μ = 0.8 for x < 2 holds the cone
/// there (surface slopes at most 0.5), μ = 0.1 for x > 2 lets the other one slide. The
/// held cone's downhill rim lies against the zones' edge: the faces there hold its
/// mass with its own cells' μ (the μ of the cell the drive empties), not the μ of the
/// dry cells it would flow into.
#[test]
fn two_friction_zones_hold_one_mass_and_release_the_other() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write_asc(&d.join("mu.asc"), (80, 20, 0.05), |x, _| {
        if x < 2.0 {
            0.8
        } else {
            0.1
        }
    });
    let text = plane("law = \"coulomb\"\nmu = { raster = \"mu.asc\" }", TWO_CONES);
    let scn = load_in(&text, d).unwrap();
    assert_eq!(
        scn.friction,
        granflow::scenario::FrictionLaw::Coulomb { mu: 0.1 }
    );
    let mut sim = build_granular_2d(&scn, 1);
    let h0 = sim.state.h.clone();
    let centre = |h: &[f64], right: bool| {
        let (mut m, mut mx) = (0.0, 0.0);
        for (k, &h) in h.iter().enumerate() {
            let x = (k % 80) as f64 * 0.05 + 0.025;
            if (x > 2.0) == right {
                m += h;
                mx += h * x;
            }
        }
        mx / m
    };
    for _ in 0..300 {
        sim.step(f64::INFINITY).unwrap();
    }
    // Held: what moves in the left half is round-off (the rest state is kept to
    // 1e-14 of the cone's 0.1 m, not to the bit).
    let (mut dh, mut dq) = (0.0f64, 0.0f64);
    for k in (0..h0.len()).filter(|k| k % 80 < 40) {
        dh = dh.max((sim.state.h[k] - h0[k]).abs());
        dq = dq.max(sim.state.hu[k].hypot(sim.state.hv[k]));
    }
    eprintln!("held cone: max |h - h0| = {dh:e} m, max |q| = {dq:e} m²/s");
    assert!(
        dh < 1e-15 && dq < 1e-15,
        "the held cone moved: {dh:e} m, {dq:e} m²/s"
    );
    let slid = centre(&sim.state.h, true) - centre(&h0, true);
    assert!(
        slid > 0.3,
        "the cone on μ = 0.1 moved its centre by {slid} m only"
    );
    // Both on μ = 0.1 or both on μ = 0.8: the zones are what tells them apart.
    for (mu, left_moves) in [("0.1", true), ("0.8", false)] {
        let text = plane(&format!("law = \"coulomb\"\nmu = {mu}"), TWO_CONES);
        let mut sim = build_granular_2d(&load_in(&text, d).unwrap(), 1);
        for _ in 0..300 {
            sim.step(f64::INFINITY).unwrap();
        }
        let moved = (0..h0.len())
            .filter(|k| k % 80 < 40)
            .fold(0.0f64, |m, k| m.max((sim.state.h[k] - h0[k]).abs()));
        assert_eq!(
            moved > 1e-3,
            left_moves,
            "μ = {mu}: the left cone moved {moved} m"
        );
    }
}

/// Voellmy's ξ in zones: a larger ξ (less turbulent drag) where the flow runs lengthens
/// the runout, between the runs with the small and the large ξ everywhere.
#[test]
fn xi_zones_change_the_voellmy_runout_in_the_expected_direction() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let front = |xi: &str| {
        let text = plane(
            &format!("law = \"voellmy\"\nmu = 0.1\nxi = {xi}"),
            "h = \"if(x < 0.6, 0.2, 0)\"",
        )
        .replace("b = \"-0.2 * x\"", "b = \"-0.4 * x\"");
        let mut sim = build_granular_2d(&load_in(&text, d).unwrap(), 1);
        let mut t = 0.0;
        while t < 1.0 {
            t += sim.step(1.0 - t).unwrap();
        }
        sim.diagnostics().front_x
    };
    let low = front("50");
    let zoned = front("\"if(x > 1.2, 5000, 50)\"");
    let high = front("5000");
    assert!(
        low < zoned && zoned <= high,
        "fronts: ξ = 50 {low}, zones {zoned}, ξ = 5000 {high}"
    );
    assert!(
        zoned - low > 0.1,
        "the zone changed the front by {} m",
        zoned - low
    );
}

/// Bad friction fields are refused naming the key and the file: a raster of another
/// size than the DEM's grid, a negative μ, a nodata cell, a ξ ≤ 0; a field on a line;
/// through the command line with exit code 2.
#[test]
fn bad_friction_fields_are_refused_naming_the_key_and_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write_asc(&d.join("dem.asc"), (20, 10, 0.1), |x, _| -0.2 * x);
    let text = |mu: &str| {
        format!(
            "[domain]\ncoordinates = \"cartesian\"\n[bed]\nb = {{ raster = \"dem.asc\" }}\n[rheology]\nlaw = \"voellmy\"\nmu = {mu}\nxi = 500\n[initial]\nh = \"if(x < 0.5, 0.1, 0)\"\n[time]\nt_end = 0.1\n"
        )
    };
    let mu = "{ raster = \"mu.asc\" }";
    write_asc(&d.join("mu.asc"), (20, 10, 0.1), |_, _| 0.3);
    assert!(load_in(&text(mu), d).is_ok());
    type Case = (&'static str, fn(&Path), &'static str, Vec<&'static str>);
    let cases: Vec<Case> = vec![
        (
            "a raster of another size",
            |d| write_asc(&d.join("mu.asc"), (21, 10, 0.1), |_, _| 0.3),
            "rheology.mu",
            vec!["mu.asc", "21 × 10"],
        ),
        (
            "a negative μ",
            |d| {
                write_asc(&d.join("mu.asc"), (20, 10, 0.1), |x, _| {
                    if x > 1.0 {
                        -0.1
                    } else {
                        0.3
                    }
                })
            },
            "rheology.mu",
            vec!["mu.asc", "-0.1", "≥ 0"],
        ),
        (
            "a nodata cell",
            |d| {
                write_asc(&d.join("mu.asc"), (20, 10, 0.1), |x, y| {
                    if x > 1.0 && y > 0.5 {
                        -9999.0
                    } else {
                        0.3
                    }
                })
            },
            "rheology.mu",
            vec!["mu.asc", "nodata"],
        ),
    ];
    fs::write(d.join("s.toml"), text(mu)).unwrap();
    for (what, make, key, words) in cases {
        make(d);
        let m = fails_at(&text(mu), d, key);
        for w in &words {
            assert!(m.contains(w), "{what}: no `{w}` in {m}");
        }
        for command in ["check", "run"] {
            let out = Command::cargo_bin("granflow")
                .unwrap()
                .current_dir(d)
                .args([command, "s.toml"])
                .output()
                .unwrap();
            let stderr = String::from_utf8_lossy(&out.stderr);
            assert_eq!(out.status.code(), Some(2), "{what} ({command}): {stderr}");
            assert!(
                stderr.contains(key) && stderr.contains("mu.asc"),
                "{stderr}"
            );
            assert!(!stderr.contains("panicked"), "{stderr}");
        }
    }
    write_asc(&d.join("mu.asc"), (20, 10, 0.1), |_, _| 0.3);
    let m = fails_at(
        &text(mu).replace("xi = 500", "xi = \"100 - 100 * x\""),
        d,
        "rheology.xi",
    );
    assert!(m.contains("> 0"), "{m}");
    let m = fails_at(
        &text("\"88 + 2 * x\"").replace("mu = ", "mu_deg = "),
        d,
        "rheology.mu_deg",
    );
    assert!(m.contains("[0, 90)"), "{m}");
    assert!(load_in(&text("\"30 - x\"").replace("mu = ", "mu_deg = "), d).is_ok());
    // A line has one law: a field is refused there.
    let line = "[domain]\nx_min = 0.0\nx_max = 1.0\ncells = 10\n[rheology]\nlaw = \"coulomb\"\nmu = \"0.3 + 0.1 * x\"\n[initial]\nh = 0.1\n[time]\nt_end = 1.0\n";
    let m = fails_at(line, d, "rheology.mu");
    assert!(m.contains("raster domain"), "{m}");
    // μ(I) has no zones: its keys are its own.
    let mu_i = text(mu).replace(
        "law = \"voellmy\"\nmu = { raster = \"mu.asc\" }\nxi = 500",
        "law = \"mu_i\"\nmu_s = { raster = \"mu.asc\" }\nmu_2 = 0.6\ni0 = 0.3",
    );
    fails_at(&mu_i, d, "rheology.mu_s");
}

/// The monolayer μ(I) collapse on an erodible bed (Fernández-Nieto et al. 2016, §4.2,
/// θ = 22°, h_i = 1.82 mm): the raster run invariant in y is the line's run, step by
/// step, to the bit.
#[test]
fn a_y_invariant_erodible_bed_run_reproduces_the_line() {
    let dir = tempfile::tempdir().unwrap();
    let line = r#"[domain]
x_min = -0.2
x_max = 1.4
cells = 160
slope_deg = 22.0

[rheology]
law = "mu_i"
mu_s_deg = 25.5
mu_2_deg = 36.5
i0 = 0.279

[initial]
h = "if(x <= 0, 0.14, 0)"
erodible_bed = 1.82e-3

[boundary]
left = "wall"
right = "outflow"

[time]
t_end = 8.0
"#;
    let raster = line
        .replace("cells = 160", "cells = [160, 3]\ny_min = 0.0\ny_max = 0.03")
        .replace(
            "left = \"wall\"\nright = \"outflow\"",
            "west = \"wall\"\neast = \"outflow\"",
        );
    let (a, b) = (
        load_in(line, dir.path()).unwrap(),
        load_in(&raster, dir.path()).unwrap(),
    );
    let (mut one, mut two) = (build_granular(&a), build_granular_2d(&b, 1));
    let nx = 160;
    for step in 0..400 {
        let (d1, d2) = (one.diagnostics(), two.diagnostics());
        assert_eq!(d1.front_x, d2.front_x, "front, step {step}");
        let dt = one.step(f64::INFINITY).unwrap();
        assert_eq!(two.step(f64::INFINITY).unwrap(), dt, "step {step}");
        for k in 0..3 * nx {
            assert_eq!(
                two.state.h[k],
                one.state.h[k % nx + 1],
                "step {step}, cell {k}"
            );
            assert_eq!(
                two.state.hu[k],
                one.state.hu[k % nx + 1],
                "step {step}, cell {k}"
            );
        }
    }
    // The bed layer was mobilised ahead of the column: the front (counted above the
    // bed) moved and cells beyond it lost part of their layer or gained.
    assert!(two.diagnostics().front_x > 0.1);
    assert!(two.state.h.iter().any(|&h| h > 0.0 && h != 1.82e-3));
}

/// An erodible layer on a slope below its angle of repose, with no release: it stays
/// at rest, and the maps (counted above the layer) stay zero; `/grid/h_bed` holds it.
#[test]
fn an_erodible_layer_below_repose_stays_at_rest_and_its_maps_stay_zero() {
    let dir = tempfile::tempdir().unwrap();
    let text = plane(
        "law = \"coulomb\"\nmu_deg = 20.0",
        "h = 0.0\nerodible_bed = \"0.01 + 0.002 * y\"",
    )
    .replace("t_end = 2.0", "t_end = 0.5\n[output]\nevery = 0.25");
    let scn = load_in(&text, dir.path()).unwrap();
    let mut sim = build_granular_2d(&scn, 1);
    let h0 = sim.state.h.clone();
    assert!(h0.iter().all(|&h| h >= 0.01));
    let mut sink = MemorySink::default();
    sim.run(&mut sink, &mut |_| {}).unwrap();
    // At rest up to round-off (1e-13 of the 1 cm layer; the reconstruction's flat
    // surface of a state at rest is exact to a few ulps per face): no flow, no creep.
    let dh = sim
        .state
        .h
        .iter()
        .zip(&h0)
        .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
    let dq = sim
        .state
        .hu
        .iter()
        .zip(&sim.state.hv)
        .fold(0.0f64, |m, (a, b)| m.max(a.hypot(*b)));
    eprintln!("erodible layer: max |h - h0| = {dh:e} m, max |q| = {dq:e} m²/s");
    assert!(
        dh < 1e-15 && dq < 1e-15,
        "the layer moved: {dh:e} m, {dq:e} m²/s"
    );
    assert_eq!(sink.h_bed, h0, "/grid/h_bed is the layer");
    let map = |name: &str| {
        &sink
            .maps
            .iter()
            .find(|(n, _)| n == name)
            .unwrap_or_else(|| panic!("no map {name}"))
            .1
    };
    for name in ["speed_max", "ppr"] {
        assert!(map(name).iter().all(|&v| v == 0.0), "{name}");
    }
    // The thickness maps count above the layer: zero up to the same round-off.
    for name in ["h_max", "deposit"] {
        let largest = map(name).iter().fold(0.0f64, |m, v| m.max(v.abs()));
        assert!(largest < 1e-15, "{name}: {largest:e}");
    }
    assert!(map("arrival_time").iter().all(|v| v.is_nan()));
    assert!(
        sink.steps.iter().all(|s| s.front_x.is_nan()),
        "a front in a bed at rest"
    );
    let area = sink
        .map_scalars
        .iter()
        .find(|(n, _)| n == "area_reached")
        .unwrap()
        .1;
    assert_eq!(area, 0.0);
}

/// A release above an erodible zone given as a raster: the collapsing column reaches
/// the zone and sets its grains moving, so that the mass in motion grows beyond the
/// released one (without the zone it cannot).
#[test]
fn a_release_entrains_a_raster_erodible_zone() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // The zone 1.2 < x < 2.5 carries 2 cm of grains.
    write_asc(&d.join("bed_layer.asc"), (80, 20, 0.05), |x, _| {
        if x > 1.2 && x < 2.5 {
            0.02
        } else {
            0.0
        }
    });
    let moving_peak = |erodible: &str| {
        let text = plane(
            "law = \"coulomb\"\nmu_deg = 20.0",
            &format!("h = \"if(x > 0.5 && x < 1.0, 0.3, 0)\"\n{erodible}"),
        )
        .replace("b = \"-0.2 * x\"", "b = \"-0.27 * x\"");
        let scn = load_in(&text, d).unwrap();
        let mut sim = build_granular_2d(&scn, 1);
        let (mut peak, mut t) = (0.0f64, 0.0);
        while t < 1.5 {
            t += sim.step(1.5 - t).unwrap();
            let s = &sim.state;
            let moving: f64 = (0..s.h.len())
                .filter(|&k| s.hu[k] != 0.0 || s.hv[k] != 0.0)
                .map(|k| s.h[k])
                .sum();
            peak = peak.max(moving * 0.05 * 0.05);
        }
        peak
    };
    let (released, zone) = (0.5 * 1.0 * 0.3, 1.3 * 1.0 * 0.02);
    let without = moving_peak("");
    let with = moving_peak("erodible_bed = { raster = \"bed_layer.asc\" }");
    eprintln!("mass in motion: {without} m³ without the zone, {with} m³ with it");
    assert!(
        without <= released * (1.0 + 1e-12),
        "{without} > {released}"
    );
    assert!(
        with - released > 0.2 * zone && with <= released + zone,
        "mass in motion {with} m³, released {released} m³, zone {zone} m³"
    );
}

/// A gauge whose interpolation reads a wall (nodata) cell of the DEM is refused, with
/// the gauge and the point; one among cells with data loads.
#[test]
fn a_gauge_on_a_wall_cell_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write_asc(&d.join("dem.asc"), (20, 10, 1.0), |x, y| {
        if x > 10.0 && x < 13.0 && y > 4.0 && y < 7.0 {
            -9999.0
        } else {
            -0.1 * x
        }
    });
    let text = |gauges: &str| {
        format!(
            "[domain]\ncoordinates = \"cartesian\"\n[bed]\nb = {{ raster = \"dem.asc\" }}\n[rheology]\nlaw = \"coulomb\"\nmu = 0.3\n[initial]\nh = \"if(x < 5, 0.5, 0)\"\n[time]\nt_end = 1.0\n[output]\ngauges = {gauges}\n"
        )
    };
    assert!(load_in(&text("[[3.5, 3.5], [15.5, 5.5]]"), d).is_ok());
    let m = fails_at(&text("[[3.5, 3.5], [11.5, 5.5]]"), d, "output.gauges");
    assert!(
        m.contains("gauge 2 at [11.5, 5.5]") && m.contains("wall"),
        "{m}"
    );
    // Beside the hole, the bilinear stencil reaches into it.
    let m = fails_at(&text("[[9.8, 5.5]]"), d, "output.gauges");
    assert!(m.contains("gauge 1") && m.contains("(10.5, 5.5)"), "{m}");
}

/// A GeoJSON file of one rectangle [x0, x1] × [y0, y1] with the property `v`.
fn write_rectangle(path: &Path, [x0, x1, y0, y1]: [f64; 4], v: f64) {
    fs::write(
        path,
        format!(
            r#"{{"type": "FeatureCollection", "features": [{{"type": "Feature", "properties": {{"v": {v}}}, "geometry": {{"type": "Polygon", "coordinates": [[[{x0}, {y0}], [{x1}, {y0}], [{x1}, {y1}], [{x0}, {y1}], [{x0}, {y0}]]]}}}}]}}"#
        ),
    )
    .unwrap();
}

/// Zones from polygons (AvaFrame's resistance and entrainment areas), rasterised as a
/// release is: μ = 0.8 in a rectangle over x < 2 and 0.1 outside gives the bits of the
/// expression `if(x < 2, 0.8, 0.1)` (cell-centre rule; the value from the feature's
/// attribute or from `value`), and an erodible bed of 2 cm over 1.2 < x < 2.5 is the
/// erodible raster of the same zone (area-fraction rule), with a note of its volume.
/// Bad keys are refused by name.
#[test]
fn zones_from_polygons_are_rasterised_as_the_release_is() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write_rectangle(&d.join("res.geojson"), [-1.0, 2.0, -1.0, 2.0], 0.8);
    let coulomb = |mu: &str| plane(&format!("law = \"coulomb\"\nmu = {mu}"), TWO_CONES);
    let expression = load_in(&coulomb("\"if(x < 2, 0.8, 0.1)\""), d).unwrap();
    for mu in [
        r#"{ polygon = "res.geojson", value = 0.8, outside = 0.1, rule = "cell_centre" }"#,
        r#"{ polygon = "res.geojson", value_attribute = "v", outside = 0.1, rule = "cell_centre" }"#,
    ] {
        let zoned = load_in(&coulomb(mu), d).unwrap();
        assert_eq!(
            zoned.friction_zones.as_ref().unwrap().mu,
            expression.friction_zones.as_ref().unwrap().mu,
            "{mu}"
        );
        same_bits(&expression, &zoned, 40);
    }

    write_asc(&d.join("bed_layer.asc"), (80, 20, 0.05), |x, _| {
        if x > 1.2 && x < 2.5 {
            0.02
        } else {
            0.0
        }
    });
    write_rectangle(&d.join("ent.geojson"), [1.2, 2.5, 0.0, 1.0], 0.02);
    let erodible = |bed: &str| {
        plane(
            "law = \"coulomb\"\nmu_deg = 20.0",
            &format!("h = \"if(x > 0.5 && x < 1.0, 0.3, 0)\"\nerodible_bed = {bed}"),
        )
    };
    let raster = load_in(&erodible(r#"{ raster = "bed_layer.asc" }"#), d).unwrap();
    let polygon = load_in(
        &erodible(r#"{ polygon = "ent.geojson", thickness = 0.02, thickness_is = "vertical" }"#),
        d,
    )
    .unwrap();
    assert!(polygon.initial.has_erodible_bed());
    let (a, b) = (&raster.sampled.h_bed, &polygon.sampled.h_bed);
    assert_eq!(a.len(), b.len());
    for k in 0..a.len() {
        assert!(
            (a[k] - b[k]).abs() < 1e-12,
            "cell {k}: {} against {}",
            a[k],
            b[k]
        );
    }
    assert!(
        polygon
            .notes
            .iter()
            .any(|n| n.contains("initial.erodible_bed") && n.contains("erodible volume 2.6")),
        "{:?}",
        polygon.notes
    );

    for (text, key) in [
        (
            coulomb(r#"{ polygon = "res.geojson", value = 0.8 }"#),
            "rheology.mu.outside",
        ),
        (
            coulomb(r#"{ polygon = "res.geojson", outside = 0.1 }"#),
            "rheology.mu.value",
        ),
        (
            coulomb(r#"{ polygon = "res.geojson", value = 0.8, outside = 0.1, colour = 1 }"#),
            "rheology.mu.colour",
        ),
        (
            coulomb(r#"{ polygon = "none.geojson", value = 0.8, outside = 0.1 }"#),
            "rheology.mu.polygon",
        ),
        (
            erodible(r#"{ polygon = "ent.geojson", thickness = 0.02 }"#),
            "initial.erodible_bed.thickness_is",
        ),
    ] {
        fails_at(&text, d, key);
    }
}
