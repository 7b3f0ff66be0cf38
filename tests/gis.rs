//! The GIS readers and writers (`granflow::gis`): exact round trips, every ESRI ASCII
//! header variant, bad inputs (one named error each), GeoTIFF georeferencing rules,
//! release-polygon rasterisation (volumes converge with the cell size, holes,
//! slope-normal thickness), cropping and coarsening, the NetCDF writer's layout.
//! Nothing here needs Python; `tests/python/test_gis_rasterio.py` checks the same files
//! with rasterio and xarray.

use std::f64::consts::PI;
use std::path::{Path, PathBuf};

use granflow::gis::geotiff::{self, Compression, SampleType, WriteOptions};
use granflow::gis::netcdf::{FieldSpec, NetCdfWriter};
use granflow::gis::release::{
    self, coverage, rasterise, slope_cosine, vertical_thickness, CoverageRule, Polygon,
    ReleaseAreas, ReleaseFeature, ThicknessSource,
};
use granflow::gis::{asc, Bbox, Crs, GisError, Raster};

const WKT_32632: &str = r#"PROJCS["WGS 84 / UTM zone 32N",GEOGCS["WGS 84",DATUM["WGS_1984",SPHEROID["WGS 84",6378137,298.257223563,AUTHORITY["EPSG","7030"]],AUTHORITY["EPSG","6326"]],PRIMEM["Greenwich",0,AUTHORITY["EPSG","8901"]],UNIT["degree",0.0174532925199433,AUTHORITY["EPSG","9122"]],AUTHORITY["EPSG","4326"]],PROJECTION["Transverse_Mercator"],PARAMETER["latitude_of_origin",0],PARAMETER["central_meridian",9],PARAMETER["scale_factor",0.9996],PARAMETER["false_easting",500000],PARAMETER["false_northing",0],UNIT["metre",1,AUTHORITY["EPSG","9001"]],AXIS["Easting",EAST],AXIS["Northing",NORTH],AUTHORITY["EPSG","32632"]]"#;

fn tmp() -> tempfile::TempDir {
    tempfile::tempdir().unwrap()
}

fn write_text(dir: &Path, name: &str, text: &str) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

/// A raster with awkward values: irrationals, tiny, huge, negative zero, nodata.
fn awkward(nx: usize, ny: usize) -> Raster {
    let mut r = Raster::filled(nx, ny, 612_345.67, 5_144_123.37, 2.5, 0.0);
    for (i, v) in r.values.iter_mut().enumerate() {
        *v = match i % 7 {
            0 => (i as f64).sqrt() * PI,
            1 => 1.0 / 3.0 + i as f64,
            2 => 1e-300 * i as f64,
            3 => -1.234_567_890_123_456_7e12,
            4 => -0.0,
            5 => -9999.0,
            _ => 2000.0 + 0.1 * i as f64,
        };
    }
    r.nodata = Some(-9999.0);
    r.crs = Crs::from_wkt(WKT_32632);
    r
}

fn same_bits(a: &[f64], b: &[f64]) -> bool {
    a.len() == b.len() && a.iter().zip(b).all(|(x, y)| x.to_bits() == y.to_bits())
}

// ---------------------------------------------------------------- ESRI ASCII grid

#[test]
fn asc_round_trip_is_exact() {
    let dir = tmp();
    let r = awkward(13, 9);
    let p1 = dir.path().join("a.asc");
    asc::write(&r, &p1).unwrap();
    let back = asc::read(&p1).unwrap();
    assert_eq!((back.nx, back.ny), (13, 9));
    assert_eq!(back.x_left, r.x_left);
    assert_eq!(back.y_top, r.y_top);
    assert_eq!(back.cell_size, r.cell_size);
    assert_eq!(back.nodata, Some(-9999.0));
    assert!(same_bits(&back.values, &r.values), "values changed");
    assert_eq!(back.crs.epsg, Some(32632));
    assert_eq!(back.crs.wkt.as_deref(), Some(WKT_32632));
    // Written again: the same bytes, .prj included.
    let p2 = dir.path().join("b.asc");
    asc::write(&back, &p2).unwrap();
    assert_eq!(std::fs::read(&p1).unwrap(), std::fs::read(&p2).unwrap());
    assert_eq!(
        std::fs::read(asc::prj_path(&p1)).unwrap(),
        std::fs::read(asc::prj_path(&p2)).unwrap()
    );
}

#[test]
fn asc_file_read_and_written_keeps_its_header_numbers() {
    let dir = tmp();
    let text = "ncols 3\nnrows 2\nxllcorner 2600000.1\nyllcorner 1200000.3\ncellsize 0.7\nNODATA_value -32768\n1 2.5 -32768\n0.1 0.2 0.3\n";
    let p = write_text(dir.path(), "in.asc", text);
    let r = asc::read(&p).unwrap();
    let out = dir.path().join("out.asc");
    asc::write(&r, &out).unwrap();
    let written = std::fs::read_to_string(&out).unwrap();
    let header: Vec<Vec<&str>> = written
        .lines()
        .take(6)
        .map(|l| l.split_whitespace().collect())
        .collect();
    assert_eq!(header[2], ["xllcorner", "2600000.1"]);
    assert_eq!(header[3], ["yllcorner", "1200000.3"]);
    assert_eq!(header[4], ["cellsize", "0.7"]);
    assert_eq!(header[5], ["NODATA_value", "-32768"]);
    assert_eq!(written.lines().nth(6).unwrap(), "1 2.5 -32768");
    assert_eq!(written.lines().nth(7).unwrap(), "0.1 0.2 0.3");
    // No CRS: no .prj, and a stale one is removed.
    assert!(!asc::prj_path(&out).exists());
}

