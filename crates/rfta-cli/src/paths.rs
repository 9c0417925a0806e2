//! Every file a command reads or writes, checked together before any work starts: nothing it
//! reads is written over, nothing is written twice, every output can be written (its folder
//! exists and takes a new file; it is a regular file, a link to one, a FIFO or a character
//! device, never a folder or a socket: [`rfta_io::check_writable`]). Two paths name the same file when they reach the same inode
//! (links, `./x` and `x`, hard links) or, for a file not yet there, the same place.
//!
//! One place for every command: `reconstruct` (the input, its sidecar, `-o`, `--report`,
//! `--points`), `mc`, `psr`, `sample`, `demo`, and `batch` (the manifest, the status file, and the
//! inputs and outputs of every row of the manifest, whichever shard runs them).

use std::collections::HashMap;
use std::path::{Component, Path, PathBuf};

use anyhow::{Result, bail};

/// The files of one command.
#[derive(Debug, Default)]
pub(crate) struct Files {
    entries: Vec<Entry>,
}

#[derive(Debug)]
struct Entry {
    /// What the file is to the command: "the input", "--report", "row 3's output", ...
    role: String,
    path: PathBuf,
    access: Access,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Access {
    Read,
    /// Written; its folder must exist.
    Write,
    /// Written; its folder is created if missing (batch outputs).
    WriteCreatingFolder,
}

/// Where a path leads: the file it names (device and inode) or, for one not there yet, its
/// absolute place with `.` and `..` resolved below the nearest folder that exists.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
enum Identity {
    File(u64, u64),
    Place(PathBuf),
}

fn identity(path: &Path) -> Identity {
    #[cfg(unix)]
    if let Ok(m) = std::fs::metadata(path) {
        use std::os::unix::fs::MetadataExt;
        return Identity::File(m.dev(), m.ino());
    }
    // The nearest ancestor that exists, resolved by the file system; the rest appended.
    let absolute = std::path::absolute(path).unwrap_or_else(|_| path.to_path_buf());
    let mut rest = Vec::new();
    let mut base = absolute.as_path();
    loop {
        if let Ok(real) = base.canonicalize() {
            let mut place = real;
            for part in rest.iter().rev() {
                match part {
                    Component::ParentDir => {
                        place.pop();
                    }
                    Component::CurDir => {}
                    other => place.push(other.as_os_str()),
                }
            }
            return Identity::Place(place);
        }
        match (base.parent(), base.components().next_back()) {
            (Some(parent), Some(last)) => {
                rest.push(last);
                base = parent;
            }
            _ => return Identity::Place(absolute.clone()),
        }
    }
}

impl Files {
    pub(crate) fn new() -> Self {
        Self::default()
    }

    fn add(&mut self, role: impl Into<String>, path: &Path, access: Access) -> &mut Self {
        self.entries.push(Entry {
            role: role.into(),
            path: path.to_path_buf(),
            access,
        });
        self
    }

    /// A file the command reads.
    pub(crate) fn read(&mut self, role: impl Into<String>, path: &Path) -> &mut Self {
        self.add(role, path, Access::Read)
    }

    /// An SDF file the command reads, and the place of its sidecar (`NAME.json`), whether or
    /// not one is there: an output written there would be read as the input's sidecar next
    /// time, and the input could no longer be read (hostile test E6).
    pub(crate) fn read_sdf(&mut self, role: impl Into<String>, path: &Path) -> &mut Self {
        let role = role.into();
        let side = rfta_io::sidecar_path(path);
        if side != path {
            self.add(
                format!("{role}'s sidecar (read for its bounds whenever it exists)"),
                &side,
                Access::Read,
            );
        }
        self.add(role, path, Access::Read)
    }

    /// A file the command writes, in a folder that exists.
    pub(crate) fn write(&mut self, role: impl Into<String>, path: &Path) -> &mut Self {
        self.add(role, path, Access::Write)
    }

    /// A file the command writes, creating its folder if needed.
    pub(crate) fn write_creating_folder(
        &mut self,
        role: impl Into<String>,
        path: &Path,
    ) -> &mut Self {
        self.add(role, path, Access::WriteCreatingFolder)
    }

