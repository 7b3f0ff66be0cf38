//! Writes and reads GIS files with `granflow::gis`, for checks by other readers
//! (`tests/python/test_gis_rasterio.py` opens them with rasterio and xarray).
//!
//!   cargo run --release --example gis_roundtrip -- write DIR
//!       writes dem.asc (+ .prj), dem_*.tif, geo.tif, series.nc and expected.json (what
//!       each file must hold: grid, nodata, EPSG code, values, NetCDF frames)
//!   cargo run --release --example gis_roundtrip -- prj DIR
//!       writes epsg_<code>.asc with the .prj granflow makes for a CRS known by its
//!       EPSG code alone, one per family of codes it knows (`tests/python/test_prj_epsg.py`)
//!   cargo run --release --example gis_roundtrip -- dump RASTER OUT.json
//!       reads RASTER (.tif or .asc) and writes its grid, nodata, CRS and values as JSON
//!       (NaN as null)

use std::path::Path;

use granflow::gis::geotiff::{self, Compression, SampleType, WriteOptions};
use granflow::gis::netcdf::{FieldSpec, NetCdfWriter};
use granflow::gis::{asc, Crs, Raster};
use serde_json::{json, Value};

const WKT_32632: &str = r#"PROJCS["WGS 84 / UTM zone 32N",GEOGCS["WGS 84",DATUM["WGS_1984",SPHEROID["WGS 84",6378137,298.257223563,AUTHORITY["EPSG","7030"]],AUTHORITY["EPSG","6326"]],PRIMEM["Greenwich",0,AUTHORITY["EPSG","8901"]],UNIT["degree",0.0174532925199433,AUTHORITY["EPSG","9122"]],AUTHORITY["EPSG","4326"]],PROJECTION["Transverse_Mercator"],PARAMETER["latitude_of_origin",0],PARAMETER["central_meridian",9],PARAMETER["scale_factor",0.9996],PARAMETER["false_easting",500000],PARAMETER["false_northing",0],UNIT["metre",1,AUTHORITY["EPSG","9001"]],AXIS["Easting",EAST],AXIS["Northing",NORTH],AUTHORITY["EPSG","32632"]]"#;

fn describe(r: &Raster) -> Value {
    let values: Vec<Value> = r
        .values
        .iter()
        .map(|&v| if v.is_nan() { Value::Null } else { json!(v) })
        .collect();
    json!({
        "nx": r.nx,
        "ny": r.ny,
        "x_left": r.x_left,
        "y_top": r.y_top,
        "cell_size": r.cell_size,
        "nodata": r.nodata.map(|v| if v.is_nan() { json!("nan") } else { json!(v) }),
        "epsg": r.crs.epsg,
        "values": values,
    })
}

fn dem() -> Raster {
    let mut r = Raster::filled(37, 23, 612_345.5, 5_144_123.25, 2.5, 0.0);
    for row in 0..r.ny {
        for col in 0..r.nx {
            let (x, y) = r.cell_centre(col, row);
            let i = r.index(col, row);
            r.values[i] = 1500.0 + 0.31 * (x - 612_345.5) - 0.17 * (y - 5_144_000.0)
                + (0.37 * col as f64).sin() * 3.3;
        }
    }
    r.nodata = Some(-9999.0);
    for i in [0, 5, 100, 36 * 23 - 1] {
        r.values[i] = -9999.0;
    }
    r.crs = Crs::from_wkt(WKT_32632);
    r
}