#[test]
fn asc_every_header_variant() {
    let dir = tmp();
    // (header, expected x_left, expected y_top, expected nodata)
    let cases: &[(&str, f64, f64, Option<f64>)] = &[
        (
            "ncols 2\nnrows 3\nxllcorner 10\nyllcorner 20\ncellsize 2\n",
            10.0,
            26.0,
            None,
        ),
        (
            "NCOLS 2\nNROWS 3\nXLLCENTER 11\nYLLCENTER 21\nCELLSIZE 2\nNODATA_VALUE -9999\n",
            10.0,
            26.0,
            Some(-9999.0),
        ),
        (
            "ncols\t2\r\nnrows \t 3\r\nxllcorner   10\r\nyllcenter\t21\r\ncellsize 2\r\n",
            10.0,
            26.0,
            None,
        ),
        (
            "NCols 2\nNRows 3\nXllCenter 11\nYllCorner 20\nCellSize 2\nNoData_Value nan\n",
            10.0,
            26.0,
            Some(f64::NAN),
        ),
        (
            "ncols 2\nnrows 3\nxllcorner 10\nyllcorner 20\ndx 2\ndy 2\nnodata_value -1.5\n",
            10.0,
            26.0,
            Some(-1.5),
        ),
        (
            "  ncols 2\n\nnrows 3\n  xllcorner 10\nyllcorner 20\ncellsize 2\n",
            10.0,
            26.0,
            None,
        ),
    ];
    for (i, (header, x, y, nodata)) in cases.iter().enumerate() {
        // Values laid out three ways: one row per line, all on one line, one per line.
        for (j, body) in ["1 2\n3 4\n5 6\n", "1 2 3 4 5 6", "1\n2\n3\n4\n5\n6\n\n"]
            .iter()
            .enumerate()
        {
            let p = write_text(
                dir.path(),
                &format!("v{i}_{j}.asc"),
                &format!("{header}{body}"),
            );
            let r = asc::read(&p).unwrap_or_else(|e| panic!("case {i}/{j}: {e}"));
            assert_eq!((r.nx, r.ny, r.cell_size), (2, 3, 2.0), "case {i}/{j}");
            assert_eq!((r.x_left, r.y_top), (*x, *y), "case {i}/{j}");
            assert_eq!(r.values, [1.0, 2.0, 3.0, 4.0, 5.0, 6.0], "case {i}/{j}");
            match (r.nodata, nodata) {
                (Some(a), Some(b)) if b.is_nan() => assert!(a.is_nan()),
                (a, b) => assert_eq!(a, *b, "case {i}/{j}"),
            }
            assert_eq!(
                r.cell_centre(0, 2),
                (11.0, 21.0),
                "lower-left centre, case {i}/{j}"
            );
        }
    }
    // Values may be nan/NaN words and exponents; a nodata cell reads as nodata.
    let p = write_text(
        dir.path(),
        "words.asc",
        "ncols 3\nnrows 1\nxllcorner 0\nyllcorner 0\ncellsize 1\nNODATA_value -9999\nNaN 1e3 -9999\n",
    );
    let r = asc::read(&p).unwrap();
    assert!(r.values[0].is_nan());
    assert_eq!(r.values[1], 1000.0);
    assert_eq!(r.get(2, 0), None);
}

fn asc_error(dir: &Path, name: &str, text: &str) -> GisError {
    let p = write_text(dir, name, text);
    let e = asc::read(&p).expect_err(name);
    assert!(
        e.to_string().contains(name),
        "the error names the file: {e}"
    );
    e
}

#[test]
fn asc_bad_inputs_give_distinct_named_errors() {
    let dir = tmp();
    let d = dir.path();
    let head = "ncols 2\nnrows 2\nxllcorner 0\nyllcorner 0\ncellsize 1\n";
    let e = asc_error(d, "empty.asc", "");
    assert!(matches!(e, GisError::EmptyFile { .. }), "{e}");
    let e = asc_error(d, "few.asc", &format!("{head}1 2\n3\n"));
    assert!(
        matches!(
            e,
            GisError::TooFewValues {
                expected: 4,
                found: 3,
                ..
            }
        ),
        "{e}"
    );
    let e = asc_error(d, "many.asc", &format!("{head}1 2\n3 4\n5\n"));
    assert!(
        matches!(
            e,
            GisError::TooManyValues {
                expected: 4,
                line: 8,
                ..
            }
        ),
        "{e}"
    );
    let e = asc_error(d, "word.asc", &format!("{head}1 2\n3 x4\n"));
    assert!(
        matches!(e, GisError::NonNumeric { line: 7, ref token, .. } if token == "x4"),
        "{e}"
    );
    let e = asc_error(
        d,
        "nosize.asc",
        "ncols 2\nnrows 2\nxllcorner 0\nyllcorner 0\n1 2 3 4\n",
    );
    assert!(
        matches!(
            e,
            GisError::MissingKey {
                key: "cellsize",
                ..
            }
        ),
        "{e}"
    );
    let e = asc_error(
        d,
        "noy.asc",
        "ncols 2\nnrows 2\nxllcorner 0\ncellsize 1\n1 2 3 4\n",
    );
    assert!(
        matches!(
            e,
            GisError::MissingKey {
                key: "yllcorner",
                ..
            }
        ),
        "{e}"
    );
    let e = asc_error(
        d,
        "neg.asc",
        "ncols 2\nnrows 2\nxllcorner 0\nyllcorner 0\ncellsize -1\n1 2 3 4\n",
    );
    assert!(
        matches!(e, GisError::NonPositiveCellSize { value, .. } if value == -1.0),
        "{e}"
    );
    let e = asc_error(
        d,
        "dxdy.asc",
        "ncols 2\nnrows 2\nxllcorner 0\nyllcorner 0\ndx 1\ndy 2\n1 2 3 4\n",
    );
    assert!(matches!(e, GisError::NonSquareCells { .. }), "{e}");
    let e = asc_error(
        d,
        "key.asc",
        "ncols 2\nnrows 2\nxllcorner 0\nyllcorner 0\ncellsize 1\nfoo 3\n1 2 3 4\n",
    );
    assert!(matches!(e, GisError::BadHeader { line: 6, .. }), "{e}");
    let e = asc_error(
        d,
        "cols.asc",
        "ncols 2.5\nnrows 2\nxllcorner 0\nyllcorner 0\ncellsize 1\n1 2 3 4\n",
    );
    assert!(matches!(e, GisError::BadHeader { line: 1, .. }), "{e}");
    let e = asc_error(
        d,
        "twice.asc",
        "ncols 2\nnrows 2\nxllcorner 0\nxllcenter 0\nyllcorner 0\ncellsize 1\n1 2 3 4\n",
    );
    assert!(matches!(e, GisError::BadHeader { line: 4, .. }), "{e}");
    let e = asc::read(&d.join("missing.asc")).unwrap_err();
    assert!(
        matches!(e, GisError::Io { .. }) && e.to_string().contains("missing.asc"),
        "{e}"
    );
    // NaN cells cannot be written without a finite nodata value.
    let mut r = Raster::filled(2, 2, 0.0, 2.0, 1.0, 1.0);
    r.values[3] = f64::NAN;
    let e = asc::write(&r, &d.join("nan.asc")).unwrap_err();
    assert!(matches!(e, GisError::NanWithoutNodata { .. }), "{e}");
    r.nodata = Some(-9999.0);
    asc::write(&r, &d.join("nan.asc")).unwrap();
    assert_eq!(asc::read(&d.join("nan.asc")).unwrap().values[3], -9999.0);
}

// ---------------------------------------------------------------- GeoTIFF

