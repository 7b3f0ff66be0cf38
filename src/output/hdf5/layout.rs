//! The HDF5 layout itself: which group, dataset and attribute holds what, in which
//! units and chunking. Each function works on an open file; [`super::Hdf5Sink`] opens
//! and closes it and turns errors into [`crate::output::OutputError`].

use rust_hdf5::{DatatypeMessage, H5Dataset, H5File, H5Group, VarLenUnicode};

use crate::grid::{GridSpec, RasterGeometry};
use crate::output::{
    CellField, GaugeRecord, GridData, RasterInfo, RunInfo, RunMaps, RunSummary, SnapshotView,
    StepRecord, FORMAT_VERSION,
};

/// Rows per chunk of the per-step series (`/diagnostics/*`, `/front/*`): 64 KiB.
pub(super) const STEP_CHUNK: usize = 8192;
/// Rows per chunk of `/snapshots/t`.
pub(super) const SNAP_T_CHUNK: usize = 256;

/// Per-step datasets, in the order of [`step_columns`]: (path, units).
pub(super) const STEP_DATASETS: [(&str, &str); 7] = [
    ("diagnostics/t", "s"),
    ("diagnostics/dt", "s"),
    ("diagnostics/mass", "m^2"),
    ("diagnostics/kinetic_energy", "m^4/s^2"),
    ("diagnostics/max_speed", "m/s"),
    ("front/t", "s"),
    ("front/x", "m"),
];

/// Root attributes, `/grid`, and the datasets every run has, empty.
pub(super) fn write_layout(
    file: &H5File,
    info: &RunInfo,
    grid: &GridData,
) -> rust_hdf5::Result<()> {
    file.set_attr_numeric("format_version", &FORMAT_VERSION)?;
    file.set_attr_string("granflow_version", &info.granflow_version)?;
    file.set_attr_string("model", &info.model)?;
    file.set_attr_string("pressure", &info.pressure)?;
    file.set_attr_numeric("layers", &(info.layers as i64))?;
    file.set_attr_string("coordinates", &info.coordinates)?;
    file.set_attr_numeric("slope_deg", &info.slope_deg)?;
    file.set_attr_string("scenario_toml", &info.scenario_toml)?;
    if let Some(r) = &info.raster {
        return write_raster_layout(file, info, r, grid);
    }

    let g = file.create_group("grid")?;
    spec_attributes(&g, grid.spec)?;
    for (name, data) in [("x", grid.x), ("b", grid.b), ("h_bed", grid.h_bed)] {
        let ds = g.new_dataset::<f64>().shape([data.len()]).create(name)?;
        ds.write_raw(data)?;
        units(&ds, "m")?;
    }

    let nx = grid.x.len();
    let s = file.create_group("snapshots")?;
    let t = series(&s, "t", SNAP_T_CHUNK)?;
    units(&t, "s")?;
    dimension_scale(&t, Dim::T)?;
    let x = s.new_dataset::<f64>().shape([nx]).create("x")?;
    x.write_raw(grid.x)?;
    units(&x, "m")?;
    dimension_scale(&x, Dim::X)?;
    layer_scale(&s, info.layers)?;
    if info.pressure == "nonhydrostatic" {
        // The axes of p_nh: the nl + 1 layer interfaces (0 the bed) and the nx + 1
        // cell faces.
        let levels: Vec<f64> = (0..=info.layers).map(|k| k as f64).collect();
        let level = s
            .new_dataset::<f64>()
            .shape([levels.len()])
            .create("level")?;
        level.write_raw(&levels)?;
        units(&level, "1")?;
        dimension_scale(&level, Dim::Level)?;
        let dx = if nx > 1 { grid.x[1] - grid.x[0] } else { 0.0 };
        let x0 = grid.x.first().copied().unwrap_or(0.0) - 0.5 * dx;
        let faces: Vec<f64> = (0..=nx).map(|i| x0 + i as f64 * dx).collect();
        let x_face = s.new_dataset::<f64>().shape([nx + 1]).create("x_face")?;
        x_face.write_raw(&faces)?;
        units(&x_face, "m")?;
        dimension_scale(&x_face, Dim::XFace)?;
    }
    frames(&s, "h", &[nx], "m", &[Dim::X])?;
    frames(&s, "u", &[info.layers, nx], "m/s", &[Dim::Layer, Dim::X])?;
    step_groups(file, info, &STEP_DATASETS)
}

