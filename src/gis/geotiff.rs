//! Single-band GeoTIFF, read and write, through the pure-Rust `tiff` crate.
//!
//! # Reading
//!
//! * Samples: one band of Float32, Float64, Float16 or 8/16/32/64-bit (un)signed
//!   integers, converted to `f64`; strips or tiles; uncompressed, LZW, Deflate or
//!   PackBits (whatever `tiff` decodes), with or without the horizontal predictor.
//!   More than one band is refused.
//! * Georeferencing: `ModelPixelScaleTag` (33550) and one `ModelTiepointTag` (33922),
//!   or a `ModelTransformationTag` (34264) without rotation or shear. A transformation
//!   with rotation/shear terms, or a set of several tiepoints (a control-point
//!   georeferencing, which may be rotated), is refused ([`GisError::Rotated`]), and so
//!   are non-square pixels ([`GisError::NonSquareCells`]) and south-up rasters.
//! * Pixel is area or point (`GTRasterTypeGeoKey`, 1025): with *PixelIsArea* (the
//!   default) the tiepoint names the top-left **corner** of the pixel; with
//!   *PixelIsPoint* it names the pixel's **centre**, so the raster's corner is half a
//!   cell up and left of it. This is GDAL's reading (without `GTIFF_POINT_GEO_IGNORE`).
//! * CRS: `ProjectedCSTypeGeoKey` (3072), else `GeographicTypeGeoKey` (2048), gives the
//!   EPSG code (32767, "user-defined", gives none).
//! * Nodata: the `GDAL_NODATA` ASCII tag (42113); for Float32 data it is rounded to
//!   `f32` so that it equals the cells that hold it.
//!
//! # Writing
//!
//! Float32 (default) or Float64 samples, uncompressed, LZW or Deflate (the default;
//! LZW is slower to write and compresses floats poorly), strips of about
//! 1 MB, *PixelIsArea*, `ModelPixelScaleTag` + one tiepoint at the top-left corner, the
//! EPSG code as `ProjectedCSTypeGeoKey` or `GeographicTypeGeoKey` (by
//! [`Crs::is_geographic`]), `GDAL_NODATA` when the raster has nodata; no GeoKey
//! directory at all when the CRS is unknown or a `LOCAL_CS` (GDAL then reads "no CRS"). A CRS with WKT but
//! no EPSG code is written as the `GTCitationGeoKey` text, which granflow reads back
//! but other readers only display. BigTIFF is used past 4 GB. [`write_band`] also
//! names the band: its description and units go into the `GDAL_METADATA` tag (42112)
//! as GDAL writes them, so GDAL (rasterio's `descriptions`, `units`) and QGIS show them.

use std::fs::File;
use std::io::{BufReader, BufWriter, Seek, Write};
use std::path::Path;

use tiff::decoder::{Decoder, DecodingResult, Limits};
use tiff::encoder::colortype::{ColorType as EncColor, Gray32Float, Gray64Float};
use tiff::encoder::{
    Compression as TiffCompression, DeflateLevel, TiffEncoder, TiffKind, TiffValue,
};
use tiff::tags::Tag;
use tiff::{ColorType, TiffError};

use super::{io_err, nearly_equal, Crs, GisError, Raster, Result};

/// GDAL's metadata tag (XML), where it keeps band descriptions and units.
const GDAL_METADATA: u16 = 42112;
const KEY_MODEL_TYPE: u16 = 1024;
const KEY_RASTER_TYPE: u16 = 1025;
const KEY_CITATION: u16 = 1026;
const KEY_GEOGRAPHIC: u16 = 2048;
const KEY_PROJECTED: u16 = 3072;
const USER_DEFINED: u16 = 32767;
const RASTER_PIXEL_IS_AREA: u16 = 1;
const RASTER_PIXEL_IS_POINT: u16 = 2;

/// Most pixels [`read`] decodes (1.6 GB as `f64`): the largest domain of a
/// run (10⁷ cells) twenty times over, for DEMs that are cropped or coarsened (`domain.crop`,
/// `domain.coarsen`) to it.
pub const MAX_READ_CELLS: u64 = 200_000_000;