#[test]
fn geotiff_round_trip_is_exact() {
    let dir = tmp();
    for compression in [Compression::None, Compression::Lzw, Compression::Deflate] {
        let mut r = awkward(37, 23);
        r.crs = Crs::from_epsg(32632);
        let opts = WriteOptions {
            sample: SampleType::F64,
            compression,
        };
        let p1 = dir.path().join(format!("a_{compression:?}.tif"));
        geotiff::write(&r, &p1, opts).unwrap();
        let back = geotiff::read(&p1).unwrap();
        assert_eq!((back.nx, back.ny), (r.nx, r.ny));
        assert_eq!(
            (back.x_left, back.y_top, back.cell_size),
            (r.x_left, r.y_top, r.cell_size)
        );
        assert_eq!(back.nodata, r.nodata);
        assert_eq!(back.crs, Crs::from_epsg(32632));
        assert!(same_bits(&back.values, &r.values), "{compression:?}");
        let p2 = dir.path().join(format!("b_{compression:?}.tif"));
        geotiff::write(&back, &p2, opts).unwrap();
        assert_eq!(
            std::fs::read(&p1).unwrap(),
            std::fs::read(&p2).unwrap(),
            "{compression:?}"
        );
    }
    // Float32: exact for f32 values; NaN nodata; a geographic CRS.
    let mut r = Raster::filled(5, 4, 7.25, 46.5, 0.25, 0.0);
    for (i, v) in r.values.iter_mut().enumerate() {
        *v = (i as f32 * 0.1f32) as f64;
    }
    r.values[7] = f64::NAN;
    r.nodata = Some(f64::NAN);
    r.crs = Crs::from_epsg(4326);
    let p = dir.path().join("f32.tif");
    geotiff::write(&r, &p, WriteOptions::default()).unwrap();
    let back = geotiff::read(&p).unwrap();
    assert!(back.nodata.unwrap().is_nan());
    assert!(back.get(2, 1).is_none());
    assert!(same_bits(&back.values, &r.values));
    assert_eq!(back.crs.epsg, Some(4326));
    assert_eq!(
        (back.x_left, back.y_top, back.cell_size),
        (7.25, 46.5, 0.25)
    );
    // A CRS known only by WKT without an authority travels in the citation key.
    let esri = r#"PROJCS["CH1903+_LV95",GEOGCS["GCS_CH1903+",DATUM["D_CH1903+",SPHEROID["Bessel_1841",6377397.155,299.1528128]]],PROJECTION["Hotine_Oblique_Mercator_Azimuth_Center"]]"#;
    r.crs = Crs::from_wkt(esri);
    geotiff::write(&r, &p, WriteOptions::default()).unwrap();
    assert_eq!(geotiff::read(&p).unwrap().crs.wkt.as_deref(), Some(esri));
}

/// A GeoTIFF written with the `tiff` encoder and the given georeferencing tags.
fn raw_tiff(
    path: &Path,
    tags: &[(u16, Vec<f64>)],
    keys: &[u16],
    nodata: Option<&str>,
    data: &[u16],
) {
    use tiff::encoder::{colortype::Gray16, TiffEncoder};
    use tiff::tags::Tag;
    let file = std::fs::File::create(path).unwrap();
    let mut enc = TiffEncoder::new(std::io::BufWriter::new(file)).unwrap();
    let mut img = enc.new_image::<Gray16>(3, 2).unwrap();
    for (tag, values) in tags {
        img.encoder()
            .write_tag(Tag::Unknown(*tag), &values[..])
            .unwrap();
    }
    if !keys.is_empty() {
        img.encoder()
            .write_tag(Tag::GeoKeyDirectoryTag, keys)
            .unwrap();
    }
    if let Some(nd) = nodata {
        img.encoder().write_tag(Tag::GdalNodata, nd).unwrap();
    }
    img.write_data(data).unwrap();
}

#[test]
fn geotiff_georeferencing_rules() {
    let dir = tmp();
    let d = dir.path();
    let data = [1u16, 2, 3, 4, 5, 65535];
    let scale = (33550, vec![10.0, 10.0, 0.0]);
    let tie = (33922, vec![0.0, 0.0, 0.0, 1000.0, 2000.0, 0.0]);
    let area = [1, 1, 0, 2, 1024, 0, 1, 1, 3072, 0, 1, 2056];
    let point = [1, 1, 0, 3, 1024, 0, 1, 1, 1025, 0, 1, 2, 3072, 0, 1, 2056];

    // Integer samples, PixelIsArea: the tiepoint is the corner; nodata from GDAL_NODATA.
    let p = d.join("area.tif");
    raw_tiff(
        &p,
        &[scale.clone(), tie.clone()],
        &area,
        Some("65535"),
        &data,
    );
    let r = geotiff::read(&p).unwrap();
    assert_eq!(
        (r.nx, r.ny, r.x_left, r.y_top, r.cell_size),
        (3, 2, 1000.0, 2000.0, 10.0)
    );
    assert_eq!(r.values, [1.0, 2.0, 3.0, 4.0, 5.0, 65535.0]);
    assert_eq!(r.get(2, 1), None);
    assert_eq!(r.crs.epsg, Some(2056));

    // PixelIsPoint: the tiepoint is the centre of pixel (0, 0).
    let p = d.join("point.tif");
    raw_tiff(&p, &[scale.clone(), tie.clone()], &point, None, &data);
    let r = geotiff::read(&p).unwrap();
    assert_eq!((r.x_left, r.y_top), (995.0, 2005.0));
    assert_eq!(r.cell_centre(0, 0), (1000.0, 2000.0));

    // A tiepoint at pixel (1, 1) is moved back to the corner of pixel (0, 0).
    let p = d.join("tie11.tif");
    raw_tiff(
        &p,
        &[
            scale.clone(),
            (33922, vec![1.0, 1.0, 0.0, 1010.0, 1990.0, 0.0]),
        ],
        &area,
        None,
        &data,
    );
    let r = geotiff::read(&p).unwrap();
    assert_eq!((r.x_left, r.y_top), (1000.0, 2000.0));

    // A north-up ModelTransformationTag is accepted...
    let m = vec![
        10.0, 0.0, 0.0, 1000.0, 0.0, -10.0, 0.0, 2000.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0,
    ];
    let p = d.join("transform.tif");
    raw_tiff(&p, &[(34264, m.clone())], &area, None, &data);
    let r = geotiff::read(&p).unwrap();
    assert_eq!((r.x_left, r.y_top, r.cell_size), (1000.0, 2000.0, 10.0));
    // ... one with rotation terms is refused,
    let mut rot = m.clone();
    let (s, c) = (0.1f64.sin() * 10.0, 0.1f64.cos() * 10.0);
    (rot[0], rot[1], rot[4], rot[5]) = (c, -s, -s, -c);
    let p = d.join("rotated.tif");
    raw_tiff(&p, &[(34264, rot)], &area, None, &data);
    let e = geotiff::read(&p).unwrap_err();
    assert!(
        matches!(e, GisError::Rotated { .. }) && e.to_string().contains("rotated.tif"),
        "{e}"
    );
    // ... and so is a set of tiepoints (control points).
    let mut ties = tie.1.clone();
    ties.extend([
        3.0, 0.0, 0.0, 1029.0, 2003.0, 0.0, 0.0, 2.0, 0.0, 1003.0, 1981.0, 0.0,
    ]);
    let p = d.join("gcps.tif");
    raw_tiff(&p, &[scale.clone(), (33922, ties)], &area, None, &data);
    assert!(matches!(
        geotiff::read(&p).unwrap_err(),
        GisError::Rotated { .. }
    ));
    // Non-square pixels.
    let p = d.join("nonsquare.tif");
    raw_tiff(
        &p,
        &[(33550, vec![10.0, 12.0, 0.0]), tie.clone()],
        &area,
        None,
        &data,
    );
    let e = geotiff::read(&p).unwrap_err();
    assert!(
        matches!(e, GisError::NonSquareCells { dx, dy, .. } if dx == 10.0 && dy == 12.0),
        "{e}"
    );
    // No georeferencing at all.
    let p = d.join("plain.tif");
    raw_tiff(&p, &[], &[], None, &data);
    assert!(matches!(
        geotiff::read(&p).unwrap_err(),
        GisError::NotGeoreferenced { .. }
    ));
    // A header that claims 10⁵ × 10⁵ pixels (80 GB) in a tiny file: an error, no abort.
    let p = d.join("huge.tif");
    raw_tiff(&p, &[scale.clone(), tie.clone()], &area, None, &data);
    let mut bytes = std::fs::read(&p).unwrap();
    assert_eq!(&bytes[..2], b"II");
    let ifd = u32::from_le_bytes(bytes[4..8].try_into().unwrap()) as usize;
    let n = u16::from_le_bytes(bytes[ifd..ifd + 2].try_into().unwrap()) as usize;
    for e in 0..n {
        let at = ifd + 2 + 12 * e;
        let tag = u16::from_le_bytes(bytes[at..at + 2].try_into().unwrap());
        if tag == 256 || tag == 257 {
            bytes[at + 8..at + 12].copy_from_slice(&100_000u32.to_le_bytes());
        }
    }
    std::fs::write(&p, &bytes).unwrap();
    let e = geotiff::read(&p).unwrap_err();
    assert!(matches!(e, GisError::UnsupportedTiff { .. }), "{e}");
    assert!(e.to_string().contains("100000 x 100000 pixels"), "{e}");
    // Empty and garbage files.
    let p = write_text(d, "empty.tif", "");
    assert!(matches!(
        geotiff::read(&p).unwrap_err(),
        GisError::EmptyFile { .. }
    ));
    let p = write_text(d, "text.tif", "ncols 2\n");
    let e = geotiff::read(&p).unwrap_err();
    assert!(
        matches!(e, GisError::Tiff { .. }) && e.to_string().contains("text.tif"),
        "{e}"
    );
}