/// `/front`, `/diagnostics` with their empty series (`datasets`: path, units) and the
/// `/summary` group with the status of an unfinished run.
fn step_groups(
    file: &H5File,
    info: &RunInfo,
    datasets: &[(&str, &str); 7],
) -> rust_hdf5::Result<()> {
    let front = file.create_group("front")?;
    front.set_attr_numeric("threshold", &info.front_threshold)?;
    file.create_group("diagnostics")?;
    for &(path, unit) in datasets {
        let (group, name) = path.split_once('/').expect("group/name");
        let ds = series(&file.root_group().group(group)?, name, STEP_CHUNK)?;
        units(&ds, unit)?;
        if path == "front/x" {
            let attr = ds.new_attr::<f64>().shape(()).create("threshold")?;
            attr.write_numeric(&info.front_threshold)?;
        }
    }
    // Replaced by the real status at finish: a file whose writer was killed says so.
    let summary = file.create_group("summary")?;
    summary.set_attr_string("status", UNFINISHED)?;
    Ok(())
}

/// The grid's spec as attributes of `/grid` (docs/output-format.md, "`/grid`"): `kind`,
/// the numbers of the geometry, on a raster its CRS and the text `spec` that granflow
/// reads back.
fn spec_attributes(g: &H5Group, spec: &GridSpec) -> rust_hdf5::Result<()> {
    match spec {
        GridSpec::Line(l) => {
            g.set_attr_string("kind", "line")?;
            g.set_attr_numeric("nx", &(l.nx as i64))?;
            for (name, value) in [("x_min", l.x_min), ("x_max", l.x_max), ("dx", l.dx)] {
                g.set_attr_numeric(name, &value)?;
            }
        }
        GridSpec::Raster(r) => {
            g.set_attr_string("kind", "raster")?;
            g.set_attr_numeric("nx", &(r.nx as i64))?;
            g.set_attr_numeric("ny", &(r.ny as i64))?;
            for (name, value) in [
                ("x_min", r.x_min),
                ("x_max", r.x_max),
                ("y_min", r.y_min),
                ("y_max", r.y_max),
                ("dx", r.dx),
                ("dy", r.dy),
            ] {
                g.set_attr_numeric(name, &value)?;
            }
            crs_attributes(g, r)?;
            g.set_attr_string("spec", &r.to_text())?;
        }
    }
    Ok(())
}

/// `crs_epsg`, `crs` (the same code as text, `EPSG:n`, which every HDF5 reader,
/// rust-hdf5 among them, reads back) and `crs_wkt`, those known.
fn crs_attributes(g: &H5Group, r: &RasterGeometry) -> rust_hdf5::Result<()> {
    if let Some(code) = r.crs.epsg {
        g.set_attr_numeric("crs_epsg", &(code as i64))?;
        g.set_attr_string("crs", &format!("EPSG:{code}"))?;
    }
    if let Some(wkt) = &r.crs.wkt {
        g.set_attr_string("crs_wkt", wkt)?;
    }
    Ok(())
}

/// The per-step datasets of a raster run: volumes in m³, energies in m⁵/s².
const RASTER_STEP_DATASETS: [(&str, &str); 7] = [
    ("diagnostics/t", "s"),
    ("diagnostics/dt", "s"),
    ("diagnostics/mass", "m^3"),
    ("diagnostics/kinetic_energy", "m^5/s^2"),
    ("diagnostics/max_speed", "m/s"),
    ("front/t", "s"),
    ("front/x", "m"),
];

