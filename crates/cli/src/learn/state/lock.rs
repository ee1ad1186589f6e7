//! One learner per state directory: an OS advisory lock on `DIR/lock`.
//!
//! Two daemons appending to one journal would interleave their records and
//! each overwrite the other's snapshots; the lock makes the second one
//! refuse to start instead. It is `flock(2)` on Unix (`File::try_lock`),
//! which the kernel releases when the holder's last descriptor closes —
//! whatever ends the process, SIGKILL included — so a crashed daemon never
//! leaves a stale lock behind, and the file itself is never removed (a
//! lock file deleted while another process opens it is the classic race).
//! The holder writes its pid into the file, only to name it in the refusal.

use std::fs::{File, OpenOptions, TryLockError};
use std::io::{Read, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};

use super::{io_error, StateError};

/// The lock file's name in the state directory.
pub const LOCK_FILE: &str = "lock";

/// The exclusive right to use a state directory, held until dropped.
#[derive(Debug)]
pub struct StateLock {
    dir: PathBuf,
    // Holding the descriptor open is what holds the lock.
    _file: File,
}

impl StateLock {
    /// Takes the lock on `dir` (which must exist), or says who holds it.
    ///
    /// # Errors
    /// [`StateError::Locked`] if another process (or another open in this
    /// one) holds it; I/O errors on the lock file.
    pub fn acquire(dir: &Path) -> Result<StateLock, StateError> {
        let path = dir.join(LOCK_FILE);
        // Not truncated on opening: until the lock is ours, the pid in it
        // is the holder's.
        let mut file = OpenOptions::new()
            .read(true)
            .write(true)
            .create(true)
            .truncate(false)
            .open(&path)
            .map_err(io_error(&path))?;
        match file.try_lock() {
            Ok(()) => {}
            Err(TryLockError::WouldBlock) => {
                return Err(StateError::Locked {
                    dir: dir.to_path_buf(),
                    holder: holder(&mut file),
                })
            }
            Err(TryLockError::Error(err)) => return Err(io_error(&path)(err)),
        }
        // The pid is a courtesy for the refusal message, not part of the
        // lock: no fsync, and a failure to write it is no reason to stop.
        let written = file
            .set_len(0)
            .and_then(|()| file.seek(SeekFrom::Start(0)))
            .and_then(|_| writeln!(file, "{}", std::process::id()));
        if let Err(err) = written {
            tracing::warn!("{}: cannot record this daemon's pid: {err}", path.display());
        }
        Ok(StateLock {
            dir: dir.to_path_buf(),
            _file: file,
        })
    }

    /// The directory locked.
    #[must_use]
    pub fn dir(&self) -> &Path {
        &self.dir
    }
}

/// The pid the holder wrote, if it has written one yet.
fn holder(file: &mut File) -> Option<u32> {
    let mut text = String::new();
    file.read_to_string(&mut text).ok()?;
    text.trim().parse().ok()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::learn::state::testing::TempDir;

    #[test]
    fn a_second_lock_on_a_directory_is_refused_naming_it_and_the_holder() {
        let dir = TempDir::new("lock");
        std::fs::create_dir_all(&dir.0).unwrap();
        let held = StateLock::acquire(&dir.0).unwrap();
        assert_eq!(held.dir(), dir.0);
        // flock belongs to the open file, not the process: a second open in
        // the same process is refused like another process would be.
        let err = StateLock::acquire(&dir.0).unwrap_err();
        assert!(
            matches!(&err, StateError::Locked { dir: d, holder: Some(pid) }
                if *d == dir.0 && *pid == std::process::id()),
            "{err:?}"
        );
        let message = err.to_string();
        assert!(
            message.contains(&dir.0.display().to_string())
                && message.contains(&format!("pid {}", std::process::id())),
            "{message}"
        );
        drop(held);
        // Released with the descriptor; the new holder's pid replaces the
        // old one rather than being appended to it.
        let again = StateLock::acquire(&dir.0).unwrap();
        let text = std::fs::read_to_string(dir.0.join(LOCK_FILE)).unwrap();
        assert_eq!(text, format!("{}\n", std::process::id()));
        drop(again);
    }

    #[test]
    fn a_holder_that_wrote_no_pid_is_refused_without_one() {
        let dir = TempDir::new("lock-nopid");
        std::fs::create_dir_all(&dir.0).unwrap();
        let path = dir.0.join(LOCK_FILE);
        let file = File::create(&path).unwrap();
        file.try_lock().unwrap();
        let err = StateLock::acquire(&dir.0).unwrap_err();
        assert!(
            matches!(err, StateError::Locked { holder: None, .. }),
            "{err:?}"
        );
        assert!(err.to_string().contains("pid unknown"), "{err}");
    }
}
