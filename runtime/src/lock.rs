//! An output folder belongs to one command at a time.
//!
//! `rig run` (also `--resume`), `rig learn` and an agent process writing checkpoints hold
//! an exclusive advisory lock (`flock(2)`) on `FOLDER/.lock` while they write into the
//! folder, and write into that file which process they are. A second command into the
//! same folder is refused with one line naming the holder, before it writes anything.
//! The operating system releases the lock when the holding process ends in any way — a
//! crash or `kill -9` too — so a folder left by a killed run is free for `--resume`.

use std::fs::{File, OpenOptions, TryLockError};
use std::io::{Read, Seek, Write};
use std::path::{Path, PathBuf};
use std::time::Duration;

use wire::Monotonic;

/// The lock file's name inside the folder it guards.
pub const LOCK_FILE: &str = ".lock";

/// How long a refused command waits for the holder to have written who it is (it writes
/// right after taking the lock).
const HOLDER_NAMED: Duration = Duration::from_millis(500);

/// Why a folder could not be locked.
#[derive(Debug, thiserror::Error)]
pub enum LockError {
    /// Another process holds the folder.
    #[error(
        "{folder} is in use by process {pid} ({command}); wait until it has ended, or write elsewhere"
    )]
    Held {
        /// The folder.
        folder: String,
        /// The holder's process id.
        pid: u32,
        /// The holder's command line.
        command: String,
    },
    /// Another process holds the folder and has not (yet) said which.
    #[error("{folder} is in use by another process; wait until it has ended, or write elsewhere")]
    HeldByUnknown {
        /// The folder.
        folder: String,
    },
    /// The lock file could not be opened or written.
    #[error("cannot lock {path}: {error}")]
    Io {
        /// The lock file.
        path: String,
        /// What the operating system said.
        error: std::io::Error,
    },
}

/// The exclusive hold of an output folder; released when dropped (or when the process
/// ends).
#[derive(Debug)]
pub struct FolderLock {
    _file: File,
}

impl FolderLock {
    /// Locks the existing folder `folder` for this process, or says who holds it.
    pub fn acquire(folder: &Path) -> Result<Self, LockError> {
        Self::acquire_at(folder, &Monotonic::host())
    }

    /// [`Self::acquire`], waiting for a holder to name itself on `time`.
    fn acquire_at(folder: &Path, time: &Monotonic) -> Result<Self, LockError> {
        let path = folder.join(LOCK_FILE);
        let io = |error| LockError::Io {
            path: path.display().to_string(),
            error,
        };
        let mut file = OpenOptions::new()
            .read(true)
            .write(true)
            .create(true)
            .truncate(false)
            .open(&path)
            .map_err(io)?;
        match file.try_lock() {
            Ok(()) => {}
            Err(TryLockError::WouldBlock) => return Err(holder(folder, &mut file, time)),
            Err(TryLockError::Error(e)) => return Err(io(e)),
        }
        file.set_len(0).map_err(io)?;
        file.rewind().map_err(io)?;
        let record = format!("{}\n{}\n", std::process::id(), command_line());
        file.write_all(record.as_bytes())
            .and_then(|()| file.flush())
            .map_err(io)?;
        Ok(Self { _file: file })
    }
}

/// The error naming the process that holds `folder` (whose lock file is `file`), as it
/// wrote itself into the file within [`HOLDER_NAMED`] on `time`.
fn holder(folder: &Path, file: &mut File, time: &Monotonic) -> LockError {
    let end = time.now_ns() + HOLDER_NAMED.as_nanos() as u64;
    let folder = folder.display().to_string();
    match time.poll_until(end, LOOK_AGAIN, || read_holder(file)) {
        Some((pid, command)) => LockError::Held {
            folder,
            pid,
            command,
        },
        None => LockError::HeldByUnknown { folder },
    }
}

/// How often a refused command reads the lock file again for its holder's name.
const LOOK_AGAIN: Duration = Duration::from_millis(10);

/// The process id and command line in a lock file, if they name a live process.
fn read_holder(file: &mut File) -> Option<(u32, String)> {
    let mut text = String::new();
    file.rewind().ok()?;
    file.read_to_string(&mut text).ok()?;
    let (pid, command) = text.split_once('\n')?;
    let pid: u32 = pid.trim().parse().ok()?;
    let command = command.strip_suffix('\n')?;
    Path::new(&format!("/proc/{pid}"))
        .exists()
        .then(|| (pid, command.to_string()))
}

/// This process's command line, its program by file name: `rig run --out out/run`.
fn command_line() -> String {
    let mut args = std::env::args_os().map(|a| a.to_string_lossy().into_owned());
    let program = args
        .next()
        .map(|p| {
            PathBuf::from(&p)
                .file_name()
                .map_or(p.clone(), |f| f.to_string_lossy().into_owned())
        })
        .unwrap_or_default();
    std::iter::once(program)
        .chain(args)
        .collect::<Vec<_>>()
        .join(" ")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_held_folder_is_refused_naming_its_holder_and_free_once_released() {
        let dir = std::env::temp_dir().join(format!("rig-lock-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let held = FolderLock::acquire(&dir).unwrap();
        // A second open file description: refused, as another process would be.
        let err = FolderLock::acquire(&dir).unwrap_err().to_string();
        let pid = std::process::id();
        assert!(
            err.contains(&format!("in use by process {pid} ("))
                && err.contains(&dir.display().to_string()),
            "{err}"
        );
        assert_eq!(err.lines().count(), 1);
        drop(held);
        FolderLock::acquire(&dir).unwrap();
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn a_missing_folder_is_an_error_naming_the_lock_file() {
        let dir = std::env::temp_dir().join(format!("rig-lock-missing-{}", std::process::id()));
        let err = FolderLock::acquire(&dir).unwrap_err().to_string();
        assert!(
            err.contains(".lock") && err.contains("No such file"),
            "{err}"
        );
    }

    #[test]
    fn a_holder_that_never_names_itself_is_unknown_after_half_a_second() {
        let dir = std::env::temp_dir().join(format!("rig-lock-unnamed-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        // Held, and nothing written into it.
        let held = File::create(dir.join(LOCK_FILE)).unwrap();
        held.try_lock().unwrap();
        let (time, _) = Monotonic::mock();
        let err = FolderLock::acquire_at(&dir, &time).err().unwrap();
        assert!(matches!(err, LockError::HeldByUnknown { .. }), "{err}");
        let waited = time.now_ns();
        let (most, look) = (HOLDER_NAMED.as_nanos() as u64, LOOK_AGAIN.as_nanos() as u64);
        assert!((most..=most + look).contains(&waited), "{waited} ns");
        drop(held);
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
