//! Atomic file writes: a temporary file beside the target, created exclusively under an
//! unpredictable name, then a rename.

use std::ffi::OsStr;
use std::fs::{File, OpenOptions};
use std::hash::{BuildHasher, Hasher};
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

use crate::{Error, Result};

/// The folder a path's file lives in (`.` for a bare name).
fn folder(path: &Path) -> &Path {
    match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    }
}

/// The start of the names of the temporary files process `pid` writes `name` through:
/// `.NAME.PID.` (then 16 random hex digits and `.tmp`).
fn temp_prefix(name: &OsStr, pid: u32) -> String {
    format!(".{}.{pid}.", name.to_string_lossy())
}

/// 64 bits no other process can predict: std's per-process random hash keys (seeded from the
/// operating system's random source) over the time and a counter.
fn random_u64() -> u64 {
    use std::sync::atomic::{AtomicU64, Ordering};
    static COUNTER: AtomicU64 = AtomicU64::new(0);
    let mut h = std::collections::hash_map::RandomState::new().build_hasher();
    h.write_u64(COUNTER.fetch_add(1, Ordering::Relaxed));
    if let Ok(t) = std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH) {
        h.write_u128(t.as_nanos());
    }
    h.finish()
}

/// Creates a new temporary file beside `path`, `.NAME.PID.RANDOM.tmp`, with `O_CREAT | O_EXCL`:
/// it never opens an existing file or follows a link someone planted under that name.
fn create_temp(path: &Path, name: &OsStr) -> std::io::Result<(PathBuf, File)> {
    let prefix = temp_prefix(name, std::process::id());
    let mut last = None;
    for _ in 0..16 {
        let tmp = folder(path).join(format!("{prefix}{:016x}.tmp", random_u64()));
        match OpenOptions::new().write(true).create_new(true).open(&tmp) {
            Ok(file) => return Ok((tmp, file)),
            Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => last = Some(e),
            Err(e) => return Err(e),
        }
    }
    Err(last.unwrap_or_else(|| std::io::Error::other("no temporary file name was free")))
}

/// Removes the temporary files that process `pid` left while writing `path` through
/// [`write_atomic`] (a process killed mid-write leaves its own; whoever killed it can remove
/// them). Never touches `path` or another process's files.
pub fn remove_temp_files(path: &Path, pid: u32) {
    let Some(name) = path.file_name() else {
        return;
    };
    let prefix = temp_prefix(name, pid);
    let Ok(entries) = std::fs::read_dir(folder(path)) else {
        return;
    };
    for entry in entries.flatten() {
        let file = entry.file_name();
        let file = file.to_string_lossy();
        if let Some(rest) = file.strip_prefix(&prefix) {
            let random = rest.strip_suffix(".tmp").unwrap_or("");
            if random.len() == 16 && random.bytes().all(|b| b.is_ascii_hexdigit()) {
                let _ = std::fs::remove_file(entry.path());
            }
        }
    }
}

/// Writes `path` atomically: `write` fills a new temporary file in the same directory (created
/// exclusively under an unpredictable name), which is flushed, synced and renamed over `path`.
/// On any error the temporary file is removed and `path` is left as it was.
///
/// # Errors
/// [`Error::Io`] naming `path` if creating, writing or renaming fails.
pub fn write_atomic(
    path: &Path,
    write: impl FnOnce(&mut dyn Write) -> std::io::Result<()>,
) -> Result<()> {
    let io_err = |source| Error::Io {
        path: path.to_path_buf(),
        source,
    };
    let name = path.file_name().ok_or_else(|| {
        io_err(std::io::Error::new(
            std::io::ErrorKind::InvalidInput,
            "the output path has no file name",
        ))
    })?;
    let (tmp, file) = create_temp(path, name).map_err(io_err)?;
    let result = (|| {
        let mut out = BufWriter::new(file);
        write(&mut out)?;
        let file = out.into_inner().map_err(|e| e.into_error())?;
        file.sync_all()?;
        std::fs::rename(&tmp, path)
    })();
    if let Err(e) = result {
        let _ = std::fs::remove_file(&tmp);
        return Err(io_err(e));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scratch(tag: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("rfta-atomic-{tag}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).expect("scratch dir");
        d
    }

    /// A link planted under the old predictable name, and under every name of this process's
    /// prefix a test can guess, is never written through.
    #[cfg(unix)]
    #[test]
    fn a_planted_link_is_not_followed() {
        let dir = scratch("link");
        let victim = dir.join("victim.txt");
        std::fs::write(&victim, "precious").expect("victim");
        let out = dir.join("o.obj");
        let pid = std::process::id();
        std::os::unix::fs::symlink(&victim, dir.join(format!(".o.obj.{pid}.tmp"))).expect("link");
        write_atomic(&out, |w| w.write_all(b"mesh")).expect("write");
        assert_eq!(
            std::fs::read_to_string(&victim).expect("victim"),
            "precious"
        );
        assert_eq!(std::fs::read_to_string(&out).expect("out"), "mesh");
        // Only the output and the planted link are left.
        assert_eq!(std::fs::read_dir(&dir).expect("dir").count(), 3);
        let _ = std::fs::remove_dir_all(dir);
    }

    #[test]
    fn two_writes_get_different_names_and_a_failed_write_leaves_nothing() {
        let dir = scratch("names");
        let out = dir.join("m.obj");
        let (a, _) = create_temp(&out, OsStr::new("m.obj")).expect("a");
        let (b, _) = create_temp(&out, OsStr::new("m.obj")).expect("b");
        assert_ne!(a, b);
        // What a killed writer leaves, removed by its pid, not another process's.
        let other = dir.join(format!(
            ".m.obj.{}.0123456789abcdef.tmp",
            std::process::id() + 1
        ));
        std::fs::write(&other, "").expect("other");
        remove_temp_files(&out, std::process::id());
        assert!(!a.exists() && !b.exists() && other.exists());
        std::fs::write(&out, "old").expect("old");
        let failed = write_atomic(&out, |_| Err(std::io::Error::other("disk full")));
        assert!(failed.is_err());
        assert_eq!(std::fs::read_to_string(&out).expect("out"), "old");
        assert_eq!(std::fs::read_dir(&dir).expect("dir").count(), 2);
        let _ = std::fs::remove_dir_all(dir);
    }
}
