//! What every test of the `rfta` binary uses: running it, its messages, a fresh folder.

#![allow(dead_code, reason = "each test file uses the helpers it needs")]

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// The `rfta` binary this package built, as a command to add arguments to.
pub(crate) fn command() -> Command {
    Command::new(env!("CARGO_BIN_EXE_rfta"))
}

/// `rfta ARGS`, run to the end.
pub(crate) fn rfta(args: &[&str]) -> Output {
    command().args(args).output().expect("run rfta")
}

/// What a run printed on stderr.
pub(crate) fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// An empty folder of its own for test `tag` of this test file.
pub(crate) fn temp(tag: &str) -> PathBuf {
    let p = std::env::temp_dir().join(format!(
        "rfta-{}-{tag}-{}",
        env!("CARGO_CRATE_NAME"),
        std::process::id()
    ));
    let _ = std::fs::remove_dir_all(&p);
    std::fs::create_dir_all(&p).expect("temp dir");
    p
}

/// A path as an argument.
pub(crate) fn s(p: &Path) -> &str {
    p.to_str().expect("utf-8 path")
}

/// A JSON file (a report, a sidecar) read back.
pub(crate) fn json(path: &Path) -> serde_json::Value {
    let bytes = std::fs::read(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    serde_json::from_slice(&bytes).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// The built-in torus as a mesh (and its 5^3 grid, `t.npy`) in `dir`.
pub(crate) fn torus_mesh(dir: &Path) -> PathBuf {
    let torus = dir.join("torus.obj");
    let made = rfta(&[
        "sample",
        "--shape",
        "torus",
        "--res",
        "4",
        "-o",
        s(&dir.join("t.npy")),
        "--save-mesh",
        s(&torus),
    ]);
    assert!(made.status.success(), "{}", stderr(&made));
    torus
}
