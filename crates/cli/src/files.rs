//! Output files written whole: the reproduction's documents and figures,
//! and the tables' CSV files (`--csv DIR`).

use std::path::{Path, PathBuf};

/// Writes `bytes` to `path` through a temporary file in the same directory
/// and a rename, so that an interrupted run leaves the old file or the new
/// one, never half of one (a rename within a directory is atomic).
///
/// # Errors
/// The file cannot be written or renamed.
pub fn write_atomically(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    let mut temporary = path.as_os_str().to_owned();
    temporary.push(".partial");
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
pub fn check_writable_dir(dir: &Path) -> std::io::Result<()> {
    std::fs::create_dir_all(dir)?;
    let probe = dir.join(format!(".pushlearn-probe-{}", std::process::id()));
    std::fs::write(&probe, b"")?;
    std::fs::remove_file(&probe)
}

#[cfg(test)]
mod tests {
    use super::*;

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
}