#[test]
fn geotiff_reads_packbits_and_multiband_is_refused() {
    use tiff::encoder::{colortype, Compression as C, TiffEncoder};
    use tiff::tags::Tag;
    let dir = tmp();
    let p = dir.path().join("packbits.tif");
    {
        let file = std::fs::File::create(&p).unwrap();
        let mut enc = TiffEncoder::new(file)
            .unwrap()
            .with_compression(C::Packbits);
        let mut img = enc.new_image::<colortype::GrayI16>(4, 3).unwrap();
        img.encoder()
            .write_tag(Tag::ModelPixelScaleTag, &[1.0, 1.0, 0.0][..])
            .unwrap();
        img.encoder()
            .write_tag(Tag::ModelTiepointTag, &[0.0, 0.0, 0.0, 0.0, 3.0, 0.0][..])
            .unwrap();
        img.write_data(&[-5i16, 0, 0, 0, 0, 0, 0, 7, 7, 7, 7, -32768])
            .unwrap();
    }
    let r = geotiff::read(&p).unwrap();
    assert_eq!(r.values[0], -5.0);
    assert_eq!(r.values[11], -32768.0);
    assert_eq!(r.crs, Crs::unknown());
    let p = dir.path().join("rgb.tif");
    {
        let file = std::fs::File::create(&p).unwrap();
        let mut enc = TiffEncoder::new(file).unwrap();
        enc.write_image::<colortype::RGB8>(2, 1, &[0, 0, 0, 1, 1, 1])
            .unwrap();
    }
    assert!(matches!(
        geotiff::read(&p).unwrap_err(),
        GisError::UnsupportedTiff { .. }
    ));
}

// ---------------------------------------------------------------- crop, coarsen

#[test]
fn crop_then_coarsen_keeps_the_grid_lines_and_the_mean() {
    let mut r = Raster::filled(40, 30, 500.0, 900.0, 5.0, 0.0);
    for row in 0..30 {
        for col in 0..40 {
            let i = r.index(col, row);
            r.values[i] = (col * 100 + row) as f64;
        }
    }
    let c = r
        .crop(Bbox {
            x_min: 551.0,
            x_max: 649.0,
            y_min: 801.0,
            y_max: 880.0,
        })
        .unwrap();
    // Centres from 552.5 to 647.5 (20 columns), 877.5 down to 802.5 (16 rows).
    assert_eq!((c.nx, c.ny, c.x_left, c.y_top), (20, 16, 550.0, 880.0));
    assert_eq!(c.values[0], (10 * 100 + 4) as f64);
    let k = c.coarsen(4).unwrap();
    assert_eq!(
        (k.nx, k.ny, k.cell_size, k.x_left, k.y_top),
        (5, 4, 20.0, 550.0, 880.0)
    );
    // The mean of a linear field over a block is its value at the block centre.
    let mean = |col0: usize, row0: usize| ((col0 as f64 + 1.5) * 100.0) + row0 as f64 + 1.5;
    assert_eq!(k.values[0], mean(10, 4));
    assert_eq!(k.values[k.index(4, 3)], mean(26, 16));
    assert!(matches!(c.coarsen(3), Err(GisError::BadCoarsen { .. })));
}

// ---------------------------------------------------------------- release polygons

fn square(x0: f64, y0: f64, side: f64) -> Vec<[f64; 2]> {
    vec![
        [x0, y0],
        [x0 + side, y0],
        [x0 + side, y0 + side],
        [x0, y0 + side],
    ]
}

fn circle(cx: f64, cy: f64, r: f64, n: usize) -> Vec<[f64; 2]> {
    (0..n)
        .map(|i| {
            let a = 2.0 * PI * i as f64 / n as f64;
            [cx + r * a.cos(), cy + r * a.sin()]
        })
        .collect()
}

fn one(polygon: Polygon, thickness: f64) -> ReleaseAreas {
    ReleaseAreas {
        features: vec![ReleaseFeature {
            polygons: vec![polygon],
            thickness,
        }],
        crs: Crs::unknown(),
    }
}

/// A 100 m × 100 m domain at cell size `d`.
fn domain(d: f64) -> Raster {
    let n = (100.0 / d).round() as usize;
    Raster::filled(n, n, 1000.0, 2100.0, d, 0.0)
}

/// Relative volume errors of both rules on grids of cell size 10, 5, 2.5, 1.25, 0.625 m.
fn errors(polygon: &Polygon, h: f64) -> Vec<(f64, f64, f64)> {
    let exact = polygon.area() * h;
    [10.0, 5.0, 2.5, 1.25, 0.625]
        .iter()
        .map(|&d| {
            let grid = domain(d);
            let areas = one(polygon.clone(), h);
            let fr = rasterise(&areas, &grid, CoverageRule::AreaFraction).unwrap();
            let cc = rasterise(&areas, &grid, CoverageRule::CellCentre).unwrap();
            (
                d,
                (fr.volume - exact).abs() / exact,
                (cc.volume - exact).abs() / exact,
            )
        })
        .collect()
}

