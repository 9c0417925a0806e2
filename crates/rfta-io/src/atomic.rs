//! Writing outputs without harming what is there: a regular file (or a new one) is written to a
//! temporary file beside it, created exclusively under an unpredictable name, then renamed over
//! it; a symbolic link is followed to the file it names, which is written that way in its own
//! folder (the link stays a link); a FIFO, a character device (a terminal, `/dev/null`) or one of
//! this process's open files (`/dev/stdout`, `/dev/fd/N`, `/proc/self/fd/N`) is streamed to, as
//! it is; anything else (a folder, a socket, a block device) is refused before a byte is written.

use std::ffi::OsStr;
use std::fs::{File, OpenOptions};
use std::hash::{BuildHasher, Hasher};
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

use crate::{Error, Result};

/// Links followed before a path is refused as a loop (Linux's own limit, `MAXSYMLINKS`).
const MAX_LINKS: usize = 40;
/// The most bytes of the output's name the temporary file's name repeats: a name of up to 255
/// bytes (the file system's limit) must leave room for the process id, the random part and
/// `.tmp` (hostile test E11: a 240-byte name failed after the work).
const NAME_KEPT: usize = 96;

/// What writing to a path does, once links are followed.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum OutputTarget {
    /// A regular file, or none yet: written atomically at this path (links resolved).
    File(PathBuf),
    /// A FIFO, a character device or an open file of this process: written as a stream,
    /// appended, never replaced.
    Stream(PathBuf),
}

impl OutputTarget {
    /// The path written.
    pub fn path(&self) -> &Path {
        match self {
            Self::File(p) | Self::Stream(p) => p,
        }
    }
}

fn refuse(path: &Path, why: String) -> Error {
    Error::Io {
        path: path.to_path_buf(),
        source: std::io::Error::new(std::io::ErrorKind::InvalidInput, why),
    }
}

/// Where writing `path` goes: links are followed one at a time (a link to a file not there yet
/// names the file to create), and the kind of what is found decides how it is written.
///
/// # Errors
/// [`Error::Io`] naming `path` for a folder, a socket, a block device or another kind of file
/// rfta does not write, a loop of links, or a folder on the way that cannot be read.
pub fn output_target(path: &Path) -> Result<OutputTarget> {
    let mut at = path.to_path_buf();
    for _ in 0..MAX_LINKS {
        let Some(name) = at.file_name().map(OsStr::to_os_string) else {
            return Err(refuse(path, "the output path has no file name".into()));
        };
        // The folder as the file system sees it: a missing one is the writer's (or the path
        // check's) to report; the path is then taken as it is.
        let Ok(dir) = folder(&at).canonicalize() else {
            return Ok(OutputTarget::File(at));
        };
        let full = dir.join(&name);
        // /proc/<pid>/fd/N and /dev/fd/N (a link to /proc/self/fd): an open file of a process,
        // which may be a pipe, a terminal or a file the shell redirected to. It is appended to.
        if is_descriptor_folder(&dir) {
            return Ok(OutputTarget::Stream(full));
        }
        let meta = match std::fs::symlink_metadata(&full) {
            Ok(m) => m,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
                return Ok(OutputTarget::File(full));
            }
            Err(e) => {
                return Err(Error::Io {
                    path: path.to_path_buf(),
                    source: e,
                });
            }
        };
        let kind = meta.file_type();
        if kind.is_symlink() {
            let link = std::fs::read_link(&full).map_err(|source| Error::Io {
                path: path.to_path_buf(),
                source,
            })?;
            at = if link.is_absolute() {
                link
            } else {
                dir.join(link)
            };
            continue;
        }
        if kind.is_file() {
            return Ok(OutputTarget::File(full));
        }
        if kind.is_dir() {
            return Err(refuse(
                path,
                format!("{} is a folder; name the file to write", full.display()),
            ));
        }
        #[cfg(unix)]
        {
            use std::os::unix::fs::FileTypeExt;
            if kind.is_fifo() || kind.is_char_device() {
                return Ok(OutputTarget::Stream(full));
            }
            let what = if kind.is_socket() {
                "a socket"
            } else if kind.is_block_device() {
                "a block device"
            } else {
                "neither a regular file, a FIFO nor a character device"
            };
            return Err(refuse(
                path,
                format!("{} is {what}, which rfta does not write to", full.display()),
            ));
        }
        #[cfg(not(unix))]
        return Err(refuse(
            path,
            format!("{} is not a regular file", full.display()),
        ));
    }
    Err(refuse(
        path,
        format!("more than {MAX_LINKS} links on the way (a loop of links?)"),
    ))
}

