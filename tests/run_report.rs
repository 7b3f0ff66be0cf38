//! What a run tells of its outcome: one status line, the mass that left through an
//! outflow boundary (report, `/summary`, sweep CSV), a front that reached the end of
//! the domain, and profile tables whose columns are named.

use std::fs;
use std::path::Path;

use assert_cmd::Command;

fn granflow() -> Command {
    Command::cargo_bin("granflow").unwrap()
}

/// A slope whose mass slides off its open end: the bed is a user's table `x,b`.
const LEAKING: &str = r#"[domain]
x_min = 0.0
x_max = 2.0
cells = 100
slope_deg = 30

[boundary]
right = "outflow"

[bed]
b = { table = "bed.csv" }

[rheology]
law = "coulomb"
mu_deg = 20

[initial]
h = "if(x < 0.5, 0.1, 0)"

[time]
t_end = 1.2
"#;

fn leaking(dir: &Path) -> std::path::PathBuf {
    fs::write(dir.join("bed.csv"), "x,b\n0,0\n2,0\n").unwrap();
    let scn = dir.join("leak.toml");
    fs::write(&scn, LEAKING).unwrap();
    scn
}

#[test]
fn mass_that_left_the_domain_is_reported_and_warned_about() {
    let dir = tempfile::tempdir().unwrap();
    let scn = leaking(dir.path());
    let h5 = dir.path().join("leak.h5");
    let out = granflow()
        .args([
            "run",
            scn.to_str().unwrap(),
            "--progress",
            "none",
            "--output",
        ])
        .arg(&h5)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    let line = stdout
        .lines()
        .find(|l| l.starts_with("  outflowed"))
        .unwrap_or_else(|| panic!("no outflow line: {stdout}"));
    let pct: f64 = line.split_whitespace().nth(1).unwrap().parse().unwrap();
    assert!(pct > 1.0 && pct < 100.0, "{line}");
    assert!(
        stderr.contains("% of the initial mass left the domain through an outflow boundary"),
        "{stderr}"
    );
    assert!(
        stderr.contains("the front reached the end of the domain at t = "),
        "{stderr}"
    );
    assert!(
        stdout.contains("(at least: the front reached the end"),
        "{stdout}"
    );
    // One status line, and no separate stop or settled lines to contradict it.
    assert_eq!(stdout.matches("granflow: ").count(), 1, "{stdout}");
    assert!(
        !stdout.contains("stop time") && !stdout.contains("  settled "),
        "{stdout}"
    );

    if let Some(python) = crate::common::python_with_h5py() {
        let out = std::process::Command::new(python)
            .args([
                "-c",
                "import sys, h5py; s = h5py.File(sys.argv[1])['summary'].attrs; \
                 print(s['outflowed_fraction'], s['front_at_end_time'])",
            ])
            .arg(&h5)
            .output()
            .unwrap();
        let text = crate::common::assert_success(&out);
        let v: Vec<f64> = text
            .split_whitespace()
            .map(|w| w.parse().unwrap())
            .collect();
        assert!((100.0 * v[0] - pct).abs() < 0.01 * pct, "{text} vs {pct}");
        assert!(v[1] > 0.0 && v[1] < 1.2, "{text}");
    }
}

#[test]
fn the_sweep_summary_has_the_outflowed_fraction() {
    let dir = tempfile::tempdir().unwrap();
    leaking(dir.path());
    let sweep = dir.path().join("sweep.toml");
    fs::write(
        &sweep,
        "scenario = \"leak.toml\"\n\n[axes]\nrheology.mu_deg = [20, 40]\n",
    )
    .unwrap();
    let out_dir = dir.path().join("out");
    let out = granflow()
        .args(["sweep", sweep.to_str().unwrap(), "--quiet", "--output"])
        .arg(&out_dir)
        .output()
        .unwrap();
    crate::common::assert_success(&out);
    let csv = fs::read_to_string(out_dir.join("summary.csv")).unwrap();
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = header
        .iter()
        .position(|&c| c == "outflowed_fraction")
        .unwrap_or_else(|| panic!("{csv}"));
    let f: Vec<f64> = lines
        .map(|l| l.split(',').nth(col).unwrap().parse().unwrap())
        .collect();
    // 20°: most of the mass has slid off; 40° (above the 30° slope): none of it.
    assert!(f[0] > 0.01 && f[1] < 1e-9, "{csv}");
}

