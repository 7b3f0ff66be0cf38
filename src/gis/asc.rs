//! ESRI ASCII grid (`.asc`, "AAIGrid"), with its optional `.prj`.
//!
//! The header is key/value lines, keys in any case, separated by any whitespace:
//!
//! ```text
//! ncols         4
//! nrows         3
//! xllcorner     1000.0      (or xllcenter: x of the centre of the lower-left cell)
//! yllcorner     2000.0      (or yllcenter)
//! cellsize      5.0         (or dx and dy, which must be equal)
//! NODATA_value  -9999       (optional)
//! ```
//!
//! then `ncols × nrows` numbers, the top row first, in any line layout. A `.prj`
//! beside the file (same stem) holds WKT text, carried in [`Crs::wkt`](super::Crs).
//!
//! The writer writes `xllcorner`/`yllcorner`, `cellsize`, `NODATA_value` when the raster
//! has a finite nodata value (NaN cells are written as that value), every number in
//! its shortest round-trip form (reading the file back gives the same `f64`s), and
//! the `.prj` when the CRS has WKT text or an EPSG code whose WKT granflow makes
//! (`crs::wkt_of_epsg`: WGS 84 and its UTM zones, ETRS89's UTM zones and LAEA, NAD83's
//! UTM zones, the Swiss, Austrian, German, French, Italian and Dutch national grids).
//! Any other CRS known only by its code gets no `.prj` (that needs the EPSG registry;
//! `granflow export` warns). The written `yllcorner` is the shortest decimal that
//! maps back to the same top edge, so a file read and written again is unchanged.

use std::io::Write;
use std::path::{Path, PathBuf};

use super::{io_err, nearly_equal, Crs, GisError, Raster, Result};

/// The `.prj` beside an `.asc` (same path, extension `prj`).
pub fn prj_path(path: &Path) -> PathBuf {
    path.with_extension("prj")
}

/// Reads an ESRI ASCII grid and the `.prj` beside it, if any.
pub fn read(path: &Path) -> Result<Raster> {
    super::regular_if_present(path)?;
    let bytes = std::fs::read(path).map_err(io_err(path))?;
    let mut raster = parse(&bytes, path)?;
    if let Some(text) = super::read_sidecar(&prj_path(path))? {
        raster.crs = Crs::from_wkt(&text);
    }
    Ok(raster)
}

#[derive(Default)]
struct Header {
    ncols: Option<usize>,
    nrows: Option<usize>,
    xll: Option<(f64, bool)>,
    yll: Option<(f64, bool)>,
    cellsize: Option<f64>,
    dx: Option<f64>,
    dy: Option<f64>,
    nodata: Option<f64>,
}

