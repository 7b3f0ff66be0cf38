//! Advisory locks that keep two granflow processes from writing the same output.
//!
//! Two sweeps into one directory, or two runs into one HDF5 file, would interleave their
//! writes and leave corrupt files that both processes report as complete. So a `run`
//! locks `<file>.h5.lock` and the file's device and inode ([`lock_output`]), and a
//! sweep locks `DIR/sweep.lock` (a shard holds it shared beside its own
//! `DIR/sweep.shard-K-of-N.lock`, so the shards of a job array run side by side but
//! never beside the whole sweep) before touching anything. The second process fails
//! at once with a message naming the holder (pid, host, start time, command), or waits
//! with `--wait`.
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
//! A lock file sits in a directory other users may write (a shared project folder,
//! the temporary directory), so it is never opened through a symbolic link, and a file
//! at its name that granflow did not make (anything but a regular file that is empty or
//! holds a holder's description) is refused, never truncated or removed: a new lock
//! file is created exclusively (`O_CREAT | O_EXCL`, which does not follow links), an
//! existing one is opened only when it is a regular file and still the file just looked
//! at.
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
    /// Something granflow did not make is in the way of the lock file.
    #[error("{path} {reason}; granflow did not make it and will neither use nor remove it (remove it yourself, or choose another output)")]
    NotOurs { path: PathBuf, reason: String },
    #[error("cannot lock {path}: {message}")]
    Io { path: PathBuf, message: String },
}

/// A held lock; released (and its file removed) on drop.
#[derive(Debug)]
pub struct Lock {
    /// `None` when the file system has no locks and the run goes on without.
    file: Option<File>,
    path: PathBuf,
    /// Held shared ([`acquire_shared`]).
    shared: bool,
}

impl Lock {
    pub fn path(&self) -> &Path {
        &self.path
    }
}

impl Drop for Lock {
    fn drop(&mut self) {
        if let Some(file) = &self.file {
            // A shared holder removes the file only when it is the last one: when the
            // lock turns exclusive.
            if self.shared && file.try_lock().is_err() {
                return;
            }
            // Remove while still holding the lock (see the module docs), and only the
            // file locked: never one put in its place.
            if still_at(file, &self.path) {
                let _ = std::fs::remove_file(&self.path);
            }
        }
    }
}

/// The lock file named after the output file `output`: `<file>.lock` beside the file
/// `output` resolves to (symbolic links followed, the directory canonical), so every
/// spelling of the path through links and `..` locks the same file, also on a file
/// system shared by several machines.
pub fn name_lock_path(output: &Path) -> PathBuf {
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
    dir.join(name)
}

/// Locks the output file `output` of a run for `what` (see [`acquire`]): first its
/// [`name_lock_path`]; then, with the file created when missing (empty, as the run
/// would create it), the lock named by its device and inode in the temporary
/// directory, `granflow-<device>-<inode>.lock`. Every name of the file shares that
/// one, also a hard link made after the run started, which no name lock can see.
pub fn lock_output(
    output: &Path,
    what: &str,
    wait: bool,
    on_wait: &mut dyn FnMut(&str),
) -> Result<OutputLock, LockError> {
    let mut locks = vec![acquire(&name_lock_path(output), what, wait, on_wait)?];
    let created = !output.exists();
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        let io = |e: std::io::Error| LockError::Io {
            path: output.to_path_buf(),
            message: e.to_string(),
        };
        // Opened without truncating: the run replaces the contents in place (same
        // inode), after its own checks.
        let file = OpenOptions::new()
            .write(true)
            .create(true)
            .truncate(false)
            .open(output)
            .map_err(io)?;
        let m = file.metadata().map_err(io)?;
        let path = std::env::temp_dir().join(format!("granflow-{}-{}.lock", m.dev(), m.ino()));
        locks.push(acquire_as(&path, what, wait, on_wait, Mode::IN_SHARED_DIR)?);
    }
    Ok(OutputLock {
        _locks: locks,
        created: created.then(|| output.to_path_buf()),
    })
}

/// The locks of a run's output file ([`lock_output`]), released on drop.
#[derive(Debug)]
pub struct OutputLock {
    _locks: Vec<Lock>,
    /// The output file when [`lock_output`] created it (empty).
    created: Option<PathBuf>,
}

