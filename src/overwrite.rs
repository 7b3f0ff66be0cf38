//! What `granflow run` may overwrite: its own earlier outputs, nothing else by surprise.
//!
//! Before a run starts, each file it would write (the HDF5 file, its `_front.csv`,
//! with gauges its `_gauges.csv`, and for a raster run its `.xmf`) is checked: an
//! existing file is replaced only when it is what granflow writes there (an HDF5 file
//! whose root group carries the attribute `granflow_version`, read as HDF5, wherever
//! it lies in the file; a front CSV by its `t,x` header; a gauge CSV by its `t,eta_`
//! header; an XDMF file by its first lines) and is not the scenario itself. Anything
//! else needs `--force`. An output name ending in a path separator names a directory,
//! never a file, and is refused before anything is created.
//!
//! The output file itself may be a symbolic link (the run writes where it points); a
//! dangling link at a companion file's name is refused: writing through it would
//! create a file elsewhere, or fail after the run began. `<file>.reserve` (the room the HDF5 writer holds, [`crate::output::hdf5::space`])
//! is removed before the run only when it is a regular file of zeros, left by an
//! earlier run; anything else there needs `--force` (which removes the name, never
//! what a link points to).

use std::io::Read;
use std::path::Path;

use crate::output::xdmf::{xdmf_path, XDMF_HEAD};
use crate::output::{front_csv_path, gauge_csv_path};

/// The 8-byte signature at the start of an HDF5 file (granflow writes the superblock at
/// offset 0).
const HDF5_SIGNATURE: &[u8; 8] = b"\x89HDF\r\n\x1a\n";

/// The root attribute granflow writes at the start of every run
/// (docs/output-format.md): its presence tells granflow's files from other HDF5 files.
const GRANFLOW_MARK: &str = "granflow_version";

/// The largest `<file>.reserve` read to see that it holds only zeros: the reserve and
/// a claim in flight when its run was killed.
const RESERVE_READ_LIMIT: u64 = 256 << 20;

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
    let csv = front_csv_path(h5);
    let gauge_csv = gauge_csv_path(h5);
    let xmf = xdmf_path(h5);
    for (companion, what) in [
        (csv.as_path(), "front CSV"),
        (gauge_csv.as_path(), "gauge CSV"),
        (xmf.as_path(), "XDMF file"),
    ] {
        if dangling(companion) {
            return Err(format!(
                "the {what} '{}' is a symbolic link to a file that does not exist; refusing to create a file through it (remove the link or choose another --output)",
                companion.display()
            ));
        }
    }
    if force {
        return Ok(());
    }
    let reserve = crate::output::hdf5::space::reserve_path(h5);
    if std::fs::symlink_metadata(&reserve).is_ok() && !zeros_only(&reserve) {
        return Err(format!(
            "'{}' exists and is not the room granflow reserves there (a regular file of zeros); refusing to remove it (remove it yourself, or --force)",
            reserve.display()
        ));
    }
    let gauge_csv = gauge_csv_path(h5);
    let mut targets = vec![(h5, "HDF5 output"), (csv.as_path(), "front CSV")];
    if gauges {
        targets.push((gauge_csv.as_path(), "gauge CSV"));
    }
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

/// Whether the HDF5 file's root group carries [`GRANFLOW_MARK`] (read as HDF5: a copy
/// of the name in another object, or in raw bytes, does not count).
fn holds_mark(path: &Path) -> bool {
    // A damaged file must give "not ours", never a panic of the reader.
    std::panic::catch_unwind(|| {
        rust_hdf5::H5File::options()
            .no_locking()
            .open(path)
            .is_ok_and(|f| f.root_group().attr_string(GRANFLOW_MARK).is_ok())
    })
    .unwrap_or(false)
}

/// Whether `path` is a symbolic link whose target does not exist.
fn dangling(path: &Path) -> bool {
    std::fs::symlink_metadata(path).is_ok_and(|m| m.file_type().is_symlink()) && !path.exists()
}

/// Whether `path` is a regular file (not a link) holding only zero bytes.
fn zeros_only(path: &Path) -> bool {
    let Ok(meta) = std::fs::symlink_metadata(path) else {
        return false;
    };
    if !meta.file_type().is_file() || meta.len() > RESERVE_READ_LIMIT {
        return false;
    }
    let Ok(mut file) = std::fs::File::open(path) else {
        return false;
    };
    let mut buf = vec![0u8; 1 << 16];
    loop {
        match file.read(&mut buf) {
            Ok(0) => return true,
            Ok(n) if buf[..n].iter().all(|&b| b == 0) => {}
            _ => return false,
        }
    }
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