/// The layout of a raster run (docs/output-format.md, "Raster runs"): `/grid/x` (nx)
/// and `/grid/y` (ny) axes, `/grid/b` and `/grid/h_bed` as (ny, nx), the raster
/// attributes, and `/snapshots/{h, u}` as (nt, ny, nx) with t, y, x dimension scales.
fn write_raster_layout(
    file: &H5File,
    info: &RunInfo,
    r: &RasterInfo,
    grid: &GridData,
) -> rust_hdf5::Result<()> {
    let spec = grid.spec.raster().expect("a raster run's grid is a raster");
    let (nx, ny) = (spec.nx, spec.ny);
    let ys = grid.y.unwrap_or(grid.x);
    let x: Vec<f64> = grid.x[..nx].to_vec();
    let y: Vec<f64> = (0..ny).map(|j| ys[j * nx]).collect();
    file.set_attr_string("grid", "raster")?;
    file.set_attr_numeric("nx", &(nx as i64))?;
    file.set_attr_numeric("ny", &(ny as i64))?;
    file.set_attr_numeric("dx", &spec.dx)?;
    file.set_attr_numeric("dy", &spec.dy)?;
    crs_attributes(&file.root_group(), spec)?;
    if spec.dx == spec.dy {
        // GDAL's order (x₀, Δx, 0, y₀, 0, −Δy), each number in the shortest text that
        // reads back to the same double: the grid exactly, which /grid/x, /grid/y (cell
        // centres) give only to rounding.
        let (x0, y0, d) = (spec.x_min, spec.y_max, spec.dx);
        file.set_attr_string("geotransform", &format!("{x0} {d} 0 {y0} 0 {}", -d))?;
    }
    let g = file.create_group("grid")?;
    spec_attributes(&g, grid.spec)?;
    for (name, data, spacing) in [("x", &x, spec.dx), ("y", &y, spec.dy)] {
        let ds = g.new_dataset::<f64>().shape([data.len()]).create(name)?;
        ds.write_raw(data)?;
        units(&ds, "m")?;
        // The cell size, which an axis of one cell cannot give by its centres.
        let attr = ds.new_attr::<f64>().shape(()).create("spacing")?;
        attr.write_numeric(&spacing)?;
    }
    // Deflated as the maps: an erodible bed is zero outside its zones.
    for (name, data) in [("b", grid.b), ("h_bed", grid.h_bed)] {
        let ds = g
            .new_dataset::<f64>()
            .shape([ny, nx])
            .chunk(&frame_chunk(&[ny, nx], true)[1..])
            .shuffle_deflate(RASTER_DEFLATE_LEVEL)
            .create(name)?;
        ds.write_raw(data)?;
        units(&ds, "m")?;
    }
    let s = file.create_group("snapshots")?;
    let t = series(&s, "t", SNAP_T_CHUNK)?;
    units(&t, "s")?;
    dimension_scale(&t, Dim::T)?;
    for (name, data, dim) in [("x", &x, Dim::X), ("y", &y, Dim::Y)] {
        let ds = s.new_dataset::<f64>().shape([data.len()]).create(name)?;
        ds.write_raw(data)?;
        units(&ds, "m")?;
        dimension_scale(&ds, dim)?;
    }
    frames(&s, "h", &[ny, nx], "m", &[Dim::Y, Dim::X])?;
    frames(&s, "u", &[ny, nx], "m/s", &[Dim::Y, Dim::X])?;
    frames(&s, "v", &[ny, nx], "m/s", &[Dim::Y, Dim::X])?;
    if info.layers > 1 {
        // The layered model's velocity profiles: `u`, `v` above are the depth means.
        layer_scale(&s, info.layers)?;
        let axes = [Dim::Layer, Dim::Y, Dim::X];
        for (name, along) in [("u_layers", "x"), ("v_layers", "y")] {
            let ds = frames(&s, name, &[info.layers, ny, nx], "m/s", &axes)?;
            let text = format!("velocity along {along} of each layer, bottom layer first");
            description(&ds, &text)?;
        }
    }
    step_groups(file, info, &RASTER_STEP_DATASETS)?;
    let summary = file.root_group().group("summary")?;
    summary.set_attr_numeric("wall_cells", &(r.wall_cells as i64))?;
    if let Some(release) = &r.release {
        summary.set_attr_numeric("release_volume", &release.volume)?;
        summary.set_attr_numeric("release_volume_on_walls", &release.volume_on_walls)?;
    }
    Ok(())
}

