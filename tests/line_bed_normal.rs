//! The bed-normal frame on a line (`domain.coordinates = "bed_normal"`,
//! docs/numerics.md): a raster run invariant in y on a curved profile is, row by row
//! and step by step, the line's run to the bit (Coulomb, μ(I), Voellmy, with and
//! without the centrifugal term); on a plane a Coulomb block accelerates at
//! g (sin θ − μ cos θ) and Voellmy's layer reaches Salm's terminal speed; masses below
//! their repose on a curved bed stay exactly at rest, a lake on a tilted plane too;
//! mass is conserved and thicknesses stay ≥ 0; a thin layer on a circular arc follows
//! the point mass with the centrifugal term in the friction. The scenario keys: the
//! frame is taken by the monolayer hydrostatic granular model and refused by name
//! elsewhere.

use super::terrain_2d::{material, raster, tan_deg};
use super::terrain_2d_bed_normal::arc_point_mass;
use granflow::grid::{BoundaryKind, Coordinates, Line, LineSpec, Sides};
use granflow::model::granular::config::{MultilayerSpec, Pressure};
use granflow::model::granular::{pipeline, Granular};
use granflow::model::granular_2d::{self, Granular2d};
use granflow::model::Model;
use granflow::numerics::viscous::{BasalCondition, Regularization, ViscosityTime};
use granflow::numerics::StepClock;
use granflow::physics::rheology::{FrictionLaw, MonolayerShear};
use granflow::pipeline::Pipeline;
use granflow::state::{LayeredState, State2d};

const G: f64 = 9.81;
const WALL: BoundaryKind = BoundaryKind::Wall;
const OUTFLOW: BoundaryKind = BoundaryKind::Outflow;

/// A bed-normal line of `nx` cells on [x_min, x_max] over the bed `b(x)`.
fn line(
    (x_min, x_max): (f64, f64),
    nx: usize,
    (left, right): (BoundaryKind, BoundaryKind),
    b: impl Fn(f64) -> f64,
) -> Line {
    let spec = LineSpec {
        x_min,
        x_max,
        cells: nx,
        slope_deg: 0.0,
        coordinates: Coordinates::BedNormal,
        left,
        right,
    };
    let bed = spec.centres().iter().map(|&x| b(x)).collect();
    Line::new(&spec, bed)
}

/// The monolayer hydrostatic pipeline of `law` on `mesh`, as a scenario builds it.
fn line_pipeline(law: &FrictionLaw, mesh: &Line) -> Pipeline<Line, LayeredState> {
    let spec = MultilayerSpec {
        layer_fractions: vec![1.0],
        basal: BasalCondition::Coulomb,
        regularization: Regularization::Delta { delta: 1e-5 },
        sidewall: None,
        c_msm: false,
        viscosity: ViscosityTime::Frozen,
        static_threshold: 1e-3,
    };
    pipeline::granular(law, &material(), mesh, Pressure::Hydrostatic, &spec, None)
}

fn model(nx: usize) -> Granular {
    Granular {
        h_bed: vec![0.0; nx],
        front_threshold: 1e-3,
        static_threshold: 1e-3,
        rest_speed: 0.0,
    }
}

/// The state of a normal thickness `h(x)` (H = h/c per horizontal length) at rest.
fn at_rest(mesh: &Line, h: impl Fn(f64) -> f64) -> LayeredState {
    let m = mesh.metric().expect("a bed-normal line");
    let hh: Vec<f64> = (0..mesh.nx).map(|i| h(mesh.x[i]) / m.cos[i]).collect();
    LayeredState::from_profiles(mesh, &[1.0], &hh, &vec![0.0; mesh.nx])
}

/// Runs `p` on `mesh` to `t_end` with the CFL steps of the line's diagnostics.
fn run_line(mesh: &Line, s: &mut LayeredState, p: &mut Pipeline<Line, LayeredState>, t_end: f64) {
    let model = model(mesh.nx);
    let mut t = 0.0;
    while t < t_end {
        let speed = model.diagnose(mesh, s).signal_speed;
        let dt = (0.45 * mesh.dx / speed).min(t_end - t);
        p.advance(mesh, StepClock::at(t, dt), s).unwrap();
        t += dt;
    }
}

