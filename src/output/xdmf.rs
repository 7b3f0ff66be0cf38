//! The XDMF file beside a raster run's HDF5 file (`run.h5` → `run.xmf`), so that
//! ParaView (or VisIt) opens the run as it is: a light XML description of the grid
//! that points into the HDF5 datasets, which stay the only copy of the data.
//!
//! Layout (XDMF 2): one temporal collection with a uniform grid per snapshot, each a
//! `2DCoRectMesh` of (ny + 1) × (nx + 1) nodes (origin = the lower-left corner of the
//! raster, spacing Δy, Δx) whose cell-centred attributes are the bed `/grid/b` and the
//! k-th frame of every `/snapshots/<field>` (a hyperslab 1 × ny × nx of the
//! (nt, ny, nx) dataset); and, once the run is over, a grid `maps` with `/maps/*`.
//! The file is rewritten at every snapshot (through a temporary file and a rename, so
//! a reader never sees half of it) and lists exactly the frames on disk.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use super::OutputError;

/// How every XDMF file granflow writes begins (`overwrite` recognises its own files
/// by it).
pub const XDMF_HEAD: &str = "<?xml version=\"1.0\" ?>\n<!-- written by granflow -->\n";

/// The datasets of `/maps` (written by raster runs at their end).
pub const MAP_NAMES: [&str; 5] = super::maps::MAP_DATASETS;

/// What the XDMF file describes.
#[derive(Debug, Clone, Copy)]
pub struct XdmfRun<'a> {
    /// File name of the HDF5 file, in the same directory.
    pub h5_name: &'a str,
    pub nx: usize,
    pub ny: usize,
    /// Lower-left corner (x, y) of the raster (m).
    pub origin: (f64, f64),
    /// (Δx, Δy) (m).
    pub spacing: (f64, f64),
    /// Time of each snapshot on disk.
    pub times: &'a [f64],
    /// The `/snapshots` fields of shape (nt, ny, nx).
    pub fields: &'a [&'a str],
    /// The `/maps` datasets, empty before the end of the run.
    pub maps: &'a [&'a str],
}

/// `run.xmf` for `run.h5`.
pub fn xdmf_path(h5: &Path) -> PathBuf {
    super::companion_path(h5, ".xmf")
}

/// Writes the description of `run` to `path` (atomically: temporary file, rename).
pub fn write(path: &Path, run: &XdmfRun) -> Result<(), OutputError> {
    let text = render(run);
    let tmp = path.with_extension("xmf.tmp");
    let io = |e: std::io::Error| OutputError::Io {
        path: path.display().to_string(),
        message: e.to_string(),
    };
    std::fs::write(&tmp, text).map_err(io)?;
    std::fs::rename(&tmp, path).map_err(io)
}

