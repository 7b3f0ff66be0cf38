//! The multilayer μ(I) model on a raster through its scenario (`model.layers` > 1 on a
//! raster domain): the line's keys, the run on any number of threads, the HDF5 output
//! (`u_layers`, `v_layers` of shape (nt, N, ny, nx), the depth means `u`, `v`, the
//! static interface and the monolayer's maps), and the refusals of what its raster
//! stages do not implement, each by its key.

use crate::common::{fails_at, load_in, read_h5};
use granflow::output::memory::MemorySink;
use std::path::Path;

/// An off-centre, lopsided μ(I) release on an inclined plane in a walled box of
/// 24 × 20 cells, four layers, an erodible bed over part of the plane.
const BOX: &str = r#"[domain]
x_min = -1.0
x_max = 1.0
y_min = -0.8
y_max = 0.8
cells = [24, 20]
slope_deg = 20.0
coordinates = "local"

[bed]
b = "0.02 * sin(3*x) * cos(2*y)"

[material]
rho_s = 2500.0
phi = 0.62
d_s = 0.7e-3

[rheology]
law = "mu_i"
mu_s_deg = 20.9
mu_2_deg = 32.8
i0 = 0.279

[model]
layers = 4

[initial]
h = "if((x + 0.4)^2 + 2*(y - 0.1)^2 < 0.09, 0.15 + 0.1*x + 0.05*y, 0)"
u = 0.2
v = -0.1
erodible_bed = "if(x > 0.2, 0.01, 0)"

[boundary]
west = "wall"
east = "wall"
south = "wall"
north = "wall"

[time]
t_end = 0.3
cfl = 0.45

[output]
every = 0.1
"#;

fn run(text: &str, threads: usize) -> MemorySink {
    let scn = load_in(text, Path::new(".")).expect("a valid layered raster scenario");
    let mut sim = granflow::setup::build_layers_2d(&scn, threads);
    let mut sink = MemorySink::default();
    sim.run(&mut sink, &mut |_| {}).expect("the run completes");
    sink
}

/// Every number of the run (snapshots with their layer velocities and static
/// interface, step records, maps) is the same on 1, 2 and 4 threads; the mass in the
/// walled box is conserved to round-off.
#[test]
fn a_layered_raster_run_gives_the_same_bits_on_any_number_of_threads() {
    let one = run(BOX, 1);
    assert!(one.steps.len() > 10, "{} steps", one.steps.len());
    assert_eq!(one.snapshots.len(), 4);
    for threads in [2, 4] {
        let other = run(BOX, threads);
        assert_eq!(other.snapshots, one.snapshots, "{threads} threads");
        assert_eq!(other.steps, one.steps, "{threads} threads");
        // By bits: the arrival map is NaN where the flow never came.
        let bits = |s: &MemorySink| -> Vec<Vec<u64>> {
            let maps = s.maps.iter();
            maps.map(|(_, m)| m.iter().map(|v| v.to_bits()).collect())
                .collect()
        };
        assert_eq!(bits(&other), bits(&one), "{threads} threads");
        assert_eq!(other.map_scalars, one.map_scalars, "{threads} threads");
    }
    let m0 = one.steps[0].mass;
    for rec in &one.steps {
        assert!((rec.mass - m0).abs() <= 1e-13 * m0, "{} vs {m0}", rec.mass);
    }
    assert!(!one.maps.is_empty(), "the monolayer's maps are written");
}

