//! Crafted input files, written byte by byte so that a test (or the fuzz target) can
//! state any header a hostile file may hold: GeoTIFFs whose sizes, georeferencing and
//! strips are whatever the test says, and polygon shapefiles whose rings run either
//! way (the `shapefile` crate's writer corrects the orientation, so it cannot write a
//! mis-oriented file).

/// A single-strip, single-band baseline TIFF with GeoTIFF tags.
#[derive(Debug, Clone)]
pub struct Tiff {
    pub width: u32,
    pub height: u32,
    /// Bits per sample (8, 16, 32, 64).
    pub bits: u16,
    /// 1 unsigned integer, 2 signed, 3 floating point.
    pub sample_format: u16,
    /// 1 none, 5 LZW, 8 Deflate.
    pub compression: u16,
    /// The strip's bytes.
    pub strip: Vec<u8>,
    /// `StripByteCounts` (the strip's length unless set; 0 makes a sparse file).
    pub strip_byte_count: Option<u32>,
    pub scale: Option<[f64; 3]>,
    pub tiepoint: Option<[f64; 6]>,
    pub transform: Option<[f64; 16]>,
    /// The `GeoKeyDirectoryTag` values, when any.
    pub geokeys: Vec<u16>,
}

impl Tiff {
    /// A north-up Float32 raster of `width × height` cells of 1 m, values 0, top-left
    /// corner (0, height), no CRS.
    pub fn float32(width: u32, height: u32) -> Tiff {
        Tiff {
            width,
            height,
            bits: 32,
            sample_format: 3,
            compression: 1,
            strip: vec![0; width as usize * height as usize * 4],
            strip_byte_count: None,
            scale: Some([1.0, 1.0, 0.0]),
            tiepoint: Some([0.0, 0.0, 0.0, 0.0, f64::from(height), 0.0]),
            transform: None,
            geokeys: Vec::new(),
        }
    }

    /// The GeoKeyDirectory of one key (`GeographicTypeGeoKey` 2048 or
    /// `ProjectedCSTypeGeoKey` 3072) with the value `code`.
    pub fn with_epsg(mut self, key: u16, code: u16) -> Tiff {
        self.geokeys = vec![1, 1, 0, 1, key, 0, 1, code];
        self
    }

    /// The file's bytes (little-endian).
    pub fn bytes(&self) -> Vec<u8> {
        // (tag, type, count, payload bytes)
        let mut entries: Vec<(u16, u16, u32, Vec<u8>)> = Vec::new();
        let long = |v: u32| v.to_le_bytes().to_vec();
        let short = |v: u16| v.to_le_bytes().to_vec();
        let doubles = |v: &[f64]| v.iter().flat_map(|d| d.to_le_bytes()).collect::<Vec<u8>>();
        entries.push((256, 4, 1, long(self.width)));
        entries.push((257, 4, 1, long(self.height)));
        entries.push((258, 3, 1, short(self.bits)));
        entries.push((259, 3, 1, short(self.compression)));
        entries.push((262, 3, 1, short(1)));
        entries.push((273, 4, 1, long(0))); // patched below
        entries.push((277, 3, 1, short(1)));
        entries.push((278, 4, 1, long(self.height)));
        let count = self.strip_byte_count.unwrap_or(self.strip.len() as u32);
        entries.push((279, 4, 1, long(count)));
        entries.push((339, 3, 1, short(self.sample_format)));
        if let Some(s) = &self.scale {
            entries.push((33550, 12, 3, doubles(s)));
        }
        if let Some(t) = &self.tiepoint {
            entries.push((33922, 12, 6, doubles(t)));
        }
        if let Some(m) = &self.transform {
            entries.push((34264, 12, 16, doubles(m)));
        }
        if !self.geokeys.is_empty() {
            let bytes = self.geokeys.iter().flat_map(|k| k.to_le_bytes()).collect();
            entries.push((34735, 3, self.geokeys.len() as u32, bytes));
        }
        let ifd_len = 2 + 12 * entries.len() + 4;
        let mut extra: Vec<u8> = Vec::new();
        let extra_start = 8 + ifd_len;
        let mut out = b"II\x2a\x00\x08\x00\x00\x00".to_vec();
        out.extend_from_slice(&(entries.len() as u16).to_le_bytes());
        // Payloads longer than 4 bytes go after the IFD; the strip after them.
        let mut offsets = Vec::new();
        for (_, _, _, payload) in &entries {
            if payload.len() > 4 {
                offsets.push(Some(extra_start + extra.len()));
                extra.extend_from_slice(payload);
                if extra.len() % 2 == 1 {
                    extra.push(0);
                }
            } else {
                offsets.push(None);
            }
        }
        let strip_offset = (extra_start + extra.len()) as u32;
        for ((tag, kind, count, payload), offset) in entries.iter().zip(&offsets) {
            out.extend_from_slice(&tag.to_le_bytes());
            out.extend_from_slice(&kind.to_le_bytes());
            out.extend_from_slice(&count.to_le_bytes());
            let mut field = match offset {
                Some(o) => (*o as u32).to_le_bytes().to_vec(),
                None if *tag == 273 => strip_offset.to_le_bytes().to_vec(),
                None => payload.clone(),
            };
            field.resize(4, 0);
            out.extend_from_slice(&field);
        }
        out.extend_from_slice(&[0, 0, 0, 0]);
        out.extend_from_slice(&extra);
        out.extend_from_slice(&self.strip);
        out
    }
}