#[test]
fn a_lake_at_rest_is_reported_at_rest() {
    let scn = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/lake_at_rest.toml");
    let dir = tempfile::tempdir().unwrap();
    let out = granflow()
        .args([
            "run",
            scn.to_str().unwrap(),
            "--progress",
            "none",
            "--output",
        ])
        .arg(dir.path().join("lake.h5"))
        .output()
        .unwrap();
    let stdout = crate::common::assert_success(&out);
    let first = stdout.lines().next().unwrap();
    assert!(
        first.starts_with("granflow: completed at t = 2.000 s: reached time.t_end; at rest"),
        "{stdout}"
    );
    assert!(
        !stdout.contains("not at rest") && !stdout.contains("not settled"),
        "{stdout}"
    );
    // A domain wet to its end has no front reaching it.
    assert!(
        !String::from_utf8_lossy(&out.stderr).contains("warning"),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

#[test]
fn a_table_whose_columns_do_not_say_which_is_the_bed_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let scn = leaking(dir.path());
    fs::write(dir.path().join("bed.csv"), "x,y,z\n0,0,1\n2,0,1\n").unwrap();
    let out = granflow()
        .args(["check", scn.to_str().unwrap()])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("bed.csv") && stderr.contains("bed.b") && stderr.contains("'x', 'y', 'z'"),
        "{stderr}"
    );
    // Named columns are read whatever their order and number.
    fs::write(dir.path().join("bed.csv"), "z,b,x\n9,0,0\n9,0,2\n").unwrap();
    let out = granflow()
        .args(["check", scn.to_str().unwrap()])
        .output()
        .unwrap();
    crate::common::assert_success(&out);
}

/// A DEM whose slope faces south (the flow goes to −y) and a release near its top:
/// 20 × 48 cells of 5 m, a 30° slope for y > 100 m and flat below.
fn south_facing(dir: &Path) -> std::path::PathBuf {
    let (nx, ny, d) = (20, 48, 5.0);
    let mut text = format!(
        "ncols {nx}\nnrows {ny}\nxllcorner 0\nyllcorner 0\ncellsize {d}\nNODATA_value -9999\n"
    );
    for row in 0..ny {
        let y = (ny - row) as f64 * d - 0.5 * d;
        let b = (y - 100.0).max(0.0) * 30f64.to_radians().tan();
        let line: Vec<String> = (0..nx).map(|_| format!("{b}")).collect();
        text.push_str(&line.join(" "));
        text.push('\n');
    }
    fs::write(dir.join("dem.asc"), text).unwrap();
    let scn = dir.join("south.toml");
    fs::write(
        &scn,
        r#"[domain]
coordinates = "cartesian"

[bed]
b = { raster = "dem.asc" }

[rheology]
law = "coulomb"
mu_deg = 22

[initial]
h = "if(abs(x - 50) < 15 && y > 190 && y < 220, 2, 0)"

[time]
t_end = 12

[output]
path = { line = "path.geojson", field = "pft", threshold = 0.001 }
"#,
    )
    .unwrap();
    // The thalweg: straight down the slope, from the top of the DEM to its foot.
    fs::write(
        dir.join("path.geojson"),
        r#"{"type": "LineString", "coordinates": [[50, 235], [50, 120], [50, 5]]}"#,
    )
    .unwrap();
    scn
}