fn mu_i() -> FrictionLaw {
    FrictionLaw::MuI {
        mu_s: tan_deg(20.9),
        mu_2: tan_deg(32.76),
        i0: 0.279,
        shear: MonolayerShear::Bagnold,
    }
}

/// A raster of 3 rows invariant in y (walls along its sides) on a curved profile,
/// released as a dam break that runs down a slope with a smooth foot (the parabola
/// b = x²/40 − x: 45° at the upper wall, curvature 0.05/m, 11° at the outflow end,
/// through which 87–100 % of the mass leaves), is the bed-normal line's run to the
/// bit: every thickness and
/// discharge of every row equal after every step (and the CFL signal speed equal),
/// the y-discharges zero, for Coulomb, μ(I) and Voellmy, with and without the
/// centrifugal term, at CFL 0.45 and 0.9 (at 0.9 the draining-time limiter acts: in
/// 17 steps of the six runs, counted with a print in the limiter). The raster's y-faces
/// carry exact zeros; the line calls the same face and cell functions
/// (`numerics::bed_normal`) with zeros in their place.
#[test]
fn a_y_invariant_raster_on_a_curved_bed_is_the_bed_normal_line_to_the_bit() {
    let bed = |x: f64| x * x / 40.0 - x;
    let voellmy = FrictionLaw::Voellmy { mu: 0.2, xi: 500.0 };
    let cases = [FrictionLaw::Coulomb { mu: 0.3 }, mu_i(), voellmy]
        .into_iter()
        .flat_map(|law| [(law, true), (law, false)])
        .flat_map(|case| [(case, 0.45), (case, 0.9)]);
    for ((law, curvature), cfl) in cases {
        let nx = 100;
        let mesh = line((0.0, 16.0), nx, (WALL, OUTFLOW), bed);
        let mesh = if curvature {
            mesh
        } else {
            mesh.without_friction_curvature()
        };
        let mut state = at_rest(&mesh, |x| if x < 4.0 { 0.4 } else { 0.0 });
        let mass0: f64 = state.h.iter().sum();
        let mut pipe_1d = line_pipeline(&law, &mesh);
        let sides = Sides {
            west: WALL,
            east: OUTFLOW,
            south: WALL,
            north: WALL,
        };
        let r = raster(
            nx,
            3,
            (0.0, 16.0),
            (0.0, 0.6),
            sides,
            Coordinates::BedNormal,
            0.0,
            move |x, _| bed(x),
        );
        let r = if curvature {
            r
        } else {
            r.without_friction_curvature()
        };
        let h: Vec<f64> = (0..3 * nx).map(|k| state.h[k % nx + 1]).collect();
        let mut s = State2d::from_velocities(h, &vec![0.0; 3 * nx], &vec![0.0; 3 * nx]);
        let mut pipe_2d = granular_2d::pipeline(&law, &material(), &r, 1).unwrap();
        let (model_1d, model_2d) = (model(nx), Granular2d::new(&r, 1e-3));
        let (mut moved, mut t) = (0.0f64, 0.0);
        for step in 0..400 {
            let speed = model_1d.diagnose(&mesh, &state).signal_speed;
            assert_eq!(speed, model_2d.diagnose(&r, &s).signal_speed, "step {step}");
            let clock = StepClock::at(t, cfl * mesh.dx / speed);
            t += clock.dt;
            pipe_1d.advance(&mesh, clock, &mut state).unwrap();
            pipe_2d.advance(&r, clock, &mut s).unwrap();
            for k in 0..3 * nx {
                let a = k % nx + 1;
                assert_eq!(
                    s.h[k], state.h[a],
                    "{law:?} {curvature}: step {step}, h at {k}"
                );
                assert_eq!(
                    s.hu[k], state.hu[a],
                    "{law:?} {curvature}: step {step}, q at {k}"
                );
                assert_eq!(s.hv[k], 0.0);
            }
            moved = moved.max(state.hu.iter().fold(0.0f64, |m, q| m.max(q.abs())));
        }
        eprintln!(
            "{law:?}, curvature {curvature}, CFL {cfl}: same bits, largest discharge {moved:.3} m²/s"
        );
        let left = 1.0 - state.h.iter().sum::<f64>() / mass0;
        eprintln!(
            "  {:.1} % of the mass left through the outflow",
            100.0 * left
        );
        assert!(moved > 0.1, "the dam break flows");
        assert!(left > 0.1, "the flow leaves through the outflow end");
    }
}