/// The bytes of a polygon shapefile (`.shp`, type 5) whose records hold the given
/// rings as they are (orientation and values untouched), one record per entry.
pub fn polygon_shp(records: &[Vec<Vec<[f64; 2]>>]) -> Vec<u8> {
    let mut body = Vec::new();
    let (mut x0, mut y0, mut x1, mut y1) = (f64::MAX, f64::MAX, f64::MIN, f64::MIN);
    for (k, rings) in records.iter().enumerate() {
        let points: Vec<[f64; 2]> = rings.iter().flatten().copied().collect();
        for p in &points {
            if p[0].is_finite() && p[1].is_finite() {
                x0 = x0.min(p[0]);
                y0 = y0.min(p[1]);
                x1 = x1.max(p[0]);
                y1 = y1.max(p[1]);
            }
        }
        let mut content = Vec::new();
        content.extend_from_slice(&5i32.to_le_bytes());
        for v in [x0, y0, x1, y1] {
            content.extend_from_slice(&v.to_le_bytes());
        }
        content.extend_from_slice(&(rings.len() as i32).to_le_bytes());
        content.extend_from_slice(&(points.len() as i32).to_le_bytes());
        let mut start = 0i32;
        for r in rings {
            content.extend_from_slice(&start.to_le_bytes());
            start += r.len() as i32;
        }
        for p in &points {
            content.extend_from_slice(&p[0].to_le_bytes());
            content.extend_from_slice(&p[1].to_le_bytes());
        }
        body.extend_from_slice(&(k as i32 + 1).to_be_bytes());
        body.extend_from_slice(&((content.len() / 2) as i32).to_be_bytes());
        body.extend_from_slice(&content);
    }
    let mut out = Vec::with_capacity(100 + body.len());
    out.extend_from_slice(&9994i32.to_be_bytes());
    out.extend_from_slice(&[0; 20]);
    out.extend_from_slice(&(((100 + body.len()) / 2) as i32).to_be_bytes());
    out.extend_from_slice(&1000i32.to_le_bytes());
    out.extend_from_slice(&5i32.to_le_bytes());
    for v in [x0, y0, x1, y1, 0.0, 0.0, 0.0, 0.0] {
        out.extend_from_slice(&v.to_le_bytes());
    }
    out.extend_from_slice(&body);
    out
}
