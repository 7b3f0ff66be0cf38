//! Room on the disk for the HDF5 writer's next batch, claimed before the batch starts.
//!
//! A batch (reopen, append, close) that runs out of space half-way leaves a file
//! whose object headers point past its end: h5py cannot read it. So the sink claims
//! the room a batch can take before it touches the file ([`Space::claim`]): a claim
//! that fails stops the run with a write error while the file is still the
//! consistent one of the previous batch. The sink also holds a reserve
//! ([`RESERVE_BYTES`]) that it gives back ([`Space::release`]) to write the final
//! status (`failed: … write error …`) of a run whose disk is full.
//!
//! [`DiskSpace`] claims real room: it writes the claimed bytes as zeros past the
//! reserve in a file beside the output, then truncates them away, so the filesystem
//! has shown it can hold them (tmpfs, quotas and delayed allocation alike) and the
//! batch can use them. Another process may take the room in between; the sink then
//! reports the failed batch and leaves the file alone.
//!
//! That file is created as `<file>.reserve`, exclusively (never through a symbolic
//! link), and on Unix its name is removed at once: the open file keeps the room, and
//! the kernel gives it back when the process ends however it ends (`kill -9`
//! included), so nothing is left beside the output. A `<file>.reserve` found there
//! (left by a version that kept the name) is removed only when it is a regular file
//! of zeros; `granflow run` refuses anything else there without `--force`
//! ([`crate::overwrite`]). [`LimitedDisk`]
//! is a disk of a given size, for tests of the full-disk path on any machine.

use std::fs::{File, OpenOptions};
use std::io::{Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};

/// Bytes held back for the end of the run: the summary attributes, the object headers
/// rewritten at close and the step records of a last batch (measured: a summary with
/// eight stage times adds under 4 KiB).
pub const RESERVE_BYTES: u64 = 64 * 1024;

/// Where the sink claims room for its writes.
pub trait Space: Send + std::fmt::Debug {
    /// Makes sure `bytes` more can be written to the output file, now `file_len` bytes
    /// long.
    fn claim(&mut self, file_len: u64, bytes: u64) -> std::io::Result<()>;
    /// Gives back the reserve, for the last writes of a run whose disk is full.
    fn release(&mut self);
}

/// Room on the output file's own filesystem, proven by writing it (module docs).
#[derive(Debug)]
pub struct DiskSpace {
    path: PathBuf,
    file: Option<File>,
    /// Bytes of the reserve now held in the file.
    held: u64,
    /// Whether the file still has its name (not on Unix), to remove at the end.
    keeps_name: bool,
}

/// `<output>.reserve`.
pub fn reserve_path(output: &Path) -> PathBuf {
    let mut name = output.as_os_str().to_owned();
    name.push(".reserve");
    PathBuf::from(name)
}

impl DiskSpace {
    /// Creates the reserve file of `output` (module docs) holding [`RESERVE_BYTES`].
    pub fn new(output: &Path) -> std::io::Result<DiskSpace> {
        let mut space = DiskSpace {
            path: reserve_path(output),
            file: None,
            held: 0,
            keeps_name: false,
        };
        let filled = space.write_zeros(RESERVE_BYTES);
        if let Err(e) = filled {
            space.release();
            return Err(e);
        }
        space.held = RESERVE_BYTES;
        Ok(space)
    }

    /// Creates the file exclusively, without a name on Unix (module docs).
    fn open_fresh(&mut self) -> std::io::Result<File> {
        let file = loop {
            match OpenOptions::new()
                .read(true)
                .write(true)
                .create_new(true)
                .open(&self.path)
            {
                Ok(f) => break f,
                Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => {
                    // Removes the name only (a symbolic link, not its target); what
                    // may be removed was checked before the run (module docs).
                    std::fs::remove_file(&self.path)?;
                }
                Err(e) => return Err(e),
            }
        };
        #[cfg(unix)]
        {
            self.keeps_name = std::fs::remove_file(&self.path).is_err();
        }
        #[cfg(not(unix))]
        {
            self.keeps_name = true;
        }
        Ok(file)
    }

    /// Writes `n` zero bytes after the held ones.
    fn write_zeros(&mut self, n: u64) -> std::io::Result<()> {
        if self.file.is_none() {
            let f = self.open_fresh()?;
            self.file = Some(f);
        }
        let file = self.file.as_mut().expect("opened above");
        file.seek(SeekFrom::Start(self.held))?;
        let zeros = [0u8; 64 * 1024];
        let mut left = n;
        while left > 0 {
            let k = left.min(zeros.len() as u64) as usize;
            file.write_all(&zeros[..k])?;
            left -= k as u64;
        }
        file.flush()
    }
}

impl Space for DiskSpace {
    fn claim(&mut self, _file_len: u64, bytes: u64) -> std::io::Result<()> {
        let written = self.write_zeros(bytes);
        if let Some(file) = &self.file {
            // Give the claimed bytes (or what a failed write took) back at once.
            file.set_len(self.held)?;
        }
        written
    }

    fn release(&mut self) {
        self.file = None;
        self.held = 0;
        if std::mem::take(&mut self.keeps_name) {
            let _ = std::fs::remove_file(&self.path);
        }
    }
}

impl Drop for DiskSpace {
    fn drop(&mut self) {
        self.release();
    }
}

/// A disk that holds `limit` bytes of output file: a claim beyond it fails as a full
/// disk does (for tests).
#[derive(Debug, Clone, Copy)]
pub struct LimitedDisk {
    pub limit: u64,
    released: bool,
}

impl LimitedDisk {
    pub fn new(limit: u64) -> LimitedDisk {
        LimitedDisk {
            limit,
            released: false,
        }
    }
}

impl Space for LimitedDisk {
    fn claim(&mut self, file_len: u64, bytes: u64) -> std::io::Result<()> {
        let room = self.limit + if self.released { RESERVE_BYTES } else { 0 };
        if file_len + bytes <= room {
            Ok(())
        } else {
            Err(std::io::Error::new(
                std::io::ErrorKind::StorageFull,
                format!("no space left on device (a disk of {} bytes)", self.limit),
            ))
        }
    }

    fn release(&mut self) {
        self.released = true;
    }
}
