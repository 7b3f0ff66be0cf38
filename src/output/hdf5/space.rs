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
//! reserve in a file beside the output (`<file>.reserve`), then truncates them away,
//! so the filesystem has shown it can hold them (tmpfs, quotas and delayed allocation
//! alike) and the batch can use them. Another process may take the room in between;
//! the sink then reports the failed batch and leaves the file alone. [`LimitedDisk`]
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
}

impl DiskSpace {
    /// Creates `<output>.reserve` holding [`RESERVE_BYTES`].
    pub fn new(output: &Path) -> std::io::Result<DiskSpace> {
        let mut name = output.as_os_str().to_owned();
        name.push(".reserve");
        let mut space = DiskSpace {
            path: PathBuf::from(name),
            file: None,
            held: 0,
        };
        space.write_zeros(RESERVE_BYTES)?;
        space.held = RESERVE_BYTES;
        Ok(space)
    }

    /// Writes `n` zero bytes after the held ones (creating the file when needed).
    fn write_zeros(&mut self, n: u64) -> std::io::Result<()> {
        if self.file.is_none() {
            let f = OpenOptions::new()
                .create(true)
                .truncate(true)
                .read(true)
                .write(true)
                .open(&self.path)?;
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
        let _ = std::fs::remove_file(&self.path);
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