/// A Coulomb block on a bed-normal line plane of 35°: its centre of mass moves along
/// the slope by ½ g (sin θ − μ cos θ) t² and its mass-weighted speed along the slope
/// is g (sin θ − μ cos θ) t, to errors that fall with Δx (first order: below 1.2 Δx
/// (m) for the centre and 0.55 Δx (m/s) for the speed, the bounds of the raster's
/// test, whose rows this line is to the bit).
#[test]
fn a_coulomb_block_on_a_bed_normal_line_plane_slides_at_g_sin_minus_mu_cos() {
    let (theta, mu, t_end) = (35f64.to_radians(), 0.3, 3.0);
    let a = G * (theta.sin() - mu * theta.cos());
    let (c, tan) = (theta.cos(), theta.tan());
    let mut errors = Vec::new();
    for dx in [2.0, 1.0, 0.5] {
        let nx = (120.0 / dx) as usize;
        let mesh = line((0.0, 120.0), nx, (OUTFLOW, OUTFLOW), |x| -x * tan);
        // A block 20 m long along the slope, 0.2 m thick, from 10 m down the slope.
        let mut s = at_rest(&mesh, |x| {
            if (10.0 * c..30.0 * c).contains(&x) {
                0.2
            } else {
                0.0
            }
        });
        let centre = |s: &LayeredState| {
            let (m, mx) = (1..=nx).fold((0.0, 0.0), |(m, mx), j| {
                (m + s.h[j], mx + s.h[j] * mesh.x[j - 1])
            });
            (mx / m / c, m)
        };
        let (x0, m0) = centre(&s);
        let mut p = line_pipeline(&FrictionLaw::Coulomb { mu }, &mesh);
        run_line(&mesh, &mut s, &mut p, t_end);
        let (x1, m1) = centre(&s);
        let metric = mesh.metric().unwrap();
        let speed = (1..=nx)
            .filter(|&j| s.h[j] > 0.0)
            .map(|j| s.h[j] * metric.speed(j - 1, s.hu[j] / s.h[j], 0.0))
            .sum::<f64>()
            / m1;
        assert!((m1 - m0).abs() < 1e-12 * m0, "mass {m0} → {m1}");
        assert!(s.h.iter().all(|&h| h >= 0.0));
        let (dist, speed_err) = (x1 - x0 - 0.5 * a * t_end * t_end, speed - a * t_end);
        eprintln!("Δx = {dx}: centre error {dist:.3e} m, speed error {speed_err:.3e} m/s");
        errors.push((dist.abs(), speed_err.abs()));
    }
    for (w, dx) in errors.windows(2).zip([1.0, 0.5]) {
        assert!(w[1].0 < w[0].0 && w[1].1 < w[0].1, "{errors:?}");
        assert!(w[1].0 < 1.2 * dx && w[1].1 < 0.55 * dx, "{errors:?}");
    }
}