/// A raster run's report and a raster sweep's table give the runout along the flow
/// (here to the south, 100 m and more), its travel angle and the area reached, not the
/// front's advance along x (zero on this slope); the report names the `.xmf` too.
#[test]
fn a_raster_run_reports_its_runout_along_the_flow() {
    let dir = tempfile::tempdir().unwrap();
    south_facing(dir.path());
    let out = granflow()
        .args(["run", "south.toml", "--progress", "none"])
        .current_dir(dir.path())
        .output()
        .unwrap();
    let stdout = crate::common::assert_success(&out);
    let line = stdout
        .lines()
        .find(|l| l.starts_with("  runout"))
        .unwrap_or_else(|| panic!("no runout line: {stdout}"));
    assert!(line.contains("m along the flow"), "{line}");
    let runout: f64 = line.split_whitespace().nth(1).unwrap().parse().unwrap();
    assert!(runout > 60.0 && runout < 240.0, "{line}");
    let angle: f64 = line
        .rsplit("travel angle ")
        .next()
        .unwrap()
        .trim_end_matches('°')
        .parse()
        .unwrap();
    assert!(angle > 10.0 && angle < 30.0, "{line}");
    assert!(stdout.contains("  area reached  "), "{stdout}");
    // Along the thalweg (output.path, pft > 1 mm as the runout above): the same runout
    // to a cell or two, the line running with the flow.
    let path_line = stdout
        .lines()
        .find(|l| l.starts_with("  path runout"))
        .unwrap_or_else(|| panic!("no path runout line: {stdout}"));
    let along: f64 = path_line
        .split_whitespace()
        .nth(2)
        .unwrap()
        .parse()
        .unwrap();
    assert!((along - runout).abs() <= 10.0, "{path_line} against {line}");
    // The report lists every file the run wrote, the XDMF description included.
    let output = stdout
        .lines()
        .find(|l| l.starts_with("  output"))
        .unwrap_or_else(|| panic!("{stdout}"));
    assert!(output.contains("south.xmf"), "{output}");
    assert!(dir.path().join("south.xmf").is_file());

    // A friction sweep: the runout shortens as μ grows.
    fs::write(
        dir.path().join("sweep.toml"),
        "scenario = \"south.toml\"\n\n[axes]\nrheology.mu_deg = [18, 26]\n",
    )
    .unwrap();
    let out_dir = dir.path().join("out");
    let out = granflow()
        .args(["sweep", "sweep.toml", "--output", "out"])
        .current_dir(dir.path())
        .output()
        .unwrap();
    let stdout = crate::common::assert_success(&out);
    let table: Vec<&str> = stdout
        .lines()
        .skip_while(|l| !l.contains("runout_m"))
        .collect();
    assert!(
        table[0].contains("travel_deg")
            && table[0].contains("area_m2")
            && table[0].contains("path_m"),
        "{stdout}"
    );
    let runout_m: Vec<f64> = table[1..3]
        .iter()
        .map(|l| l.split_whitespace().nth(1).unwrap().parse().unwrap())
        .collect();
    assert!(runout_m[0] > runout_m[1] && runout_m[1] > 30.0, "{stdout}");
    let csv = fs::read_to_string(out_dir.join("summary.csv")).unwrap();
    let header: Vec<&str> = csv.lines().next().unwrap().split(',').collect();
    let col = header
        .iter()
        .position(|&c| c == "runout_length")
        .unwrap_or_else(|| panic!("{csv}"));
    assert!(header.contains(&"path_runout_length"), "{csv}");
    let lengths: Vec<f64> = csv
        .lines()
        .skip(1)
        .map(|l| l.split(',').nth(col).unwrap().parse().unwrap())
        .collect();
    assert_eq!(lengths.len(), 2, "{csv}");
    for (a, b) in lengths.iter().zip(&runout_m) {
        assert!((a - b).abs() <= 1e-3 * a, "{csv} against {stdout}");
    }
}

/// A raster run says where its time goes: its progress lines and its report give the
/// wet fraction of its cells and the cell updates per second counted on the wet ones,
/// and `/summary` holds them. The release covers 3 × 6 of the 960 cells (under 2 %);
/// the flow wets more of them, never all.
#[test]
fn a_raster_run_reports_its_wet_fraction_and_its_rate_on_wet_cells() {
    let dir = tempfile::tempdir().unwrap();
    south_facing(dir.path());
    let out = granflow()
        .args([
            "run",
            "south.toml",
            "--progress",
            "lines",
            "--progress-every",
            "0",
        ])
        .args(["--set", "time.t_end=2"])
        .current_dir(dir.path())
        .output()
        .unwrap();
    let stdout = crate::common::assert_success(&out);
    let stderr = String::from_utf8_lossy(&out.stderr);
    let progress = stderr
        .lines()
        .rfind(|l| l.starts_with("granflow: t = "))
        .unwrap_or_else(|| panic!("no progress line: {stderr}"));
    assert!(
        progress.contains("% of 960 cells, ") && progress.ends_with(" wet-cell updates/s"),
        "{progress}"
    );
    let line = stdout
        .lines()
        .find(|l| l.starts_with("  wet cells"))
        .unwrap_or_else(|| panic!("no wet cells line: {stdout}"));
    let mean: f64 = line.split_whitespace().nth(2).unwrap().parse().unwrap();
    assert!(mean > 1.5 && mean < 100.0, "{line}");
    assert!(line.contains("% of 960 on average, "), "{line}");
    assert!(line.contains(" wet-cell updates/s (") && line.ends_with(" on the cells stepped)"));

    let Some(python) = crate::common::python_with_h5py() else {
        return;
    };
    let out = std::process::Command::new(python)
        .args([
            "-c",
            "import sys, h5py; s = h5py.File(sys.argv[1])['summary'].attrs; \
             print(*[s[k] for k in ('flow_cells', 'wet_fraction_mean', 'wet_fraction_peak', \
             'wet_cell_updates_per_s', 'cell_updates_per_s')])",
        ])
        .arg(dir.path().join("south.h5"))
        .output()
        .unwrap();
    let text = crate::common::assert_success(&out);
    let v: Vec<f64> = text
        .split_whitespace()
        .map(|w| w.parse().unwrap())
        .collect();
    assert_eq!(v[0], 960.0, "{text}");
    let (mean_h5, peak) = (v[1], v[2]);
    assert!(
        (100.0 * mean_h5 - mean).abs() <= 0.01 * mean,
        "{mean_h5} vs {line}"
    );
    assert!(peak >= mean_h5 && peak < 1.0, "{peak}");
    // Fewer wet-cell updates than updates of the cells stepped (the wet ones and the dry
    // ones of the active tiles), both counted on the same time.
    let (wet_rate, all_rate) = (v[3], v[4]);
    assert!(
        wet_rate > 0.0 && wet_rate < all_rate,
        "{wet_rate} vs {all_rate}"
    );
}