/// Sample type of a written GeoTIFF.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum SampleType {
    /// 32-bit floats (values rounded to `f32`).
    #[default]
    F32,
    /// 64-bit floats (exact).
    F64,
}

/// Compression of a written GeoTIFF.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Compression {
    /// None: fastest to write and read.
    None,
    /// LZW.
    Lzw,
    /// Deflate (zlib) at the fast level.
    #[default]
    Deflate,
}

/// How [`write()`] encodes a raster.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct WriteOptions {
    pub sample: SampleType,
    pub compression: Compression,
}

fn tiff_err(path: &Path) -> impl FnOnce(TiffError) -> GisError + '_ {
    move |source| GisError::Tiff {
        path: path.to_path_buf(),
        source,
    }
}

/// Reads a single-band GeoTIFF.
pub fn read(path: &Path) -> Result<Raster> {
    super::regular_if_present(path)?;
    let file = File::open(path).map_err(io_err(path))?;
    if file.metadata().map_err(io_err(path))?.len() == 0 {
        return Err(GisError::EmptyFile {
            path: path.to_path_buf(),
        });
    }
    // Rasters up to 8 GiB decoded (10⁹ Float64 cells); a header that claims more (a
    // corrupt file, say) is an error, not an allocation that aborts.
    let mut limits = Limits::default();
    limits.decoding_buffer_size = 8 << 30;
    limits.intermediate_buffer_size = 8 << 30;
    limits.ifd_value_size = 64 << 20;
    let terr = tiff_err(path);
    let mut dec = match Decoder::new(BufReader::with_capacity(1 << 20, file)) {
        Ok(d) => d.with_limits(limits),
        Err(e) => return Err(terr(e)),
    };
    let unsupported = |reason: String| GisError::UnsupportedTiff {
        path: path.to_path_buf(),
        reason,
    };
    let (width, height) = dec.dimensions().map_err(tiff_err(path))?;
    // Before anything is decoded: a header may promise any size (40 000² pixels in
    // a 1.7 MB Deflate file), and the decoded samples and their f64 copy are allocated
    // at once.
    let cells = u64::from(width) * u64::from(height);
    if cells > MAX_READ_CELLS {
        return Err(unsupported(format!(
            "{width} x {height} pixels ({cells} cells) is more than the {MAX_READ_CELLS} \
             cells granflow reads (a run takes at most 10⁷): crop or coarsen it first \
             (e.g. gdal_translate -projwin, gdalwarp -tr)"
        )));
    }
    match dec.colortype().map_err(tiff_err(path))? {
        ColorType::Gray(_) => {}
        ColorType::Multiband { num_samples, .. } => {
            return Err(unsupported(format!(
                "{num_samples} bands; granflow reads single-band rasters"
            )))
        }
        other => {
            return Err(unsupported(format!(
                "colour type {other:?}; granflow reads single-band rasters"
            )))
        }
    }
    let f64s = |dec: &mut Decoder<_>, tag| -> Result<Option<Vec<f64>>> {
        dec.find_tag(tag)
            .and_then(|v| v.map(|v| v.into_f64_vec()).transpose())
            .map_err(tiff_err(path))
    };
    let transform = f64s(&mut dec, Tag::ModelTransformationTag)?;
    let scale = f64s(&mut dec, Tag::ModelPixelScaleTag)?;
    let ties = f64s(&mut dec, Tag::ModelTiepointTag)?;
    let keys = dec
        .find_tag(Tag::GeoKeyDirectoryTag)
        .and_then(|v| v.map(|v| v.into_u16_vec()).transpose())
        .map_err(tiff_err(path))?;
    let ascii_params = dec
        .find_tag(Tag::GeoAsciiParamsTag)
        .and_then(|v| v.map(|v| v.into_string()).transpose())
        .map_err(tiff_err(path))?;
    let nodata_text = dec
        .find_tag(Tag::GdalNodata)
        .and_then(|v| v.map(|v| v.into_string()).transpose())
        .map_err(tiff_err(path))?;

    let geo = GeoKeys::parse(keys.as_deref(), ascii_params.as_deref());
    let (x0, y0, sx, sy) = georeference(path, transform, scale, ties)?;
    if !nearly_equal(sx, sy) {
        return Err(GisError::NonSquareCells {
            path: path.to_path_buf(),
            dx: sx,
            dy: sy,
        });
    }
    let (x_left, y_top) = if geo.raster_type == RASTER_PIXEL_IS_POINT {
        (x0 - 0.5 * sx, y0 + 0.5 * sy)
    } else {
        (x0, y0)
    };

    // GDAL's sparse files (SPARSE_OK) leave blocks without data: offset and byte count
    // 0, which the decoder would report as a corrupt stream.
    for tag in [Tag::StripByteCounts, Tag::TileByteCounts] {
        let counts = dec
            .find_tag(tag)
            .and_then(|v| v.map(|v| v.into_u64_vec()).transpose())
            .map_err(tiff_err(path))?;
        if let Some(empty) = counts.and_then(|c| c.iter().position(|&n| n == 0)) {
            return Err(unsupported(format!(
                "a sparse GeoTIFF: {} {empty} holds no data (blocks left empty, GDAL's \
                 SPARSE_OK); granflow reads only complete files: write it out in full \
                 first (e.g. gdal_translate in.tif out.tif)",
                if tag == Tag::StripByteCounts {
                    "strip"
                } else {
                    "tile"
                }
            )));
        }
    }
    let data = dec.read_image().map_err(tiff_err(path))?;
    let mut is_f32 = false;
    let values: Vec<f64> = match data {
        DecodingResult::F32(v) => {
            is_f32 = true;
            v.into_iter().map(f64::from).collect()
        }
        DecodingResult::F64(v) => v,
        DecodingResult::F16(v) => {
            is_f32 = true;
            v.into_iter().map(|x| x.to_f64()).collect()
        }
        DecodingResult::U8(v) => v.into_iter().map(f64::from).collect(),
        DecodingResult::U16(v) => v.into_iter().map(f64::from).collect(),
        DecodingResult::U32(v) => v.into_iter().map(f64::from).collect(),
        DecodingResult::U64(v) => v.into_iter().map(|x| x as f64).collect(),
        DecodingResult::I8(v) => v.into_iter().map(f64::from).collect(),
        DecodingResult::I16(v) => v.into_iter().map(f64::from).collect(),
        DecodingResult::I32(v) => v.into_iter().map(f64::from).collect(),
        DecodingResult::I64(v) => v.into_iter().map(|x| x as f64).collect(),
    };
    let (nx, ny) = (width as usize, height as usize);
    if values.len() != nx * ny {
        return Err(unsupported(format!(
            "decoded {} samples for {nx} x {ny} pixels",
            values.len()
        )));
    }
    let nodata = match nodata_text {
        None => None,
        Some(text) => {
            let t = text.trim_matches(|c: char| c == '\0' || c.is_whitespace());
            let v = parse_nodata(t)
                .ok_or_else(|| unsupported(format!("GDAL_NODATA `{t}` is not a number")))?;
            Some(if is_f32 { v as f32 as f64 } else { v })
        }
    };
    let crs = match geo.epsg {
        Some(code) => Crs::from_epsg(code),
        None => match geo.citation {
            Some(c) if looks_like_wkt(&c) => Crs::from_wkt(&c),
            _ => Crs::default(),
        },
    };
    Ok(Raster {
        nx,
        ny,
        x_left,
        y_top,
        cell_size: sx,
        values,
        nodata,
        crs,
    })
}