/// A uniform Voellmy layer of 1 m normal thickness on a 34° bed-normal line reaches
/// Salm's terminal speed √(ξ h (sin θ − μ cos θ)) = 41.5 m/s within 0.5 %, 1 m thick.
#[test]
fn voellmy_on_a_bed_normal_line_reaches_salms_terminal_speed() {
    let (theta, mu, xi) = (34f64.to_radians(), 0.155, 4000.0);
    let tan = theta.tan();
    let mesh = line((0.0, 6000.0), 150, (OUTFLOW, OUTFLOW), |x| -x * tan);
    let mut s = at_rest(&mesh, |_| 1.0);
    let mut p = line_pipeline(&FrictionLaw::Voellmy { mu, xi }, &mesh);
    run_line(&mesh, &mut s, &mut p, 60.0);
    let salm = (xi * (theta.sin() - mu * theta.cos())).sqrt();
    // Far from the upper end, whose rarefaction has not reached the middle.
    let (j, m) = (121, mesh.metric().unwrap());
    let h = s.h[j];
    let speed = m.speed(j - 1, s.hu[j] / h, 0.0);
    eprintln!("terminal speed {speed:.4} m/s, Salm {salm:.4} m/s");
    assert!((speed / salm - 1.0).abs() < 5e-3, "{speed} against {salm}");
    assert!(
        (h * m.cos[j - 1] - 1.0).abs() < 1e-9,
        "the layer stays 1 m thick"
    );
}

/// Deterministic pseudo-random numbers in [0, 1).
fn rand01(k: u64) -> f64 {
    let mut z = k.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    (z ^ (z >> 31)) as f64 / u64::MAX as f64
}

/// A Coulomb layer on a curved bed whose slopes stay below the friction (b = 0.15
/// sin 0.7x + 0.1x: slopes up to 0.205 against μ = 0.8, curvature up to 0.074/m), with
/// dry patches, a wall and an outflow: every discharge stays exactly 0 and the
/// thickness unchanged to round-off over 300 steps.
#[test]
fn a_layer_below_repose_on_a_curved_bed_normal_line_stays_exactly_at_rest() {
    let nx = 120;
    let mesh = line((0.0, 24.0), nx, (WALL, OUTFLOW), |x| {
        0.15 * (0.7 * x).sin() + 0.1 * x
    });
    let m = mesh.metric().unwrap();
    let h0: Vec<f64> = (0..nx)
        .map(|i| {
            if rand01(i as u64) < 0.2 {
                0.0
            } else {
                0.1 / m.cos[i]
            }
        })
        .collect();
    let mut s = LayeredState::from_profiles(&mesh, &[1.0], &h0, &vec![0.0; nx]);
    let mut p = line_pipeline(&FrictionLaw::Coulomb { mu: 0.8 }, &mesh);
    for k in 0..300 {
        p.advance(&mesh, StepClock::at(k as f64 * 0.01, 0.01), &mut s)
            .unwrap();
    }
    assert!(s.hu.iter().all(|&q| q == 0.0), "moved");
    let dh = (0..nx)
        .map(|i| (s.h[i + 1] - h0[i]).abs())
        .fold(0.0, f64::max);
    eprintln!("largest change of thickness {dh:e} m");
    assert!(dh < 1e-14, "thickness changed by {dh:e}");
    assert_eq!(model(nx).diagnose(&mesh, &s).kinetic_energy, 0.0);
}

/// A frictionless lake on a tilted bed-normal line (walls at both ends): the top of
/// the normal column, b + c h, is level, H = (K − b)/c², and stays at rest to
/// round-off.
#[test]
fn a_lake_on_a_tilted_bed_normal_line_stays_at_rest() {
    let theta = 20f64.to_radians();
    let tan = theta.tan();
    let nx = 40;
    let mesh = line((0.0, 20.0), nx, (WALL, WALL), |x| -x * tan);
    let c2 = theta.cos().powi(2);
    let h0: Vec<f64> = mesh.b.iter().map(|b| (0.5 - b) / c2).collect();
    let mut s = LayeredState::from_profiles(&mesh, &[1.0], &h0, &vec![0.0; nx]);
    let mut p = line_pipeline(&FrictionLaw::Coulomb { mu: 0.0 }, &mesh);
    for k in 0..300 {
        p.advance(&mesh, StepClock::at(k as f64 * 0.002, 0.002), &mut s)
            .unwrap();
    }
    let dh = (0..nx)
        .map(|i| (s.h[i + 1] - h0[i]).abs())
        .fold(0.0, f64::max);
    let dq = s.hu.iter().fold(0.0f64, |m, q| m.max(q.abs()));
    eprintln!("lake: |Δh| {dh:e} m, |q| {dq:e} m²/s");
    assert!(dh < 1e-12 && dq < 1e-12, "|Δh| {dh:e}, |q| {dq:e}");
}

