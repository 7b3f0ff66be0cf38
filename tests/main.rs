//! The integration tests, one crate with a module per area (linked once).
//!
//! Run one area with `cargo test --test main AREA::`, e.g.
//! `cargo test --test main analytic::`.
//!
//! Two tiers. `cargo test` runs the quick tier: unit tests, properties, exact solutions
//! on small grids, the CLI, and in every area at least one quick check of its physics.
//! The paper reproductions and refinement studies that take seconds each are the slow
//! tier, one line under their `#[test]`:
//! `#[ignore = "slow: paper reproduction"]` or `#[ignore = "slow: refinement study"]`.
//! `cargo test -- --ignored` runs the slow tier alone, `cargo test -- --include-ignored`
//! both (CI does); add `--include-ignored` to run one slow test by name. No test is
//! ignored for any other reason.

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
mod line_bed_normal;
mod multilayer;
mod multilayer_2d;
mod multilayer_2d_scenario;
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
mod second_order_dilatant;
mod second_order_multilayer;
mod second_order_nh;
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

/// Every `#[ignore]` in the tests and in the crate is a slow-tier marker with one of
/// its two reasons, so that `cargo test -- --include-ignored` (CI) runs the quick tier
/// and the slow tier and nothing that was set aside for another reason.
#[test]
fn every_ignored_test_is_in_the_slow_tier() {
    const MARKERS: [&str; 2] = [
        "#[ignore = \"slow: paper reproduction\"]",
        "#[ignore = \"slow: refinement study\"]",
    ];
    fn visit(dir: &std::path::Path, bad: &mut Vec<String>, marked: &mut usize) {
        for entry in std::fs::read_dir(dir).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                visit(&path, bad, marked);
            } else if path.extension().is_some_and(|e| e == "rs") {
                let text = std::fs::read_to_string(&path).unwrap();
                for (k, line) in text.lines().enumerate() {
                    let line = line.trim();
                    if MARKERS.contains(&line) {
                        *marked += 1;
                    } else if line.starts_with("#[ignore") {
                        bad.push(format!("{}:{}: {line}", path.display(), k + 1));
                    }
                }
            }
        }
    }
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let (mut bad, mut marked) = (Vec::new(), 0);
    for dir in ["src", "tests", "benches", "examples"] {
        visit(&root.join(dir), &mut bad, &mut marked);
    }
    assert!(
        marked > 0,
        "no slow-tier marker found: the scan looks at the wrong files"
    );
    assert!(
        bad.is_empty(),
        "ignored for another reason than the slow tier:\n  {}",
        bad.join("\n  ")
    );
}
