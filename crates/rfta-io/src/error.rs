//! Errors of the I/O crate: each names the file and what is wrong with it.

use std::path::PathBuf;

/// What went wrong reading or writing a file.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// The operating system refused (missing file, permissions, full disk).
    #[error("{}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The cause.
        source: std::io::Error,
    },
    /// The file's contents are malformed.
    #[error("{}: {}{detail}", path.display(), line.map(|l| format!("line {l}: ")).unwrap_or_default())]
    Parse {
        /// The file.
        path: PathBuf,
        /// The 1-based line, for text formats.
        line: Option<usize>,
        /// What is wrong.
        detail: String,
    },
    /// The extension names no supported format.
    #[error("{}: unsupported file type; expected {expected}", path.display())]
    UnknownFormat {
        /// The file.
        path: PathBuf,
        /// What would have been accepted.
        expected: &'static str,
    },
    /// The data parsed but is not valid (e.g. NaN values, a face index out of range).
    #[error("{}: {source}", path.display())]
    Geom {
        /// The file.
        path: PathBuf,
        /// The cause.
        source: rfta_geom::Error,
    },
}

/// Shorthand for results whose error is this crate's [`Error`].
pub type Result<T, E = Error> = std::result::Result<T, E>;

/// A parse failure before the file name is known.
#[derive(Debug)]
pub(crate) struct ParseError {
    pub(crate) line: Option<usize>,
    pub(crate) detail: String,
}

impl ParseError {
    pub(crate) fn new(detail: impl Into<String>) -> Self {
        Self {
            line: None,
            detail: detail.into(),
        }
    }

    pub(crate) fn at_line(line: usize, detail: impl Into<String>) -> Self {
        Self {
            line: Some(line),
            detail: detail.into(),
        }
    }

    pub(crate) fn at(self, path: &std::path::Path) -> Error {
        Error::Parse {
            path: path.to_path_buf(),
            line: self.line,
            detail: self.detail,
        }
    }
}

pub(crate) type ParseResult<T> = std::result::Result<T, ParseError>;
