//! The files the memory writes its bytes into: the disk, or in unit tests a
//! disk that fills up or turns read-only after some bytes
//! (`testing::FailingDisk`), so that every point where a write can fail is
//! tested without filling a real file system.
//!
//! Only creating files, writing and syncing them go through here; renames,
//! removals and directory syncs are made on the file system directly (they
//! write no data; the end-to-end test with a file size limit covers the
//! real thing).

use std::fs::{File, OpenOptions};
use std::io::{self, Write};
use std::path::Path;
use std::sync::Arc;

/// Creates the files the journal and the snapshots are written to.
pub(super) trait Storage: Send + Sync {
    /// Creates `path` (truncating it if it exists) for writing.
    fn create(&self, path: &Path) -> io::Result<Box<dyn StorageFile>>;
}

/// A file being written: bytes, then a sync that makes them durable.
pub(super) trait StorageFile: Write + Send {
    /// `fdatasync`: the data, and the metadata needed to read it back.
    fn sync_data(&mut self) -> io::Result<()>;
    /// `fsync`.
    fn sync_all(&mut self) -> io::Result<()>;
}

/// The real file system.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct Disk;

impl Disk {
    pub(super) fn shared() -> Arc<dyn Storage> {
        Arc::new(Disk)
    }
}

impl Storage for Disk {
    fn create(&self, path: &Path) -> io::Result<Box<dyn StorageFile>> {
        let file = OpenOptions::new()
            .create(true)
            .truncate(true)
            .write(true)
            .open(path)?;
        Ok(Box::new(file))
    }
}

impl StorageFile for File {
    fn sync_data(&mut self) -> io::Result<()> {
        File::sync_data(self)
    }

    fn sync_all(&mut self) -> io::Result<()> {
        File::sync_all(self)
    }
}
