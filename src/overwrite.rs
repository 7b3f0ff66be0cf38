//! What `granflow run` may overwrite: its own earlier outputs, nothing else by surprise.
//!
//! Before a run starts, each file it would write (the HDF5 file, its `_front.csv`,
//! with gauges its `_gauges.csv`, and for a raster run its `.xmf`) is checked: an
//! existing file is replaced only when it is what granflow writes there (an HDF5 file
//! with granflow's root attributes; a front CSV by its `t,x` header; a gauge CSV by its
//! `t,eta_` header; an XDMF file by its first lines) and is not the scenario itself. Anything else needs `--force`. An output name ending in a path separator
//! names a directory, never a file, and is refused before anything is created.

use std::io::Read;
use std::path::Path;

use crate::output::xdmf::{xdmf_path, XDMF_HEAD};
use crate::output::{front_csv_path, gauge_csv_path};

/// The 8-byte signature at the start of an HDF5 file (granflow writes the superblock at
/// offset 0).
const HDF5_SIGNATURE: &[u8; 8] = b"\x89HDF\r\n\x1a\n";

/// The name of a root attribute granflow writes at the start of every run
/// (docs/output-format.md): its presence tells granflow's files from other HDF5 files.
const GRANFLOW_MARK: &[u8] = b"granflow_version";

/// How far into an HDF5 file (from its start, and from its end) the mark is looked for:
/// the root attributes are written when the run begins, and again when it ends.
const MARK_WINDOW: u64 = 4 << 20;

/// Checks that writing `h5` (and its front CSV, its gauge CSV when `gauges`, its XDMF
/// file when `xdmf`) for the scenario file `scenario` would not replace anything it
/// should not. Returns the reason otherwise.
pub fn check_outputs(
    scenario: &Path,
    h5: &Path,
    gauges: bool,
    xdmf: bool,
    force: bool,
) -> Result<(), String> {
    let name = h5.as_os_str().to_string_lossy();
    if name.ends_with('/') || name.ends_with(std::path::MAIN_SEPARATOR) {
        return Err(format!(
            "the HDF5 output '{}' names a directory; give a file name, e.g. '{}'",
            h5.display(),
            h5.join("run.h5").display()
        ));
    }
    if force {
        return Ok(());
    }
    let csv = front_csv_path(h5);
    let gauge_csv = gauge_csv_path(h5);
    let mut targets = vec![(h5, "HDF5 output"), (csv.as_path(), "front CSV")];
    if gauges {
        targets.push((gauge_csv.as_path(), "gauge CSV"));
    }
    let xmf = xdmf_path(h5);
    if xdmf {
        targets.push((xmf.as_path(), "XDMF file"));
    }
    for (target, what) in targets {
        if !target.exists() {
            continue;
        }
        if same_file(target, scenario) {
            return Err(format!(
                "the {what} '{}' is the scenario file itself; refusing to overwrite it (choose another --output, or --force)",
                target.display()
            ));
        }
        if target.is_dir() {
            return Err(format!("the {what} '{}' is a directory", target.display()));
        }
        let (ours, kind) = match what {
            "HDF5 output" if !starts_with(target, HDF5_SIGNATURE) => (false, "not an HDF5 file"),
            "HDF5 output" => (
                holds_mark(target),
                "an HDF5 file that granflow did not write",
            ),
            "front CSV" => (starts_with(target, b"t,x\n"), "not a granflow front CSV"),
            "XDMF file" => (
                starts_with(target, XDMF_HEAD.as_bytes()),
                "not an XDMF file granflow wrote",
            ),
            _ => (starts_with(target, b"t,eta_"), "not a granflow gauge CSV"),
        };
        if !ours {
            return Err(format!(
                "'{}' exists and is {kind}; refusing to overwrite it with the {what} (choose another --output, or --force to replace it)",
                target.display()
            ));
        }
    }
    Ok(())
}

fn starts_with(path: &Path, head: &[u8]) -> bool {
    let mut buf = vec![0u8; head.len()];
    std::fs::File::open(path)
        .and_then(|mut f| f.read_exact(&mut buf))
        .is_ok()
        && buf == head
}

/// Whether the file holds [`GRANFLOW_MARK`] in its first or last [`MARK_WINDOW`] bytes.
fn holds_mark(path: &Path) -> bool {
    use std::io::{Seek, SeekFrom};
    let Ok(mut file) = std::fs::File::open(path) else {
        return false;
    };
    let len = file.metadata().map_or(0, |m| m.len());
    let mut window = |start: u64| -> bool {
        let mut buf = Vec::new();
        file.seek(SeekFrom::Start(start)).is_ok()
            && (&mut file).take(MARK_WINDOW).read_to_end(&mut buf).is_ok()
            && buf.windows(GRANFLOW_MARK.len()).any(|w| w == GRANFLOW_MARK)
    };
    window(0) || (len > MARK_WINDOW && window(len - MARK_WINDOW))
}

/// Whether `a` and `b` name the same existing file (whatever their spelling).
fn same_file(a: &Path, b: &Path) -> bool {
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        if let (Ok(x), Ok(y)) = (std::fs::metadata(a), std::fs::metadata(b)) {
            return x.dev() == y.dev() && x.ino() == y.ino();
        }
    }
    match (a.canonicalize(), b.canonicalize()) {
        (Ok(x), Ok(y)) => x == y,
        _ => false,
    }
}