fn parse_nodata(t: &str) -> Option<f64> {
    let lower = t.to_ascii_lowercase();
    if lower.trim_start_matches(['-', '+']) == "nan" {
        return Some(f64::NAN);
    }
    lower.parse().ok()
}

fn looks_like_wkt(text: &str) -> bool {
    let t = text.trim_start().to_ascii_uppercase();
    [
        "PROJCS[",
        "GEOGCS[",
        "PROJCRS[",
        "GEOGCRS[",
        "GEODCRS[",
        "COMPD_CS[",
        "COMPOUNDCRS[",
    ]
    .iter()
    .any(|p| t.starts_with(p))
}

/// The top-left point (of pixel (0, 0)'s corner, or of its centre for PixelIsPoint)
/// and the pixel sizes.
fn georeference(
    path: &Path,
    transform: Option<Vec<f64>>,
    scale: Option<Vec<f64>>,
    ties: Option<Vec<f64>>,
) -> Result<(f64, f64, f64, f64)> {
    let not_geo = |reason: &str| GisError::NotGeoreferenced {
        path: path.to_path_buf(),
        reason: reason.to_string(),
    };
    let (x0, y0, sx, sy) = if let Some(m) = transform {
        if m.len() < 16 {
            return Err(not_geo("ModelTransformationTag has fewer than 16 values"));
        }
        let identity = [
            1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0,
        ];
        if m[..16] == identity {
            return Err(not_geo(
                "the ModelTransformationTag is the identity (pixel coordinates, as written \
                 by tools that had no georeferencing to store)",
            ));
        }
        if m[1] != 0.0 || m[4] != 0.0 {
            return Err(GisError::Rotated {
                path: path.to_path_buf(),
                what: format!(
                    "ModelTransformationTag with rotation/shear terms {} and {}",
                    m[1], m[4]
                ),
            });
        }
        (m[3], m[7], m[0], -m[5])
    } else {
        let scale =
            scale.ok_or_else(|| not_geo("no ModelPixelScaleTag or ModelTransformationTag"))?;
        let ties = ties.ok_or_else(|| not_geo("ModelPixelScaleTag without ModelTiepointTag"))?;
        if scale.len() < 2 || ties.len() < 6 {
            return Err(not_geo("truncated ModelPixelScaleTag or ModelTiepointTag"));
        }
        if ties.len() > 6 {
            return Err(GisError::Rotated {
                path: path.to_path_buf(),
                what: format!(
                    "{} tiepoints, a control-point georeferencing that may be rotated",
                    ties.len() / 6
                ),
            });
        }
        let (sx, sy) = (scale[0], scale[1]);
        (ties[3] - ties[0] * sx, ties[4] + ties[1] * sy, sx, sy)
    };
    if !(sx.is_finite() && sx > 0.0) {
        return Err(GisError::NonPositiveCellSize {
            path: path.to_path_buf(),
            value: sx,
        });
    }
    if !(sy.is_finite() && sy > 0.0) {
        return Err(GisError::UnsupportedTiff {
            path: path.to_path_buf(),
            reason: format!(
                "pixel height {sy}: rows run south to north; granflow needs north-up rasters"
            ),
        });
    }
    if !(x0.is_finite() && y0.is_finite()) {
        return Err(not_geo("the tiepoint is not finite"));
    }
    Ok((x0, y0, sx, sy))
}

