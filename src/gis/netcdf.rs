//! A CF-1.8 NetCDF writer for a time series of 2-D fields on a [`Raster`]'s grid.
//!
//! The file is NetCDF-3 "64-bit offset" (CDF-2), which every NetCDF reader opens
//! (xarray with the scipy or netCDF4 engine, GDAL, ncview, Panoply). It is written by
//! this module, streaming: [`NetCdfWriter::write_frame`] appends one record (a time and
//! one 2-D slab per field) and updates the record count, so the file is readable after
//! every frame, also when a run dies.
//!
//! Layout:
//!
//! ```text
//! dimensions: time = UNLIMITED, y = ny, x = nx
//! double x(x)     cell centres; axis "X", units "m" (or "degrees_east"),
//!                 standard_name projection_x_coordinate (or longitude)
//! double y(y)     cell centres, top row first (decreasing); axis "Y", ...
//! double time(time)  units "s", axis "T", long_name "time since release"
//! int crs         grid mapping: crs_wkt and spatial_ref (the WKT, when known or made
//!                 from an EPSG code of WGS 84, its UTM zones or ETRS89 UTM),
//!                 epsg_code "EPSG:n" (when known), GeoTransform (GDAL's 6 numbers),
//!                 grid_mapping_name "latitude_longitude" for geographic CRS
//! float FIELD(time, y, x)  units, long_name, [standard_name], grid_mapping "crs"
//!                 (when the CRS is known), _FillValue NaN (nodata cells of the grid)
//! global: Conventions "CF-1.8", title, source "granflow VERSION"
//! ```
//!
//! A projected CRS known only by WKT gets no `grid_mapping_name` (that would need the
//! projection's CF parameters); GDAL and rioxarray read `spatial_ref`/`crs_wkt`.

use std::fs::File;
use std::io::{BufWriter, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};

use super::{io_err, GisError, Raster, Result};

const NC_DIMENSION: u32 = 10;
const NC_VARIABLE: u32 = 11;
const NC_ATTRIBUTE: u32 = 12;
const NC_CHAR: u32 = 2;
const NC_INT: u32 = 4;
const NC_FLOAT: u32 = 5;
const NC_DOUBLE: u32 = 6;

/// One field of the time series.
#[derive(Debug, Clone, PartialEq)]
pub struct FieldSpec {
    /// Variable name (letters, digits, `_`; starting with a letter).
    pub name: String,
    /// UDUNITS string, e.g. "m".
    pub units: String,
    pub long_name: String,
    /// CF standard name, if one applies.
    pub standard_name: Option<String>,
}

impl FieldSpec {
    pub fn new(name: &str, units: &str, long_name: &str) -> FieldSpec {
        FieldSpec {
            name: name.into(),
            units: units.into(),
            long_name: long_name.into(),
            standard_name: None,
        }
    }
}

enum AttrValue {
    Text(String),
    Float(f32),
}

struct Var {
    name: String,
    dims: Vec<u32>,
    attrs: Vec<(String, AttrValue)>,
    nc_type: u32,
    vsize: u64,
    begin: u64,
}

/// Streams frames of 2-D fields into a CF NetCDF file (see the [module docs](self)).
pub struct NetCdfWriter {
    out: BufWriter<File>,
    path: PathBuf,
    cells: usize,
    fields: usize,
    numrecs: u32,
    mask: Vec<bool>,
    buf: Vec<u8>,
}

fn text(s: &str) -> AttrValue {
    AttrValue::Text(s.to_string())
}

fn put_u32(b: &mut Vec<u8>, v: u32) {
    b.extend_from_slice(&v.to_be_bytes());
}

fn put_name(b: &mut Vec<u8>, name: &str) {
    put_u32(b, name.len() as u32);
    b.extend_from_slice(name.as_bytes());
    pad(b);
}

fn pad(b: &mut Vec<u8>) {
    while !b.len().is_multiple_of(4) {
        b.push(0);
    }
}

fn put_attrs(b: &mut Vec<u8>, attrs: &[(String, AttrValue)]) {
    if attrs.is_empty() {
        b.extend_from_slice(&[0; 8]);
        return;
    }
    put_u32(b, NC_ATTRIBUTE);
    put_u32(b, attrs.len() as u32);
    for (name, value) in attrs {
        put_name(b, name);
        match value {
            AttrValue::Text(s) => {
                put_u32(b, NC_CHAR);
                put_u32(b, s.len() as u32);
                b.extend_from_slice(s.as_bytes());
                pad(b);
            }
            AttrValue::Float(v) => {
                put_u32(b, NC_FLOAT);
                put_u32(b, 1);
                b.extend_from_slice(&v.to_be_bytes());
            }
        }
    }
}

fn valid_name(name: &str) -> bool {
    let mut chars = name.chars();
    matches!(chars.next(), Some(c) if c.is_ascii_alphabetic())
        && chars.all(|c| c.is_ascii_alphanumeric() || c == '_')
}

