//! How `granflow export` and `granflow maps` put their files in place: nothing a user
//! did not ask to replace is touched, and a write that fails (a full disk) leaves the
//! previous files as they were.
//!
//! Every file to write is first checked: an existing file is replaced only when it is
//! what granflow writes there ([`Owner`]), or with `--force`. Then each file is written
//! to a temporary name beside it (`.<name>.granflow-<pid>.tmp`, created exclusively,
//! so never through a planted link) and synced; only when all of them are written are
//! they renamed over the old ones, each rename atomic. A failure before that removes
//! the temporary files and leaves every old file whole; a failure among the renames
//! (rare: they need no room) leaves each file whole, old or new.
//!
//! An ESRI ASCII grid's `.prj` is a file of its own here: written beside a grid with a
//! CRS, and, beside a grid without one, removed only when it belongs to an earlier
//! export (the grid it stands beside is granflow's): a user's `.prj` is refused, since
//! it would give the new grid a CRS the run does not have.

use std::io::Read;
use std::path::{Path, PathBuf};

use super::ResultsError;

/// How a file granflow writes can be told from a user's file of the same name.
#[derive(Debug, Clone)]
pub enum Owner {
    /// A GeoTIFF whose `Software` tag names granflow.
    Geotiff,
    /// An ESRI ASCII grid whose header has the layout granflow writes (its keys padded
    /// to 14 characters; other programs pad them otherwise), on any grid.
    Asc,
    /// A `.prj` holding exactly this text, or standing beside a grid of granflow's
    /// (the path of that grid and how to tell it).
    Prj {
        text: Option<String>,
        grid: PathBuf,
        grid_owner: Box<Owner>,
    },
    /// A classic NetCDF file whose header names granflow (its `source` attribute).
    NetCdf,
    /// A text file starting with this line.
    TextHead(&'static str),
}

impl Owner {
    /// Whether the existing regular file `path` is one granflow wrote.
    pub fn owns(&self, path: &Path) -> bool {
        match self {
            Owner::Geotiff => crate::gis::geotiff::written_by_granflow(path),
            Owner::Asc => {
                let mut head = Vec::new();
                let read = std::fs::File::open(path)
                    .and_then(|f| f.take(1024).read_to_end(&mut head))
                    .is_ok();
                let text = String::from_utf8_lossy(&head);
                read && text
                    .lines()
                    .zip(ASC_KEYS)
                    .filter(|(line, key)| line.starts_with(key))
                    .count()
                    == ASC_KEYS.len()
            }
            Owner::Prj {
                text,
                grid,
                grid_owner,
            } => {
                let same = text.as_ref().is_some_and(|t| {
                    std::fs::read(path)
                        .is_ok_and(|b| b == t.as_bytes() || b == t.trim_end().as_bytes())
                });
                same || (regular(grid) && grid_owner.owns(grid))
            }
            Owner::NetCdf => {
                let mut head = Vec::new();
                std::fs::File::open(path)
                    .and_then(|f| f.take(1 << 16).read_to_end(&mut head))
                    .is_ok()
                    && head.starts_with(b"CDF")
                    && head.windows(9).any(|w| w == b"granflow ")
            }
            Owner::TextHead(line) => head_is(path, line.as_bytes()),
        }
    }
}

/// The first lines of an ESRI ASCII grid as granflow writes them, up to their values.
const ASC_KEYS: [&str; 6] = [
    "ncols         ",
    "nrows         ",
    "xllcorner     ",
    "yllcorner     ",
    "cellsize      ",
    "NODATA_value  ",
];

fn head_is(path: &Path, head: &[u8]) -> bool {
    let mut buf = Vec::new();
    std::fs::File::open(path)
        .and_then(|f| f.take(head.len() as u64).read_to_end(&mut buf))
        .is_ok()
        && buf == head
}

/// Whether `path` is a regular file (a symbolic link to one counts).
fn regular(path: &Path) -> bool {
    std::fs::metadata(path).is_ok_and(|m| m.is_file())
}

/// What is to become of one file.
#[derive(Debug)]
enum Plan {
    /// Written by the closure to the temporary name, then renamed.
    Write(PathBuf),
    /// Removed (a stale `.prj` of an earlier export).
    Remove,
}

/// The files of one `export` or `maps` command, checked, written aside, then put in
/// place (module docs).
#[derive(Debug)]
pub struct Publish {
    force: bool,
    /// (final path, plan), in the order given.
    files: Vec<(PathBuf, Plan)>,
}

impl Publish {
    pub fn new(force: bool) -> Publish {
        Publish {
            force,
            files: Vec::new(),
        }
    }

