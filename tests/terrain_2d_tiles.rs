//! The active tiles of a raster run (`state::tiles`): a step that visits only the
//! tiles where the flow is gives the same bits as the full sweep (every tile stepped)
//! — snapshots, per-step records, maps and the final state — on 1, 2 and 4 threads,
//! and the work follows the flow.

use granflow::grid::{BoundaryKind, Coordinates, Grid, Raster2d, RasterSpec, Sides};
use granflow::model::granular_2d;
use granflow::numerics::{Stage, StageError, StepClock};
use granflow::output::memory::MemorySink;
use granflow::physics::rheology::FrictionLaw;
use granflow::physics::Material;
use granflow::state::State2d;

/// A stage that refuses the first attempt of every fifth step (after the model's
/// stages changed the state): the run loop restores its copy of the state and
/// retries with half the step.
struct Refuses {
    calls: usize,
}

impl Stage<Raster2d, State2d> for Refuses {
    fn name(&self) -> &'static str {
        "refuses"
    }

    fn apply(&mut self, _: &Raster2d, _: StepClock, _: &mut State2d) -> Result<(), StageError> {
        self.calls += 1;
        if self.calls % 6 == 5 {
            return Err(StageError::NegativeThickness { cell: 0, h: -1.0 });
        }
        Ok(())
    }
}

/// A bundled scenario's run with `sets`, on `threads` threads, every tile stepped
/// (`every`) or the active ones: its outputs and final state. `sets` beginning with
/// "refuse" adds the [`Refuses`] stage.
fn run(file: &str, sets: &[&str], threads: usize, every: bool) -> (MemorySink, State2d) {
    let refuse = sets.first() == Some(&"refuse");
    let sets = if refuse { &sets[1..] } else { sets };
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios");
    let text = std::fs::read_to_string(dir.join(file)).unwrap();
    let sets: Vec<String> = sets.iter().map(|s| s.to_string()).collect();
    let scn = granflow::scenario::load_str(&text, &dir, &sets).unwrap();
    let mut sim = granflow::setup::build_granular_2d(&scn, threads);
    if every {
        sim.state.tiles.step_every_tile();
    }
    if refuse {
        sim.push_stage(Box::new(Refuses { calls: 0 }));
    }
    let mut sink = MemorySink::default();
    sim.run(&mut sink, &mut |_| {}).expect("the run completes");
    // The numbers that are not the run's: its wall-clock times and rates.
    if let Some(summary) = sink.summary.as_mut() {
        summary.wall_time_s = 0.0;
        summary.stage_times.clear();
        // Rates per second of wall time (and the full sweep updates more cells).
        if let Some(wet) = summary.wet.as_mut() {
            (wet.wet_updates_per_s, wet.cell_updates_per_s) = (0.0, 0.0);
        }
    }
    (sink, sim.state)
}

/// Whether two states hold the same bits.
fn same_state(a: &State2d, b: &State2d) -> bool {
    let same = |x: &[f64], y: &[f64]| x.iter().zip(y).all(|(p, q)| p.to_bits() == q.to_bits());
    same(&a.h, &b.h) && same(&a.hu, &b.hu) && same(&a.hv, &b.hv)
}

/// Every number of two runs, to the bit (the shortest round-trip form of `Debug`
/// differs between any two different f64, ±0 included).
fn same_bits(a: &(MemorySink, State2d), b: &(MemorySink, State2d)) -> bool {
    let (da, db) = (format!("{:?}", a.0), format!("{:?}", b.0));
    if let Some(k) = da.bytes().zip(db.bytes()).position(|(x, y)| x != y) {
        let at = |s: &str| s[k.saturating_sub(200)..(k + 100).min(s.len())].to_string();
        eprintln!("first difference:\n{}\n---\n{}", at(&da), at(&db));
    }
    da == db && same_state(&a.1, &b.1)
}

