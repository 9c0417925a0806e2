//! NumPy `.npy` arrays of floats (format versions 1.0, 2.0 and 3.0).
//!
//! Reads `float32` and `float64` in either byte order, C or Fortran order, any shape; writes
//! little-endian `float64` in C order. Specification: NumPy Enhancement Proposal 1
//! ("A simple file format for NumPy arrays").

use std::io::Write;

use crate::error::{ParseError, ParseResult};

/// An array read from a `.npy` file, converted to `f64` in C order (last axis fastest).
#[derive(Debug, Clone, PartialEq)]
pub struct NpyArray {
    /// The shape.
    pub shape: Vec<usize>,
    /// The values in C order.
    pub data: Vec<f64>,
}

/// Parses the bytes of a `.npy` file.
///
/// # Errors
/// A message saying what is wrong: bad magic, unsupported dtype (only float32/float64), a
/// malformed header, or a data section shorter or longer than the shape requires.
pub fn parse_npy(bytes: &[u8]) -> Result<NpyArray, String> {
    parse(bytes).map_err(|e| e.detail)
}

/// What the header of a `.npy` file says.
pub(crate) struct Header {
    pub(crate) shape: Vec<usize>,
    big: bool,
    size: usize,
    fortran: bool,
    descr: String,
    /// Offset of the data section.
    data_start: usize,
    /// Values in the array (the product of the shape).
    pub(crate) len: usize,
}

/// Parses the header of a `.npy` file from its first bytes (the whole file, or a prefix that
/// holds the header).
pub(crate) fn parse_header(bytes: &[u8]) -> ParseResult<Header> {
    if !bytes.starts_with(b"\x93NUMPY") {
        return Err(ParseError::new(
            "not a .npy file: missing the '\\x93NUMPY' magic",
        ));
    }
    let major = *bytes
        .get(6)
        .ok_or_else(|| ParseError::new("truncated .npy header"))?;
    let (header_len, start): (usize, usize) = match major {
        1 => {
            let b = bytes
                .get(8..10)
                .ok_or_else(|| ParseError::new("truncated .npy header"))?;
            (u16::from_le_bytes([b[0], b[1]]) as usize, 10)
        }
        2 | 3 => {
            let b = bytes
                .get(8..12)
                .ok_or_else(|| ParseError::new("truncated .npy header"))?;
            (u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as usize, 12)
        }
        v => {
            return Err(ParseError::new(format!(
                "unsupported .npy format version {v}"
            )));
        }
    };
    let header = bytes
        .get(start..start.saturating_add(header_len))
        .ok_or_else(|| ParseError::new("truncated .npy header"))?;
    let header =
        std::str::from_utf8(header).map_err(|_| ParseError::new("the .npy header is not text"))?;
    // A key given twice: numpy takes the last, a first-match reader the first; neither guess is
    // safe for a shape.
    for key in ["descr", "fortran_order", "shape"] {
        if header.matches(&format!("'{key}'")).count()
            + header.matches(&format!("\"{key}\"")).count()
            > 1
        {
            return Err(ParseError::new(format!(
                "the .npy header names '{key}' twice"
            )));
        }
    }
    let descr = dict_value(header, "descr")
        .ok_or_else(|| ParseError::new("the .npy header has no 'descr'"))?;
    let descr = descr.trim().trim_matches(|c| c == '\'' || c == '"');
    let (big, size) = match descr {
        "<f8" | "=f8" | "f8" => (false, 8),
        ">f8" => (true, 8),
        "<f4" | "=f4" | "f4" => (false, 4),
        ">f4" => (true, 4),
        other => {
            return Err(ParseError::new(format!(
                "unsupported dtype '{other}': expected float32 ('<f4') or float64 ('<f8'); convert with arr.astype(np.float64)"
            )));
        }
    };
    let fortran = match dict_value(header, "fortran_order").map(str::trim) {
        Some("True") => true,
        Some("False") => false,
        _ => {
            return Err(ParseError::new(
                "the .npy header has no valid 'fortran_order'",
            ));
        }
    };
    let shape_text = dict_value(header, "shape")
        .ok_or_else(|| ParseError::new("the .npy header has no 'shape'"))?;
    let shape = parse_shape(shape_text)?;
    let n = shape
        .iter()
        .try_fold(1usize, |acc, &d| acc.checked_mul(d))
        .ok_or_else(|| ParseError::new(format!("shape {shape:?} is too large")))?;
    Ok(Header {
        shape,
        big,
        size,
        fortran,
        descr: descr.to_string(),
        data_start: start + header_len,
        len: n,
    })
}