/// `/snapshots/layer`: the layer indices 0 … `layers` − 1, the dimension scale of the
/// per-layer fields.
fn layer_scale(s: &H5Group, layers: usize) -> rust_hdf5::Result<()> {
    let index: Vec<f64> = (0..layers).map(|k| k as f64).collect();
    let layer = s.new_dataset::<f64>().shape([layers]).create("layer")?;
    layer.write_raw(&index)?;
    units(&layer, "1")?;
    dimension_scale(&layer, Dim::Layer)
}

/// Writes the maps of a raster run, `/maps/<name>` (ny, nx): created with their units
/// when `create`, else overwritten. Chunked and deflated as the snapshot fields
/// ([`frame_chunk`]): a map is zero (or NaN) where the flow never came.
pub(super) fn write_map_fields(
    file: &H5File,
    (nx, ny): (usize, usize),
    fields: &[CellField],
    create: bool,
) -> rust_hdf5::Result<()> {
    if create {
        let g = file.create_group("maps")?;
        for field in fields {
            let ds = g
                .new_dataset::<f64>()
                .shape([ny, nx])
                .chunk(&frame_chunk(&[ny, nx], true)[1..])
                .shuffle_deflate(RASTER_DEFLATE_LEVEL)
                .create(field.name)?;
            ds.write_raw(field.data)?;
            units(&ds, field.units)?;
            description(&ds, field.description)?;
        }
    } else {
        for field in fields {
            file.dataset_writer(&format!("maps/{}", field.name))?
                .write_raw(field.data)?;
        }
    }
    Ok(())
}

/// Writes what a raster run gathered at its end: the maps ([`write_map_fields`]), the
/// per-step series as `/diagnostics/<name>`, the numbers as `/summary` attributes.
pub(super) fn write_maps(
    file: &H5File,
    raster: (usize, usize),
    maps: &RunMaps,
    create: bool,
) -> rust_hdf5::Result<()> {
    write_map_fields(file, raster, maps.maps, create)?;
    let d = file.root_group().group("diagnostics")?;
    for &(name, unit, values) in maps.series {
        let ds = d.new_dataset::<f64>().shape([values.len()]).create(name)?;
        ds.write_raw(values)?;
        units(&ds, unit)?;
    }
    let summary = file.root_group().group("summary")?;
    for &(name, value) in maps.scalars {
        summary.set_attr_numeric(name, &value)?;
    }
    if !maps.profile.is_empty() {
        let g = file.create_group("path")?;
        for &(name, unit, values) in maps.profile {
            let ds = g.new_dataset::<f64>().shape([values.len()]).create(name)?;
            ds.write_raw(values)?;
            units(&ds, unit)?;
        }
    }
    Ok(())
}

/// `/summary` `status` of a file whose run has not finished (or was killed).
pub const UNFINISHED: &str = "unfinished";

