//! Helpers for line-oriented text formats.

use crate::error::{ParseError, ParseResult};

/// The file as UTF-8 text (a clear error otherwise).
/// The text of a file, without the UTF-8 byte order mark that spreadsheet programs put first
/// (kept, it made the first token unreadable, and a headerless file lost its first row).
pub(crate) fn as_text(bytes: &[u8]) -> ParseResult<&str> {
    let bytes = bytes.strip_prefix("\u{feff}".as_bytes()).unwrap_or(bytes);
    std::str::from_utf8(bytes).map_err(|e| {
        ParseError::new(format!(
            "not a text file: invalid UTF-8 at byte {}",
            e.valid_up_to()
        ))
    })
}

/// Parses a finite-or-not float token; `what` names it in the error.
pub(crate) fn parse_f64(tok: &str, line: usize, what: &str) -> ParseResult<f64> {
    tok.parse::<f64>()
        .map_err(|_| ParseError::at_line(line, format!("{what}: '{tok}' is not a number")))
}

/// Parses a non-negative integer count.
pub(crate) fn parse_count(tok: &str, line: usize, what: &str) -> ParseResult<usize> {
    tok.parse::<usize>().map_err(|_| {
        ParseError::at_line(
            line,
            format!("{what}: '{tok}' is not a non-negative integer"),
        )
    })
}

/// Lines with their 1-based numbers, comments (from `#`) and surrounding blanks removed,
/// empty lines skipped.
pub(crate) fn content_lines(text: &str) -> impl Iterator<Item = (usize, &str)> {
    text.lines().enumerate().filter_map(|(i, l)| {
        let l = l.split('#').next().unwrap_or("").trim();
        (!l.is_empty()).then_some((i + 1, l))
    })
}

/// Splits a polygon into a triangle fan; fewer than three corners is an error.
pub(crate) fn fan(corners: &[u32], line: usize, faces: &mut Vec<[u32; 3]>) -> ParseResult<()> {
    if corners.len() < 3 {
        return Err(ParseError::at_line(
            line,
            format!("a face needs at least 3 vertices, found {}", corners.len()),
        ));
    }
    for k in 1..corners.len() - 1 {
        faces.push([corners[0], corners[k], corners[k + 1]]);
    }
    Ok(())
}