/// A μ(I) release in a bowl between two walls (b = (x − 10)²/20 on [0, 20]): the mass
/// ∫H dx is conserved to round-off and every thickness stays ≥ 0 at every step while
/// the flow runs through the bowl and up the far side.
#[test]
fn a_release_in_a_bed_normal_bowl_conserves_mass_and_stays_positive() {
    let nx = 200;
    let mesh = line((0.0, 20.0), nx, (WALL, WALL), |x| {
        (x - 10.0) * (x - 10.0) / 20.0
    });
    let mut s = at_rest(&mesh, |x| (0.3 - 0.3 * ((x - 3.0) / 1.5).powi(2)).max(0.0));
    let mass0 = model(nx).diagnose(&mesh, &s).mass;
    let mut p = line_pipeline(&mu_i(), &mesh);
    let (mut t, mut fastest) = (0.0, 0.0f64);
    while t < 6.0 {
        let d = model(nx).diagnose(&mesh, &s);
        let dt = 0.45 * mesh.dx / d.signal_speed;
        p.advance(&mesh, StepClock::at(t, dt), &mut s).unwrap();
        t += dt;
        assert!(
            s.h.iter().all(|&h| h >= 0.0),
            "negative thickness at t = {t}"
        );
        fastest = fastest.max(d.max_speed);
    }
    let mass = model(nx).diagnose(&mesh, &s).mass;
    eprintln!("mass {mass0} → {mass}, fastest {fastest:.3} m/s");
    assert!((mass - mass0).abs() < 1e-13 * mass0, "{mass0} → {mass}");
    assert!(fastest > 1.0, "it flows");
}

/// A thin Coulomb layer (4 m long, 2 cm thick) released on a circular bowl of radius
/// 100 m at 40° follows the point mass: its centre's travel along the arc after 6 s
/// converges with Δx (1, 0.5, 0.25, 0.125 m) to the point-mass equation with the
/// centrifugal term in the friction, and without it when the term is dropped
/// (`domain.curvature = false`); the Richardson extrapolation 2 T(Δx/2) − T(Δx) of
/// the two finest is within 1 % of it, and the term's effect on the travel (without
/// minus with) within 5 % of the point mass's.
#[test]
fn a_thin_layer_on_a_circular_arc_follows_the_point_mass_with_centrifugal_friction() {
    let (radius, phi0, mu, t_end): (f64, f64, f64, f64) = (100.0, 40f64.to_radians(), 0.2, 6.0);
    let x0 = -radius * phi0.sin();
    let mut rows = Vec::new();
    for curvature in [true, false] {
        let exact = arc_point_mass(radius, phi0, mu, curvature, t_end);
        let mut travels = Vec::new();
        for dx in [1.0, 0.5, 0.25, 0.125] {
            let nx = (140.0 / dx) as usize;
            let mesh = line((-80.0, -80.0 + nx as f64 * dx), nx, (WALL, WALL), |x| {
                radius - (radius * radius - x * x).max(0.0).sqrt()
            });
            let mesh = if curvature {
                mesh
            } else {
                mesh.without_friction_curvature()
            };
            let mut s = at_rest(&mesh, |x| {
                if (x - x0).abs() < 2.0 * phi0.cos() {
                    0.02
                } else {
                    0.0
                }
            });
            let mut p = line_pipeline(&FrictionLaw::Coulomb { mu }, &mesh);
            let arc = |s: &LayeredState| {
                let (m, mx) = (1..=nx).fold((0.0, 0.0), |(m, mx), j| {
                    (m + s.h[j], mx + s.h[j] * (mesh.x[j - 1] / radius).asin())
                });
                radius * mx / m
            };
            let start = arc(&s);
            run_line(&mesh, &mut s, &mut p, t_end);
            let travel = arc(&s) - start;
            eprintln!(
                "curvature {curvature}, Δx = {dx}: travel {travel:.3} m, point mass {exact:.3} m"
            );
            travels.push(travel);
        }
        let extrapolated = 2.0 * travels[3] - travels[2];
        for w in travels.windows(2) {
            assert!((w[1] - exact).abs() < (w[0] - exact).abs(), "{travels:?}");
        }
        eprintln!("extrapolated {extrapolated:.3} m against {exact:.3} m");
        assert!(
            (extrapolated - exact).abs() < 0.01 * exact,
            "{travels:?} against {exact}"
        );
        rows.push((exact, extrapolated));
    }
    let (point, layer) = (rows[1].0 - rows[0].0, rows[1].1 - rows[0].1);
    eprintln!("curvature shortens the travel by {layer:.3} m (point mass {point:.3} m)");
    assert!(
        point > 1.0 && (layer / point - 1.0).abs() < 0.05,
        "{rows:?}"
    );
}