/// Creates `/snapshots/w` and `/snapshots/p_nh`, which exist only when the first
/// snapshot carries them.
pub(super) fn create_optional(
    file: &H5File,
    (nx, nl): (usize, usize),
    (w, p_nh): (bool, bool),
) -> rust_hdf5::Result<()> {
    let group = file.root_group().group("snapshots")?;
    if w {
        frames(&group, "w", &[nl, nx], "m/s", &[Dim::Layer, Dim::X])?;
    }
    if p_nh {
        frames(
            &group,
            "p_nh",
            &[nl + 1, nx + 1],
            "m^2/s^2",
            &[Dim::Level, Dim::XFace],
        )?;
    }
    Ok(())
}

/// Creates `/snapshots/<name>` (nt, nx) for the model-specific per-cell fields, which
/// exist only when the first snapshot carries them.
pub(super) fn create_cell_fields(
    file: &H5File,
    nx: usize,
    raster: Option<(usize, usize)>,
    fields: &[CellField],
) -> rust_hdf5::Result<()> {
    if fields.is_empty() {
        return Ok(());
    }
    let group = file.root_group().group("snapshots")?;
    for field in fields {
        let ds = match raster {
            Some((nx, ny)) => frames(
                &group,
                field.name,
                &[ny, nx],
                field.units,
                &[Dim::Y, Dim::X],
            )?,
            None => frames(&group, field.name, &[nx], field.units, &[Dim::X])?,
        };
        description(&ds, field.description)?;
    }
    Ok(())
}

/// Values per chunk of the gauge datasets: 32 KiB.
pub(super) const GAUGE_CHUNK_VALUES: usize = 4096;

/// Creates `/gauges` with the positions `x` and empty `t`, `eta`, `h_grains`.
pub(super) fn create_gauges(file: &H5File, x: &[f64]) -> rust_hdf5::Result<()> {
    let n = x.len();
    let g = file.create_group("gauges")?;
    let ds = g.new_dataset::<f64>().shape([n]).create("x")?;
    ds.write_raw(x)?;
    units(&ds, "m")?;
    let rows = (GAUGE_CHUNK_VALUES / n.max(1)).max(1);
    let t = series(&g, "t", rows)?;
    units(&t, "s")?;
    for name in ["eta", "h_grains"] {
        let ds = g
            .new_dataset::<f64>()
            .shape([0, n])
            .chunk(&[rows, n])
            .max_shape(&[None, Some(n)])
            .create(name)?;
        units(&ds, "m")?;
    }
    Ok(())
}

/// Writes `/gauges/y`, the gauges' y on a raster.
pub(super) fn gauge_y(file: &H5File, y: &[f64]) -> rust_hdf5::Result<()> {
    let g = file.root_group().group("gauges")?;
    let ds = g.new_dataset::<f64>().shape([y.len()]).create("y")?;
    ds.write_raw(y)?;
    units(&ds, "m")
}

/// Gauge rows waiting for the next write: times and row-major (row, gauge) values.
#[derive(Debug, Default)]
pub(super) struct GaugeRows {
    pub t: Vec<f64>,
    pub eta: Vec<f64>,
    pub h_grains: Vec<f64>,
}

impl GaugeRows {
    pub fn push(&mut self, rec: &GaugeRecord) {
        self.t.push(rec.t);
        self.eta.extend_from_slice(rec.eta);
        self.h_grains.extend_from_slice(rec.h_grains);
    }

    pub fn clear(&mut self) {
        self.t.clear();
        self.eta.clear();
        self.h_grains.clear();
    }

    pub fn values(&self) -> usize {
        self.t.len() + self.eta.len() + self.h_grains.len()
    }
}

/// Appends the pending gauge rows to `/gauges/{t, eta, h_grains}`.
pub(super) fn append_gauges(file: &H5File, rows: &GaugeRows) -> rust_hdf5::Result<()> {
    if rows.t.is_empty() {
        return Ok(());
    }
    file.dataset_writer("gauges/t")?.append(&rows.t)?;
    file.dataset_writer("gauges/eta")?.append(&rows.eta)?;
    file.dataset_writer("gauges/h_grains")?
        .append(&rows.h_grains)
}