/// Parses the text of an ESRI ASCII grid; `path` only names the file in errors.
pub fn parse(bytes: &[u8], path: &Path) -> Result<Raster> {
    if bytes.is_empty() {
        return Err(GisError::EmptyFile {
            path: path.to_path_buf(),
        });
    }
    let text = std::str::from_utf8(bytes).map_err(|e| GisError::BadHeader {
        path: path.to_path_buf(),
        line: 1 + bytes[..e.valid_up_to()]
            .iter()
            .filter(|&&b| b == b'\n')
            .count(),
        reason: "not text (invalid UTF-8)".into(),
    })?;
    // A byte-order mark (some Windows editors write one) is not part of the first key.
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let bad = |line: usize, reason: String| GisError::BadHeader {
        path: path.to_path_buf(),
        line,
        reason,
    };
    let mut h = Header::default();
    let mut lines = text.lines().enumerate().peekable();
    // Header: lines whose first token is a word (not a number such as `nan`).
    while let Some(&(i, line)) = lines.peek() {
        let lineno = i + 1;
        let mut tokens = line.split_ascii_whitespace();
        let Some(key) = tokens.next() else {
            lines.next();
            continue;
        };
        if !key.starts_with(|c: char| c.is_ascii_alphabetic()) || key.parse::<f64>().is_ok() {
            break;
        }
        lines.next();
        let value = tokens
            .next()
            .ok_or_else(|| bad(lineno, format!("`{key}` has no value")))?;
        if let Some(extra) = tokens.next() {
            return Err(bad(lineno, format!("`{key}` has a second value `{extra}`")));
        }
        let number = || -> Result<f64> {
            value
                .parse::<f64>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or_else(|| {
                    bad(
                        lineno,
                        format!("`{key}` = `{value}` is not a finite number"),
                    )
                })
        };
        let count = || -> Result<usize> {
            value
                .parse::<usize>()
                .ok()
                .filter(|&n| n > 0)
                .ok_or_else(|| {
                    bad(
                        lineno,
                        format!("`{key}` = `{value}` is not a positive integer"),
                    )
                })
        };
        let lower = key.to_ascii_lowercase();
        let duplicate = match lower.as_str() {
            "ncols" => h.ncols.replace(count()?).is_some(),
            "nrows" => h.nrows.replace(count()?).is_some(),
            "xllcorner" => h.xll.replace((number()?, false)).is_some(),
            "xllcenter" | "xllcentre" => h.xll.replace((number()?, true)).is_some(),
            "yllcorner" => h.yll.replace((number()?, false)).is_some(),
            "yllcenter" | "yllcentre" => h.yll.replace((number()?, true)).is_some(),
            "cellsize" => h.cellsize.replace(number()?).is_some(),
            "dx" => h.dx.replace(number()?).is_some(),
            "dy" => h.dy.replace(number()?).is_some(),
            "nodata_value" | "nodata" => {
                let v = value
                    .parse::<f64>()
                    .map_err(|_| bad(lineno, format!("`{key}` = `{value}` is not a number")))?;
                h.nodata.replace(v).is_some()
            }
            _ => return Err(bad(lineno, format!("unknown key `{key}`"))),
        };
        if duplicate {
            return Err(bad(
                lineno,
                format!("`{key}` given twice (or both corner and centre forms)"),
            ));
        }
    }
    let missing = |key| GisError::MissingKey {
        path: path.to_path_buf(),
        key,
    };
    let nx = h.ncols.ok_or_else(|| missing("ncols"))?;
    let ny = h.nrows.ok_or_else(|| missing("nrows"))?;
    let (xll, x_centre) = h.xll.ok_or_else(|| missing("xllcorner"))?;
    let (yll, y_centre) = h.yll.ok_or_else(|| missing("yllcorner"))?;
    let d = match (h.cellsize, h.dx, h.dy) {
        (Some(d), None, None) => d,
        (None, Some(dx), Some(dy)) => {
            if dx > 0.0 && dy > 0.0 && !nearly_equal(dx, dy) {
                return Err(GisError::NonSquareCells {
                    path: path.to_path_buf(),
                    dx,
                    dy,
                });
            }
            dx.min(dy)
        }
        (None, None, None) => return Err(missing("cellsize")),
        _ => {
            return Err(bad(
                1,
                "give either `cellsize` or both `dx` and `dy`".to_string(),
            ))
        }
    };
    if d <= 0.0 {
        return Err(GisError::NonPositiveCellSize {
            path: path.to_path_buf(),
            value: d,
        });
    }
    let expected = nx
        .checked_mul(ny)
        .ok_or_else(|| bad(1, format!("{nx} x {ny} cells is too many")))?;
    // The values: the text from the first line after the header (its 0-based line
    // index is `first`), parsed in chunks of whole lines in parallel.
    let (first, data) = match lines.peek() {
        Some(&(i, line)) => (i, &text[line.as_ptr() as usize - text.as_ptr() as usize..]),
        None => (0, ""),
    };
    let values = parse_values(data, first, expected, path, CHUNK_BYTES)?;
    let x_left = if x_centre { xll - 0.5 * d } else { xll };
    let y_bottom = if y_centre { yll - 0.5 * d } else { yll };
    Ok(Raster {
        nx,
        ny,
        x_left,
        y_top: y_bottom + ny as f64 * d,
        cell_size: d,
        values,
        nodata: h.nodata,
        crs: Crs::default(),
    })
}

/// Bytes of values per chunk parsed on one thread (whole lines; a line longer than
/// this is one chunk).
const CHUNK_BYTES: usize = 1 << 20;

/// One chunk's values: those parsed, and the byte offset (in the chunk) and text of
/// the first token that is not a number.
struct Chunk<'a> {
    values: Vec<f64>,
    bad: Option<(usize, &'a str)>,
}

/// The tokens of `text` with their byte offsets.
fn tokens(text: &str) -> impl Iterator<Item = (usize, &str)> {
    let base = text.as_ptr() as usize;
    text.split_ascii_whitespace()
        .map(move |t| (t.as_ptr() as usize - base, t))
}