/// `/proc/PID/fd` (and `/proc/PID/task/TID/fd`): the folder of a process's open files.
fn is_descriptor_folder(dir: &Path) -> bool {
    dir.starts_with("/proc") && dir.file_name() == Some(OsStr::new("fd"))
}

/// Checks, before any work, that `path` can be written: what it leads to is a kind rfta writes
/// ([`output_target`]) and, for a file, its folder takes a new file (one is created and removed:
/// a read-only or immutable folder, a full quota of files or a name too long are found now, not
/// after the work). A stream is not opened (opening a FIFO waits for its reader).
///
/// # Errors
/// As [`output_target`]; [`Error::Io`] naming `path` when no file can be created beside it.
pub fn check_writable(path: &Path) -> Result<OutputTarget> {
    let target = output_target(path)?;
    if let OutputTarget::File(file) = &target {
        let name = file.file_name().unwrap_or(OsStr::new("output"));
        let (tmp, f) = create_temp(file, name).map_err(|source| Error::Io {
            path: path.to_path_buf(),
            source,
        })?;
        drop(f);
        let _ = std::fs::remove_file(tmp);
    }
    Ok(target)
}

/// The folder a path's file lives in (`.` for a bare name).
fn folder(path: &Path) -> &Path {
    match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    }
}