impl OutputLock {
    /// Removes the output file this lock created when nothing was written to it (a run
    /// that failed before it began): a failed start leaves no empty file behind.
    pub fn remove_if_unwritten(&self) {
        if let Some(path) = &self.created {
            if std::fs::metadata(path).is_ok_and(|m| m.is_file() && m.len() == 0) {
                let _ = std::fs::remove_file(path);
            }
        }
    }
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
    acquire_as(path, what, wait, on_wait, Mode::default())
}

/// How [`acquire_as`] takes a lock.
#[derive(Debug, Clone, Copy, Default)]
struct Mode {
    /// Shared ([`acquire_shared`]) rather than exclusive.
    shared: bool,
    /// The lock file lies in a directory every user shares (the temporary directory):
    /// it is made writable by all, so that a file left by one user's killed run, whose
    /// inode another user's file has taken since, cannot lock that user out.
    in_shared_dir: bool,
}

impl Mode {
    const IN_SHARED_DIR: Mode = Mode {
        shared: false,
        in_shared_dir: true,
    };
}

/// [`acquire`] shared: any number of shared holders at once, none beside an exclusive
/// one (the shards of a sweep beside each other, never beside the whole sweep). The
/// first shared holder describes itself; the last one removes the file.
pub fn acquire_shared(
    path: &Path,
    what: &str,
    wait: bool,
    on_wait: &mut dyn FnMut(&str),
) -> Result<Lock, LockError> {
    let mode = Mode {
        shared: true,
        in_shared_dir: false,
    };
    acquire_as(path, what, wait, on_wait, mode)
}

fn acquire_as(
    path: &Path,
    what: &str,
    wait: bool,
    on_wait: &mut dyn FnMut(&str),
    mode: Mode,
) -> Result<Lock, LockError> {
    let shared = mode.shared;
    let io = |e: std::io::Error| LockError::Io {
        path: path.to_path_buf(),
        message: e.to_string(),
    };
    let mut waited = false;
    loop {
        let Some(mut file) = open_lock_file(path, mode.in_shared_dir)? else {
            // Removed between a look and an open: look again.
            continue;
        };
        let tried = if shared {
            file.try_lock_shared()
        } else {
            file.try_lock()
        };
        match tried {
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
                if shared {
                    file.lock_shared().map_err(io)?;
                } else {
                    file.lock().map_err(io)?;
                }
            }
            Err(TryLockError::Error(e)) if e.kind() == std::io::ErrorKind::Unsupported => {
                crate::terminal::print_err(&format!(
                    "warning: {} does not support file locks; running without one, so make sure no other granflow process writes {what}\n",
                    path.display()
                ));
                return Ok(Lock {
                    file: None,
                    path: path.to_path_buf(),
                    shared,
                });
            }
            Err(TryLockError::Error(e)) => return Err(io(e)),
        }
        if !still_at(&file, path) {
            // The previous holder removed the file between our open and our lock.
            continue;
        }
        if !holds_a_description(&mut file) {
            return Err(LockError::NotOurs {
                path: path.to_path_buf(),
                reason: "exists and is not a granflow lock file".to_owned(),
            });
        }
        let undescribed = file.metadata().is_ok_and(|m| m.len() == 0);
        let lock = Lock {
            file: Some(file),
            path: path.to_path_buf(),
            shared,
        };
        // The description only serves the message of a second process: a disk too
        // full to hold it leaves the lock undescribed, not a failure (and the lock's
        // drop still removes the file). Shared holders keep the first one's.
        if !shared || undescribed {
            let _ = lock.describe();
        }
        return Ok(lock);
    }
}