/// The snapshot's `u`, `v` are the depth means Σ l_α u_α of the layer velocities it
/// carries (layer-major, N × cells), the layers differ (a velocity profile, not a
/// plug), and the static interface lies between the bed and the top of the flow.
#[test]
fn the_snapshots_carry_the_layer_velocities_and_their_depth_means() {
    let sink = run(BOX, 1);
    let (n, cells) = (4, 24 * 20);
    let last = sink.snapshots.last().unwrap();
    let (ul, vl) = last.layer_uv.as_ref().expect("layer velocities");
    assert_eq!((ul.len(), vl.len()), (n * cells, n * cells));
    let mut sheared = 0;
    for k in 0..cells {
        let mean = |q: &[f64]| (0..n).map(|a| 0.25 * q[a * cells + k]).sum::<f64>();
        let scale = 1.0 + ul[k].abs() + vl[k].abs();
        assert!((mean(ul) - last.u[k]).abs() <= 1e-12 * scale, "cell {k}");
        let top = ul[(n - 1) * cells + k].hypot(vl[(n - 1) * cells + k]);
        let bottom = ul[k].hypot(vl[k]);
        if last.h[k] > 0.01 && top > bottom + 1e-3 {
            sheared += 1;
        }
    }
    assert!(sheared > 10, "{sheared} sheared columns");
    let interface = last.field("static_interface").unwrap();
    for (k, (&z, &h)) in interface.iter().zip(&last.h).enumerate() {
        assert!((0.0..=h).contains(&z), "cell {k}: {z} over h = {h}");
    }
}

/// `granflow run` writes the layer velocities as (nt, N, ny, nx) beside the (nt, ny, nx)
/// fields of a raster run, and the file passes the output checker when h5py is there.
#[test]
fn a_layered_raster_run_writes_its_layer_velocities_to_the_hdf5_file() {
    let dir = tempfile::tempdir().unwrap();
    let scn = dir.path().join("box.toml");
    std::fs::write(&scn, BOX).unwrap();
    let h5 = dir.path().join("box.h5");
    let out = assert_cmd::Command::cargo_bin("granflow")
        .unwrap()
        .arg("run")
        .arg(&scn)
        .args(["-o", h5.to_str().unwrap()])
        .output()
        .unwrap();
    crate::common::assert_success(&out);
    let f = rust_hdf5::H5File::open(&h5).unwrap();
    let shape = |name: &str| f.dataset(name).unwrap().shape();
    assert_eq!(shape("snapshots/u_layers"), vec![4, 4, 20, 24]);
    assert_eq!(shape("snapshots/v_layers"), vec![4, 4, 20, 24]);
    assert_eq!(shape("snapshots/u"), vec![4, 20, 24]);
    assert_eq!(shape("snapshots/static_interface"), vec![4, 20, 24]);
    assert_eq!(read_h5(&f, "snapshots/layer"), vec![0.0, 1.0, 2.0, 3.0]);
    let from_memory = run(BOX, 1);
    let last = from_memory.snapshots.last().unwrap();
    let u_layers = read_h5(&f, "snapshots/u_layers");
    assert_eq!(
        &u_layers[3 * 4 * 480..],
        &last.layer_uv.as_ref().unwrap().0[..]
    );
    if let Some(report) = crate::common::check_output_with_h5py(&h5, 4) {
        assert!(report.starts_with("OK"), "{report}");
    }
}

/// What the raster's layered stages do not implement is refused by its key, with the
/// line of the key, and what to do instead.
#[test]
fn a_layered_raster_refuses_what_its_stages_do_not_implement_by_key() {
    let dir = Path::new(".");
    let with = |from: &str, to: &str| {
        assert!(BOX.contains(from), "{from}");
        BOX.replacen(from, to, 1)
    };
    let message = fails_at(
        &with(
            "slope_deg = 20.0\ncoordinates = \"local\"",
            "coordinates = \"bed_normal\"",
        ),
        dir,
        "domain.coordinates",
    );
    assert!(message.contains("\"local\" or \"cartesian\""), "{message}");
    let message = fails_at(
        &with("i0 = 0.279", "i0 = 0.279\nviscosity = \"implicit\""),
        dir,
        "rheology.viscosity",
    );
    assert!(message.contains("\"lagged\""), "{message}");
    fails_at(
        &with("i0 = 0.279", "i0 = 0.279\nc_msm = true"),
        dir,
        "rheology.c_msm",
    );
    fails_at(
        &with(
            "i0 = 0.279",
            "i0 = 0.279\nmu_w_deg = 10.0\nchannel_width = 0.1",
        ),
        dir,
        "rheology.channel_width",
    );
    let message = fails_at(
        &with("[model]\n", "[numerics]\norder = 2\n\n[model]\n"),
        dir,
        "numerics.order",
    );
    assert!(message.contains("on a raster"), "{message}");
    // The non-hydrostatic pressure is the line's alone.
    let message = fails_at(
        &with("layers = 4", "layers = 4\npressure = \"nonhydrostatic\""),
        dir,
        "model.pressure",
    );
    assert!(message.contains("raster"), "{message}");
}