/// A line scenario in the bed-normal frame runs through the scenario's set-up: the
/// state holds H = h/c (`initial.h` normal to the bed), the snapshots report it, the
/// run info names the frame, and `domain.curvature = false` is taken.
#[test]
fn a_bed_normal_line_scenario_holds_h_per_horizontal_length() {
    use granflow::output::memory::MemorySink;
    let text = r#"[domain]
x_min = 0.0
x_max = 10.0
cells = 50
coordinates = "bed_normal"
curvature = false

[bed]
b = "-0.5 * x"

[rheology]
law = "coulomb"
mu = 0.3

[initial]
h = "if(x < 3, 0.2, 0)"

[time]
t_end = 0.5
"#;
    let scn = granflow::scenario::load_str(text, std::path::Path::new("."), &[]).unwrap();
    assert_eq!(scn.domain.coordinates, Coordinates::BedNormal);
    assert!(!scn.domain.curvature);
    let mut sim = granflow::setup::build_granular(&scn);
    let c = 1.0 / 1.25f64.sqrt();
    assert!(
        (sim.state.h[1] - 0.2 / c).abs() < 1e-14,
        "{}",
        sim.state.h[1]
    );
    assert!(!sim.grid.metric().unwrap().in_friction);
    let mut sink = MemorySink::default();
    sim.run(&mut sink, &mut |_| {}).expect("the run completes");
    assert!((sink.snapshots[0].h[0] - 0.2 / c).abs() < 1e-14);
    assert_eq!(sink.info.as_ref().unwrap().coordinates, "bed_normal");
}

/// The frame on a line is the monolayer hydrostatic granular model's: the other
/// models, layer counts, the non-hydrostatic pressure and order 2 refuse it by name,
/// and `domain.curvature` needs it.
#[test]
fn bed_normal_lines_refuse_what_they_do_not_solve() {
    let text = r#"[domain]
x_min = 0.0
x_max = 1.0
cells = 10
coordinates = "bed_normal"

[rheology]
law = "coulomb"
mu = 0.5

[initial]
h = 0.1

[time]
t_end = 1.0
"#;
    let load = |sets: &[&str]| {
        let sets: Vec<String> = sets.iter().map(|s| s.to_string()).collect();
        granflow::scenario::load_str(text, std::path::Path::new("."), &sets)
    };
    assert!(load(&[]).is_ok());
    for (sets, key) in [
        (&["model.layers=4"][..], "domain.coordinates"),
        (
            &["model.pressure=\"nonhydrostatic\""][..],
            "domain.coordinates",
        ),
        (&["numerics.order=2"][..], "numerics.order"),
        (
            &["domain.coordinates=\"local\"", "domain.curvature=false"][..],
            "domain.curvature",
        ),
    ] {
        let e = load(sets).unwrap_err().to_string();
        eprintln!("{sets:?}: {e}");
        assert!(e.contains(key), "{sets:?}: {e}");
    }
    // The bundled line scenarios of the other models.
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios");
    for file in ["dilatancy_dense.toml", "submarine_landslide.toml"] {
        let text = std::fs::read_to_string(dir.join(file)).unwrap();
        let sets = ["domain.coordinates=\"bed_normal\"", "domain.slope_deg=0"].map(String::from);
        let e = granflow::scenario::load_str(&text, &dir, &sets)
            .unwrap_err()
            .to_string();
        eprintln!("{file}: {e}");
        assert!(
            e.contains("domain.coordinates") && e.contains("model.kind"),
            "{e}"
        );
    }
}