fn header(dims: &[(&str, u32)], gattrs: &[(String, AttrValue)], vars: &[Var]) -> Vec<u8> {
    let mut b = Vec::with_capacity(4096);
    b.extend_from_slice(b"CDF\x02");
    put_u32(&mut b, 0); // numrecs, updated after every frame
    put_u32(&mut b, NC_DIMENSION);
    put_u32(&mut b, dims.len() as u32);
    for (name, len) in dims {
        put_name(&mut b, name);
        put_u32(&mut b, *len);
    }
    put_attrs(&mut b, gattrs);
    put_u32(&mut b, NC_VARIABLE);
    put_u32(&mut b, vars.len() as u32);
    for v in vars {
        put_name(&mut b, &v.name);
        put_u32(&mut b, v.dims.len() as u32);
        for d in &v.dims {
            put_u32(&mut b, *d);
        }
        put_attrs(&mut b, &v.attrs);
        put_u32(&mut b, v.nc_type);
        put_u32(&mut b, u32::try_from(v.vsize).unwrap_or(u32::MAX));
        b.extend_from_slice(&v.begin.to_be_bytes());
    }
    b
}

impl NetCdfWriter {
    /// Creates (truncates) `path` with the grid, CRS and nodata mask of `grid` and one
    /// variable per field. Nodata cells of `grid` are written as NaN in every frame.
    pub fn create(
        path: &Path,
        grid: &Raster,
        fields: &[FieldSpec],
        title: &str,
    ) -> Result<NetCdfWriter> {
        let bad = |reason: String| GisError::NetCdf {
            path: path.to_path_buf(),
            reason,
        };
        grid.check().map_err(&bad)?;
        if fields.is_empty() {
            return Err(bad("no field to write".into()));
        }
        for f in fields {
            if !valid_name(&f.name) || ["x", "y", "time", "crs"].contains(&f.name.as_str()) {
                return Err(bad(format!(
                    "`{}` is not a usable variable name (letters, digits, _; not x, y, time, crs)",
                    f.name
                )));
            }
        }
        let (nx, ny) = (grid.nx, grid.ny);
        let slab = (nx * ny) as u64 * 4;
        if slab >= u32::MAX as u64 - 4 || nx > i32::MAX as usize || ny > i32::MAX as usize {
            return Err(bad(format!("{nx} x {ny} cells is too large for NetCDF-3")));
        }
        let geographic = grid.crs.is_geographic();
        let crs_known = !grid.crs.is_unknown();
        let (xs, ys) = if geographic {
            (
                [
                    ("standard_name", "longitude"),
                    ("long_name", "longitude of the cell centre"),
                    ("units", "degrees_east"),
                    ("axis", "X"),
                ],
                [
                    ("standard_name", "latitude"),
                    ("long_name", "latitude of the cell centre"),
                    ("units", "degrees_north"),
                    ("axis", "Y"),
                ],
            )
        } else {
            (
                [
                    ("standard_name", "projection_x_coordinate"),
                    ("long_name", "x of the cell centre"),
                    ("units", "m"),
                    ("axis", "X"),
                ],
                [
                    ("standard_name", "projection_y_coordinate"),
                    ("long_name", "y of the cell centre"),
                    ("units", "m"),
                    ("axis", "Y"),
                ],
            )
        };
        let owned = |a: &[(&str, &str)]| {
            a.iter()
                .map(|(k, v)| (k.to_string(), text(v)))
                .collect::<Vec<_>>()
        };
        let mut crs_attrs = Vec::new();
        if geographic {
            crs_attrs.push(("grid_mapping_name".to_string(), text("latitude_longitude")));
        }
        if let Some(wkt) = grid.crs.wkt_text() {
            crs_attrs.push(("crs_wkt".to_string(), text(&wkt)));
            crs_attrs.push(("spatial_ref".to_string(), text(&wkt)));
        }
        if let Some(code) = grid.crs.epsg {
            crs_attrs.push((
                "epsg_code".to_string(),
                AttrValue::Text(format!("EPSG:{code}")),
            ));
        }
        crs_attrs.push((
            "GeoTransform".to_string(),
            AttrValue::Text(format!(
                "{} {} 0 {} 0 {}",
                grid.x_left, grid.cell_size, grid.y_top, -grid.cell_size
            )),
        ));
        let mut vars = vec![
            Var {
                name: "x".into(),
                dims: vec![2],
                attrs: owned(&xs),
                nc_type: NC_DOUBLE,
                vsize: nx as u64 * 8,
                begin: 0,
            },
            Var {
                name: "y".into(),
                dims: vec![1],
                attrs: owned(&ys),
                nc_type: NC_DOUBLE,
                vsize: ny as u64 * 8,
                begin: 0,
            },
            Var {
                name: "crs".into(),
                dims: vec![],
                attrs: crs_attrs,
                nc_type: NC_INT,
                vsize: 4,
                begin: 0,
            },
            Var {
                name: "time".into(),
                dims: vec![0],
                attrs: owned(&[
                    ("long_name", "time since release"),
                    ("units", "s"),
                    ("axis", "T"),
                ]),
                nc_type: NC_DOUBLE,
                vsize: 8,
                begin: 0,
            },
        ];
        for f in fields {
            let mut attrs = vec![
                ("long_name".to_string(), text(&f.long_name)),
                ("units".to_string(), text(&f.units)),
            ];
            if let Some(s) = &f.standard_name {
                attrs.push(("standard_name".to_string(), text(s)));
            }
            if crs_known {
                attrs.push(("grid_mapping".to_string(), text("crs")));
            }
            attrs.push(("_FillValue".to_string(), AttrValue::Float(f32::NAN)));
            vars.push(Var {
                name: f.name.clone(),
                dims: vec![0, 1, 2],
                attrs,
                nc_type: NC_FLOAT,
                vsize: slab,
                begin: 0,
            });
        }
        let dims = [("time", 0u32), ("y", ny as u32), ("x", nx as u32)];
        let gattrs = vec![
            ("Conventions".to_string(), text("CF-1.8")),
            ("title".to_string(), text(title)),
            (
                "source".to_string(),
                AttrValue::Text(format!("granflow {}", env!("CARGO_PKG_VERSION"))),
            ),
        ];
        // The header's size does not depend on the offsets (8 bytes each in CDF-2).
        let mut offset = header(&dims, &gattrs, &vars).len() as u64;
        for v in vars.iter_mut().filter(|v| v.dims.first() != Some(&0)) {
            v.begin = offset;
            offset += v.vsize;
        }
        for v in vars.iter_mut().filter(|v| v.dims.first() == Some(&0)) {
            v.begin = offset;
            offset += v.vsize;
        }
        let head = header(&dims, &gattrs, &vars);
        let file = File::create(path).map_err(io_err(path))?;
        let mut out = BufWriter::with_capacity(1 << 20, file);
        let mut fixed = head;
        for i in 0..nx {
            fixed.extend_from_slice(
                &(grid.x_left + (i as f64 + 0.5) * grid.cell_size).to_be_bytes(),
            );
        }
        for j in 0..ny {
            fixed
                .extend_from_slice(&(grid.y_top - (j as f64 + 0.5) * grid.cell_size).to_be_bytes());
        }
        fixed.extend_from_slice(&0i32.to_be_bytes());
        out.write_all(&fixed).map_err(io_err(path))?;
        out.flush().map_err(io_err(path))?;
        Ok(NetCdfWriter {
            out,
            path: path.to_path_buf(),
            cells: nx * ny,
            fields: fields.len(),
            numrecs: 0,
            mask: grid.values.iter().map(|&v| grid.is_nodata(v)).collect(),
            buf: Vec::with_capacity(nx * ny * 4),
        })
    }

