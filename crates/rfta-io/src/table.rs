//! CSV tables with a header of column names, as `rfta batch` reads its manifests and status
//! files and spreadsheet programs write them: fields separated by commas, RFC 4180 quoting
//! (a field in double quotes may hold commas; `""` is a quote), an optional UTF-8 byte order
//! mark, `\n` or `\r\n` line ends.
//!
//! ```
//! use rfta_io::table::{decode_table, join_csv};
//! let t = decode_table(b"input,Output\na.npy,\"b,1.obj\"\n\n", "m.csv".as_ref()).expect("a table");
//! assert_eq!(t.columns, ["input", "output"]);
//! assert_eq!(t.rows.len(), 1); // blank lines at the end are not rows
//! assert_eq!(t.get(&t.rows[0], "output"), Some("b,1.obj"));
//! assert_eq!(join_csv(&t.rows[0].fields), "a.npy,\"b,1.obj\"");
//! ```

use std::path::Path;

use crate::error::{ParseError, ParseResult};
use crate::{Result, read_bytes};

/// A table: its column names and its rows.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Table {
    /// The header's names, trimmed and in lower case, each once.
    pub columns: Vec<String>,
    /// The lines after the header, blank ones included (they keep later rows' numbers), blank
    /// lines at the end of the file left out.
    pub rows: Vec<Row>,
}

/// One line of a [`Table`].
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Row {
    /// The line number in the file (1 is the header).
    pub line: usize,
    /// The fields as written (quotes resolved, not trimmed); one empty field for a blank line.
    pub fields: Vec<String>,
    /// Whether the line ended with a line break. A table written a row at a time ends each row
    /// with one, so a last line without it was cut short (a killed writer).
    pub complete: bool,
}

impl Row {
    /// Whether the line holds nothing but white space.
    pub fn is_blank(&self) -> bool {
        self.fields.iter().all(|f| f.trim().is_empty())
    }
}

impl Table {
    /// The index of column `name` (lower case).
    pub fn column(&self, name: &str) -> Option<usize> {
        self.columns.iter().position(|c| c == name)
    }

    /// `row`'s field in column `name`, trimmed; `None` when the column or the field is missing
    /// or empty.
    pub fn get<'a>(&self, row: &'a Row, name: &str) -> Option<&'a str> {
        let i = self.column(name)?;
        row.fields
            .get(i)
            .map(|f| f.trim())
            .filter(|f| !f.is_empty())
    }
}

/// Reads the table at `path` (through the crate's bounded reader).
///
/// # Errors
/// [`crate::Error::Io`] if it cannot be read; as [`decode_table`].
pub fn read_table(path: &Path) -> Result<Table> {
    decode_table(&read_bytes(path)?, path)
}

/// Decodes a table; `path` names it in errors.
///
/// # Errors
/// [`crate::Error::Parse`] for bytes that are not UTF-8 text, a file without a header line, or
/// a header that names a column twice (which of the two a row means is no reader's guess).
pub fn decode_table(bytes: &[u8], path: &Path) -> Result<Table> {
    parse(bytes).map_err(|e| e.at(path))
}

fn parse(bytes: &[u8]) -> ParseResult<Table> {
    let text = crate::text::as_text(bytes)?;
    let mut lines = text.split_inclusive('\n').enumerate();
    let Some((_, head)) = lines.next().filter(|(_, h)| !h.trim().is_empty()) else {
        return Err(ParseError::new("no header line (column names)"));
    };
    let mut columns: Vec<String> = Vec::new();
    for name in split_csv(head) {
        let name = name.trim().to_ascii_lowercase();
        if columns.contains(&name) {
            return Err(ParseError::at_line(
                1,
                format!("the header names the column '{name}' twice"),
            ));
        }
        columns.push(name);
    }
    let mut rows: Vec<Row> = lines
        .map(|(i, l)| Row {
            line: i + 1,
            fields: split_csv(l),
            complete: l.ends_with('\n'),
        })
        .collect();
    while rows.last().is_some_and(Row::is_blank) {
        rows.pop();
    }
    Ok(Table { columns, rows })
}

/// Splits one CSV line (RFC 4180 quoting; the line end, if any, dropped).
pub fn split_csv(line: &str) -> Vec<String> {
    let mut fields = Vec::new();
    let mut field = String::new();
    let mut quoted = false;
    let mut chars = line.trim_end_matches(['\r', '\n']).chars().peekable();
    while let Some(c) = chars.next() {
        match (c, quoted) {
            ('"', true) if chars.peek() == Some(&'"') => {
                field.push('"');
                chars.next();
            }
            ('"', true) => quoted = false,
            ('"', false) if field.trim().is_empty() => {
                field.clear();
                quoted = true;
            }
            (',', false) => fields.push(std::mem::take(&mut field)),
            _ => field.push(c),
        }
    }
    fields.push(field);
    fields
}

/// One CSV line (no line end), quoting the fields that need it; line breaks inside a field
/// become spaces.
pub fn join_csv(fields: &[String]) -> String {
    fields
        .iter()
        .map(|f| {
            let f = f.replace(['\n', '\r'], " ");
            if f.contains([',', '"']) {
                format!("\"{}\"", f.replace('"', "\"\""))
            } else {
                f
            }
        })
        .collect::<Vec<_>>()
        .join(",")
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn table(text: &str) -> Result<Table> {
        decode_table(text.as_bytes(), Path::new("t.csv"))
    }

    #[test]
    fn a_byte_order_mark_blank_lines_and_cut_lines() {
        let t = table("\u{feff}Input, output\r\na,b\r\n\nc,d\n\n\n").expect("table");
        assert_eq!(t.columns, ["input", "output"]);
        // The blank line between rows stays a row; those at the end do not.
        assert_eq!(t.rows.len(), 3);
        assert!(t.rows[1].is_blank() && t.rows[1].line == 3);
        assert_eq!(t.get(&t.rows[2], "output"), Some("d"));
        assert!(t.rows.iter().all(|r| r.complete));
        let cut = table("row,status\n0,ok\n1,o").expect("table");
        assert_eq!(
            cut.rows.iter().map(|r| r.complete).collect::<Vec<_>>(),
            [true, false]
        );
    }

    #[test]
    fn a_column_named_twice_and_a_missing_header_are_refused() {
        let e = table("input,output,Output\n").expect_err("twice");
        assert!(e.to_string().contains("'output' twice"), "{e}");
        assert!(table("").is_err());
        assert!(table("\n\n").is_err());
    }

    proptest! {
        /// Any fields (without line breaks) come back from their CSV line as they were.
        #[test]
        fn csv_lines_round_trip(fields in proptest::collection::vec("[^\r\n]{0,12}", 1..8)) {
            prop_assert_eq!(split_csv(&join_csv(&fields)), fields);
        }
    }

    #[test]
    fn quoted_fields() {
        assert_eq!(split_csv("x, \"1,2\" ,y"), ["x", "1,2 ", "y"]);
        assert_eq!(split_csv("\"say \"\"hi\"\"\",\n"), ["say \"hi\"", ""]);
    }
}