/// The same scenario on a line and on a raster of 3 rows (the profiles do not depend
/// on y; an erodible bed under a release, both normal to the bed) gives, through the
/// scenario set-up and the run loop, the same steps and, row by row, the same
/// snapshots to the bit (`h` is H, `u` the horizontal velocity), the same largest speed
/// along the bed and front at every step, and the raster's mass is the line's times
/// the raster's width to round-off: the outputs mean the same on both.
#[test]
fn a_bed_normal_line_scenario_writes_the_numbers_of_a_y_invariant_raster_scenario() {
    use granflow::output::memory::MemorySink;
    let common = r#"
coordinates = "bed_normal"

[bed]
b = "x*x/40 - x"

[rheology]
law = "coulomb"
mu = 0.3

[initial]
h = "if(x < 4, 0.4, 0)"
erodible_bed = 0.02

[boundary]
left = "wall"
right = "outflow"

[time]
t_end = 3.0
cfl = 0.45

[output]
every = 0.5
"#;
    let line_text = format!("[domain]\nx_min = 0.0\nx_max = 16.0\ncells = 100\n{common}");
    let raster_text = format!(
        "[domain]\nx_min = 0.0\nx_max = 16.0\ny_min = 0.0\ny_max = 0.6\ncells = [100, 3]\n{common}"
    );
    let dir = std::path::Path::new(".");
    let line_scn = granflow::scenario::load_str(&line_text, dir, &[]).unwrap();
    let raster_scn = granflow::scenario::load_str(&raster_text, dir, &[]).unwrap();
    let mut line_sim = granflow::setup::build_granular(&line_scn);
    let mut raster_sim = granflow::setup::build_granular_2d(&raster_scn, 1);
    let (mut a, mut b) = (MemorySink::default(), MemorySink::default());
    line_sim
        .run(&mut a, &mut |_| {})
        .expect("the line run completes");
    raster_sim
        .run(&mut b, &mut |_| {})
        .expect("the raster run completes");
    assert_eq!(a.steps.len(), b.steps.len());
    assert!(a.steps.len() > 100, "{} steps", a.steps.len());
    let width = 0.6;
    for (p, q) in a.steps.iter().zip(&b.steps) {
        assert_eq!((p.t, p.dt), (q.t, q.dt));
        assert_eq!(p.max_speed, q.max_speed, "t = {}", p.t);
        assert_eq!(p.front_x.to_bits(), q.front_x.to_bits(), "t = {}", p.t);
        assert!(
            (q.mass / width - p.mass).abs() <= 1e-14 * p.mass,
            "t = {}",
            p.t
        );
    }
    assert_eq!(a.snapshots.len(), b.snapshots.len());
    for (p, q) in a.snapshots.iter().zip(&b.snapshots) {
        for (k, (h, u)) in q.h.iter().zip(&q.u).enumerate() {
            assert_eq!(
                (*h, *u),
                (p.h[k % 100], p.u[k % 100]),
                "t = {}, cell {k}",
                p.t
            );
        }
    }
    assert_eq!(a.info.unwrap().coordinates, b.info.unwrap().coordinates);
    let last = a.steps.last().unwrap();
    eprintln!(
        "{} steps, front at {} m, largest speed {:.3} m/s at the end",
        a.steps.len(),
        last.front_x,
        last.max_speed
    );
}