/// A bed with nodata cells (wall cells) and a friction field are refused for the
/// layered raster by the key that brings them, while the monolayer takes both.
#[test]
fn a_layered_raster_refuses_nodata_beds_and_friction_fields() {
    let dir = tempfile::tempdir().unwrap();
    let asc = |name: &str, value: &dyn Fn(usize, usize) -> f64| {
        let mut text =
            "ncols 4\nnrows 3\nxllcorner 0\nyllcorner 0\ncellsize 1\nNODATA_value -9999\n"
                .to_string();
        for r in 0..3 {
            let row: Vec<String> = (0..4).map(|c| value(c, r).to_string()).collect();
            text += &(row.join(" ") + "\n");
        }
        std::fs::write(dir.path().join(name), text).unwrap();
    };
    asc("dem.asc", &|c, r| {
        if (c, r) == (3, 0) {
            -9999.0
        } else {
            0.1 * c as f64
        }
    });
    asc("flat.asc", &|c, _| 0.1 * c as f64);
    asc("mu.asc", &|c, _| 0.3 + 0.1 * c as f64);
    let scenario = |dem: &str, friction: &str, layers: usize| {
        format!(
            "[domain]\ncoordinates = \"cartesian\"\n\n[bed]\nb = {{ raster = \"{dem}\" }}\n\n\
             [rheology]\nlaw = \"coulomb\"\n{friction}\n\n[model]\nlayers = {layers}\n\n\
             [initial]\nh = \"if(x < 1.5, 0.2, 0)\"\n\n[time]\nt_end = 0.1\n"
        )
    };
    let nodata = scenario("dem.asc", "mu = 0.4", 3);
    let message = fails_at(&nodata, dir.path(), "bed.b");
    assert!(message.contains("1 cells without data"), "{message}");
    let zones = scenario("flat.asc", "mu = { raster = \"mu.asc\" }", 3);
    fails_at(&zones, dir.path(), "rheology.mu");
    for monolayer in [
        scenario("dem.asc", "mu = 0.4", 1),
        scenario("flat.asc", "mu = { raster = \"mu.asc\" }", 1),
    ] {
        load_in(&monolayer, dir.path()).expect("the monolayer takes it");
    }
    load_in(&scenario("flat.asc", "mu = 0.4", 3), dir.path()).expect("a full bed and one μ");
}

/// The radial collapse of `scenarios/radial_collapse_layers.toml` on n × n cells with
/// `layers` layers, on one thread: the final state's runout along +x and, at
/// t = 0.3 s, the profile at the front (see [`front_profile`]); and the CPU time.
struct RadialRun {
    runout: f64,
    profile: FrontProfile,
    seconds: f64,
}

/// The column at the front at t = 0.3 s: the outermost cell on the +x axis whose
/// thickness exceeds 5 mm; its x, h, and the velocity along x of each layer.
#[derive(Debug)]
struct FrontProfile {
    x: f64,
    h: f64,
    u: Vec<f64>,
}

/// Thickness along the +x axis: the mean of the two rows beside y = 0 (n even).
fn axis_profile(h: &[f64], n: usize) -> Vec<f64> {
    let (a, b) = (n / 2 - 1, n / 2);
    (0..n)
        .map(|i| 0.5 * (h[a * n + i] + h[b * n + i]))
        .collect()
}

/// Where the axis profile last exceeds `threshold`, linearly between cell centres.
fn front_along_x(p: &[f64], x: impl Fn(usize) -> f64, threshold: f64) -> f64 {
    let n = p.len();
    let i = (n / 2..n)
        .rev()
        .find(|&i| p[i] > threshold)
        .expect("a wet axis");
    if i + 1 == n {
        return x(i);
    }
    let s = (p[i] - threshold) / (p[i] - p[i + 1]);
    x(i) + s * (x(i + 1) - x(i))
}

