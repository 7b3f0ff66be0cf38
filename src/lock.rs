//! Advisory locks that keep two granflow processes from writing the same output.
//!
//! Two sweeps into one directory, or two runs into one HDF5 file, would interleave their
//! writes and leave corrupt files that both processes report as complete. So a `run`
//! locks `<file>.h5.lock` and a sweep locks `DIR/sweep.lock` (one per shard,
//! `DIR/sweep.shard-K-of-N.lock`, so the shards of a job array still run side by side)
//! before touching anything. The second process fails at once with a message naming
//! the holder (pid, host, start time, command), or waits with `--wait`.
//!
//! The lock is the operating system's advisory whole-file lock (`flock` on Unix,
//! `LockFileEx` on Windows, through `std::fs::File::try_lock`), not the mere existence
//! of the file: the kernel drops it when its process dies, even by `kill -9`, so a lock
//! file left behind by a dead process is stale by construction and is simply taken
//! over. The file only carries the holder's description for the message.
//!
//! Removing the file on release races with a process that opened it just before and is
//! blocked on it: that process would then hold a lock on a deleted file while a third
//! one creates a new file and locks that. So after locking, the holder checks that the
//! path still names the file it locked, and starts over if not.
//!
//! File systems without locks (some network mounts) answer "unsupported": the run then
//! goes on without a lock, with a warning.

use std::fs::{File, OpenOptions, TryLockError};
use std::io::{Read, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};
use std::time::{SystemTime, UNIX_EPOCH};

/// Why a lock was not taken.
#[derive(Debug, thiserror::Error)]
pub enum LockError {
    /// Another process holds it.
    #[error("{what} is in use by another granflow process ({holder}; lock file {path}); wait for it to end, pass --wait to wait, or choose another output")]
    Busy {
        what: String,
        holder: String,
        path: PathBuf,
    },
    #[error("cannot lock {path}: {message}")]
    Io { path: PathBuf, message: String },
}

/// A held lock; released (and its file removed) on drop.
#[derive(Debug)]
pub struct Lock {
    /// `None` when the file system has no locks and the run goes on without.
    file: Option<File>,
    path: PathBuf,
}

impl Lock {
    pub fn path(&self) -> &Path {
        &self.path
    }
}

impl Drop for Lock {
    fn drop(&mut self) {
        if self.file.is_some() {
            // Remove while still holding the lock (see the module docs).
            let _ = std::fs::remove_file(&self.path);
        }
    }
}

/// The lock files of the output file `output`, in the order to take them: always
/// `<file>.lock` beside the file `output` resolves to (symbolic links followed, the
/// directory canonical), so every spelling of the path locks the same file; and when
/// the file exists with more than one hard link, `granflow-<device>-<inode>.lock` in
/// the temporary directory, which every link shares.
pub fn lock_paths(output: &Path) -> Vec<PathBuf> {
    let resolved = resolve_links(output);
    let mut name = resolved
        .file_name()
        .map_or_else(|| resolved.as_os_str().to_owned(), |n| n.to_owned());
    name.push(".lock");
    let dir = resolved
        .parent()
        .filter(|d| !d.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    let dir = dir.canonicalize().unwrap_or_else(|_| dir.to_path_buf());
    let mut paths = vec![dir.join(name)];
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        if let Ok(m) = std::fs::metadata(&resolved) {
            if m.is_file() && m.nlink() > 1 {
                paths.push(std::env::temp_dir().join(format!(
                    "granflow-{}-{}.lock",
                    m.dev(),
                    m.ino()
                )));
            }
        }
    }
    paths
}

/// `path` with its symbolic links followed (also a dangling last one), at most 40 deep.
fn resolve_links(path: &Path) -> PathBuf {
    let mut path = path.to_path_buf();
    for _ in 0..40 {
        match std::fs::read_link(&path) {
            Ok(target) => {
                path = match path.parent() {
                    Some(dir) if target.is_relative() => dir.join(target),
                    _ => target,
                };
            }
            Err(_) => break,
        }
    }
    path
}

/// Takes the lock file `path` for `what` (e.g. "output file run.h5"). Without `wait`
/// a held lock is an immediate [`LockError::Busy`]; with it, `on_wait` is called once
/// with the holder's description and the call blocks until the lock is free.
pub fn acquire(
    path: &Path,
    what: &str,
    wait: bool,
    on_wait: &mut dyn FnMut(&str),
) -> Result<Lock, LockError> {
    let io = |e: std::io::Error| LockError::Io {
        path: path.to_path_buf(),
        message: e.to_string(),
    };
    let mut waited = false;
    loop {
        let mut file = OpenOptions::new()
            .read(true)
            .write(true)
            .create(true)
            .truncate(false)
            .open(path)
            .map_err(io)?;
        match file.try_lock() {
            Ok(()) => {}
            Err(TryLockError::WouldBlock) => {
                let holder = describe_holder(&mut file);
                if !wait {
                    return Err(LockError::Busy {
                        what: what.to_owned(),
                        holder,
                        path: path.to_path_buf(),
                    });
                }
                if !waited {
                    on_wait(&holder);
                    waited = true;
                }
                file.lock().map_err(io)?;
            }
            Err(TryLockError::Error(e)) if e.kind() == std::io::ErrorKind::Unsupported => {
                crate::terminal::print_err(&format!(
                    "warning: {} does not support file locks; running without one, so make sure no other granflow process writes {what}\n",
                    path.display()
                ));
                return Ok(Lock {
                    file: None,
                    path: path.to_path_buf(),
                });
            }
            Err(TryLockError::Error(e)) => return Err(io(e)),
        }
        if !still_at(&file, path) {
            // The previous holder removed the file between our open and our lock.
            continue;
        }
        file.set_len(0).map_err(io)?;
        file.seek(SeekFrom::Start(0)).map_err(io)?;
        file.write_all(holder_text().as_bytes()).map_err(io)?;
        file.flush().map_err(io)?;
        return Ok(Lock {
            file: Some(file),
            path: path.to_path_buf(),
        });
    }
}