/// Opens the lock file `path` for reading and writing: created exclusively when
/// missing; when present, opened only if it is a regular file, not a symbolic link
/// (nor a directory, FIFO, …), and the open reached that very file. `None` when it
/// vanished in between.
fn open_lock_file(path: &Path, for_all: bool) -> Result<Option<File>, LockError> {
    let io = |e: std::io::Error| LockError::Io {
        path: path.to_path_buf(),
        message: e.to_string(),
    };
    match OpenOptions::new()
        .read(true)
        .write(true)
        .create_new(true)
        .open(path)
    {
        Ok(file) => {
            #[cfg(unix)]
            if for_all {
                use std::os::unix::fs::PermissionsExt;
                // On the open file: the umask does not apply, and no link is followed.
                let _ = file.set_permissions(std::fs::Permissions::from_mode(0o666));
            }
            #[cfg(not(unix))]
            let _ = for_all;
            return Ok(Some(file));
        }
        Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => {}
        Err(e) => return Err(io(e)),
    }
    let seen = match std::fs::symlink_metadata(path) {
        Ok(m) => m,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
        Err(e) => return Err(io(e)),
    };
    if !seen.file_type().is_file() {
        let kind = if seen.file_type().is_symlink() {
            "is a symbolic link"
        } else if seen.is_dir() {
            "is a directory"
        } else {
            "is not a regular file"
        };
        return Err(LockError::NotOurs {
            path: path.to_path_buf(),
            reason: kind.to_owned(),
        });
    }
    let file = match OpenOptions::new().read(true).write(true).open(path) {
        Ok(f) => f,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
        Err(e) => return Err(io(e)),
    };
    // A link swapped in between the look and the open: look again.
    Ok(still_at(&file, path).then_some(file))
}

/// Whether a lock file holds what granflow writes there: nothing yet (a holder
/// between its creation and its description, or a disk that was full), or a
/// holder's description.
fn holds_a_description(file: &mut File) -> bool {
    let mut head = Vec::new();
    if file.seek(SeekFrom::Start(0)).is_err() || file.take(6).read_to_end(&mut head).is_err() {
        return false;
    }
    head.is_empty() || head == b"pid = "
}

impl Lock {
    /// Writes the holder's description into the lock file.
    fn describe(&self) -> std::io::Result<()> {
        let Some(mut file) = self.file.as_ref() else {
            return Ok(());
        };
        file.set_len(0)?;
        file.seek(SeekFrom::Start(0))?;
        file.write_all(holder_text().as_bytes())?;
        file.flush()
    }
}

/// Whether `path` still names the open `file`.
fn still_at(file: &File, path: &Path) -> bool {
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        match (file.metadata(), std::fs::symlink_metadata(path)) {
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

    #[cfg(unix)]
    #[test]
    fn a_link_or_a_foreign_file_at_the_name_is_refused_and_left_alone() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("x.lock");
        let victim = dir.path().join("victim");
        std::fs::write(&victim, "data").unwrap();
        std::os::unix::fs::symlink(&victim, &path).unwrap();
        let e = acquire(&path, "x", false, &mut |_| {}).unwrap_err();
        assert!(matches!(e, LockError::NotOurs { .. }), "{e}");
        assert_eq!(std::fs::read_to_string(&victim).unwrap(), "data");
        std::fs::remove_file(&path).unwrap();
        std::os::unix::fs::symlink(dir.path().join("missing"), &path).unwrap();
        assert!(acquire(&path, "x", false, &mut |_| {}).is_err());
        assert!(!dir.path().join("missing").exists());
        std::fs::remove_file(&path).unwrap();
        std::fs::write(&path, "notes").unwrap();
        let e = acquire(&path, "x", false, &mut |_| {}).unwrap_err();
        assert!(e.to_string().contains("not a granflow lock file"), "{e}");
        assert_eq!(std::fs::read_to_string(&path).unwrap(), "notes");
    }

    #[test]
    fn shared_holders_share_and_keep_out_an_exclusive_one() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("x.lock");
        let a = acquire_shared(&path, "x", false, &mut |_| {}).unwrap();
        let b = acquire_shared(&path, "x", false, &mut |_| {}).unwrap();
        let e = acquire(&path, "x", false, &mut |_| {}).unwrap_err();
        assert!(matches!(e, LockError::Busy { .. }), "{e}");
        drop(a);
        assert!(path.exists(), "removed while shared by another");
        assert!(acquire(&path, "x", false, &mut |_| {}).is_err());
        drop(b);
        assert!(!path.exists());
        let whole = acquire(&path, "x", false, &mut |_| {}).unwrap();
        assert!(acquire_shared(&path, "x", false, &mut |_| {}).is_err());
        drop(whole);
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