pub(crate) fn parse(bytes: &[u8]) -> ParseResult<NpyArray> {
    let Header {
        shape,
        big,
        size,
        fortran,
        descr,
        data_start,
        len: n,
    } = parse_header(bytes)?;
    let data = &bytes[data_start..];
    let expected = n
        .checked_mul(size)
        .ok_or_else(|| ParseError::new(format!("shape {shape:?} is too large")))?;
    if data.len() != expected {
        return Err(ParseError::new(format!(
            "data section has {} bytes but shape {shape:?} of {descr} needs {expected}{}",
            data.len(),
            if data.len() < expected {
                " (truncated file)"
            } else {
                ""
            }
        )));
    }
    let raw: Vec<f64> = data
        .chunks_exact(size)
        .map(|c| {
            let mut b = [0u8; 8];
            b[..size].copy_from_slice(c);
            if big {
                b[..size].reverse();
            }
            if size == 8 {
                f64::from_le_bytes(b)
            } else {
                f32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64
            }
        })
        .collect();
    let data = if fortran && shape.len() > 1 {
        fortran_to_c(&raw, &shape)
    } else {
        raw
    };
    Ok(NpyArray { shape, data })
}

/// The text of `key`'s value in the header's Python dict literal.
fn dict_value<'a>(header: &'a str, key: &str) -> Option<&'a str> {
    let pat_a = format!("'{key}'");
    let pat_b = format!("\"{key}\"");
    let at = header
        .find(&pat_a)
        .map(|i| i + pat_a.len())
        .or_else(|| header.find(&pat_b).map(|i| i + pat_b.len()))?;
    let rest = header[at..].trim_start().strip_prefix(':')?;
    let rest = rest.trim_start();
    let end = if rest.starts_with('(') {
        rest.find(')')? + 1
    } else {
        rest.find([',', '}']).unwrap_or(rest.len())
    };
    Some(&rest[..end])
}

fn parse_shape(text: &str) -> ParseResult<Vec<usize>> {
    let inner = text
        .trim()
        .strip_prefix('(')
        .and_then(|t| t.strip_suffix(')'))
        .ok_or_else(|| ParseError::new(format!("shape '{text}' is not a tuple")))?;
    inner
        .split(',')
        .map(str::trim)
        .filter(|t| !t.is_empty())
        .map(|t| {
            t.trim_end_matches('L')
                .parse::<usize>()
                .map_err(|_| ParseError::new(format!("shape entry '{t}' is not an integer")))
        })
        .collect()
}

/// Reorders a Fortran-order (first axis fastest) array into C order (last axis fastest).
fn fortran_to_c(raw: &[f64], shape: &[usize]) -> Vec<f64> {
    let nd = shape.len();
    let mut f_strides = vec![1usize; nd];
    for a in 1..nd {
        f_strides[a] = f_strides[a - 1] * shape[a - 1];
    }
    let mut out = Vec::with_capacity(raw.len());
    let mut idx = vec![0usize; nd];
    for _ in 0..raw.len() {
        out.push(
            raw[idx
                .iter()
                .zip(&f_strides)
                .map(|(i, s)| i * s)
                .sum::<usize>()],
        );
        // Advance the C-order multi-index.
        for a in (0..nd).rev() {
            idx[a] += 1;
            if idx[a] < shape[a] {
                break;
            }
            idx[a] = 0;
        }
    }
    out
}