fn assert_converges(name: &str, errs: &[(f64, f64, f64)], perimeter: f64, area: f64) {
    eprintln!("{name}: (cell size, area-fraction error, cell-centre error) {errs:?}");
    for &(d, fraction, centre) in errs {
        assert!(
            fraction < 1e-12,
            "{name}: area-fraction error {fraction:e} at d = {d}"
        );
        // The cell-centre rule misses at most the boundary cells: |ΔA| ≤ perimeter × d.
        let bound = perimeter * d / area;
        assert!(
            centre <= bound,
            "{name}: centre error {centre:e} > {bound:e} at d = {d}"
        );
    }
    let (coarse, fine) = (errs[0].2, errs[errs.len() - 1].2);
    assert!(
        fine < coarse / 4.0,
        "{name}: the centre-rule error does not shrink with the cell size: {errs:?}"
    );
}

#[test]
fn square_release_volume_converges_to_area_times_thickness() {
    // Not aligned with any of the grids.
    let sq = Polygon::new(square(1013.3, 2023.7, 41.9));
    let errs = errors(&sq, 2.5);
    assert_converges("square", &errs, 4.0 * 41.9, 41.9 * 41.9);
}

#[test]
fn circle_release_volume_converges_to_area_times_thickness() {
    let c = Polygon::new(circle(1051.1, 2048.7, 30.3, 720));
    let errs = errors(&c, 1.5);
    assert_converges("circle", &errs, 2.0 * PI * 30.3, c.area());
    // And the polygon's area is the circle's to 10⁻⁴.
    assert!((c.area() / (PI * 30.3 * 30.3) - 1.0).abs() < 1e-4);
}

#[test]
fn a_hole_subtracts_and_orientation_does_not_matter() {
    let grid = domain(1.0);
    let outer = square(1010.0, 2010.0, 60.0);
    let mut hole = square(1030.5, 2030.5, 20.0);
    let full = rasterise(
        &one(Polygon::new(outer.clone()), 2.0),
        &grid,
        CoverageRule::AreaFraction,
    )
    .unwrap();
    assert!((full.volume - 3600.0 * 2.0).abs() < 1e-9);
    for reverse in [false, true] {
        if reverse {
            hole.reverse();
        }
        let mut outer = outer.clone();
        if reverse {
            outer.reverse();
        }
        let p = Polygon {
            exterior: outer,
            holes: vec![hole.clone()],
        };
        let fr = rasterise(&one(p.clone(), 2.0), &grid, CoverageRule::AreaFraction).unwrap();
        assert!(
            (fr.volume - (3600.0 - 400.0) * 2.0).abs() < 1e-9,
            "{}",
            fr.volume
        );
        // Cells half and a quarter covered by the hole (x 1030..1031; y 2040..2041 and
        // 2030..2031): thickness 2 × ½ and 2 × ¾.
        let t = &fr.thickness;
        assert!(
            (t.values[grid.index(30, 59)] - 1.0).abs() < 1e-12,
            "{}",
            t.values[grid.index(30, 59)]
        );
        assert!(
            (t.values[grid.index(30, 69)] - 1.5).abs() < 1e-12,
            "{}",
            t.values[grid.index(30, 69)]
        );
        let cc = rasterise(&one(p, 2.0), &grid, CoverageRule::CellCentre).unwrap();
        // Centres at .5: the hole [1030.5, 1050.5] takes the 20 centres 1031.5..1050.5.
        assert!(
            (cc.volume - (3600.0 - 400.0) * 2.0).abs() < 1e-9,
            "{}",
            cc.volume
        );
    }
}

#[test]
fn coverage_fractions_of_a_triangle() {
    // Triangle (0,0) (2,0) (0,2) on a 2 × 2 grid of unit cells: fractions 1, ½, ½, 0.
    let grid = Raster::filled(2, 2, 0.0, 2.0, 1.0, 0.0);
    let tri = Polygon::new(vec![[0.0, 0.0], [2.0, 0.0], [0.0, 2.0]]);
    let f = coverage(
        std::slice::from_ref(&tri),
        &grid,
        CoverageRule::AreaFraction,
    );
    // Row 0 is the top: cells (0,0)=top-left ½, (1,0)=top-right 0, bottom-left 1, bottom-right ½.
    let expect = [0.5, 0.0, 1.0, 0.5];
    for (a, b) in f.iter().zip(expect) {
        assert!((a - b).abs() < 1e-15, "{f:?}");
    }
    // Centres (0.5, 1.5) and (1.5, 0.5) lie outside x/2 + y/1.9 < 1, (0.5, 0.5) inside.
    let tri = Polygon::new(vec![[0.0, 0.0], [2.0, 0.0], [0.0, 1.9]]);
    assert_eq!(
        coverage(&[tri], &grid, CoverageRule::CellCentre),
        [0.0, 0.0, 1.0, 0.0]
    );
}

#[test]
fn slope_normal_thickness_on_a_30_degree_plane() {
    let d = 2.0;
    let theta = 30f64.to_radians();
    let mut dem = Raster::filled(50, 40, 0.0, 80.0, d, 0.0);
    for row in 0..40 {
        for col in 0..50 {
            let (x, _) = dem.cell_centre(col, row);
            let i = dem.index(col, row);
            dem.values[i] = 500.0 - x * theta.tan();
        }
    }
    let cos = slope_cosine(&dem);
    for v in &cos.values {
        assert!((v - theta.cos()).abs() < 1e-12, "cos θ = {v}");
    }
    let areas = one(Polygon::new(square(20.0, 20.0, 40.0)), 1.5);
    let normal = rasterise(&areas, &dem, CoverageRule::AreaFraction).unwrap();
    assert!((normal.volume - 1600.0 * 1.5).abs() < 1e-9);
    let vertical = vertical_thickness(&normal.thickness, &dem).unwrap();
    let inside = vertical.values[dem.index(20, 20)];
    assert!((inside - 1.5 / theta.cos()).abs() < 1e-12, "h_v = {inside}");
    let volume: f64 = vertical.values.iter().sum::<f64>() * d * d;
    // The released volume grows by 1 / cos θ.
    assert!((volume / normal.volume - 1.0 / theta.cos()).abs() < 1e-12);
    // A flat DEM leaves the thickness alone; a mismatched grid is refused.
    let flat = dem.same_grid(3.0);
    assert_eq!(
        vertical_thickness(&normal.thickness, &flat).unwrap().values,
        normal.thickness.values
    );
    assert!(matches!(
        vertical_thickness(
            &normal.thickness,
            &dem.crop(Bbox {
                x_min: 0.0,
                x_max: 50.0,
                y_min: 0.0,
                y_max: 80.0
            })
            .unwrap()
        ),
        Err(GisError::GridMismatch { .. })
    ));
}