    /// Checks that `target` may be replaced: missing, or a regular file `owner` says
    /// granflow wrote, or anything but a directory with `--force`.
    pub fn check(&self, target: &Path, owner: &Owner) -> Result<(), ResultsError> {
        let Ok(meta) = std::fs::symlink_metadata(target) else {
            return Ok(());
        };
        if meta.is_dir() || target.is_dir() {
            return Err(ResultsError::input(format!(
                "{} is a directory; refusing to replace it",
                target.display()
            )));
        }
        if self.force || (regular(target) && owner.owns(target)) {
            return Ok(());
        }
        Err(ResultsError::input(format!(
            "{} exists and granflow did not write it; refusing to replace it (remove it, choose another --output, or pass --force)",
            target.display()
        )))
    }

    /// Checks that a stale `.prj` at `target` may be removed (as [`Publish::check`]) and
    /// plans its removal; nothing when there is none.
    pub fn remove(&mut self, target: &Path, owner: &Owner) -> Result<(), ResultsError> {
        if std::fs::symlink_metadata(target).is_err() {
            return Ok(());
        }
        self.check(target, owner).map_err(|_| {
            ResultsError::input(format!(
                "{} would give the grid beside it a CRS the run does not have, and granflow did not write it; refusing to remove it (remove it, choose another --output, or pass --force)",
                target.display()
            ))
        })?;
        self.files.push((target.to_path_buf(), Plan::Remove));
        Ok(())
    }

    /// Writes `target` aside with `write` (given the temporary path) after checking it
    /// may be replaced; the file takes its name at [`Publish::commit`].
    pub fn write(
        &mut self,
        target: &Path,
        owner: &Owner,
        write: impl FnOnce(&Path) -> Result<(), ResultsError>,
    ) -> Result<(), ResultsError> {
        self.check(target, owner)?;
        let tmp = temporary_name(target);
        let fail = |e: std::io::Error| {
            ResultsError::failure(format!("cannot write {}: {e}", tmp.display()))
        };
        // Created exclusively: a planted link at the temporary name is never followed.
        let _ = std::fs::remove_file(&tmp);
        std::fs::OpenOptions::new()
            .write(true)
            .create_new(true)
            .open(&tmp)
            .map_err(fail)?;
        self.files
            .push((target.to_path_buf(), Plan::Write(tmp.clone())));
        write(&tmp)?;
        // A disk that accepted the writes but cannot hold them says so here.
        std::fs::File::open(&tmp)
            .and_then(|f| f.sync_all())
            .map_err(fail)
    }

    /// Puts every written file in place and removes the planned ones; returns the
    /// files written.
    pub fn commit(mut self) -> Result<Vec<PathBuf>, ResultsError> {
        let mut written = Vec::new();
        for (target, plan) in std::mem::take(&mut self.files) {
            match plan {
                Plan::Write(tmp) => {
                    if let Err(e) = std::fs::rename(&tmp, &target) {
                        let _ = std::fs::remove_file(&tmp);
                        return Err(ResultsError::failure(format!(
                            "cannot put {} in place: {e}",
                            target.display()
                        )));
                    }
                    written.push(target);
                }
                Plan::Remove => {
                    std::fs::remove_file(&target).map_err(|e| {
                        ResultsError::failure(format!("cannot remove {}: {e}", target.display()))
                    })?;
                }
            }
        }
        Ok(written)
    }
}

impl Drop for Publish {
    /// Removes the temporary files of a publication that did not commit.
    fn drop(&mut self) {
        for (_, plan) in &self.files {
            if let Plan::Write(tmp) = plan {
                let _ = std::fs::remove_file(tmp);
            }
        }
    }
}

/// `.<name>.granflow-<pid>.tmp` beside `target`.
fn temporary_name(target: &Path) -> PathBuf {
    let name = target
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    target.with_file_name(format!(".{name}.granflow-{}.tmp", std::process::id()))
}
