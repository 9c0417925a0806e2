//! MISE (multiresolution isosurface extraction, Mescheder et al., Occupancy Networks, CVPR 2019),
//! the adaptive extractor neural-field code runs, through the shared peer runner
//! (`../shared/peer-tests/mise/mise_mesh.py`, its original code): a coarse grid, every cell whose
//! corners change sign split, to 128^3, then marching cubes; the oracle is the mesh's exact
//! signed distance. Run beside the adaptive mode when a venv with it exists, as gpytoolbox's own
//! tests run beside the drop-in; never copied into the repository.

use std::path::{Path, PathBuf};
use std::process::Command;

use anyhow::{Context, Result, bail};
use rfta_geom::TriMesh;

/// The runner and the Python that runs it.
pub(crate) struct Mise {
    python: PathBuf,
    script: PathBuf,
}

/// What one MISE run gave.
pub(crate) struct MiseRun {
    /// Evaluations of the oracle.
    pub(crate) evaluations: usize,
    /// Seconds outside the oracle (MISE and marching cubes).
    pub(crate) seconds: f64,
    /// Seconds in the oracle.
    pub(crate) oracle_seconds: f64,
    /// Its mesh.
    pub(crate) mesh: TriMesh,
}

impl Mise {
    /// The runner with the venv `venv` (else `$RFTA_MISE_VENV`); `None` when neither is given.
    ///
    /// # Errors
    /// When the venv's Python cannot import `mise` or the shared runner is missing: what to run
    /// to build it.
    pub(crate) fn find(venv: Option<&Path>) -> Result<Option<Self>> {
        let Some(venv) = venv
            .map(Path::to_path_buf)
            .or_else(|| std::env::var_os("RFTA_MISE_VENV").map(PathBuf::from))
        else {
            return Ok(None);
        };
        let data = crate::data_dir();
        let peer = data.parent().unwrap_or(&data).join("peer-tests/mise");
        let peer = std::fs::canonicalize(&peer).unwrap_or(peer);
        let script = peer.join("mise_mesh.py");
        let python = venv.join("bin/python");
        let builds = format!(
            "bash {} {}",
            peer.join("build.sh").display(),
            venv.display()
        );
        if !script.is_file() {
            bail!("MISE's runner {} is missing", script.display());
        }
        let imports = Command::new(&python)
            .args(["-c", "import mise, gpytoolbox, skimage"])
            .status()
            .is_ok_and(|s| s.success());
        if !imports {
            bail!(
                "{} cannot import mise; build it with: {builds}",
                python.display()
            );
        }
        Ok(Some(Self { python, script }))
    }

    /// MISE to 128^3 over [-1, 1]^3 on the exact distance of the mesh at `mesh`; its mesh is
    /// written to `out`.
    ///
    /// # Errors
    /// When the runner fails or its answer cannot be read.
    pub(crate) fn run(&self, mesh: &Path, out: &Path) -> Result<MiseRun> {
        let mut command = Command::new(&self.python);
        command
            .arg(&self.script)
            .arg(mesh)
            .arg(out)
            .args(["--r0", "16", "--depth", "3"]);
        answer(command, mesh, out)
    }

    /// MISE to 128^3 over [-1, 1]^3 on the inexact evaluation's network at `net`
    /// (`tools/rfta-eval/inexact/mise_network.py`, the same settings); its mesh is written to
    /// `out`.
    ///
    /// # Errors
    /// When the runner fails or its answer cannot be read.
    pub(crate) fn run_network(&self, net: &Path, out: &Path) -> Result<MiseRun> {
        let script = crate::workspace_root().join("tools/rfta-eval/inexact/mise_network.py");
        let mut command = Command::new(&self.python);
        command.arg(script).arg(net).arg(out);
        answer(command, net, out)
    }
}

/// What `command`, a MISE runner on `input` writing `out`, answered.
fn answer(mut command: Command, input: &Path, out: &Path) -> Result<MiseRun> {
    let output = command
        .output()
        .with_context(|| format!("cannot run {command:?}"))?;
    if !output.status.success() {
        bail!(
            "MISE on {} failed: {}",
            input.display(),
            String::from_utf8_lossy(&output.stderr)
        );
    }
    let text = String::from_utf8_lossy(&output.stdout);
    let (evaluations, seconds, oracle_seconds) = parse(&text)?;
    Ok(MiseRun {
        evaluations,
        seconds,
        oracle_seconds,
        mesh: rfta_io::read_mesh(out)?,
    })
}

/// `(evaluations, seconds outside the oracle, seconds in it)` from the runner's JSON line (its
/// last line).
fn parse(text: &str) -> Result<(usize, f64, f64)> {
    let line = text.lines().last().unwrap_or_default();
    let v: serde_json::Value =
        serde_json::from_str(line).with_context(|| format!("MISE's answer {line:?}"))?;
    let number = |k: &str| {
        v.get(k)
            .and_then(serde_json::Value::as_f64)
            .with_context(|| format!("MISE's answer has no {k}: {line}"))
    };
    Ok((
        number("evaluations")? as usize,
        number("seconds_outside_oracle")?,
        number("seconds_oracle")?,
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_runners_answer_is_read_and_a_broken_one_named() {
        let line = r#"{"evaluations": 47546, "seconds_outside_oracle": 0.28, "seconds_oracle": 3.1, "faces": 9000, "out": "x.obj"}"#;
        assert_eq!(
            parse(&format!("building\n{line}\n")).ok(),
            Some((47546, 0.28, 3.1))
        );
        let err = parse(r#"{"evaluations": 5}"#).err().map(|e| e.to_string());
        assert!(
            err.as_deref()
                .is_some_and(|e| e.contains("seconds_outside_oracle")),
            "{err:?}"
        );
        assert!(parse("Traceback (most recent call last)").is_err());
    }
}