#[test]
fn release_errors_outside_partly_outside_crs_and_walls() {
    let mut grid = domain(1.0);
    let far = one(Polygon::new(square(0.0, 0.0, 10.0)), 1.0);
    let e = rasterise(&far, &grid, CoverageRule::AreaFraction).unwrap_err();
    assert!(
        matches!(e, GisError::PolygonOutsideRaster { feature: 0, .. }),
        "{e}"
    );
    let edge = one(Polygon::new(square(1090.0, 2050.0, 20.0)), 1.0);
    let e = rasterise(&edge, &grid, CoverageRule::CellCentre).unwrap_err();
    assert!(
        matches!(e, GisError::PolygonPartlyOutside { percent, .. } if (percent - 50.0).abs() < 1e-6),
        "{e}"
    );
    let mut inside = one(Polygon::new(square(1010.0, 2010.0, 20.0)), 1.0);
    inside.crs = Crs::from_epsg(2056);
    grid.crs = Crs::from_epsg(32632);
    let e = rasterise(&inside, &grid, CoverageRule::AreaFraction).unwrap_err();
    assert!(
        matches!(
            e,
            GisError::CrsMismatch {
                a: 32632,
                b: 2056,
                ..
            }
        ),
        "{e}"
    );
    // Unknown on one side is not compared.
    inside.crs = Crs::unknown();
    rasterise(&inside, &grid, CoverageRule::AreaFraction).unwrap();
    // Nodata cells of the grid are walls: no thickness, the volume reported apart.
    grid.nodata = Some(-9999.0);
    for row in 70..90 {
        let i = grid.index(15, row);
        grid.values[i] = -9999.0;
    }
    let r = rasterise(&inside, &grid, CoverageRule::AreaFraction).unwrap();
    assert!((r.volume - 380.0).abs() < 1e-9, "{}", r.volume);
    assert!((r.volume_on_nodata - 20.0).abs() < 1e-9);
    assert_eq!(r.thickness.get(15, 75), None);
}

#[test]
fn geojson_polygons_multipolygons_holes_and_properties() {
    let dir = tmp();
    let text = r#"{
      "type": "FeatureCollection",
      "crs": {"type": "name", "properties": {"name": "urn:ogc:def:crs:EPSG::32632"}},
      "features": [
        {"type": "Feature", "properties": {"h": 2.0, "name": "a"},
         "geometry": {"type": "Polygon", "coordinates": [
            [[1010, 2010], [1050, 2010], [1050, 2050], [1010, 2050], [1010, 2010]],
            [[1020, 2020], [1020, 2030], [1030, 2030], [1030, 2020], [1020, 2020]]]}},
        {"type": "Feature", "properties": {"h": "0.5"},
         "geometry": {"type": "MultiPolygon", "coordinates": [
            [[[1060, 2060], [1070, 2060], [1070, 2070], [1060, 2060]]],
            [[[1080, 2080], [1090, 2080], [1090, 2090], [1080, 2090], [1080, 2080]]]]}},
        {"type": "Feature", "properties": {"h": 9}, "geometry": null}
      ]}"#;
    let p = write_text(dir.path(), "release.geojson", text);
    let areas = release::read(&p, ThicknessSource::Attribute("h")).unwrap();
    assert_eq!(areas.crs.epsg, Some(32632));
    assert_eq!(areas.features.len(), 2);
    assert_eq!(areas.features[0].polygons[0].holes.len(), 1);
    assert_eq!(areas.features[1].polygons.len(), 2);
    let mut grid = domain(0.5);
    grid.crs = Crs::from_epsg(32632);
    let r = rasterise(&areas, &grid, CoverageRule::AreaFraction).unwrap();
    let expect = (1600.0 - 100.0) * 2.0 + (50.0 + 100.0) * 0.5;
    assert!((r.volume - expect).abs() < 1e-9, "{} vs {expect}", r.volume);
    // Uniform thickness, and the errors.
    let uniform = release::read(&p, ThicknessSource::Uniform(1.0)).unwrap();
    assert!(uniform.features.iter().all(|f| f.thickness == 1.0));
    let e = release::read(&p, ThicknessSource::Attribute("depth")).unwrap_err();
    assert!(
        matches!(e, GisError::MissingAttribute { feature: 0, ref available, .. } if available == "h, name"),
        "{e}"
    );
    let p2 = write_text(
        dir.path(),
        "neg.geojson",
        r#"{"type": "Feature", "properties": {"h": -1}, "geometry": {"type": "Polygon", "coordinates": [[[0,0],[1,0],[1,1]]]}}"#,
    );
    assert!(matches!(
        release::read(&p2, ThicknessSource::Attribute("h")).unwrap_err(),
        GisError::BadThickness { .. }
    ));
    let p3 = write_text(
        dir.path(),
        "point.geojson",
        r#"{"type": "Point", "coordinates": [0, 0]}"#,
    );
    assert!(matches!(
        release::read(&p3, ThicknessSource::Uniform(1.0)).unwrap_err(),
        GisError::GeoJson { .. }
    ));
    let p4 = write_text(dir.path(), "broken.geojson", r#"{"type": "Feature", "#);
    let e = release::read(&p4, ThicknessSource::Uniform(1.0)).unwrap_err();
    assert!(
        matches!(e, GisError::Json { .. }) && e.to_string().contains("broken.geojson"),
        "{e}"
    );
    let p5 = write_text(
        dir.path(),
        "none.geojson",
        r#"{"type": "FeatureCollection", "features": []}"#,
    );
    assert!(matches!(
        release::read(&p5, ThicknessSource::Uniform(1.0)).unwrap_err(),
        GisError::NoPolygons { .. }
    ));
    let p6 = write_text(dir.path(), "empty.geojson", "");
    assert!(matches!(
        release::read(&p6, ThicknessSource::Uniform(1.0)).unwrap_err(),
        GisError::EmptyFile { .. }
    ));
}

#[test]
fn shapefile_with_thickness_attribute_holes_and_prj() {
    use shapefile::dbase::{FieldValue, Record, TableWriterBuilder};
    use shapefile::{Point, PolygonRing};
    let dir = tmp();
    let p = dir.path().join("release.shp");
    {
        let table = TableWriterBuilder::new()
            .add_numeric_field("thick".try_into().unwrap(), 10, 3)
            .add_character_field("name".try_into().unwrap(), 20);
        let mut w = shapefile::Writer::from_path(&p, table).unwrap();
        let pts = |v: Vec<[f64; 2]>| {
            v.into_iter()
                .map(|[x, y]| Point::new(x, y))
                .collect::<Vec<_>>()
        };
        let with_hole = shapefile::Polygon::with_rings(vec![
            PolygonRing::Outer(pts(square(1010.0, 2010.0, 40.0))),
            PolygonRing::Inner(pts(square(1020.0, 2020.0, 10.0))),
        ]);
        let plain = shapefile::Polygon::new(PolygonRing::Outer(pts(square(1060.0, 2060.0, 20.0))));
        for (poly, h, name) in [(with_hole, 1.25, "north"), (plain, 0.5, "south")] {
            let mut rec = Record::default();
            rec.insert("thick".into(), FieldValue::Numeric(Some(h)));
            rec.insert("name".into(), FieldValue::Character(Some(name.into())));
            w.write_shape_and_record(&poly, &rec).unwrap();
        }
    }
    std::fs::write(p.with_extension("prj"), WKT_32632).unwrap();
    let areas = release::read(&p, ThicknessSource::Attribute("thick")).unwrap();
    assert_eq!(areas.crs.epsg, Some(32632));
    assert_eq!(areas.features.len(), 2);
    assert_eq!(areas.features[0].thickness, 1.25);
    assert_eq!(areas.features[0].polygons[0].holes.len(), 1);
    let mut grid = domain(1.0);
    grid.crs = Crs::from_epsg(32632);
    let r = rasterise(&areas, &grid, CoverageRule::AreaFraction).unwrap();
    let expect = (1600.0 - 100.0) * 1.25 + 400.0 * 0.5;
    assert!((r.volume - expect).abs() < 1e-9, "{} vs {expect}", r.volume);
    let e = release::read(&p, ThicknessSource::Attribute("depth")).unwrap_err();
    assert!(
        matches!(e, GisError::MissingAttribute { ref available, .. } if available == "name, thick"),
        "{e}"
    );
    grid.crs = Crs::from_epsg(2056);
    assert!(matches!(
        rasterise(&areas, &grid, CoverageRule::CellCentre),
        Err(GisError::CrsMismatch { .. })
    ));
    // Without a .dbf a uniform thickness still works.
    std::fs::remove_file(p.with_extension("dbf")).unwrap();
    assert_eq!(
        release::read(&p, ThicknessSource::Uniform(3.0))
            .unwrap()
            .features
            .len(),
        2
    );
    assert!(matches!(
        release::read(&p, ThicknessSource::Attribute("thick")),
        Err(GisError::MissingSidecar { .. })
    ));
}