fn radial_run(n: usize, layers: usize) -> RadialRun {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/radial_collapse_layers.toml");
    let text = std::fs::read_to_string(&path).unwrap();
    let sets = [
        format!("domain.cells=[{n},{n}]"),
        format!("model.layers={layers}"),
    ];
    let scn = granflow::scenario::load_str(&text, path.parent().unwrap(), &sets).unwrap();
    let mut run = granflow::setup::build_threads(&scn, 1);
    let mut sink = MemorySink::default();
    let start = std::time::Instant::now();
    run.run(&mut sink, &mut |_| {}).expect("the collapse runs");
    let seconds = start.elapsed().as_secs_f64();
    let dx = 3.0 / n as f64;
    let x = |i: usize| -1.5 + (i as f64 + 0.5) * dx;
    let last = sink.snapshots.last().unwrap();
    let runout = front_along_x(&axis_profile(&last.h, n), x, 1e-3);
    let at = sink
        .snapshots
        .iter()
        .find(|s| (s.t - 0.3).abs() < 1e-9)
        .expect("a snapshot at 0.3 s");
    let p = axis_profile(&at.h, n);
    let i = (n / 2..n).rev().find(|&i| p[i] > 5e-3).unwrap();
    let cells = n * n;
    let (a, b) = ((n / 2 - 1) * n + i, (n / 2) * n + i);
    let u = match &at.layer_uv {
        Some((u, _)) => (0..layers)
            .map(|l| 0.5 * (u[l * cells + a] + u[l * cells + b]))
            .collect(),
        None => vec![0.5 * (at.u[a] + at.u[b])],
    };
    RadialRun {
        runout,
        profile: FrontProfile {
            x: x(i),
            h: p[i],
            u,
        },
        seconds,
    }
}

/// The radial collapse with 10 layers against one (the depth-averaged model), on
/// 40², 80² and 160² cells: the velocity profile u(z) at the front at t = 0.3 s and
/// the runouts along +x of the deposits. The difference of the runouts converges with
/// Δx (its changes shrink), and the ten layers carry a sheared profile at the front,
/// slowest at the bed. Prints the table of docs/validation.md ("radial-layers").
#[test]
#[ignore = "slow: refinement study"]
fn radial_collapse_with_ten_layers_against_one_converges_with_dx() {
    let mut differences = Vec::new();
    println!(
        "| cells | runout, N = 1 (m) | runout, N = 10 (m) | difference (m) | wall s, N = 1 / 10 |"
    );
    println!("|---|---|---|---|---|");
    let mut profiles = Vec::new();
    for n in [40, 80, 160] {
        let (one, ten) = (radial_run(n, 1), radial_run(n, 10));
        let d = ten.runout - one.runout;
        println!(
            "| {n}² | {:.4} | {:.4} | {d:+.4} | {:.2} / {:.2} |",
            one.runout, ten.runout, one.seconds, ten.seconds
        );
        differences.push(d);
        profiles.push((n, one.profile, ten.profile));
    }
    for (n, one, ten) in &profiles {
        println!(
            "{n}²: N = 1 at x = {:.4} m, h = {:.4} m: u = {:.4} m/s",
            one.x, one.h, one.u[0]
        );
        let u: Vec<String> = ten.u.iter().map(|u| format!("{u:.4}")).collect();
        println!(
            "{n}²: N = 10 at x = {:.4} m, h = {:.4} m: u_α = [{}] m/s (bed first)",
            ten.x,
            ten.h,
            u.join(", ")
        );
        let u = &ten.u;
        assert!(
            u[9] > u[0] + 0.05 && u.windows(2).all(|w| w[1] >= w[0] - 1e-3),
            "{u:?}"
        );
    }
    let changes = [
        (differences[1] - differences[0]).abs(),
        (differences[2] - differences[1]).abs(),
    ];
    println!("changes of the difference: {changes:?}");
    assert!(changes[1] < changes[0], "{differences:?}");
}