    /// Frames written so far.
    pub fn frames(&self) -> usize {
        self.numrecs as usize
    }

    /// Appends one frame: the time (s) and one slab per field, in the order given to
    /// [`create`](Self::create), each in the grid's cell order. Values are stored as
    /// `f32`.
    pub fn write_frame(&mut self, time: f64, fields: &[&[f64]]) -> Result<()> {
        let bad = |reason: String| GisError::NetCdf {
            path: self.path.clone(),
            reason,
        };
        if fields.len() != self.fields {
            return Err(bad(format!(
                "{} fields given, {} declared",
                fields.len(),
                self.fields
            )));
        }
        if let Some(f) = fields.iter().find(|f| f.len() != self.cells) {
            return Err(bad(format!(
                "a field of {} values for {} cells",
                f.len(),
                self.cells
            )));
        }
        if self.numrecs == i32::MAX as u32 {
            return Err(bad("too many frames for NetCDF-3".into()));
        }
        let path = self.path.clone();
        self.out
            .write_all(&time.to_be_bytes())
            .map_err(io_err(&path))?;
        for field in fields {
            self.buf.clear();
            for (&v, &wall) in field.iter().zip(&self.mask) {
                let v = if wall { f32::NAN } else { v as f32 };
                self.buf.extend_from_slice(&v.to_be_bytes());
            }
            self.out.write_all(&self.buf).map_err(io_err(&path))?;
        }
        self.numrecs += 1;
        let mut update = || -> std::io::Result<()> {
            self.out.flush()?;
            let file = self.out.get_mut();
            let end = file.stream_position()?;
            file.seek(SeekFrom::Start(4))?;
            file.write_all(&self.numrecs.to_be_bytes())?;
            file.seek(SeekFrom::Start(end))?;
            Ok(())
        };
        update().map_err(io_err(&path))
    }

    /// Flushes and closes the file.
    pub fn finish(mut self) -> Result<()> {
        let path = self.path.clone();
        self.out.flush().map_err(io_err(&path))
    }
}
