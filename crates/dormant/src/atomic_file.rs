//! Writing files so that readers never see a partial one: write a temporary file in the same
//! directory (`.NAME.PID.tmp`), sync it, then rename it over the target. On failure the
//! temporary is removed; a process killed while writing leaves it behind, and
//! [`remove_stale_temporaries`] clears those.

use std::fs;
use std::io::{self, Write};
use std::path::Path;

/// Writes `bytes` to `path` atomically. The error is the underlying I/O error; callers name
/// the file in their own error types.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> io::Result<()> {
    write_atomic_with(path, |w| w.write_all(bytes))
}

/// Writes what `contents` writes to `path` atomically, through a buffer: for large files
/// written again and again (a long run's statistics), building them in memory first grows
/// the heap with every write (docs/lab/soak-and-build.md#2026-12-01-the-10000-frame-soak).
pub(crate) fn write_atomic_with(
    path: &Path,
    contents: impl FnOnce(&mut dyn Write) -> io::Result<()>,
) -> io::Result<()> {
    let dir = path.parent().filter(|d| !d.as_os_str().is_empty()).unwrap_or(Path::new("."));
    let name = path
        .file_name()
        .ok_or_else(|| io::Error::new(io::ErrorKind::InvalidInput, "path has no file name"))?;
    let tmp = dir.join(temporary_name(&name.to_string_lossy(), std::process::id()));
    let result = (|| {
        let mut w = io::BufWriter::new(fs::File::create(&tmp)?);
        contents(&mut w)?;
        let f = w.into_inner().map_err(io::IntoInnerError::into_error)?;
        f.sync_all()?;
        fs::rename(&tmp, path)
    })();
    if result.is_err() {
        let _ = fs::remove_file(&tmp);
    }
    result
}

fn temporary_name(name: &str, pid: u32) -> String {
    format!(".{name}.{pid}.tmp")
}

/// Removes the temporaries in `dir` that other processes left while writing a file `keep`
/// accepts the name of (a killed run's); returns how many. Temporaries of this process stay.
pub(crate) fn remove_stale_temporaries(dir: &Path, keep: impl Fn(&str) -> bool) -> io::Result<usize> {
    let mut removed = 0;
    for entry in fs::read_dir(dir)? {
        let entry = entry?;
        let file_name = entry.file_name();
        let Some(stem) = file_name.to_str().and_then(|n| n.strip_prefix('.')?.strip_suffix(".tmp")) else {
            continue;
        };
        let Some((name, pid)) = stem.rsplit_once('.') else { continue };
        let pid_ok = pid.parse::<u32>().is_ok_and(|p| p != std::process::id());
        if pid_ok && keep(name) && entry.file_type()?.is_file() {
            fs::remove_file(entry.path())?;
            removed += 1;
        }
    }
    Ok(removed)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn failed_write_leaves_no_file() {
        let dir = std::env::temp_dir().join(format!("dormant-atomic-{}", std::process::id()));
        let missing = dir.join("no/such/dir/frame.png");
        assert!(write_atomic(&missing, b"x").is_err());
        assert!(!missing.exists());
    }

    #[test]
    fn replaces_existing_content() {
        let dir = std::env::temp_dir().join(format!("dormant-atomic-ok-{}", std::process::id()));
        fs::create_dir_all(&dir).unwrap();
        let path = dir.join("a.txt");
        write_atomic(&path, b"one").unwrap();
        write_atomic(&path, b"two").unwrap();
        assert_eq!(fs::read(&path).unwrap(), b"two");
        let names: Vec<_> = fs::read_dir(&dir).unwrap().map(|e| e.unwrap().file_name()).collect();
        assert_eq!(names.len(), 1);
        fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn stale_temporaries_of_other_processes_are_removed() {
        let dir = std::env::temp_dir().join(format!("dormant-atomic-stale-{}", std::process::id()));
        fs::create_dir_all(&dir).unwrap();
        let own = temporary_name("frame_0001.png", std::process::id());
        for name in [".frame_0000.png.1.tmp", ".other.txt.2.tmp", ".frame_0002.png.x.tmp", own.as_str()] {
            fs::write(dir.join(name), b"partial").unwrap();
        }
        let removed = remove_stale_temporaries(&dir, |n| n.starts_with("frame_")).unwrap();
        assert_eq!(removed, 1);
        let mut left: Vec<_> =
            fs::read_dir(&dir).unwrap().map(|e| e.unwrap().file_name().into_string().unwrap()).collect();
        left.sort();
        let mut want = vec![".frame_0002.png.x.tmp".to_string(), ".other.txt.2.tmp".into(), own];
        want.sort();
        assert_eq!(left, want);
        fs::remove_dir_all(&dir).unwrap();
    }
}