// ---------------------------------------------------------------- NetCDF

#[test]
fn netcdf_layout_and_streaming_record_count() {
    let dir = tmp();
    let p = dir.path().join("run.nc");
    let mut grid = Raster::filled(4, 3, 100.0, 60.0, 10.0, 0.0);
    grid.nodata = Some(-1.0);
    grid.values[5] = -1.0;
    grid.crs = Crs::from_wkt(WKT_32632);
    let fields = [
        FieldSpec::new("h", "m", "flow thickness"),
        FieldSpec::new("speed", "m s-1", "depth-averaged speed"),
    ];
    let mut w = NetCdfWriter::create(&p, &grid, &fields, "test").unwrap();
    let header_and_fixed = std::fs::metadata(&p).unwrap().len();
    let h: Vec<f64> = (0..12).map(|i| i as f64 * 0.5).collect();
    let u: Vec<f64> = (0..12).map(|i| -(i as f64)).collect();
    for k in 0..3 {
        w.write_frame(k as f64 * 0.25, &[&h, &u]).unwrap();
        let bytes = std::fs::read(&p).unwrap();
        assert_eq!(&bytes[..4], b"CDF\x02");
        assert_eq!(
            u32::from_be_bytes(bytes[4..8].try_into().unwrap()),
            k + 1,
            "numrecs"
        );
        let record = 8 + 2 * 12 * 4;
        assert_eq!(
            bytes.len() as u64,
            header_and_fixed + (k as u64 + 1) * record
        );
        // The last value of the last frame, big-endian f32.
        let last = f32::from_be_bytes(bytes[bytes.len() - 4..].try_into().unwrap());
        assert_eq!(last, -11.0);
        // The wall cell (index 5) of h in this frame is NaN.
        let start = bytes.len() - record as usize + 8;
        let wall = f32::from_be_bytes(bytes[start + 20..start + 24].try_into().unwrap());
        assert!(wall.is_nan());
        let text = String::from_utf8_lossy(&bytes);
        for needle in [
            "Conventions",
            "CF-1.8",
            "projection_x_coordinate",
            "grid_mapping",
            "crs_wkt",
            "spatial_ref",
            "EPSG:32632",
            "_FillValue",
        ] {
            assert!(text.contains(needle), "{needle}");
        }
    }
    assert!(matches!(
        w.write_frame(1.0, &[&h]),
        Err(GisError::NetCdf { .. })
    ));
    w.finish().unwrap();
    let bad = [FieldSpec::new("2h", "m", "x")];
    assert!(matches!(
        NetCdfWriter::create(&p, &grid, &bad, "t"),
        Err(GisError::NetCdf { .. })
    ));
}

// ---------------------------------------------------------------- hostile files

/// A 1.7 MB file may declare 40 000² pixels: the size is refused from the header,
/// before any sample is decoded or allocated.
#[test]
fn a_geotiff_header_too_large_to_decode_is_refused_by_its_size() {
    let dir = tmp();
    let mut t = crate::common::crafted::Tiff::float32(1, 1);
    (t.width, t.height, t.bits, t.sample_format, t.compression) = (40_000, 40_000, 8, 1, 8);
    t.strip = vec![0x78, 0x9c, 0x03, 0x00, 0x00, 0x00, 0x00, 0x01];
    let p = dir.path().join("huge.tif");
    std::fs::write(&p, t.bytes()).unwrap();
    let e = geotiff::read(&p).unwrap_err();
    let text = e.to_string();
    assert!(matches!(e, GisError::UnsupportedTiff { .. }), "{text}");
    assert!(text.contains("huge.tif"), "{text}");
    assert!(text.contains("40000 x 40000 pixels"), "{text}");
    assert!(text.contains("crop or coarsen"), "{text}");
}

/// The texts of refused GeoTIFFs say what is wrong: an identity transformation is no
/// georeferencing, a sparse file (empty strips) is named as such.
#[test]
fn identity_transform_and_sparse_geotiffs_are_refused_with_their_own_reason() {
    let dir = tmp();
    let mut t = crate::common::crafted::Tiff::float32(3, 2);
    t.scale = None;
    t.tiepoint = None;
    let mut identity = [0.0; 16];
    for k in [0, 5, 10, 15] {
        identity[k] = 1.0;
    }
    t.transform = Some(identity);
    let p = dir.path().join("pixels.tif");
    std::fs::write(&p, t.bytes()).unwrap();
    let text = geotiff::read(&p).unwrap_err().to_string();
    assert!(text.contains("no georeferencing"), "{text}");
    assert!(text.contains("identity"), "{text}");
    assert!(!text.contains("south to north"), "{text}");

    let mut sparse = crate::common::crafted::Tiff::float32(3, 2);
    sparse.compression = 8;
    sparse.strip = Vec::new();
    sparse.strip_byte_count = Some(0);
    let p = dir.path().join("sparse.tif");
    std::fs::write(&p, sparse.bytes()).unwrap();
    let text = geotiff::read(&p).unwrap_err().to_string();
    assert!(text.contains("sparse GeoTIFF"), "{text}");
    assert!(!text.contains("corrupt"), "{text}");
    // The crafted file itself is sound: with its strip it reads.
    let p = dir.path().join("plain.tif");
    std::fs::write(&p, crate::common::crafted::Tiff::float32(3, 2).bytes()).unwrap();
    let r = geotiff::read(&p).unwrap();
    assert_eq!((r.nx, r.ny, r.cell_size, r.y_top), (3, 2, 1.0, 2.0));
}