struct GeoKeys {
    raster_type: u16,
    epsg: Option<u32>,
    citation: Option<String>,
}

impl GeoKeys {
    fn parse(keys: Option<&[u16]>, ascii: Option<&str>) -> GeoKeys {
        let mut out = GeoKeys {
            raster_type: RASTER_PIXEL_IS_AREA,
            epsg: None,
            citation: None,
        };
        let Some(keys) = keys else { return out };
        if keys.len() < 4 {
            return out;
        }
        let n = keys[3] as usize;
        let (mut projected, mut geographic) = (None, None);
        for entry in keys[4..].chunks_exact(4).take(n) {
            let (id, location, count, value) = (entry[0], entry[1], entry[2], entry[3]);
            match (id, location) {
                (KEY_RASTER_TYPE, 0) => out.raster_type = value,
                (KEY_PROJECTED, 0) => projected = Some(value),
                (KEY_GEOGRAPHIC, 0) => geographic = Some(value),
                (KEY_CITATION, 34737) => {
                    if let Some(a) = ascii {
                        let start = value as usize;
                        let end = (start + count as usize).min(a.len());
                        if start < end && a.is_char_boundary(start) && a.is_char_boundary(end) {
                            out.citation =
                                Some(a[start..end].trim_end_matches(['|', '\0']).to_string());
                        }
                    }
                }
                _ => {}
            }
        }
        let known = |c: Option<u16>| c.filter(|&c| c != 0 && c != USER_DEFINED).map(u32::from);
        out.epsg = known(projected).or(known(geographic));
        out
    }
}