/// Parses the `expected` values of `data` (whose first line is line `first + 1` of
/// the file): chunks of about `chunk_bytes` whole lines are parsed in parallel (each
/// number by `str::parse::<f64>`, so the values are exactly those of a serial read),
/// then checked in file order, so that the error is the one a serial read meets
/// first: a value beyond `expected` (too many), a token that is not a number, or too
/// few values.
fn parse_values(
    data: &str,
    first: usize,
    expected: usize,
    path: &Path,
    chunk_bytes: usize,
) -> Result<Vec<f64>> {
    use rayon::prelude::*;
    let mut bounds = vec![0];
    let mut start = 0;
    while start < data.len() {
        let mut end = (start + chunk_bytes).min(data.len());
        end = match data.as_bytes()[end..].iter().position(|&b| b == b'\n') {
            Some(k) => end + k + 1,
            None => data.len(),
        };
        bounds.push(end);
        start = end;
    }
    let chunks: Vec<Chunk> = bounds
        .par_windows(2)
        .map(|w| {
            let text = &data[w[0]..w[1]];
            let mut values = Vec::with_capacity(text.len() / 6 + 1);
            for (offset, token) in tokens(text) {
                match token.parse::<f64>() {
                    Ok(v) => values.push(v),
                    Err(_) => {
                        return Chunk {
                            values,
                            bad: Some((offset, token)),
                        }
                    }
                }
            }
            Chunk { values, bad: None }
        })
        .collect();
    let line_at = |chunk: usize, offset: usize| {
        let upto = bounds[chunk] + offset;
        first
            + 1
            + data.as_bytes()[..upto]
                .iter()
                .filter(|&&b| b == b'\n')
                .count()
    };
    let too_many = |chunk: usize, index: usize| {
        let (offset, _) = tokens(&data[bounds[chunk]..bounds[chunk + 1]])
            .nth(index)
            .expect("the chunk holds that token");
        GisError::TooManyValues {
            path: path.to_path_buf(),
            expected,
            found: expected + 1,
            line: line_at(chunk, offset),
        }
    };
    let mut count = 0;
    for (c, chunk) in chunks.iter().enumerate() {
        let parsed = chunk.values.len();
        if count + parsed > expected || (chunk.bad.is_some() && count + parsed == expected) {
            return Err(too_many(c, expected - count));
        }
        if let Some((offset, token)) = chunk.bad {
            return Err(GisError::NonNumeric {
                path: path.to_path_buf(),
                line: line_at(c, offset),
                token: token.chars().take(40).collect(),
            });
        }
        count += parsed;
    }
    if count < expected {
        return Err(GisError::TooFewValues {
            path: path.to_path_buf(),
            expected,
            found: count,
        });
    }
    let mut values = Vec::with_capacity(expected);
    for chunk in chunks {
        values.extend_from_slice(&chunk.values);
    }
    Ok(values)
}

/// The `yllcorner` to write for `raster`: among the `f64`s `c` next to
/// `y_top − ny·d` with `c + ny·d == y_top` (what [`parse`] computes), the one with the
/// shortest decimal form, so that a value read from a file is written back as it was.
fn yll_corner(raster: &Raster) -> f64 {
    let span = raster.ny as f64 * raster.cell_size;
    let guess = raster.y_top - span;
    let mut best = guess;
    let mut best_len = usize::MAX;
    let mut c = guess;
    for _ in 0..8 {
        c = c.next_down();
    }
    for _ in 0..17 {
        if c + span == raster.y_top {
            let len = number(c).len();
            if len < best_len || (len == best_len && (c - guess).abs() < (best - guess).abs()) {
                best = c;
                best_len = len;
            }
        }
        c = c.next_up();
    }
    best
}

/// Appends `v` in its shortest round-trip form (`zmij`, without a trailing `.0`):
/// `1500.25`, `-9999`, `1e-300`, `1e+16`.
fn push_number(out: &mut String, v: f64) {
    let mut buffer = zmij::Buffer::new();
    let s = buffer.format(v);
    out.push_str(s.strip_suffix(".0").unwrap_or(s));
}

fn number(v: f64) -> String {
    let mut s = String::new();
    push_number(&mut s, v);
    s
}

