//! Output files written whole or not at all, and folders checked for writing before the work.
//!
//! Every file the project writes (images, reports, tables, charts, exported scenes) goes
//! through [`write_atomic`]: the bytes go to a temporary file beside the target, which is
//! renamed over it only once complete, so a render interrupted or failing while it writes
//! never leaves an existing output half-written (a rename within one folder is atomic on
//! POSIX file systems).

use std::fs::File;
use std::io::{self, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

/// Writes `path` through `write`, which fills a new temporary file in the same folder; the
/// file is flushed to disk and renamed over `path` only when `write` succeeded, and removed
/// otherwise.
pub fn write_atomic(
    path: &Path,
    write: impl FnOnce(&mut File) -> io::Result<()>,
) -> io::Result<()> {
    let temporary = temporary_path(path);
    let mut file = File::create_new(&temporary)?;
    let written = write(&mut file)
        .and_then(|()| file.sync_all())
        .and_then(|()| std::fs::rename(&temporary, path));
    if written.is_err() {
        let _ = std::fs::remove_file(&temporary);
    }
    written
}

/// Writes `bytes` to `path` with [`write_atomic`].
pub fn write_bytes(path: &Path, bytes: impl AsRef<[u8]>) -> io::Result<()> {
    write_atomic(path, |file| file.write_all(bytes.as_ref()))
}

/// Checks that files can be created in `dir` by creating one and removing it: permissions
/// alone do not say (a read-only file system refuses even root), so a render that would fail
/// at its end fails before it starts.
pub fn check_writable_folder(dir: &Path) -> io::Result<()> {
    let probe = temporary_path(&dir.join("probe"));
    File::create_new(&probe)?;
    std::fs::remove_file(&probe)
}

/// A name beside `path` that no other writer uses: hidden, with the process id and a counter.
fn temporary_path(path: &Path) -> PathBuf {
    static COUNTER: AtomicU64 = AtomicU64::new(0);
    let n = COUNTER.fetch_add(1, Ordering::Relaxed);
    let name = path.file_name().unwrap_or_default().to_string_lossy();
    path.with_file_name(format!(".{name}.{}-{n}.tmp", std::process::id()))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scratch(name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("ppm-output-{}-{name}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        dir
    }

    #[test]
    fn a_failed_write_leaves_the_old_file_whole_and_no_temporary() {
        let dir = scratch("failed");
        let path = dir.join("report.json");
        write_bytes(&path, "old contents").unwrap();
        let failed = write_atomic(&path, |file| {
            file.write_all(b"half of the new")?;
            Err(io::Error::other("the writer failed midway"))
        });
        assert!(failed.is_err());
        assert_eq!(std::fs::read_to_string(&path).unwrap(), "old contents");
        let names: Vec<_> = std::fs::read_dir(&dir)
            .unwrap()
            .map(|e| e.unwrap().file_name())
            .collect();
        std::fs::remove_dir_all(&dir).ok();
        assert_eq!(names, ["report.json"], "the temporary file was left behind");
    }

    #[test]
    fn a_complete_write_replaces_the_file() {
        let dir = scratch("complete");
        let path = dir.join("a.csv");
        write_bytes(&path, "one").unwrap();
        write_bytes(&path, "two").unwrap();
        let text = std::fs::read_to_string(&path).unwrap();
        let count = std::fs::read_dir(&dir).unwrap().count();
        std::fs::remove_dir_all(&dir).ok();
        assert_eq!((text.as_str(), count), ("two", 1));
    }

    #[test]
    fn a_folder_that_refuses_files_is_caught_before_any_work() {
        let dir = scratch("probe");
        assert!(check_writable_folder(&dir).is_ok());
        assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 0, "probe removed");
        std::fs::remove_dir_all(&dir).ok();
        assert!(check_writable_folder(&dir).is_err(), "a missing folder");
        if cfg!(target_os = "linux") {
            // procfs refuses new files to everyone, root included.
            assert!(check_writable_folder(Path::new("/proc/self")).is_err());
        }
    }
}