/// What a band holds, written with it by [`write_band`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Band<'a> {
    /// The band's description (GDAL's `GetDescription`), e.g. `pft: peak flow thickness`.
    pub description: &'a str,
    /// The unit of its values (GDAL's `GetUnitType`), e.g. `m`.
    pub units: &'a str,
}

impl Band<'_> {
    /// The `GDAL_METADATA` text: XML with the description and the units of band 0.
    /// The tag is ASCII: other characters become `?`.
    fn gdal_metadata(&self) -> String {
        let text = |s: &str| -> String {
            s.chars()
                .map(|c| match c {
                    '&' => "&amp;".to_string(),
                    '<' => "&lt;".to_string(),
                    '>' => "&gt;".to_string(),
                    '"' => "&quot;".to_string(),
                    c if c.is_ascii() && !c.is_ascii_control() => c.to_string(),
                    _ => "?".to_string(),
                })
                .collect()
        };
        format!(
            "<GDALMetadata>\n  <Item name=\"DESCRIPTION\" sample=\"0\" role=\"description\">{}</Item>\n  <Item name=\"UNITTYPE\" sample=\"0\" role=\"unittype\">{}</Item>\n</GDALMetadata>",
            text(self.description),
            text(self.units)
        )
    }
}

/// The `Software` tag of the GeoTIFF files granflow writes.
pub const SOFTWARE: &str = concat!("granflow ", env!("CARGO_PKG_VERSION"));

/// Whether `path` is a TIFF file whose `Software` tag says granflow wrote it (read from
/// the directory only, no image data).
pub fn written_by_granflow(path: &Path) -> bool {
    let Ok(file) = File::open(path) else {
        return false;
    };
    tiff::decoder::Decoder::new(std::io::BufReader::new(file))
        .ok()
        .and_then(|mut d| d.get_tag_ascii_string(Tag::Software).ok())
        .is_some_and(|s| s.starts_with("granflow "))
}

/// Writes `raster` as a single-band GeoTIFF (see the [module docs](self)).
pub fn write(raster: &Raster, path: &Path, options: WriteOptions) -> Result<()> {
    write_band(raster, path, options, None)
}

/// [`write()`], with the band's description and units when `band` is given.
pub fn write_band(
    raster: &Raster,
    path: &Path,
    options: WriteOptions,
    band: Option<Band>,
) -> Result<()> {
    raster.check().map_err(|reason| GisError::BadGrid {
        path: path.to_path_buf(),
        reason,
    })?;
    let nx = u32::try_from(raster.nx).map_err(|_| GisError::BadGrid {
        path: path.to_path_buf(),
        reason: format!("{} columns is more than TIFF allows", raster.nx),
    })?;
    let ny = u32::try_from(raster.ny).map_err(|_| GisError::BadGrid {
        path: path.to_path_buf(),
        reason: format!("{} rows is more than TIFF allows", raster.ny),
    })?;
    let file = File::create(path).map_err(io_err(path))?;
    let out = BufWriter::with_capacity(1 << 20, file);
    let compression = match options.compression {
        Compression::None => TiffCompression::Uncompressed,
        Compression::Lzw => TiffCompression::Lzw,
        Compression::Deflate => TiffCompression::Deflate(DeflateLevel::Fast),
    };
    let sample_bytes = match options.sample {
        SampleType::F32 => 4,
        SampleType::F64 => 8,
    };
    let big = (raster.values.len() as u64) * sample_bytes > 3_900_000_000;
    let result = if big {
        TiffEncoder::new_big(out).and_then(|e| {
            encode(
                e.with_compression(compression),
                raster,
                nx,
                ny,
                options.sample,
                band,
            )
        })
    } else {
        TiffEncoder::new(out).and_then(|e| {
            encode(
                e.with_compression(compression),
                raster,
                nx,
                ny,
                options.sample,
                band,
            )
        })
    };
    result.map_err(tiff_err(path))
}

