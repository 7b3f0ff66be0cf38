//! What `granflow run` may overwrite: its own earlier outputs, nothing else by surprise.
//!
//! `--output x.toml` next to the scenario `x.toml` used to replace the scenario with
//! HDF5. Before a run starts, each file it would write (the HDF5 file and its
//! `_front.csv`) is checked: an existing file is replaced only when it is what granflow
//! writes there (an HDF5 file, by its signature; a front CSV, by its `t,x` header) and
//! is not the scenario itself. Anything else needs `--force`.

use std::io::Read;
use std::path::Path;

use crate::output::front_csv_path;

/// The 8-byte signature at the start of an HDF5 file (granflow writes the superblock at
/// offset 0).
const HDF5_SIGNATURE: &[u8; 8] = b"\x89HDF\r\n\x1a\n";

/// Checks that writing `h5` (and its front CSV) for the scenario file `scenario` would
/// not replace anything it should not. Returns the reason otherwise.
pub fn check_outputs(scenario: &Path, h5: &Path, force: bool) -> Result<(), String> {
    if force {
        return Ok(());
    }
    let csv = front_csv_path(h5);
    for (target, what) in [(h5, "HDF5 output"), (csv.as_path(), "front CSV")] {
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
        let ours = if target == h5 {
            starts_with(target, HDF5_SIGNATURE)
        } else {
            starts_with(target, b"t,x\n")
        };
        if !ours {
            let kind = if target == h5 {
                "not an HDF5 file"
            } else {
                "not a granflow front CSV"
            };
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