/// Appends step records to `/diagnostics/*` and `/front/*`.
pub(super) fn append_steps(file: &H5File, recs: &[StepRecord]) -> rust_hdf5::Result<()> {
    if recs.is_empty() {
        return Ok(());
    }
    for ((name, _), column) in STEP_DATASETS.iter().zip(step_columns(recs)) {
        file.dataset_writer(name)?.append(&column)?;
    }
    Ok(())
}

/// Appends one snapshot; its lengths have been checked against the datasets.
pub(super) fn append_snapshot(file: &H5File, snap: &SnapshotView) -> rust_hdf5::Result<()> {
    let fields = [
        ("snapshots/t", Some(std::slice::from_ref(&snap.t))),
        ("snapshots/h", Some(snap.h)),
        ("snapshots/u", Some(snap.u)),
        ("snapshots/v", snap.v),
        ("snapshots/w", snap.w),
        ("snapshots/p_nh", snap.p_nh),
        ("snapshots/u_layers", snap.layer_uv.map(|uv| uv.0)),
        ("snapshots/v_layers", snap.layer_uv.map(|uv| uv.1)),
    ];
    for (name, data) in fields {
        if let Some(data) = data {
            file.dataset_writer(name)?.append(data)?;
        }
    }
    for field in snap.extra {
        file.dataset_writer(&format!("snapshots/{}", field.name))?
            .append(field.data)?;
    }
    Ok(())
}

/// Writes the `/summary` attributes. Without `begun` the file is the empty one
/// `Hdf5Sink::create` made: it gets the format version and the group too, so a run
/// that failed before `begin` still records its status.
pub(super) fn write_summary(
    file: &H5File,
    summary: &RunSummary,
    begun: bool,
) -> rust_hdf5::Result<()> {
    let group = if begun {
        file.root_group().group("summary")?
    } else {
        file.set_attr_numeric("format_version", &FORMAT_VERSION)?;
        file.create_group("summary")?
    };
    let set = |name: &str, value: f64| group.set_attr_numeric(name, &value);
    set("runout", summary.runout)?;
    set("stop_time", summary.stop_time)?;
    set("settled_time", summary.settled_time)?;
    set("h_max_final", summary.h_max_final)?;
    set("t_end", summary.t_end)?;
    set("wall_time_s", summary.wall_time_s)?;
    set("outflowed_fraction", summary.outflowed_fraction)?;
    set("front_at_end_time", summary.front_at_end_time)?;
    set("max_speed_final", summary.max_speed_final)?;
    group.set_attr_numeric("steps", &(summary.steps as i64))?;
    group.set_attr_string("status", &summary.status)?;
    group.set_attr_string(
        "stop_reason",
        &crate::output::stop_reason::stop_reason(summary),
    )?;
    set("settle_fraction", summary.settle_fraction)?;
    if let Some(a) = summary.max_wave_amplitude {
        set("max_wave_amplitude", a)?;
    }
    if let Some(w) = &summary.wet {
        group.set_attr_numeric("flow_cells", &(w.flow_cells as i64))?;
        set("wet_fraction_mean", w.mean_fraction)?;
        set("wet_fraction_peak", w.peak_fraction)?;
        set("wet_cell_updates_per_s", w.wet_updates_per_s)?;
        set("cell_updates_per_s", w.cell_updates_per_s)?;
    }
    for (stage, seconds) in &summary.stage_times {
        set(&stage_attr_name(stage), *seconds)?;
    }
    Ok(())
}

/// `time_<stage>_s`, with anything but ASCII letters, digits and `_` replaced by `_`
/// so the name is a plain identifier in Python.
pub fn stage_attr_name(stage: &str) -> String {
    let clean: String = stage
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '_' {
                c
            } else {
                '_'
            }
        })
        .collect();
    format!("time_{clean}_s")
}