/// A FIFO where the `.prj` of a grid or a shapefile would be is refused, not waited on
/// (a read would block until some writer opened it). Each read runs in a thread so
/// that a hang fails the test instead of stalling it.
#[cfg(unix)]
#[test]
fn a_fifo_side_car_file_is_refused_not_read() {
    let dir = tmp();
    let asc_path = write_text(
        dir.path(),
        "dem.asc",
        "ncols 2\nnrows 2\nxllcorner 0\nyllcorner 0\ncellsize 1\n1 2\n3 4\n",
    );
    let fifo = asc::prj_path(&asc_path);
    let made = std::process::Command::new("mkfifo")
        .arg(&fifo)
        .status()
        .unwrap();
    assert!(made.success());
    let shp = dir.path().join("dem.shp");
    let square = vec![vec![
        [0.0, 0.0],
        [0.0, 1.0],
        [1.0, 1.0],
        [1.0, 0.0],
        [0.0, 0.0],
    ]];
    std::fs::write(&shp, crate::common::crafted::polygon_shp(&[square])).unwrap();
    let (tx, rx) = std::sync::mpsc::channel();
    let (a, s) = (asc_path.clone(), shp.clone());
    std::thread::spawn(move || {
        let r1 = asc::read(&a).map(|_| ()).map_err(|e| e.to_string());
        let r2 = release::read(&s, ThicknessSource::Uniform(1.0))
            .map(|_| ())
            .map_err(|e| e.to_string());
        let _ = tx.send((r1, r2));
    });
    let (r1, r2) = rx
        .recv_timeout(std::time::Duration::from_secs(60))
        .expect("reading beside a FIFO hung");
    for r in [r1, r2] {
        let e = r.unwrap_err();
        assert!(
            e.contains("dem.prj") && e.contains("not a regular file"),
            "{e}"
        );
    }
}

/// A byte-order mark before the first key is not part of it.
#[test]
fn an_ascii_grid_with_a_byte_order_mark_reads() {
    let dir = tmp();
    let p = write_text(
        dir.path(),
        "bom.asc",
        "\u{feff}ncols 2\nnrows 1\nxllcorner 0\nyllcorner 0\ncellsize 1\n1 2\n",
    );
    let r = asc::read(&p).unwrap();
    assert_eq!(r.values, vec![1.0, 2.0]);
}

/// Invalid polygons are refused naming the file and the feature, whatever their
/// format: a bow-tie, a hole outside its ring, a zero-area ring (GeoJSON), and in a
/// shapefile rings that all run the wrong way, a NaN vertex and rings that cancel.
#[test]
fn invalid_release_polygons_are_refused_naming_file_and_feature() {
    let dir = tmp();
    let ring = |pts: &[[f64; 2]]| {
        let mut v: Vec<String> = pts
            .iter()
            .map(|p| format!("[{}, {}]", p[0], p[1]))
            .collect();
        v.push(v[0].clone());
        format!("[{}]", v.join(", "))
    };
    let collection = |polygons: &[String]| {
        let features: Vec<String> = polygons
            .iter()
            .map(|p| {
                format!(
                    r#"{{"type": "Feature", "properties": {{}}, "geometry": {{"type": "Polygon", "coordinates": {p}}}}}"#
                )
            })
            .collect();
        format!(
            r#"{{"type": "FeatureCollection", "features": [{}]}}"#,
            features.join(", ")
        )
    };
    let good = format!(
        "[{}]",
        ring(&[[0.0, 0.0], [10.0, 0.0], [10.0, 10.0], [0.0, 10.0]])
    );
    let cases = [
        (
            "bowtie",
            format!(
                "[{}]",
                ring(&[[0.0, 0.0], [10.0, 10.0], [10.0, 0.0], [0.0, 10.0]])
            ),
            "crosses or touches itself",
        ),
        (
            "hole_outside",
            format!(
                "[{}, {}]",
                ring(&[[0.0, 0.0], [10.0, 0.0], [10.0, 10.0], [0.0, 10.0]]),
                ring(&[[20.0, 20.0], [22.0, 20.0], [22.0, 22.0], [20.0, 22.0]])
            ),
            "hole 1 lies outside the exterior ring",
        ),
        (
            "flat",
            format!("[{}]", ring(&[[0.0, 0.0], [5.0, 5.0], [10.0, 10.0]])),
            "encloses no area",
        ),
    ];
    for (name, bad, words) in cases {
        let p = write_text(
            dir.path(),
            &format!("{name}.geojson"),
            &collection(&[good.clone(), bad]),
        );
        let e = release::read(&p, ThicknessSource::Uniform(1.0)).unwrap_err();
        let text = e.to_string();
        assert!(
            matches!(e, GisError::InvalidPolygon { feature: 1, .. }),
            "{name}: {text}"
        );
        assert!(text.contains(&format!("{name}.geojson")), "{text}");
        assert!(text.contains("feature 1"), "{text}");
        assert!(text.contains(words), "{name}: {text}");
    }
    // Shapefiles: rings as written (clockwise is exterior in this format).
    let cw = vec![
        [0.0, 0.0],
        [0.0, 10.0],
        [10.0, 10.0],
        [10.0, 0.0],
        [0.0, 0.0],
    ];
    let ccw: Vec<[f64; 2]> = cw.iter().rev().copied().collect();
    let nan = vec![
        [0.0, 0.0],
        [0.0, 10.0],
        [f64::NAN, 10.0],
        [10.0, 0.0],
        [0.0, 0.0],
    ];
    let cases = [
        ("misoriented", vec![ccw.clone()], "no exterior ring"),
        ("nan_vertex", vec![nan], "not finite"),
        ("cancelling", vec![cw.clone(), ccw], "cross or overlap"),
    ];
    for (name, rings, words) in cases {
        let p = dir.path().join(format!("{name}.shp"));
        std::fs::write(
            &p,
            crate::common::crafted::polygon_shp(&[vec![cw.clone()], rings]),
        )
        .unwrap();
        let e = release::read(&p, ThicknessSource::Uniform(1.0)).unwrap_err();
        let text = e.to_string();
        assert!(
            matches!(e, GisError::InvalidPolygon { feature: 1, .. }),
            "{name}: {text}"
        );
        assert!(text.contains(&format!("{name}.shp")), "{text}");
        assert!(text.contains(words), "{name}: {text}");
    }
    // The valid shapefile of the same writer reads.
    let p = dir.path().join("valid.shp");
    std::fs::write(&p, crate::common::crafted::polygon_shp(&[vec![cw]])).unwrap();
    let areas = release::read(&p, ThicknessSource::Uniform(1.0)).unwrap();
    assert_eq!(areas.features[0].polygons[0].area(), 100.0);
}

/// A shapefile whose thickness attribute needs the `.dbf` that is missing says so in
/// words (the library's own error is the bare `MissingDbf`).
#[test]
fn a_missing_dbf_is_named_in_words() {
    let dir = tmp();
    let p = dir.path().join("nodbf.shp");
    let cw = vec![
        [0.0, 0.0],
        [0.0, 10.0],
        [10.0, 10.0],
        [10.0, 0.0],
        [0.0, 0.0],
    ];
    std::fs::write(&p, crate::common::crafted::polygon_shp(&[vec![cw]])).unwrap();
    let text = release::read(&p, ThicknessSource::Attribute("d"))
        .unwrap_err()
        .to_string();
    assert!(text.contains("nodbf.dbf") && text.contains("`d`"), "{text}");
    assert!(!text.contains("MissingDbf"), "{text}");
}