/// Writes a C-order little-endian float64 array (format version 1.0).
///
/// # Errors
/// Any error of the writer; `InvalidInput` if `data` does not match `shape`.
pub fn write_npy_f64(w: &mut dyn Write, shape: &[usize], data: &[f64]) -> std::io::Result<()> {
    if shape.iter().product::<usize>() != data.len() {
        return Err(std::io::Error::new(
            std::io::ErrorKind::InvalidInput,
            "data length does not match the shape",
        ));
    }
    let dims: Vec<String> = shape.iter().map(|d| d.to_string()).collect();
    let shape_text = if dims.len() == 1 {
        format!("({},)", dims[0])
    } else {
        format!("({})", dims.join(", "))
    };
    let mut header = format!("{{'descr': '<f8', 'fortran_order': False, 'shape': {shape_text}, }}");
    // Pad with spaces so that magic + version + length + header + newline is a multiple of 64.
    let unpadded = 10 + header.len() + 1;
    header.push_str(&" ".repeat((64 - unpadded % 64) % 64));
    header.push('\n');
    w.write_all(b"\x93NUMPY\x01\x00")?;
    w.write_all(&(header.len() as u16).to_le_bytes())?;
    w.write_all(header.as_bytes())?;
    for v in data {
        w.write_all(&v.to_le_bytes())?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn npy_bytes(descr: &str, fortran: bool, shape: &str, payload: &[u8]) -> Vec<u8> {
        let header = format!(
            "{{'descr': '{descr}', 'fortran_order': {}, 'shape': {shape}, }}\n",
            if fortran { "True" } else { "False" }
        );
        let mut b = b"\x93NUMPY\x01\x00".to_vec();
        b.extend_from_slice(&(header.len() as u16).to_le_bytes());
        b.extend_from_slice(header.as_bytes());
        b.extend_from_slice(payload);
        b
    }

    #[test]
    fn reads_every_supported_dtype_and_order() {
        // Values 0..6 of a (2, 3) array; Fortran order stores columns first: 0 3 1 4 2 5.
        let c_order: Vec<u8> = (0..6).flat_map(|v| (v as f32).to_le_bytes()).collect();
        let a = parse(&npy_bytes("<f4", false, "(2, 3)", &c_order)).expect("valid");
        assert_eq!(
            (a.shape.clone(), a.data.clone()),
            (vec![2, 3], vec![0.0, 1.0, 2.0, 3.0, 4.0, 5.0])
        );
        let f_order: Vec<u8> = [0, 3, 1, 4, 2, 5]
            .iter()
            .flat_map(|&v| (v as f64).to_be_bytes())
            .collect();
        let b = parse(&npy_bytes(">f8", true, "(2, 3)", &f_order)).expect("valid");
        assert_eq!(b.data, a.data);
        // 3-D Fortran order: element (i, j, k) of shape (2, 3, 4) at i + 2 j + 6 k.
        let shape = [2usize, 3, 4];
        let mut f = [0.0; 24];
        for i in 0..2 {
            for j in 0..3 {
                for k in 0..4 {
                    f[i + 2 * j + 6 * k] = (100 * i + 10 * j + k) as f64;
                }
            }
        }
        let payload: Vec<u8> = f.iter().flat_map(|v| v.to_le_bytes()).collect();
        let c = parse(&npy_bytes("<f8", true, "(2, 3, 4)", &payload)).expect("valid");
        assert_eq!(c.shape, shape);
        let c_index = |i: usize, j: usize, k: usize| (i * 3 + j) * 4 + k;
        assert_eq!(c.data[c_index(1, 2, 3)], 123.0);
        assert_eq!(c.data[c_index(0, 1, 2)], 12.0);
    }

    #[test]
    fn round_trip_and_header_alignment() {
        let mut out = Vec::new();
        write_npy_f64(
            &mut out,
            &[2, 2, 2],
            &[1.5, -2.0, 3.0, 4.0, 5.0, 6.0, 7.0, f64::MIN_POSITIVE],
        )
        .expect("write");
        assert_eq!((10 + u16::from_le_bytes([out[8], out[9]]) as usize) % 64, 0);
        let back = parse(&out).expect("read");
        assert_eq!(back.shape, vec![2, 2, 2]);
        assert_eq!(back.data[7], f64::MIN_POSITIVE);
    }

    #[test]
    fn malformed_files_get_clear_errors() {
        let ok: Vec<u8> = (0..8).flat_map(|v| (v as f64).to_le_bytes()).collect();
        let cases: Vec<(Vec<u8>, &str)> = vec![
            (b"NUMPY".to_vec(), "magic"),
            (b"\x93NUMPY\x01".to_vec(), "truncated"),
            (
                npy_bytes("<i8", false, "(2, 2, 2)", &ok),
                "unsupported dtype",
            ),
            (
                npy_bytes("<f8", false, "(2, 2, 2)", &ok[..60]),
                "truncated file",
            ),
            (npy_bytes("<f8", false, "(2, 2)", &ok), "needs 32"),
            (npy_bytes("<f8", false, "(2, x)", &ok), "not an integer"),
            (
                npy_bytes("<f8", false, "(99999999999, 99999999999, 99999999999)", &ok),
                "too large",
            ),
        ];
        for (bytes, needle) in cases {
            let err = parse(&bytes).expect_err(needle).detail;
            assert!(err.contains(needle), "'{err}' should mention '{needle}'");
        }
    }
}