fn write_all(dir: &Path) -> Result<(), Box<dyn std::error::Error>> {
    std::fs::create_dir_all(dir)?;
    let mut expected = serde_json::Map::new();
    let r = dem();
    asc::write(&r, &dir.join("dem.asc"))?;
    expected.insert("dem.asc".into(), describe(&r));
    for (name, sample, compression) in [
        ("dem_f64_none.tif", SampleType::F64, Compression::None),
        ("dem_f64_lzw.tif", SampleType::F64, Compression::Lzw),
        ("dem_f32_deflate.tif", SampleType::F32, Compression::Deflate),
    ] {
        geotiff::write(
            &r,
            &dir.join(name),
            WriteOptions {
                sample,
                compression,
            },
        )?;
        let mut stored = r.clone();
        if sample == SampleType::F32 {
            stored.values.iter_mut().for_each(|v| *v = *v as f32 as f64);
        }
        expected.insert(name.into(), describe(&stored));
    }
    // Geographic, NaN nodata, EPSG code only.
    let mut g = Raster::filled(20, 10, 7.25, 46.5, 0.125, 0.0);
    for (i, v) in g.values.iter_mut().enumerate() {
        *v = ((i as f32) * 0.25f32) as f64;
    }
    g.values[3] = f64::NAN;
    g.nodata = Some(f64::NAN);
    g.crs = Crs::from_epsg(4326);
    geotiff::write(&g, &dir.join("geo.tif"), WriteOptions::default())?;
    expected.insert("geo.tif".into(), describe(&g));

    // NetCDF: three frames of two fields on the DEM grid (its nodata cells are walls).
    let fields = [
        FieldSpec::new("h", "m", "flow thickness"),
        FieldSpec::new("speed", "m s-1", "depth-averaged speed"),
    ];
    let mut w = NetCdfWriter::create(&dir.join("series.nc"), &r, &fields, "gis_roundtrip")?;
    let mut frames = Vec::new();
    for k in 0..3 {
        let t = 0.5 * k as f64;
        let h: Vec<f64> = (0..r.nx * r.ny)
            .map(|i| (i % 17) as f64 * 0.125 + k as f64)
            .collect();
        let u: Vec<f64> = (0..r.nx * r.ny).map(|i| -(i as f64) / 3.0).collect();
        w.write_frame(t, &[&h, &u])?;
        let as_stored = |f: &[f64]| -> Vec<Value> {
            f.iter()
                .zip(&r.values)
                .map(|(&v, &z)| {
                    if r.is_nodata(z) {
                        Value::Null
                    } else {
                        json!(v as f32 as f64)
                    }
                })
                .collect()
        };
        frames.push(json!({"time": t, "h": as_stored(&h), "speed": as_stored(&u)}));
    }
    w.finish()?;
    expected.insert(
        "series.nc".into(),
        json!({"grid": describe(&r), "frames": frames, "wkt": WKT_32632}),
    );
    std::fs::write(
        dir.join("expected.json"),
        serde_json::to_string(&Value::Object(expected))?,
    )?;
    Ok(())
}

fn dump(input: &Path, output: &Path) -> Result<(), Box<dyn std::error::Error>> {
    let ext = input.extension().and_then(|e| e.to_str()).unwrap_or("");
    let r = if ext.eq_ignore_ascii_case("asc") {
        asc::read(input)?
    } else {
        geotiff::read(input)?
    };
    std::fs::write(output, serde_json::to_string(&describe(&r))?)?;
    Ok(())
}

/// One code of each family `wkt_of_epsg` knows (both ends of the ranges).
const EPSG_CODES: [u32; 30] = [
    4326, 32601, 32632, 32660, 32701, 32719, 32760, 25828, 25833, 25838, 26901, 26911, 26923, 3035,
    2056, 21781, 31254, 31255, 31256, 31257, 31258, 31259, 31287, 2154, 31466, 31467, 31468, 31469,
    3003, 28992,
];

/// `epsg_<code>.asc` (+ `.prj`) for each of [`EPSG_CODES`] and `3004`.
fn write_prj(dir: &Path) -> Result<(), Box<dyn std::error::Error>> {
    std::fs::create_dir_all(dir)?;
    for code in EPSG_CODES.into_iter().chain([3004]) {
        let mut r = Raster::filled(2, 2, 500_000.0, 5_000_000.0, 10.0, 1.0);
        r.crs = Crs::from_epsg(code);
        asc::write(&r, &dir.join(format!("epsg_{code}.asc")))?;
    }
    Ok(())
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let result = match args.iter().map(String::as_str).collect::<Vec<_>>()[..] {
        ["write", dir] => write_all(Path::new(dir)),
        ["dump", input, output] => dump(Path::new(input), Path::new(output)),
        ["prj", dir] => write_prj(Path::new(dir)),
        _ => {
            eprintln!(
                "usage: gis_roundtrip write DIR | gis_roundtrip prj DIR | gis_roundtrip dump RASTER OUT.json"
            );
            std::process::exit(2);
        }
    };
    if let Err(e) = result {
        eprintln!("error: {e}");
        std::process::exit(1);
    }
}