/// The maxima along the path (`/path/*`): on a line straight down the middle of the
/// slope, through cell centres, each station is one row of the DEM, so its pft, pfv
/// and ppr are the row's largest values of the maps; a band of 10 m keeps the line's
/// column and its two neighbours. The sweep table's maxima are the largest of the
/// profiles, and the report prints them.
#[test]
fn the_maxima_along_the_path_are_those_of_the_maps_across_its_band() {
    use rust_hdf5::H5File;
    let dir = tempfile::tempdir().unwrap();
    let scn = south_facing(dir.path());
    // The column x = 52.5 m (column 10), from the centre of the top row (y = 237.5 m)
    // down.
    fs::write(
        dir.path().join("centre.geojson"),
        r#"{"type": "LineString", "coordinates": [[52.5, 237.5], [52.5, 2.5]]}"#,
    )
    .unwrap();
    let text = fs::read_to_string(&scn).unwrap().replace(
        r#"path = { line = "path.geojson", field = "pft", threshold = 0.001 }"#,
        r#"path = { line = "centre.geojson", field = "pft", threshold = 0.001, width = 10 }"#,
    );
    fs::write(&scn, text).unwrap();
    fs::write(
        dir.path().join("sweep.toml"),
        "scenario = \"south.toml\"\n\n[axes]\nrheology.mu_deg = [22]\n",
    )
    .unwrap();
    let out = granflow()
        .args(["sweep", "sweep.toml", "--output", "out"])
        .current_dir(dir.path())
        .output()
        .unwrap();
    let stdout = crate::common::assert_success(&out);
    assert!(stdout.contains("max_ppr_kPa"), "{stdout}");
    let out_dir = dir.path().join("out");
    let h5 = fs::read_dir(&out_dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .find(|p| p.extension().is_some_and(|e| e == "h5"))
        .unwrap();
    let file = H5File::open(&h5).unwrap();
    let read = |name: &str| crate::common::read_h5(&file, name);
    let csv = fs::read_to_string(out_dir.join("summary.csv")).unwrap();
    let header: Vec<&str> = csv.lines().next().unwrap().split(',').collect();
    let row: Vec<&str> = csv.lines().nth(1).unwrap().split(',').collect();
    let column = |name: &str| -> f64 {
        let c = header.iter().position(|&c| c == name);
        row[c.unwrap_or_else(|| panic!("no {name}: {csv}"))]
            .parse()
            .unwrap()
    };
    // The maps' row j (row 0 south) is at y = /grid/y[j], station s = 237.5 − y.
    let (nx, y) = (20, read("grid/y"));
    let s = read("path/s");
    assert_eq!(s.len(), y.len(), "{s:?}");
    let row_of = |s: f64| y.iter().position(|&y| 237.5 - y == s).unwrap();
    for (map, profile, units, name) in [
        ("maps/h_max", "path/pft_max", "m", "path_max_pft"),
        ("maps/speed_max", "path/pfv_max", "m/s", "path_max_pfv"),
        ("maps/ppr", "path/ppr_max", "Pa", "path_max_ppr"),
    ] {
        let values = read(map);
        let along = read(profile);
        let unit = file.dataset(profile).unwrap().attr("units").unwrap();
        assert_eq!(unit.read_string().unwrap(), units);
        for (i, &s) in s.iter().enumerate() {
            assert_eq!(s, 5.0 * i as f64);
            let j = row_of(s);
            let direct = values[j * nx + 9..=j * nx + 11]
                .iter()
                .copied()
                .fold(f64::NEG_INFINITY, f64::max);
            assert_eq!(along[i], direct, "{profile} at s = {s}");
        }
        let largest = along.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        assert!(largest > 0.0, "{profile}: {along:?}");
        assert_eq!(column(name), largest, "{name}");
    }
    // The thalweg's bed, and the line's points.
    let b = read("grid/b");
    let z: Vec<f64> = s.iter().map(|&s| b[row_of(s) * nx + 10]).collect();
    assert_eq!(read("path/z"), z);
    assert!(read("path/x").iter().all(|&x| x == 52.5));
    // The runout along the path is the last station where pft exceeds the threshold.
    let pft = read("path/pft_max");
    let last = pft.iter().rposition(|&v| v > 0.001).unwrap();
    let top = 237.5 - 217.5;
    assert_eq!(column("path_runout_length"), s[last] - top);
}