/// Whether `path` still names the open `file`.
fn still_at(file: &File, path: &Path) -> bool {
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        match (file.metadata(), std::fs::metadata(path)) {
            (Ok(a), Ok(b)) => a.dev() == b.dev() && a.ino() == b.ino(),
            _ => false,
        }
    }
    #[cfg(not(unix))]
    {
        let _ = file;
        path.exists()
    }
}

/// The holder's description as written in its lock file, on one line.
fn describe_holder(file: &mut File) -> String {
    let mut text = String::new();
    let _ = file.take(4096).read_to_string(&mut text);
    let fields: Vec<String> = text
        .lines()
        .filter_map(|l| l.split_once('='))
        .map(|(k, v)| format!("{} {}", k.trim(), v.trim().trim_matches('"')))
        .collect();
    if fields.is_empty() {
        "holder not yet described".to_owned()
    } else {
        fields.join(", ")
    }
}

/// What a lock file says about its holder.
fn holder_text() -> String {
    let command: Vec<String> = std::env::args().collect();
    let mut command = command.join(" ");
    if command.len() > 300 {
        let cut = (0..=300).rev().find(|&i| command.is_char_boundary(i));
        command.truncate(cut.unwrap_or(0));
        command.push('…');
    }
    format!(
        "pid = {}\nhost = {:?}\nstarted = {:?}\ncommand = {:?}\n",
        std::process::id(),
        host_name(),
        utc_now(),
        command
    )
}

fn host_name() -> String {
    ["/proc/sys/kernel/hostname", "/etc/hostname"]
        .iter()
        .find_map(|p| std::fs::read_to_string(p).ok())
        .map(|s| s.trim().to_owned())
        .filter(|s| !s.is_empty())
        .or_else(|| std::env::var("HOSTNAME").ok())
        .or_else(|| std::env::var("COMPUTERNAME").ok())
        .unwrap_or_else(|| "unknown host".to_owned())
}

/// The current time as `YYYY-MM-DDTHH:MM:SSZ`.
fn utc_now() -> String {
    let secs = SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .map_or(0, |d| d.as_secs());
    utc_text(secs)
}

/// `secs` since 1970 as an ISO 8601 UTC time (proleptic Gregorian calendar, days to
/// civil date by the usual era arithmetic: 400-year eras of 146 097 days).
fn utc_text(secs: u64) -> String {
    let days = (secs / 86_400) as i64;
    let rem = secs % 86_400;
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z.rem_euclid(146_097);
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let day = doy - (153 * mp + 2) / 5 + 1;
    let month = if mp < 10 { mp + 3 } else { mp - 9 };
    let year = yoe + era * 400 + i64::from(month <= 2);
    format!(
        "{year:04}-{month:02}-{day:02}T{:02}:{:02}:{:02}Z",
        rem / 3600,
        rem % 3600 / 60,
        rem % 60
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn utc_text_known_dates() {
        assert_eq!(utc_text(0), "1970-01-01T00:00:00Z");
        assert_eq!(utc_text(951_782_400), "2000-02-29T00:00:00Z");
        assert_eq!(utc_text(1_795_000_000), "2026-11-18T11:06:40Z");
    }

    #[test]
    fn second_lock_is_busy_naming_the_holder_and_free_after_release() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("x.lock");
        let first = acquire(&path, "x", false, &mut |_| {}).unwrap();
        let e = acquire(&path, "x", false, &mut |_| {}).unwrap_err();
        let text = e.to_string();
        assert!(
            text.contains(&format!("pid {}", std::process::id())),
            "{text}"
        );
        assert!(text.contains("host") && text.contains("started"), "{text}");
        drop(first);
        assert!(!path.exists());
        let again = acquire(&path, "x", false, &mut |_| {}).unwrap();
        assert!(path.exists());
        drop(again);
    }

    #[test]
    fn a_stale_lock_file_is_taken_over() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("x.lock");
        std::fs::write(&path, "pid = 999999999\nhost = \"gone\"\n").unwrap();
        let lock = acquire(&path, "x", false, &mut |_| {}).unwrap();
        let text = std::fs::read_to_string(lock.path()).unwrap();
        assert!(
            text.contains(&format!("pid = {}", std::process::id())),
            "{text}"
        );
    }

    #[test]
    fn waiting_gets_the_lock_when_the_holder_lets_go() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("x.lock");
        let first = acquire(&path, "x", false, &mut |_| {}).unwrap();
        let p = path.clone();
        let waiter = std::thread::spawn(move || {
            let mut told = 0;
            let lock = acquire(&p, "x", true, &mut |_| told += 1).unwrap();
            (told, lock.path().exists())
        });
        std::thread::sleep(std::time::Duration::from_millis(200));
        drop(first);
        let (told, exists) = waiter.join().unwrap();
        assert_eq!(told, 1);
        assert!(exists);
    }
}
