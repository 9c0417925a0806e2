//! Rules 7 to 9 of [`super`]: file and function lengths, the public constants, and import
//! circles between sibling files.

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

use anyhow::Result;

/// Most lines of a library or tool file.
const FILE_LINES: usize = 600;
/// Most lines of a library function.
const FN_LINES: usize = 100;
/// Most lines of `xtask/src` together.
const XTASK_LINES: usize = 2_000;
/// Most `pub const` items across the library crates.
const PUB_CONSTS: usize = 10;

/// Checks `files` (every Rust file of the repository), adding what breaks a rule to `problems`.
pub(super) fn check(
    root: &Path,
    files: &[std::path::PathBuf],
    problems: &mut Vec<String>,
) -> Result<()> {
    let mut xtask = 0;
    let mut consts = Vec::new();
    let mut crates: BTreeMap<String, Vec<(String, String)>> = BTreeMap::new();
    for file in files {
        let text = std::fs::read_to_string(file)?;
        let rel = file
            .strip_prefix(root)
            .unwrap_or(file)
            .display()
            .to_string();
        if rel.starts_with("xtask/src/") {
            xtask += text.lines().count();
        }
        if rel.starts_with("tools/") && rel.contains("/src/") && text.lines().count() > FILE_LINES {
            problems.push(format!(
                "{rel}: {} lines, over {FILE_LINES}",
                text.lines().count()
            ));
        }
        if let Some((krate, module)) = rel.split_once("/src/")
            && (rel.starts_with("crates/") || rel.starts_with("tools/"))
            && !module.ends_with("tests.rs")
        {
            crates
                .entry(krate.to_string())
                .or_default()
                .push((module.to_string(), code_of(&text).to_string()));
        }
        let library = rel.starts_with("crates/") && rel.contains("/src/");
        if !library || rel.ends_with("/tests.rs") {
            continue;
        }
        let code = code_of(&text);
        let n = code.lines().count();
        if n > FILE_LINES {
            problems.push(format!("{rel}: {n} lines outside tests, over {FILE_LINES}"));
        }
        for (line, name, len) in long_functions(code) {
            problems.push(format!(
                "{rel}:{line}: fn {name} is {len} lines, over {FN_LINES}"
            ));
        }
        if !rel.starts_with("crates/rfta-cli/") {
            consts.extend(pub_consts(code).map(|c| format!("{rel}: {c}")));
        }
    }
    if xtask >= XTASK_LINES {
        problems.push(format!("xtask/src: {xtask} lines, {XTASK_LINES} at most"));
    }
    if consts.len() > PUB_CONSTS {
        problems.push(format!(
            "{} `pub const` in the library crates, {PUB_CONSTS} at most:\n    {}",
            consts.len(),
            consts.join("\n    ")
        ));
    }
    for (krate, modules) in &crates {
        for (a, b) in circles(modules) {
            problems.push(format!("{krate}/src: {a} and {b} import from each other"));
        }
    }
    Ok(())
}

/// The code before the first test module.
fn code_of(text: &str) -> &str {
    text.split("#[cfg(test)]").next().unwrap_or("")
}

/// `(line, name, length)` of each function longer than [`FN_LINES`]: from its `fn` line to the
/// line that closes it at the same indentation (rustfmt's layout).
fn long_functions(code: &str) -> Vec<(usize, String, usize)> {
    let lines: Vec<&str> = code.lines().collect();
    let mut out = Vec::new();
    for (i, line) in lines.iter().enumerate() {
        let trimmed = line.trim_start();
        let indent = &line[..line.len() - trimmed.len()];
        let Some(name) = fn_name(trimmed) else {
            continue;
        };
        let close = format!("{indent}}}");
        // A declaration without a body (a trait's) ends at its `;` before any `{`.
        let Some(end) = lines[i..].iter().position(|l| {
            *l == close
                || (l.ends_with(';')
                    && !l.contains('{')
                    && l.starts_with(indent)
                    && !l[indent.len()..].starts_with(' '))
        }) else {
            continue;
        };
        if lines[i + end] == close && end + 1 > FN_LINES {
            out.push((i + 1, name.to_string(), end + 1));
        }
    }
    out
}

/// The name of the function a trimmed line starts, if it does.
fn fn_name(trimmed: &str) -> Option<&str> {
    let mut rest = trimmed;
    for prefix in [
        "pub(crate) ",
        "pub(super) ",
        "pub ",
        "const ",
        "async ",
        "unsafe ",
    ] {
        rest = rest.strip_prefix(prefix).unwrap_or(rest);
    }
    let rest = rest.strip_prefix("fn ")?;
    let end = rest.find(|c: char| !(c.is_alphanumeric() || c == '_'))?;
    Some(&rest[..end])
}