/// An empty 1-D series growing without bound.
fn series(group: &H5Group, name: &str, chunk: usize) -> rust_hdf5::Result<H5Dataset> {
    group
        .new_dataset::<f64>()
        .shape([0])
        .chunk(&[chunk])
        .max_shape(&[None])
        .create(name)
}

/// An empty dataset of frames of shape `frame`, one chunk per frame, growing along
/// an unlimited first axis.
/// The dimensions of `/snapshots`, each with a coordinate dataset there that is an
/// HDF5 dimension scale. rust-hdf5 cannot write the `DIMENSION_LIST` attribute (a
/// variable-length array of object references) that attaches scales to a dataset, so
/// the data are labelled the way netCDF-4 labels multidimensional coordinate
/// variables, which h5netcdf (xarray's `engine="h5netcdf"`) reads without references:
/// every scale carries `CLASS = "DIMENSION_SCALE"` (a fixed-length string), `NAME`
/// and `_Netcdf4Dimid`, and every field `CLASS = "DIMENSION_SCALE"` and
/// `_Netcdf4Coordinates`, the dimension ids of its axes (docs/output-format.md).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Dim {
    T = 0,
    X = 1,
    Layer = 2,
    Level = 3,
    XFace = 4,
    Y = 5,
}

impl Dim {
    fn name(self) -> &'static str {
        match self {
            Dim::T => "t",
            Dim::X => "x",
            Dim::Layer => "layer",
            Dim::Level => "level",
            Dim::XFace => "x_face",
            Dim::Y => "y",
        }
    }
}

/// A fixed-length ASCII string attribute (h5py reads it as bytes, as the dimension
/// scale API writes `CLASS` and `NAME`).
fn fixed_string(ds: &H5Dataset, name: &str, value: &str) -> rust_hdf5::Result<()> {
    let mut bytes = value.as_bytes().to_vec();
    bytes.push(0);
    let datatype = DatatypeMessage::FixedString {
        size: bytes.len() as u32,
        padding: 0,
        charset: 0,
    };
    ds.set_attr_typed(name, datatype, bytes)
}

/// Makes `ds` the dimension scale of `dim`.
fn dimension_scale(ds: &H5Dataset, dim: Dim) -> rust_hdf5::Result<()> {
    fixed_string(ds, "CLASS", "DIMENSION_SCALE")?;
    fixed_string(ds, "NAME", dim.name())?;
    ds.new_attr::<i32>()
        .shape(())
        .create("_Netcdf4Dimid")?
        .write_numeric(&(dim as i32))
}

/// The `_Netcdf4Dimid` of the field `name`. h5netcdf registers every dataset with
/// `CLASS = "DIMENSION_SCALE"` as a dimension too, and without an id of its own it
/// would take one by position that may be an axis's (which then gets the field's name):
/// ids from 16 up, distinct for distinct names, are never an axis's.
fn field_dimid(name: &str) -> i32 {
    let mut hash = 0xcbf2_9ce4_8422_2325u64;
    for b in name.bytes() {
        hash ^= b as u64;
        hash = hash.wrapping_mul(0x100_0000_01b3);
    }
    16 + (hash % 1_000_000_000) as i32
}

/// Labels the axes of the field `ds`: t, then `axes`.
fn label_axes(ds: &H5Dataset, name: &str, axes: &[Dim]) -> rust_hdf5::Result<()> {
    let dims: Vec<i32> = std::iter::once(Dim::T)
        .chain(axes.iter().copied())
        .map(|d| d as i32)
        .collect();
    fixed_string(ds, "CLASS", "DIMENSION_SCALE")?;
    ds.new_attr::<i32>()
        .shape(())
        .create("_Netcdf4Dimid")?
        .write_numeric(&field_dimid(name))?;
    ds.new_attr::<i32>()
        .shape([dims.len()])
        .create("_Netcdf4Coordinates")?
        .write_array(&dims)
}