/// The bundled raster scenarios (Cartesian collapse; a DEM with nodata walls in the
/// bed-normal frame; AvaFrame's hockey stick and helix on coarse grids, Voellmy and
/// Coulomb), run on the active tiles, give the full sweep's bits on 1, 2 and 4 threads;
/// also with steps refused and retried (the state restored from the run loop's copy,
/// which copies only the tiles that changed).
#[test]
fn the_bundled_raster_scenarios_give_the_full_sweeps_bits_on_one_two_and_four_threads() {
    let coarse = [
        "domain.x_min=980",
        "domain.x_max=6020",
        "domain.y_min=-5020",
        "domain.y_max=-2980",
        "domain.cells=[126,51]",
        "time.t_end=60",
        "output.every=10",
    ];
    let with = |extra: &[&'static str]| [&coarse[..], extra].concat();
    let cases: Vec<(&str, Vec<&str>)> = vec![
        ("radial_collapse.toml", vec!["time.t_end=0.6"]),
        ("radial_collapse.toml", vec!["refuse", "time.t_end=0.6"]),
        ("dem_release.toml", vec!["time.t_end=12", "output.every=1"]),
        ("hockey_channel.toml", with(&[])),
        ("hockey_channel.toml", with(&["rheology.law=\"coulomb\""])),
        ("helix_channel.toml", with(&[])),
    ];
    for (file, sets) in &cases {
        let full = run(file, sets, 1, true);
        assert!(full.0.steps.len() > 20 && !full.0.maps.is_empty());
        for threads in [1, 2, 4] {
            let tiled = run(file, sets, threads, false);
            assert!(
                same_bits(&tiled, &full),
                "{file} {sets:?} on {threads} threads differs from the full sweep"
            );
        }
    }
}

/// A cone on a random bed with wall cells, over a raster whose last tiles are partial
/// (75 × 50 cells: 2 tiles of 32 columns and one of 11, 3 bands of 16 rows and one of
/// 2), in local coordinates on a 30° plane with Coulomb friction below the slope: its
/// fronts cross tile edges and corners and run the draining limiter. Every step gives
/// the full sweep's state to the bit, the run loop's copy of the state (of the tiles
/// that changed) equals the state, and the stepped tiles cover the flow and little
/// more: while the flow is on a small part of the raster, so is the work.
/// The raster of [`a_flow_across_tile_edges_gives_the_full_sweeps_bits_at_every_step`]
/// (75 × 50 cells of 0.1 m, partial last tiles, walls west and south, outflow east and
/// north, a block of wall cells astride a tile corner, a bed of small noise falling by
/// `tilt` along x; in local coordinates on a 30° plane, else horizontal) and its cone
/// of thickness 0.3 − 0.4 r about (1.2, 1.5).
pub(crate) fn cone_across_tiles(coordinates: Coordinates, tilt: f64) -> (Raster2d, Vec<f64>) {
    let (nx, ny) = (75, 50);
    let spec = RasterSpec {
        nx,
        ny,
        x_min: 0.0,
        x_max: 7.5,
        y_min: 0.0,
        y_max: 5.0,
        sides: Sides {
            west: BoundaryKind::Wall,
            east: BoundaryKind::Outflow,
            south: BoundaryKind::Wall,
            north: BoundaryKind::Outflow,
        },
        coordinates,
        slope_deg: if coordinates == Coordinates::Local {
            30.0
        } else {
            0.0
        },
    };
    let noise = |k: usize| ((k as f64 * 0.618_033_988_75).fract() - 0.5) * 0.02;
    let bed: Vec<f64> = (0..nx * ny)
        .map(|k| noise(k) - tilt * 0.1 * (k % nx) as f64)
        .collect();
    // A block of wall cells in the path, astride a tile corner (column 32, row 16).
    let walls: Vec<bool> = (0..nx * ny)
        .map(|k| (30..35).contains(&(k % nx)) && (14..18).contains(&(k / nx)))
        .collect();
    let raster = Raster2d::with_walls(spec, bed, walls.clone()).unwrap();
    let h: Vec<f64> = (0..nx * ny)
        .map(|k| {
            let (x, y) = (raster.x(k % nx) - 1.2, raster.y(k / nx) - 1.5);
            if walls[k] {
                0.0
            } else {
                (0.3 - 0.4 * (x * x + y * y).sqrt()).max(0.0)
            }
        })
        .collect();
    (raster, h)
}

#[test]
fn a_flow_across_tile_edges_gives_the_full_sweeps_bits_at_every_step() {
    let (raster, h) = cone_across_tiles(Coordinates::Local, 0.0);
    let (nx, ny) = (raster.nx(), raster.ny());
    let zeros = vec![0.0; nx * ny];
    let law = FrictionLaw::Coulomb {
        mu: 20f64.to_radians().tan(),
    };
    let material = Material {
        rho_s: 2500.0,
        phi: 0.6,
        d_s: 1e-3,
    };
    let model = granular_2d::Granular2d::new(&raster, 1e-3);
    for threads in [1, 2, 4] {
        let mut full = State2d::from_velocities(h.clone(), &zeros, &zeros);
        full.tiles.step_every_tile();
        let mut tiled = State2d::from_velocities(h.clone(), &zeros, &zeros);
        let mut p_full = granular_2d::pipeline(&law, &material, &raster, 1).unwrap();
        let mut p_tiled = granular_2d::pipeline(&law, &material, &raster, threads).unwrap();
        let (mut least, mut most) = (1.0f64, 0.0f64);
        let (mut backup, mut t) = (tiled.clone(), 0.0);
        for step in 0..400 {
            // The run loop's copy of the state of t^n (only the tiles the last step
            // changed are copied) equals the state.
            granflow::model::Model::save_state(&model, &mut backup, &tiled);
            assert!(
                same_state(&backup, &tiled),
                "the copy of the state before step {step} differs from it"
            );
            let d = granflow::model::Model::diagnose(&model, &raster, &full);
            let clock = StepClock::at(t, 0.45 * raster.cfl_length() / d.signal_speed);
            t += clock.dt;
            p_full.advance(&raster, clock, &mut full).unwrap();
            p_tiled.advance(&raster, clock, &mut tiled).unwrap();
            assert!(
                same_state(&full, &tiled),
                "step {step} on {threads} threads differs from the full sweep"
            );
            let d_tiled = granflow::model::Model::diagnose(&model, &raster, &tiled);
            let d_full = granflow::model::Model::diagnose(&model, &raster, &full);
            assert_eq!(format!("{d_tiled:?}"), format!("{d_full:?}"));
            let fraction = tiled.tiles.stepped_fraction();
            (least, most) = (least.min(fraction), most.max(fraction));
        }
        // 12 tiles: the cone starts on 2 of them (west column, bands 0 and 1, away
        // from their east and north edges: 1024 of 3750 cells) and spreads.
        println!("{threads} threads: stepped fraction {least:.3} … {most:.3}");
        assert_eq!(least, 1024.0 / 3750.0);
        assert!(most > least, "the flow leaves its first tiles");
    }
}