/// Writes `raster` as an ESRI ASCII grid, and its WKT (if any, or one made from its
/// EPSG code) as the `.prj` beside it; a stale `.prj` there is removed when the raster
/// has none.
pub fn write(raster: &Raster, path: &Path) -> Result<()> {
    write_grid(raster, path)?;
    let prj = prj_path(path);
    match raster.crs.wkt_text() {
        Some(wkt) => std::fs::write(&prj, format!("{wkt}\n")).map_err(io_err(&prj))?,
        None => match std::fs::remove_file(&prj) {
            Err(e) if e.kind() != std::io::ErrorKind::NotFound => return Err(io_err(&prj)(e)),
            _ => {}
        },
    }
    Ok(())
}

/// The header lines [`write_grid`] writes for `raster` (`ncols` to `cellsize`, and
/// `NODATA_value` when the raster has a finite one). `granflow export` tells its own
/// grids by this layout (`crate::results::publish`).
fn header(raster: &Raster) -> String {
    let mut header = format!(
        "ncols         {}\nnrows         {}\nxllcorner     {}\nyllcorner     {}\ncellsize      {}\n",
        raster.nx,
        raster.ny,
        number(raster.x_left),
        number(yll_corner(raster)),
        number(raster.cell_size)
    );
    if let Some(nd) = raster.nodata.filter(|v| v.is_finite()) {
        header.push_str(&format!("NODATA_value  {}\n", number(nd)));
    }
    header
}

/// Writes `raster` as an ESRI ASCII grid, without the `.prj`.
pub fn write_grid(raster: &Raster, path: &Path) -> Result<()> {
    raster.check().map_err(|reason| GisError::BadGrid {
        path: path.to_path_buf(),
        reason,
    })?;
    let nodata = raster.nodata.filter(|v| v.is_finite());
    if nodata.is_none() && raster.values.iter().any(|v| v.is_nan()) {
        return Err(GisError::NanWithoutNodata {
            path: path.to_path_buf(),
        });
    }
    let file = std::fs::File::create(path).map_err(io_err(path))?;
    let mut out = std::io::BufWriter::with_capacity(1 << 20, file);
    let header = header(raster);
    let mut line = String::with_capacity(raster.nx * 12);
    let result = (|| -> std::io::Result<()> {
        out.write_all(header.as_bytes())?;
        for row in raster.values.chunks(raster.nx) {
            line.clear();
            for (i, &v) in row.iter().enumerate() {
                if i > 0 {
                    line.push(' ');
                }
                let v = if v.is_nan() { nodata.unwrap_or(v) } else { v };
                push_number(&mut line, v);
            }
            line.push('\n');
            out.write_all(line.as_bytes())?;
        }
        out.flush()
    })();
    result.map_err(io_err(path))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The values and errors of a chunked read are those of a read in one chunk,
    /// whatever the chunk size (chunks of whole lines).
    #[test]
    fn chunked_values_are_those_of_one_chunk() {
        let path = Path::new("t.asc");
        let texts = [
            "1 2.5\n3e2 -4\n\n5 6\n",
            "1 2\n3 4 5 6\n7\n",
            "1 2\n3\nx4 5 6\n",
            "1 2\n3 4 5 6 x\n",
            "1 2\n3 4 5\n",
            "1\t2\r\n3 nan\r\n5 6",
        ];
        let show = |r: Result<Vec<f64>>| match r {
            Ok(v) => format!("{v:?}"),
            Err(e) => e.to_string(),
        };
        for text in texts {
            let one = show(parse_values(text, 6, 6, path, usize::MAX / 2));
            for chunk in 1..=12 {
                assert_eq!(show(parse_values(text, 6, 6, path, chunk)), one, "{text:?}");
            }
        }
        let e = show(parse_values("1 2\n3 4 5 6\n7\n", 6, 6, path, 1));
        assert!(e.contains("line 9 holds value 7"), "{e}");
        let e = show(parse_values("1 2\n3\nx4 5 6\n", 6, 6, path, 1));
        assert!(e.contains("line 9") && e.contains("`x4`"), "{e}");
    }

    #[test]
    fn yll_corner_recovers_the_decimal_that_was_read() {
        for (yll, ny, d) in [(100.1, 7, 0.3), (5_144_123.37, 1001, 2.5), (-33.3, 3, 0.1)] {
            let text = format!(
                "ncols 1\nnrows {ny}\nxllcorner 0\nyllcorner {yll}\ncellsize {d}\n{}",
                "1\n".repeat(ny)
            );
            let r = parse(text.as_bytes(), Path::new("t.asc")).unwrap();
            assert_eq!(yll_corner(&r), yll);
        }
    }
}
