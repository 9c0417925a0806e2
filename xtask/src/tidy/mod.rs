//! Repository rules, checked by `cargo xtask tidy` and by `cargo test` (the test below):
//!
//! 1. every workspace crate sets `[lints] workspace = true` and has a description;
//! 2. every crate under `crates/` has a README.md;
//! 3. every Rust file starts with a `//!` doc comment;
//! 4. each crate's normal dependencies are among those ARCHITECTURE.md allows (the
//!    `tidy:deps` block), and every crate is listed there;
//! 5. exactly one version of glam is locked (obvhs' range and ours must meet);
//! 6. library code (`crates/*/src`, outside tests, testkit and the CLI) has no `.unwrap()`,
//!    `.expect(`, `println!` or `eprintln!`;
//! 7. no file of `crates/*/src` is over 600 lines and no function there over 100 (test modules
//!    aside), no file of `tools/` over 600 lines, and `xtask/src` stays under 2,000 lines;
//! 8. at most 10 `pub const` across the library crates (tuning constants are crate-private or
//!    fields of the parameters they belong to);
//! 9. no two sibling files of a crate import from each other (a circle a newcomer walks).

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};
use std::process::Command;

use anyhow::{Context, Result, bail};

mod sizes;

pub(crate) fn run(root: &Path) -> Result<()> {
    let mut problems = Vec::new();
    let packages = workspace_packages(root)?;
    let allowed = allowed_deps(root)?;
    for pkg in &packages {
        let manifest = std::fs::read_to_string(&pkg.manifest)?;
        if !manifest.contains("[lints]\nworkspace = true") {
            problems.push(format!(
                "{}: Cargo.toml lacks `[lints] workspace = true`",
                pkg.name
            ));
        }
        if !manifest.contains("description =") {
            problems.push(format!("{}: Cargo.toml lacks a description", pkg.name));
        }
        let dir = pkg.manifest.parent().unwrap_or(root);
        if dir.starts_with(root.join("crates")) && !dir.join("README.md").is_file() {
            problems.push(format!("{}: no README.md", pkg.name));
        }
        match allowed.get(&pkg.name) {
            None => problems.push(format!(
                "{}: missing from the dependency graph in ARCHITECTURE.md",
                pkg.name
            )),
            Some(ok) => {
                for dep in &pkg.normal_deps {
                    if !ok.contains(dep) {
                        problems.push(format!(
                            "{}: depends on {dep}, which ARCHITECTURE.md does not allow (add the edge there if intended)",
                            pkg.name
                        ));
                    }
                }
            }
        }
    }
    for file in rust_files(root) {
        let text = std::fs::read_to_string(&file)?;
        let rel = file
            .strip_prefix(root)
            .unwrap_or(&file)
            .display()
            .to_string();
        if !text.trim_start().starts_with("//!") {
            problems.push(format!("{rel}: does not start with a `//!` doc comment"));
        }
        let library = rel.starts_with("crates/")
            && rel.contains("/src/")
            && !rel.starts_with("crates/rfta-cli/")
            && !rel.starts_with("crates/rfta-testkit/")
            && !rel.ends_with("/tests.rs");
        if library {
            // Stop at the first test module: tests may unwrap.
            let code = text.split("#[cfg(test)]").next().unwrap_or("");
            for (i, line) in code.lines().enumerate() {
                let l = line.trim_start();
                if l.starts_with("//") {
                    continue;
                }
                for banned in [".unwrap()", ".expect(", "println!", "eprintln!"] {
                    if l.contains(banned) {
                        problems.push(format!("{rel}:{}: `{banned}` in library code", i + 1));
                    }
                }
            }
        }
    }
    sizes::check(root, &rust_files(root), &mut problems)?;
    let lock = std::fs::read_to_string(root.join("Cargo.lock")).context("Cargo.lock")?;
    let n_glam = lock.matches("\nname = \"glam\"\n").count();
    if n_glam != 1 {
        problems.push(format!(
            "Cargo.lock has {n_glam} versions of glam; exactly one is allowed"
        ));
    }
    if problems.is_empty() {
        println!("tidy: {} crates, all rules hold", packages.len());
        Ok(())
    } else {
        bail!(
            "tidy found {} problems:\n  {}",
            problems.len(),
            problems.join("\n  ")
        )
    }
}

struct Package {
    name: String,
    manifest: PathBuf,
    normal_deps: Vec<String>,
}

fn workspace_packages(root: &Path) -> Result<Vec<Package>> {
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let out = Command::new(cargo)
        .args([
            "metadata",
            "--format-version",
            "1",
            "--no-deps",
            "--offline",
        ])
        .current_dir(root)
        .output()
        .context("cannot run cargo metadata")?;
    if !out.status.success() {
        bail!(
            "cargo metadata failed: {}",
            String::from_utf8_lossy(&out.stderr)
        );
    }
    let meta: serde_json::Value = serde_json::from_slice(&out.stdout)?;
    let pkgs = meta["packages"]
        .as_array()
        .context("cargo metadata: no packages")?;
    Ok(pkgs
        .iter()
        .map(|p| Package {
            name: p["name"].as_str().unwrap_or_default().to_string(),
            manifest: PathBuf::from(p["manifest_path"].as_str().unwrap_or_default()),
            normal_deps: p["dependencies"]
                .as_array()
                .map(|deps| {
                    deps.iter()
                        .filter(|d| d["kind"].is_null())
                        .filter_map(|d| d["name"].as_str().map(str::to_string))
                        .collect()
                })
                .unwrap_or_default(),
        })
        .collect())
}

/// The `name: dep, dep` lines of the fenced block after `<!-- tidy:deps -->` in ARCHITECTURE.md.
fn allowed_deps(root: &Path) -> Result<BTreeMap<String, BTreeSet<String>>> {
    let text = std::fs::read_to_string(root.join("ARCHITECTURE.md")).context("ARCHITECTURE.md")?;
    let start = text
        .find("<!-- tidy:deps -->")
        .context("ARCHITECTURE.md has no <!-- tidy:deps --> block")?;
    let block = text[start..]
        .split("```")
        .nth(1)
        .context("the tidy:deps marker must precede a fenced block")?;
    let mut map = BTreeMap::new();
    for line in block
        .lines()
        .map(str::trim)
        .filter(|l| !l.is_empty() && !l.starts_with('#'))
    {
        let Some((name, deps)) = line.split_once(':') else {
            continue;
        };
        let deps = deps
            .split(',')
            .map(str::trim)
            .filter(|d| !d.is_empty() && *d != "-")
            .map(str::to_string)
            .collect();
        map.insert(name.trim().to_string(), deps);
    }
    Ok(map)
}

fn rust_files(root: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    let mut stack = vec![
        root.join("crates"),
        root.join("tests"),
        root.join("tools"),
        root.join("xtask"),
    ];
    while let Some(dir) = stack.pop() {
        let Ok(rd) = std::fs::read_dir(&dir) else {
            continue;
        };
        for e in rd.filter_map(|e| e.ok()) {
            let p = e.path();
            if p.is_dir() {
                stack.push(p);
            } else if p.extension().is_some_and(|x| x == "rs") {
                out.push(p);
            }
        }
    }
    out.sort();
    out
}

#[cfg(test)]
mod tests {
    #[test]
    fn tidy() {
        super::run(&crate::workspace_root()).expect("tidy");
    }
}