fn encode<W: Write + Seek, K: TiffKind>(
    mut enc: TiffEncoder<W, K>,
    raster: &Raster,
    nx: u32,
    ny: u32,
    sample: SampleType,
    band: Option<Band>,
) -> std::result::Result<(), TiffError> {
    match sample {
        SampleType::F32 => {
            let data: Vec<f32> = raster.values.iter().map(|&v| v as f32).collect();
            encode_as::<W, K, Gray32Float>(&mut enc, (raster, band), nx, ny, &data)
        }
        SampleType::F64 => {
            encode_as::<W, K, Gray64Float>(&mut enc, (raster, band), nx, ny, &raster.values)
        }
    }
}

fn encode_as<W: Write + Seek, K: TiffKind, C: EncColor>(
    enc: &mut TiffEncoder<W, K>,
    (raster, band): (&Raster, Option<Band>),
    nx: u32,
    ny: u32,
    data: &[C::Inner],
) -> std::result::Result<(), TiffError>
where
    [C::Inner]: TiffValue,
{
    let mut image = enc.new_image::<C>(nx, ny)?;
    let d = raster.cell_size;
    let dir = image.encoder();
    // Tells granflow's files from others when an export would replace one.
    dir.write_tag(Tag::Software, SOFTWARE)?;
    dir.write_tag(Tag::ModelPixelScaleTag, &[d, d, 0.0][..])?;
    dir.write_tag(
        Tag::ModelTiepointTag,
        &[0.0, 0.0, 0.0, raster.x_left, raster.y_top, 0.0][..],
    )?;
    // No CRS, no key directory: GDAL reads a directory without a model type as an
    // unnamed LOCAL_CS, which `rio info` and others fail on; without one it reads
    // "no CRS". (PixelIsArea, the only other key, is the default.)
    if !(raster.crs.is_unknown() || raster.crs.is_local()) {
        let (keys, ascii) = geo_keys(&raster.crs);
        dir.write_tag(Tag::GeoKeyDirectoryTag, &keys[..])?;
        if let Some(ascii) = ascii {
            dir.write_tag(Tag::GeoAsciiParamsTag, ascii.as_str())?;
        }
    }
    if let Some(nd) = raster.nodata {
        let text = if nd.is_nan() {
            "nan".to_string()
        } else {
            format!("{nd}")
        };
        dir.write_tag(Tag::GdalNodata, text.as_str())?;
    }
    if let Some(band) = band {
        dir.write_tag(Tag::Unknown(GDAL_METADATA), band.gdal_metadata().as_str())?;
    }
    image.write_data(data)
}

/// The GeoKeyDirectory entries (sorted by key) and the GeoAsciiParams text.
fn geo_keys(crs: &Crs) -> (Vec<u16>, Option<String>) {
    let mut entries: Vec<[u16; 4]> = Vec::new();
    let mut ascii = None;
    let code = crs.epsg.and_then(|c| u16::try_from(c).ok());
    if code.is_some() || crs.wkt.is_some() {
        let model = if crs.is_geographic() { 2 } else { 1 };
        entries.push([KEY_MODEL_TYPE, 0, 1, model]);
    }
    entries.push([KEY_RASTER_TYPE, 0, 1, RASTER_PIXEL_IS_AREA]);
    match (code, &crs.wkt) {
        (Some(code), _) => {
            let key = if crs.is_geographic() {
                KEY_GEOGRAPHIC
            } else {
                KEY_PROJECTED
            };
            entries.push([key, 0, 1, code]);
        }
        (None, Some(wkt)) => {
            let text = format!("{wkt}|");
            if let Ok(len) = u16::try_from(text.len()) {
                entries.push([KEY_CITATION, 34737, len, 0]);
                ascii = Some(text);
            }
        }
        (None, None) => {}
    }
    entries.sort_by_key(|e| e[0]);
    let mut keys = vec![1, 1, 0, entries.len() as u16];
    for e in entries {
        keys.extend_from_slice(&e);
    }
    (keys, ascii)
}