/// The `pub const NAME` items of `code` (not `pub const fn`).
fn pub_consts(code: &str) -> impl Iterator<Item = String> + '_ {
    code.lines().filter_map(|l| {
        let rest = l.trim_start().strip_prefix("pub const ")?;
        (!rest.starts_with("fn ")).then(|| rest.split(':').next().unwrap_or(rest).to_string())
    })
}

/// Pairs of sibling files (neither inside the other's module) whose code names each other's
/// module with `crate::` or `super::`.
fn circles(modules: &[(String, String)]) -> Vec<(String, String)> {
    // A file's module path: `a/b.rs` and `a/b/mod.rs` are `a::b`; `lib.rs` and `main.rs` the root.
    let path = |file: &str| -> String {
        let f = file.trim_end_matches(".rs");
        let f = f.strip_suffix("/mod").unwrap_or(f);
        if f == "lib" || f == "main" {
            String::new()
        } else {
            f.replace('/', "::")
        }
    };
    let paths: Vec<String> = modules.iter().map(|(f, _)| path(f)).collect();
    let known: BTreeSet<&str> = paths.iter().map(String::as_str).collect();
    let mut uses: Vec<BTreeSet<String>> = Vec::new();
    for ((_, text), me) in modules.iter().zip(&paths) {
        // Code only: a doc comment's link is no import.
        let code: String = text
            .lines()
            .filter(|l| !l.trim_start().starts_with("//"))
            .collect::<Vec<_>>()
            .join("\n");
        let parent = me.rsplit_once("::").map_or("", |(p, _)| p);
        let mut found = BTreeSet::new();
        for (prefix, base) in [("crate::", String::new()), ("super::", parent.to_string())] {
            for (at, _) in code.match_indices(prefix) {
                let after = &code[at + prefix.len()..];
                // `crate::{a, b::c}` names each of its paths; `crate::a::b` one.
                let paths: Vec<&str> = match after.strip_prefix('{') {
                    Some(group) => group
                        .split('}')
                        .next()
                        .unwrap_or("")
                        .split(',')
                        .map(str::trim)
                        .collect(),
                    None => vec![after],
                };
                for path in paths {
                    let rest: String = path
                        .chars()
                        .take_while(|c| c.is_alphanumeric() || *c == '_' || *c == ':')
                        .collect();
                    let mut target = base.clone();
                    for part in rest.split("::").filter(|p| !p.is_empty()) {
                        let next = if target.is_empty() {
                            part.to_string()
                        } else {
                            format!("{target}::{part}")
                        };
                        if !known.contains(next.as_str()) {
                            break;
                        }
                        target = next;
                    }
                    if !target.is_empty() && target != *me {
                        found.insert(target);
                    }
                }
            }
        }
        uses.push(found);
    }
    let inside = |a: &str, b: &str| a.is_empty() || b.starts_with(&format!("{a}::"));
    let mut out = Vec::new();
    for (i, a) in paths.iter().enumerate() {
        for (j, b) in paths.iter().enumerate().skip(i + 1) {
            if uses[i].contains(b) && uses[j].contains(a) && !inside(a, b) && !inside(b, a) {
                out.push((modules[i].0.clone(), modules[j].0.clone()));
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_long_function_is_found_and_a_short_one_is_not() {
        let body = "    let x = 1;\n".repeat(FN_LINES);
        let code = format!("fn short() {{\n}}\n\npub(crate) fn long() {{\n{body}}}\n");
        assert_eq!(
            long_functions(&code),
            vec![(4, "long".to_string(), FN_LINES + 2)]
        );
    }

    #[test]
    fn pub_const_fns_are_not_constants() {
        let code = "pub const A: u32 = 1;\n    pub const fn new() -> Self {}\npub(crate) const B: u8 = 2;\n";
        assert_eq!(pub_consts(code).collect::<Vec<_>>(), vec!["A".to_string()]);
    }

    #[test]
    fn siblings_that_import_each_other_are_a_circle() {
        let m = |f: &str, c: &str| (f.to_string(), c.to_string());
        let modules = [
            m("lib.rs", "mod a; mod b; mod c; use crate::a::x;"),
            m("a.rs", "use crate::{b::y, c};"),
            m("b.rs", "use crate::a::x;"),
            m("c/mod.rs", "use crate::c::d::z;"),
            m("c/d.rs", "use super::w;"),
        ];
        assert_eq!(
            circles(&modules),
            vec![("a.rs".to_string(), "b.rs".to_string())]
        );
    }
}