    /// Refuses, naming both, any file written that is also read or written again, and any output
    /// that cannot be written: a folder, a socket, a folder that is missing or takes no new file.
    pub(crate) fn check(&self) -> Result<()> {
        let mut seen: HashMap<Identity, &Entry> = HashMap::new();
        for e in &self.entries {
            // A written path is known by what it leads to (a link by the file it names).
            let mut path = e.path.clone();
            if e.access != Access::Read {
                if e.path.is_dir() {
                    bail!(
                        "{} ({}) is a folder; name the file to write",
                        e.role,
                        e.path.display()
                    );
                }
                let folder = match e.path.parent() {
                    Some(d) if !d.as_os_str().is_empty() => d,
                    _ => Path::new("."),
                };
                if e.access == Access::Write && !folder.is_dir() {
                    bail!(
                        "{} ({}): the folder {} does not exist",
                        e.role,
                        e.path.display(),
                        folder.display()
                    );
                }
                // A folder batch creates is checked when it exists.
                if folder.is_dir() {
                    let target = rfta_io::check_writable(&e.path)
                        .map_err(|err| anyhow::anyhow!("{} cannot be written: {err}", e.role))?;
                    path = target.path().to_path_buf();
                }
            }
            match seen.entry(identity(&path)) {
                std::collections::hash_map::Entry::Vacant(v) => {
                    v.insert(e);
                }
                std::collections::hash_map::Entry::Occupied(o) => {
                    let first = *o.get();
                    if first.access == Access::Read && e.access == Access::Read {
                        continue;
                    }
                    let same = if first.path == e.path {
                        format!("{}", e.path.display())
                    } else {
                        format!("{} and {}", first.path.display(), e.path.display())
                    };
                    let why = if first.access == Access::Read || e.access == Access::Read {
                        "rfta never writes over a file it reads"
                    } else {
                        "one would silently replace the other"
                    };
                    bail!(
                        "{} and {} are the same file ({same}): {why}",
                        first.role,
                        e.role
                    );
                }
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scratch(tag: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("rfta-paths-{tag}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(d.join("sub")).expect("scratch");
        d
    }

    #[test]
    fn aliases_of_one_file_are_refused_and_distinct_files_pass() {
        let d = scratch("alias");
        let input = d.join("in.npy");
        std::fs::write(&input, "x").expect("input");
        std::fs::write(d.join("in.json"), "{}").expect("sidecar");
        let check = |reads: &[&Path], writes: &[&Path]| {
            let mut f = Files::new();
            f.read_sdf("the input", &input);
            for r in reads {
                f.read("another input", r);
            }
            for (k, w) in writes.iter().enumerate() {
                f.write(format!("output {k}"), w);
            }
            f.check()
        };
        assert!(check(&[], &[&d.join("out.obj"), &d.join("r.json")]).is_ok());
        // Reading one file twice is fine.
        assert!(check(&[&input], &[&d.join("out.obj")]).is_ok());
        let dotted = d.join("sub/../in.npy");
        for bad in [
            input.clone(),
            dotted,
            d.join("in.json"),
            d.join("sub/../out.obj"),
        ] {
            let e = check(&[], &[&d.join("out.obj"), &bad]).expect_err("refused");
            assert!(e.to_string().contains("are the same file"), "{e}");
        }
        #[cfg(unix)]
        {
            let link = d.join("link.npy");
            std::os::unix::fs::symlink(&input, &link).expect("link");
            let hard = d.join("hard.npy");
            std::fs::hard_link(&input, &hard).expect("hard link");
            for bad in [&link, &hard] {
                assert!(check(&[], &[bad]).is_err(), "{}", bad.display());
            }
        }
        let _ = std::fs::remove_dir_all(d);
    }

    #[test]
    fn an_output_that_is_a_folder_or_in_a_missing_one_is_refused() {
        let d = scratch("folders");
        let e = Files::new()
            .write("-o", &d.join("sub"))
            .check()
            .expect_err("a folder");
        assert!(e.to_string().contains("is a folder"), "{e}");
        let e = Files::new()
            .write("--report", &d.join("missing/r.json"))
            .check()
            .expect_err("missing folder");
        assert!(e.to_string().contains("does not exist"), "{e}");
        assert!(
            Files::new()
                .write_creating_folder("row 0's output", &d.join("missing/m.obj"))
                .check()
                .is_ok()
        );
        let e = Files::new()
            .write_creating_folder("row 0's output", &d.join("new/m.obj"))
            .write_creating_folder("row 1's output", &d.join("new/./m.obj"))
            .check()
            .expect_err("the same new file");
        assert!(e.to_string().contains("silently replace"), "{e}");
        let _ = std::fs::remove_dir_all(d);
    }
}