/// Values per chunk of a raster field (1 MiB of f64): a chunk is a band of whole rows
/// of one frame, (1, rows, nx), so a snapshot appends whole chunks and a reader of one
/// frame decompresses only that frame's chunks.
pub(super) const RASTER_CHUNK_VALUES: usize = 1 << 17;

/// Deflate level of the raster fields (behind the shuffle filter). Level 1: a dry
/// band (all zeros) shrinks as much as at level 6 and a wet one almost as much, at a
/// fraction of the time (docs/performance.md, "Snapshots of a large raster").
pub(super) const RASTER_DEFLATE_LEVEL: u32 = 1;

/// The chunk of a field of frames `frame`: (1, frame…) on a line; on a raster
/// (`frame` = [ny, nx], or [nl, ny, nx] per layer) a band of rows of one layer of
/// about [`RASTER_CHUNK_VALUES`] values.
pub(super) fn frame_chunk(frame: &[usize], raster: bool) -> Vec<usize> {
    let rows = |ny: usize, nx: usize| (RASTER_CHUNK_VALUES / nx.max(1)).clamp(1, ny.max(1));
    match *frame {
        [ny, nx] if raster => vec![1, rows(ny, nx), nx],
        [_, ny, nx] if raster => vec![1, 1, rows(ny, nx), nx],
        _ => std::iter::once(1).chain(frame.iter().copied()).collect(),
    }
}

/// Creates the field `name` of shape (nt, frame…), its axes after t being `axes`.
/// A raster field is shuffled and deflated ([`RASTER_DEFLATE_LEVEL`]): its dry
/// cells (zeros) take almost no room. A line's frames are small and stay raw.
fn frames(
    group: &H5Group,
    name: &str,
    frame: &[usize],
    unit: &str,
    axes: &[Dim],
) -> rust_hdf5::Result<H5Dataset> {
    let dims: Vec<usize> = std::iter::once(0).chain(frame.iter().copied()).collect();
    let max: Vec<Option<usize>> = std::iter::once(None)
        .chain(frame.iter().map(|&n| Some(n)))
        .collect();
    let raster = axes.contains(&Dim::Y);
    let builder = group
        .new_dataset::<f64>()
        .shape(dims)
        .chunk(&frame_chunk(frame, raster))
        .max_shape(&max);
    let builder = if raster {
        builder.shuffle_deflate(RASTER_DEFLATE_LEVEL)
    } else {
        builder
    };
    let ds = builder.create(name)?;
    units(&ds, unit)?;
    label_axes(&ds, name, axes)?;
    Ok(ds)
}

fn units(ds: &H5Dataset, unit: &str) -> rust_hdf5::Result<()> {
    ds.new_attr::<VarLenUnicode>()
        .shape(())
        .create("units")?
        .write_string(unit)
}

/// The `description` attribute, when there is one.
fn description(ds: &H5Dataset, text: &str) -> rust_hdf5::Result<()> {
    if text.is_empty() {
        return Ok(());
    }
    ds.new_attr::<VarLenUnicode>()
        .shape(())
        .create("description")?
        .write_string(text)
}

/// The step records as the columns of [`STEP_DATASETS`].
fn step_columns(recs: &[StepRecord]) -> [Vec<f64>; 7] {
    let col = |f: fn(&StepRecord) -> f64| recs.iter().map(f).collect::<Vec<f64>>();
    [
        col(|r| r.t),
        col(|r| r.dt),
        col(|r| r.mass),
        col(|r| r.kinetic_energy),
        col(|r| r.max_speed),
        col(|r| r.t),
        col(|r| r.front_x),
    ]
}

#[cfg(test)]
mod tests {
    use super::stage_attr_name;

    #[test]
    fn stage_names_become_identifiers() {
        assert_eq!(stage_attr_name("hyperbolic"), "time_hyperbolic_s");
        assert_eq!(
            stage_attr_name("friction/viscous"),
            "time_friction_viscous_s"
        );
    }
}
