//! Benchmarks of the GIS readers and writers (not tests: nothing is asserted).
//!
//!   cargo bench --bench gis
//!
//! A 4000 × 2500 raster (10⁷ cells, a smooth DEM-like surface with a nodata corner):
//! wall time of writing and reading it as GeoTIFF (Float32 uncompressed, LZW and Deflate;
//! Float64 uncompressed), as an ESRI ASCII grid, as one NetCDF frame of three fields,
//! of a result map as `granflow export` and `granflow maps` write it (GeoTIFF Float32
//! Deflate, ESRI ASCII), and of rasterising a 2000-vertex circular release on it (both
//! rules). Target: read and write each raster under 1 s. Best of 3, files in a
//! temporary directory.

use std::path::Path;
use std::time::Instant;

use granflow::gis::geotiff::{self, Compression, SampleType, WriteOptions};
use granflow::gis::netcdf::{FieldSpec, NetCdfWriter};
use granflow::gis::release::{rasterise, CoverageRule, Polygon, ReleaseAreas, ReleaseFeature};
use granflow::gis::{asc, Crs, Raster};
use granflow::results::publish::Publish;
use granflow::results::{write_raster, RasterFormat};

const NX: usize = 4000;
const NY: usize = 2500;

fn dem() -> Raster {
    let mut r = Raster::filled(NX, NY, 600_000.0, 5_200_000.0, 2.0, 0.0);
    for row in 0..NY {
        for col in 0..NX {
            let (x, y) = (col as f64 / NX as f64, row as f64 / NY as f64);
            let i = r.index(col, row);
            r.values[i] =
                2500.0 - 1200.0 * x - 300.0 * y + 40.0 * (9.0 * x).sin() * (7.0 * y).cos();
        }
    }
    r.nodata = Some(-9999.0);
    for row in 0..200 {
        for col in 0..300 {
            let i = r.index(col, row);
            r.values[i] = -9999.0;
        }
    }
    r.crs = Crs::from_epsg(32632);
    r
}

/// Best of `n` wall times (s) of `f`.
fn best<T>(n: usize, mut f: impl FnMut() -> T) -> (f64, T) {
    let mut out = None;
    let mut t_best = f64::INFINITY;
    for _ in 0..n {
        let t0 = Instant::now();
        let v = f();
        t_best = t_best.min(t0.elapsed().as_secs_f64());
        out = Some(v);
    }
    (t_best, out.unwrap())
}

fn mb(path: &Path) -> f64 {
    std::fs::metadata(path)
        .map(|m| m.len() as f64 / 1e6)
        .unwrap_or(f64::NAN)
}

fn main() {
    let dir = tempfile::tempdir().expect("temporary directory");
    let r = dem();
    println!("GIS I/O, {NX} x {NY} = {} cells, best of 3", NX * NY);
    println!(
        "{:<28} {:>9} {:>9} {:>9}",
        "format", "write s", "read s", "MB"
    );
    let tiffs = [
        (
            "GeoTIFF f32 uncompressed",
            SampleType::F32,
            Compression::None,
        ),
        ("GeoTIFF f32 LZW", SampleType::F32, Compression::Lzw),
        ("GeoTIFF f32 Deflate", SampleType::F32, Compression::Deflate),
        (
            "GeoTIFF f64 uncompressed",
            SampleType::F64,
            Compression::None,
        ),
    ];
    for (i, (name, sample, compression)) in tiffs.into_iter().enumerate() {
        let path = dir.path().join(format!("r{i}.tif"));
        let opts = WriteOptions {
            sample,
            compression,
        };
        let (tw, _) = best(3, || geotiff::write(&r, &path, opts).expect("write"));
        let (tr, back) = best(3, || geotiff::read(&path).expect("read"));
        assert_eq!(back.values.len(), NX * NY);
        println!("{name:<28} {tw:>9.3} {tr:>9.3} {:>9.1}", mb(&path));
    }
    let path = dir.path().join("r.asc");
    let (tw, _) = best(3, || asc::write(&r, &path).expect("write"));
    let (tr, _) = best(3, || asc::read(&path).expect("read"));
    println!(
        "{:<28} {tw:>9.3} {tr:>9.3} {:>9.1}",
        "ESRI ASCII grid",
        mb(&path)
    );

    let path = dir.path().join("r.nc");
    let fields = [
        FieldSpec::new("h", "m", "flow thickness"),
        FieldSpec::new("speed", "m s-1", "speed"),
        FieldSpec::new("pressure", "Pa", "basal pressure"),
    ];
    let (tw, _) = best(3, || {
        let mut w = NetCdfWriter::create(&path, &r, &fields, "bench").expect("create");
        w.write_frame(0.0, &[&r.values, &r.values, &r.values])
            .expect("frame");
        w.finish().expect("finish");
    });
    println!(
        "{:<28} {tw:>9.3} {:>9} {:>9.1}",
        "NetCDF, 1 frame x 3 fields",
        "-",
        mb(&path)
    );

    // A result map as `granflow export` and `granflow maps` write it: a peak flow
    // thickness over a fifth of the domain, zero elsewhere (NaN → nodata).
    let mut pft = r.values.clone();
    for (k, v) in pft.iter_mut().enumerate() {
        let (col, row) = (k % NX, k / NX);
        *v = if (1000..2600).contains(&col) && (500..1750).contains(&row) {
            0.01 * ((col * 7 + row * 3) % 500) as f64
        } else {
            0.0
        };
    }
    for (format, name) in [
        (RasterFormat::Geotiff, "result map, GeoTIFF f32 Deflate"),
        (RasterFormat::Asc, "result map, ESRI ASCII"),
    ] {
        let path = dir.path().join(format!("pft.{}", format.extension()));
        let (tw, _) = best(3, || {
            // As export writes it: aside, synced, then renamed into place.
            let mut publish = Publish::new(true);
            write_raster(&mut publish, &r, pft.clone(), format, false, &path).expect("write");
            publish.commit().expect("rename")
        });
        println!("{name:<28} {tw:>9.3} {:>9} {:>9.1}", "-", mb(&path));
    }

    let circle: Vec<[f64; 2]> = (0..2000)
        .map(|k| {
            let a = 2.0 * std::f64::consts::PI * k as f64 / 2000.0;
            [604_000.0 + 1500.0 * a.cos(), 5_197_500.0 + 1500.0 * a.sin()]
        })
        .collect();
    let areas = ReleaseAreas {
        features: vec![ReleaseFeature {
            polygons: vec![Polygon::new(circle)],
            thickness: 2.0,
        }],
        crs: Crs::from_epsg(32632),
    };
    for rule in [CoverageRule::AreaFraction, CoverageRule::CellCentre] {
        let (t, rel) = best(3, || rasterise(&areas, &r, rule).expect("rasterise"));
        println!(
            "rasterise r = 1500 m circle ({rule:?}): {t:.3} s, volume {:.6e} m3",
            rel.volume
        );
    }
}
