//! The files a command writes: checked before any work starts, so that a
//! typo in a path does not cost a long run, and written whole (the
//! reproduction's documents and figures, `--json`, the tables' CSV files).

use std::io;
use std::path::{Path, PathBuf};

/// Why an output path cannot be used.
#[derive(Debug, thiserror::Error)]
pub enum OutputError {
    #[error("cannot write {flag} {}: the directory {} does not exist", path.display(), dir.display())]
    NoDirectory {
        flag: &'static str,
        path: PathBuf,
        dir: PathBuf,
    },
    #[error("cannot write {flag} {}: it is a directory", path.display())]
    IsDirectory { flag: &'static str, path: PathBuf },
    #[error("cannot write {flag} {}: {source}", path.display())]
    NotWritable {
        flag: &'static str,
        path: PathBuf,
        source: io::Error,
    },
}

/// Checks that the file `path` (given as `flag`) can be written: its
/// directory exists and takes a new file, and it is not itself a directory.
/// Nothing is left behind.
///
/// # Errors
/// [`OutputError`], naming the flag and the path.
pub fn check_file(path: &Path, flag: &'static str) -> Result<(), OutputError> {
    let dir = path
        .parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    if !dir.is_dir() {
        return Err(OutputError::NoDirectory {
            flag,
            path: path.to_path_buf(),
            dir: dir.to_path_buf(),
        });
    }
    if path.is_dir() {
        return Err(OutputError::IsDirectory {
            flag,
            path: path.to_path_buf(),
        });
    }
    probe(dir).map_err(|source| OutputError::NotWritable {
        flag,
        path: path.to_path_buf(),
        source,
    })
}

/// Writes `bytes` to `path` through a temporary file beside it, renamed
/// over `path` once complete: a reader never sees half a file, and an
/// interrupted write leaves the old one. The temporary name carries the
/// process id, so that two processes writing the same file (a requeued
/// Slurm task and the one it replaced) never write into each other's.
///
/// # Errors
/// The file cannot be written or renamed.
pub fn write_atomically(path: &Path, bytes: &[u8]) -> io::Result<()> {
    let mut temporary = path.as_os_str().to_owned();
    temporary.push(format!(".{}.partial", std::process::id()));
    let temporary = PathBuf::from(temporary);
    std::fs::write(&temporary, bytes)?;
    std::fs::rename(&temporary, path).inspect_err(|_| {
        let _ = std::fs::remove_file(&temporary);
    })
}

/// Checks that `dir` can take output files before any work starts: creates
/// it if needed and writes (then removes) a probe file, so that a typo or a
/// read-only directory fails at once rather than after a whole run.
///
/// # Errors
/// The directory cannot be created or written, with the reason.
pub fn check_writable_dir(dir: &Path) -> io::Result<()> {
    std::fs::create_dir_all(dir)?;
    probe(dir)
}

/// Writes and removes a file in `dir`: whether it takes new files.
fn probe(dir: &Path) -> io::Result<()> {
    let probe = dir.join(format!(".pushlearn-probe-{}", std::process::id()));
    std::fs::write(&probe, b"")?;
    std::fs::remove_file(&probe)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_file_in_a_missing_directory_or_a_directory_is_refused_naming_the_flag() {
        let missing = Path::new("/nonexistent-pushlearn-dir/x.json");
        let err = check_file(missing, "--json").unwrap_err().to_string();
        assert_eq!(
            err,
            "cannot write --json /nonexistent-pushlearn-dir/x.json: the directory /nonexistent-pushlearn-dir does not exist"
        );
        let dir = std::env::temp_dir();
        let err = check_file(&dir, "--save-model").unwrap_err().to_string();
        assert!(err.ends_with("it is a directory"), "{err}");
        let ok = dir.join("pushlearn-output-check-ok.json");
        check_file(&ok, "--json").unwrap();
        assert!(!ok.exists());
        check_file(Path::new("relative.json"), "--json").unwrap();
    }

    #[test]
    fn files_are_replaced_whole_and_unwritable_dirs_are_refused() {
        let dir = std::env::temp_dir().join(format!("pushlearn-files-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        check_writable_dir(&dir.join("nested")).unwrap();
        let path = dir.join("nested").join("a.csv");
        write_atomically(&path, b"one\n").unwrap();
        write_atomically(&path, b"two\n").unwrap();
        assert_eq!(std::fs::read(&path).unwrap(), b"two\n");
        let names: Vec<_> = std::fs::read_dir(dir.join("nested")).unwrap().collect();
        assert_eq!(names.len(), 1, "no temporary or probe file is left");
        // Under a file, no directory can be made.
        assert!(check_writable_dir(&path.join("below")).is_err());
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn an_atomic_write_replaces_the_whole_file_and_leaves_no_temporary() {
        let path = std::env::temp_dir().join(format!("pushlearn-atomic-{}", std::process::id()));
        std::fs::write(&path, "old, and longer than the new text").unwrap();
        write_atomically(&path, b"new").unwrap();
        assert_eq!(std::fs::read_to_string(&path).unwrap(), "new");
        let mut partial = path.clone().into_os_string();
        partial.push(format!(".{}.partial", std::process::id()));
        assert!(!Path::new(&partial).exists());
        std::fs::remove_file(&path).unwrap();
    }
}