/// Escapes the characters XML reserves in attribute values and text.
fn escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// The XDMF text of `run`.
pub fn render(run: &XdmfRun) -> String {
    let (nx, ny, nt) = (run.nx, run.ny, run.times.len());
    let h5 = escape(run.h5_name);
    let mut out = String::new();
    let w = &mut out;
    w.push_str(XDMF_HEAD);
    let _ = writeln!(w, "<!DOCTYPE Xdmf SYSTEM \"Xdmf.dtd\" []>");
    let _ = writeln!(w, "<Xdmf Version=\"2.0\">");
    let _ = writeln!(w, " <Domain>");
    let geometry = |w: &mut String, indent: &str| {
        let _ = writeln!(
            w,
            "{indent}<Topology TopologyType=\"2DCoRectMesh\" Dimensions=\"{} {}\"/>",
            ny + 1,
            nx + 1
        );
        let _ = writeln!(w, "{indent}<Geometry GeometryType=\"ORIGIN_DXDY\">");
        let _ = writeln!(
            w,
            "{indent} <DataItem Format=\"XML\" NumberType=\"Float\" Precision=\"8\" Dimensions=\"2\">{:e} {:e}</DataItem>",
            run.origin.1, run.origin.0
        );
        let _ = writeln!(
            w,
            "{indent} <DataItem Format=\"XML\" NumberType=\"Float\" Precision=\"8\" Dimensions=\"2\">{:e} {:e}</DataItem>",
            run.spacing.1, run.spacing.0
        );
        let _ = writeln!(w, "{indent}</Geometry>");
    };
    let plain = |w: &mut String, indent: &str, name: &str, path: &str| {
        let _ = writeln!(
            w,
            "{indent}<Attribute Name=\"{name}\" AttributeType=\"Scalar\" Center=\"Cell\">"
        );
        let _ = writeln!(
            w,
            "{indent} <DataItem Format=\"HDF\" NumberType=\"Float\" Precision=\"8\" Dimensions=\"{ny} {nx}\">{h5}:{path}</DataItem>"
        );
        let _ = writeln!(w, "{indent}</Attribute>");
    };
    let _ = writeln!(
        w,
        "  <Grid Name=\"snapshots\" GridType=\"Collection\" CollectionType=\"Temporal\">"
    );
    for (k, t) in run.times.iter().enumerate() {
        let _ = writeln!(w, "   <Grid Name=\"t{k}\" GridType=\"Uniform\">");
        let _ = writeln!(w, "    <Time Value=\"{t:e}\"/>");
        geometry(w, "    ");
        plain(w, "    ", "b", "/grid/b");
        for field in run.fields {
            let field = escape(field);
            let _ = writeln!(
                w,
                "    <Attribute Name=\"{field}\" AttributeType=\"Scalar\" Center=\"Cell\">"
            );
            let _ = writeln!(
                w,
                "     <DataItem ItemType=\"HyperSlab\" Dimensions=\"1 {ny} {nx}\" Type=\"HyperSlab\">"
            );
            let _ = writeln!(
                w,
                "      <DataItem Format=\"XML\" NumberType=\"UInt\" Dimensions=\"3 3\">{k} 0 0 1 1 1 1 {ny} {nx}</DataItem>"
            );
            let _ = writeln!(
                w,
                "      <DataItem Format=\"HDF\" NumberType=\"Float\" Precision=\"8\" Dimensions=\"{nt} {ny} {nx}\">{h5}:/snapshots/{field}</DataItem>"
            );
            let _ = writeln!(w, "     </DataItem>");
            let _ = writeln!(w, "    </Attribute>");
        }
        let _ = writeln!(w, "   </Grid>");
    }
    let _ = writeln!(w, "  </Grid>");
    if !run.maps.is_empty() {
        let _ = writeln!(w, "  <Grid Name=\"maps\" GridType=\"Uniform\">");
        geometry(w, "   ");
        plain(w, "   ", "b", "/grid/b");
        for name in run.maps {
            let name = escape(name);
            plain(w, "   ", &name, &format!("/maps/{name}"));
        }
        let _ = writeln!(w, "  </Grid>");
    }
    let _ = writeln!(w, " </Domain>");
    let _ = writeln!(w, "</Xdmf>");
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frames_and_maps_point_into_the_hdf5_file() {
        let run = XdmfRun {
            h5_name: "a&b.h5",
            nx: 3,
            ny: 2,
            origin: (0.0, -1.0),
            spacing: (0.5, 1.0),
            times: &[0.0, 0.5],
            fields: &["h", "u", "v"],
            maps: &MAP_NAMES,
        };
        let text = render(&run);
        assert_eq!(text.matches("<Grid Name=\"t").count(), 2);
        assert!(text.contains("Dimensions=\"3 4\""), "{text}");
        assert!(text.contains(">1 0 0 1 1 1 1 2 3<"), "{text}");
        assert!(text.contains("a&amp;b.h5:/snapshots/v"), "{text}");
        assert!(text.contains("a&amp;b.h5:/maps/arrival_time"), "{text}");
        assert!(!text.contains("a&b"), "{text}");
    }
}