/// The start of the names of the temporary files process `pid` writes `name` through:
/// `.NAME.PID.` (then 16 random hex digits and `.tmp`), `NAME` cut to its first [`NAME_KEPT`]
/// bytes (at a character boundary).
fn temp_prefix(name: &OsStr, pid: u32) -> String {
    let name = name.to_string_lossy();
    let mut end = name.len().min(NAME_KEPT);
    while !name.is_char_boundary(end) {
        end -= 1;
    }
    format!(".{}.{pid}.", &name[..end])
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
    let Ok(OutputTarget::File(path)) = output_target(path) else {
        return;
    };
    let path = path.as_path();
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

/// Writes `path` without harming what is there ([`output_target`]): a regular or new file is
/// filled through a new temporary file in its folder (created exclusively under an
/// unpredictable name), flushed, synced and renamed over it, a link being followed to the file
/// it names; a FIFO, a character device or an open file of this process is streamed to. On any
/// error a temporary file is removed and a regular file is left as it was.
///
/// # Errors
/// [`Error::Io`] naming `path` for a kind of file rfta does not write, or if creating, writing
/// or renaming fails.
pub fn write_atomic(
    path: &Path,
    write: impl FnOnce(&mut dyn Write) -> std::io::Result<()>,
) -> Result<()> {
    let io_err = |source| Error::Io {
        path: path.to_path_buf(),
        source,
    };
    let file_path = match output_target(path)? {
        OutputTarget::Stream(stream) => {
            // Appended, never created or truncated: a FIFO's reader, a terminal, or the file
            // the shell opened for this process's output gets the bytes in order.
            let file = OpenOptions::new()
                .append(true)
                .open(&stream)
                .map_err(io_err)?;
            let mut out = BufWriter::new(file);
            return write(&mut out).and_then(|()| out.flush()).map_err(io_err);
        }
        OutputTarget::File(file) => file,
    };
    let name = file_path.file_name().ok_or_else(|| {
        io_err(std::io::Error::new(
            std::io::ErrorKind::InvalidInput,
            "the output path has no file name",
        ))
    })?;
    let (tmp, file) = create_temp(&file_path, name).map_err(io_err)?;
    let result = (|| {
        let mut out = BufWriter::new(file);
        write(&mut out)?;
        let file = out.into_inner().map_err(|e| e.into_error())?;
        file.sync_all()?;
        std::fs::rename(&tmp, &file_path)
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

    /// A link is written through: the file it names gets the bytes (created if missing) and
    /// the link stays a link (hostile test E3: links were replaced by files).
    #[cfg(unix)]
    #[test]
    fn links_are_followed_to_the_file_they_name() {
        let dir = scratch("follow");
        std::fs::create_dir_all(dir.join("real")).expect("real");
        std::fs::write(dir.join("real/t.html"), "old").expect("target");
        let link = dir.join("linked.html");
        std::os::unix::fs::symlink("real/t.html", &link).expect("link");
        write_atomic(&link, |w| w.write_all(b"page")).expect("write");
        assert!(
            std::fs::symlink_metadata(&link)
                .expect("link")
                .file_type()
                .is_symlink()
        );
        assert_eq!(
            std::fs::read_to_string(dir.join("real/t.html")).expect("t"),
            "page"
        );
        // A link to a file not there yet (through a second link) creates that file.
        let dangling = dir.join("d.obj");
        std::os::unix::fs::symlink(dir.join("d2.obj"), &dangling).expect("d");
        std::os::unix::fs::symlink("real/new.obj", dir.join("d2.obj")).expect("d2");
        write_atomic(&dangling, |w| w.write_all(b"mesh")).expect("write");
        assert_eq!(
            std::fs::read_to_string(dir.join("real/new.obj")).expect("new"),
            "mesh"
        );
        assert!(
            std::fs::symlink_metadata(&dangling)
                .expect("d")
                .file_type()
                .is_symlink()
        );
        // A loop of links is refused, and both links stay.
        std::os::unix::fs::symlink("b", dir.join("a")).expect("a");
        std::os::unix::fs::symlink("a", dir.join("b")).expect("b");
        let e = write_atomic(&dir.join("a"), |w| w.write_all(b"x")).expect_err("loop");
        assert!(e.to_string().contains("links"), "{e}");
        assert!(
            std::fs::symlink_metadata(dir.join("a"))
                .expect("a")
                .file_type()
                .is_symlink()
        );
        let _ = std::fs::remove_dir_all(dir);
    }

    /// A FIFO is streamed to and stays a FIFO; so is an open file of this process named
    /// through /proc/self/fd (what /dev/stdout links to); a socket is refused untouched.
    #[cfg(target_os = "linux")]
    #[test]
    fn streams_are_written_as_streams_and_sockets_refused() {
        use std::io::Read;
        use std::os::unix::fs::FileTypeExt;
        let dir = scratch("streams");
        let fifo = dir.join("fifo.json");
        let status = std::process::Command::new("mkfifo")
            .arg(&fifo)
            .status()
            .expect("mkfifo");
        assert!(status.success());
        let reader = {
            let fifo = fifo.clone();
            std::thread::spawn(move || std::fs::read_to_string(fifo).expect("read fifo"))
        };
        write_atomic(&fifo, |w| w.write_all(b"{\"report\": 1}")).expect("fifo");
        assert_eq!(reader.join().expect("reader"), "{\"report\": 1}");
        assert!(
            std::fs::metadata(&fifo)
                .expect("fifo")
                .file_type()
                .is_fifo()
        );
        // A pipe of this process, by its descriptor's name; and /dev/fd/N, a link to it.
        let (mut rx, tx) = std::io::pipe().expect("pipe");
        use std::os::fd::AsRawFd;
        let fd = tx.as_raw_fd();
        for name in [format!("/proc/self/fd/{fd}"), format!("/dev/fd/{fd}")] {
            let target = output_target(Path::new(&name)).expect("target");
            assert!(matches!(target, OutputTarget::Stream(_)), "{target:?}");
            write_atomic(Path::new(&name), |w| w.write_all(b"abc")).expect("pipe");
        }
        drop(tx);
        let mut got = String::new();
        rx.read_to_string(&mut got).expect("read pipe");
        assert_eq!(got, "abcabc");
        let sock = dir.join("s.json");
        let _listener = std::os::unix::net::UnixListener::bind(&sock).expect("bind");
        let e = write_atomic(&sock, |w| w.write_all(b"x")).expect_err("socket");
        assert!(e.to_string().contains("socket"), "{e}");
        assert!(
            std::fs::symlink_metadata(&sock)
                .expect("s")
                .file_type()
                .is_socket()
        );
        let e = check_writable(&dir).expect_err("folder");
        assert!(e.to_string().contains("folder"), "{e}");
        let _ = std::fs::remove_dir_all(dir);
    }

    /// A name of 240 bytes is written (the temporary name repeats only its start), and a folder
    /// where no file can be made is found by the check, before any writing.
    #[test]
    fn long_names_are_written_and_unwritable_folders_found_first() {
        let dir = scratch("long");
        let long = dir.join(format!("{}.obj", "n".repeat(236)));
        check_writable(&long).expect("writable");
        write_atomic(&long, |w| w.write_all(b"mesh")).expect("write");
        assert_eq!(std::fs::read_to_string(&long).expect("long"), "mesh");
        assert_eq!(std::fs::read_dir(&dir).expect("dir").count(), 1);
        #[cfg(target_os = "linux")]
        assert!(check_writable(Path::new("/proc/rfta-no-file-here.obj")).is_err());
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
