//! Files replaced atomically.

use std::fs::{self, File};
use std::io;
use std::path::Path;

/// Replaces the file at `path` by what `write` writes, atomically: into a temporary file in
/// the same directory, flushed to the disk (fsync), renamed over `path`, and the directory
/// flushed so the rename itself survives a crash. A reader, or a crash at any moment, sees
/// the old file or the new one, never a mix. On error the temporary file is removed and
/// `path` is untouched.
///
/// ```
/// use std::io::Write;
/// let path = std::env::temp_dir().join(format!("replace-doc-{}.json", std::process::id()));
/// pathtracer::run::checkpoint::replace_file(&path, |f| f.write_all(b"{}"))?;
/// assert_eq!(std::fs::read(&path)?, b"{}");
/// # std::fs::remove_file(&path)?;
/// # Ok::<(), std::io::Error>(())
/// ```
///
/// # Errors
/// Whatever `write` or the file system reports.
pub fn replace_file(
    path: &Path,
    write: impl FnOnce(&mut File) -> io::Result<()>,
) -> io::Result<()> {
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    let name = path
        .file_name()
        .ok_or_else(|| io::Error::other(format!("{} names no file", path.display())))?;
    let tmp = dir.join(format!(
        ".{}.tmp{}",
        name.to_string_lossy(),
        std::process::id()
    ));
    let result = (|| {
        let mut file = File::create(&tmp)?;
        write(&mut file)?;
        file.sync_all()?;
        drop(file);
        fs::rename(&tmp, path)?;
        // The rename is an entry of the directory: flush it too (Unix; elsewhere a no-op).
        if let Ok(d) = File::open(dir) {
            let _ = d.sync_all();
        }
        Ok(())
    })();
    if result.is_err() {
        let _ = fs::remove_file(&tmp);
    }
    result
}

#[cfg(test)]
mod tests {
    use std::io::Write;

    use super::*;

    /// A failing write (here a full disk, simulated: the writer stops half-way with ENOSPC)
    /// leaves the old file whole and no temporary file behind.
    #[test]
    fn a_failed_write_leaves_the_old_file_and_no_temporary() {
        let dir = std::env::temp_dir().join(format!("plateau-replace-{}", std::process::id()));
        let _ = fs::remove_dir_all(&dir);
        fs::create_dir_all(&dir).unwrap();
        let path = dir.join("checkpoint.json");
        replace_file(&path, |f| f.write_all(b"old")).unwrap();
        let err = replace_file(&path, |f| {
            f.write_all(b"new, half")?;
            Err(io::Error::from(io::ErrorKind::StorageFull))
        })
        .unwrap_err();
        assert_eq!(err.kind(), io::ErrorKind::StorageFull);
        assert_eq!(fs::read(&path).unwrap(), b"old");
        assert_eq!(
            fs::read_dir(&dir).unwrap().count(),
            1,
            "a temporary file is left"
        );
        replace_file(&path, |f| f.write_all(b"new")).unwrap();
        assert_eq!(fs::read(&path).unwrap(), b"new");
        let _ = fs::remove_dir_all(&dir);
    }
}
