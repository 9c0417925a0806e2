//! WGSL validation with naga: every `shaders/*.wgsl` must parse and validate.

use std::path::Path;

use anyhow::{Result, bail};

/// Parses and validates one WGSL source; the error is naga's report with file and line.
pub(crate) fn validate_wgsl(name: &str, src: &str) -> Result<(), String> {
    let module =
        naga::front::wgsl::parse_str(src).map_err(|e| e.emit_to_string_with_path(src, name))?;
    naga::valid::Validator::new(
        naga::valid::ValidationFlags::all(),
        naga::valid::Capabilities::default(),
    )
    .validate(&module)
    .map_err(|e| e.emit_to_string_with_path(src, name))?;
    Ok(())
}

pub(crate) fn run(root: &Path) -> Result<()> {
    let dir = root.join("shaders");
    let mut files: Vec<_> = std::fs::read_dir(&dir)
        .map(|rd| {
            rd.filter_map(|e| e.ok())
                .map(|e| e.path())
                .filter(|p| p.extension().is_some_and(|x| x == "wgsl"))
                .collect()
        })
        .unwrap_or_default();
    files.sort();
    let mut failures = 0;
    for path in &files {
        let name = path
            .strip_prefix(root)
            .unwrap_or(path)
            .display()
            .to_string();
        let src = std::fs::read_to_string(path)?;
        match validate_wgsl(&name, &src) {
            Ok(()) => println!("ok    {name}"),
            Err(report) => {
                failures += 1;
                eprintln!("error {name}\n{report}");
            }
        }
    }
    if failures > 0 {
        bail!("{failures} of {} shaders failed validation", files.len());
    }
    println!("{} shaders valid", files.len());
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn accepts_a_valid_compute_shader_and_reports_errors_with_lines() {
        let good = "@group(0) @binding(0) var<storage, read_write> out: array<u32>;\n\
                    @compute @workgroup_size(64) fn main(@builtin(global_invocation_id) id: vec3<u32>) {\n\
                    out[id.x] = id.x * id.x + 7u;\n}\n";
        assert!(validate_wgsl("good.wgsl", good).is_ok());
        // A type error: f32 assigned to a u32 array.
        let bad = good.replace("id.x * id.x + 7u", "1.5");
        let report = validate_wgsl("bad.wgsl", &bad).expect_err("type error");
        assert!(report.contains("bad.wgsl:3"), "{report}");
    }

    #[test]
    fn repository_shaders_are_valid() {
        run(&crate::workspace_root()).expect("shaders validate");
    }
}
