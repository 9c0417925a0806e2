//! SDF grids as OpenEXR images.
//!
//! OpenEXR has no 3-D images (deep data is something else), so a volume of shape `(nx, ny, nz)`
//! is stored as one layer whose image is `nz` pixels wide and `nx * ny` pixels high, with a
//! single float32 channel named `sdf`. Pixel `(x = k, y = i * ny + j)` holds `S[i, j, k]`: the
//! image's row-major pixel order is exactly the grid's C order, and the picture shows `nx`
//! stacked tiles of `ny` rows each (one tile per x slice). Attributes on the layer:
//!
//! | attribute | type | meaning |
//! |---|---|---|
//! | `rfta_dims` | v3i | `(nx, ny, nz)` (required) |
//! | `rfta_origin_x`, `_y`, `_z` | double | position of sample `(0, 0, 0)` (optional) |
//! | `rfta_spacing_x`, `_y`, `_z` | double | distance between samples per axis (optional) |
//!
//! Values are stored as float32 (about 7 significant digits); use `.npy` for float64.

use std::collections::HashMap;
use std::io::Cursor;

use exr::prelude::*;
use rfta_geom::{Grid, glam::DVec3};

use crate::error::{ParseError, ParseResult};

/// A grid read from an EXR file: its shape, the optional origin/spacing, and the values.
pub(crate) struct ExrVolume {
    pub(crate) dims: [usize; 3],
    pub(crate) origin_spacing: Option<(DVec3, DVec3)>,
    pub(crate) values: Vec<f64>,
}

/// The most pixel data a file of `len` bytes may declare: DEFLATE, the strongest of OpenEXR's
/// lossless codecs, expands at most 1032 to 1 (RLE 64 to 1, PIZ's Huffman stage 16 to 1).
fn max_declared_bytes(len: usize) -> u64 {
    (len as u64).saturating_mul(1100).saturating_add(64 << 20)
}

/// The first layer of an EXR file and its SDF channel (named `sdf`, or the only one), after
/// refusing headers that declare more pixels than the file can hold.
fn first_layer(bytes: &[u8]) -> ParseResult<(Layer<AnyChannels<FlatSamples>>, usize)> {
    // The exr crate allocates every declared layer before reading a byte of pixel data: a
    // 200-byte header declaring a 40 GB image must be refused from the header.
    let meta = exr::meta::MetaData::read_from_buffered(Cursor::new(bytes), false)
        .map_err(|e| ParseError::new(format!("invalid OpenEXR file: {e}")))?;
    let declared = meta.headers.iter().fold(0u64, |acc, h| {
        let layer = (h.layer_size.width() as u64)
            .saturating_mul(h.layer_size.height() as u64)
            .saturating_mul(h.channels.bytes_per_pixel as u64);
        acc.saturating_add(layer)
    });
    if declared > max_declared_bytes(bytes.len()) {
        return Err(ParseError::new(format!(
            "the OpenEXR header declares {declared} bytes of pixels, more than a {}-byte file can hold (truncated or corrupt)",
            bytes.len()
        )));
    }
    let image = read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .all_layers()
        .all_attributes()
        .from_buffered(Cursor::new(bytes))
        .map_err(|e| ParseError::new(format!("invalid OpenEXR file: {e}")))?;
    let layer = image
        .layer_data
        .into_iter()
        .next()
        .ok_or_else(|| ParseError::new("the EXR file has no layers"))?;
    let channels = &layer.channel_data.list;
    let channel = channels
        .iter()
        .position(|c| c.name.as_slice() == b"sdf")
        .or_else(|| (channels.len() == 1).then_some(0))
        .ok_or_else(|| {
            ParseError::new(format!(
                "the EXR layer has {} channels and none is named 'sdf'",
                channels.len()
            ))
        })?;
    Ok((layer, channel))
}

/// Whether the EXR file is a 2D image (its first layer has no `rfta_dims`), from its header.
pub(crate) fn is_image(header: impl std::io::Read) -> ParseResult<bool> {
    let meta = exr::meta::MetaData::read_from_buffered(header, false)
        .map_err(|e| ParseError::new(format!("invalid OpenEXR file: {e}")))?;
    Ok(meta.headers.first().is_some_and(|h| {
        !h.own_attributes
            .other
            .keys()
            .any(|k| k.as_slice() == b"rfta_dims")
    }))
}

/// A 2D grid from an EXR image without `rfta_dims`: its SDF channel's values, pixel
/// `(x = col, y = row)` at grid point `(col, height - 1 - row)` (image up is `+y`), in the 2D
/// grids' C order. Returns the dims `[width, height]` and the values.
pub(crate) fn parse_image(bytes: &[u8]) -> ParseResult<([usize; 2], Vec<f64>)> {
    let (layer, channel) = first_layer(bytes)?;
    let (w, h) = (layer.size.width(), layer.size.height());
    let pixels: Vec<f64> = layer.channel_data.list[channel]
        .sample_data
        .values_as_f32()
        .map(f64::from)
        .collect();
    let mut values = Vec::with_capacity(w * h);
    for col in 0..w {
        for j in 0..h {
            values.push(pixels[(h - 1 - j) * w + col]);
        }
    }
    Ok(([w, h], values))
}

pub(crate) fn parse(bytes: &[u8]) -> ParseResult<ExrVolume> {
    let (layer, channel) = first_layer(bytes)?;
    let channel = &layer.channel_data.list[channel];
    let attrs = &layer.attributes.other;
    let dims = match get(attrs, "rfta_dims") {
        Some(AttributeValue::IntVec3((x, y, z))) => {
            let d = [*x, *y, *z];
            if d.iter().any(|&v| v <= 0) {
                return Err(ParseError::new(format!("rfta_dims {d:?} must be positive")));
            }
            d.map(|v| v as usize)
        }
        _ => {
            return Err(ParseError::new(
                "the EXR file has no 'rfta_dims' (v3i) attribute giving the volume's (nx, ny, nz)",
            ));
        }
    };
    let size = layer.size;
    if size.width() != dims[2] || size.height() != dims[0] * dims[1] {
        return Err(ParseError::new(format!(
            "image is {}x{} pixels but rfta_dims {dims:?} needs {}x{} (width nz, height nx*ny)",
            size.width(),
            size.height(),
            dims[2],
            dims[0] * dims[1]
        )));
    }
    let values: Vec<f64> = channel.sample_data.values_as_f32().map(f64::from).collect();
    let f = |name: &str| match get(attrs, name) {
        Some(AttributeValue::F64(v)) => Some(*v),
        Some(AttributeValue::F32(v)) => Some(*v as f64),
        _ => None,
    };
    let origin = [f("rfta_origin_x"), f("rfta_origin_y"), f("rfta_origin_z")];
    let spacing = [
        f("rfta_spacing_x"),
        f("rfta_spacing_y"),
        f("rfta_spacing_z"),
    ];
    let origin_spacing = match (origin, spacing) {
        ([Some(ox), Some(oy), Some(oz)], [Some(sx), Some(sy), Some(sz)]) => {
            Some((DVec3::new(ox, oy, oz), DVec3::new(sx, sy, sz)))
        }
        _ => None,
    };
    Ok(ExrVolume {
        dims,
        origin_spacing,
        values,
    })
}

fn get<'a>(attrs: &'a HashMap<Text, AttributeValue>, name: &str) -> Option<&'a AttributeValue> {
    attrs
        .iter()
        .find(|(k, _)| k.as_slice() == name.as_bytes())
        .map(|(_, v)| v)
}

pub(crate) fn to_bytes(grid: &Grid, values: &[f64]) -> ParseResult<Vec<u8>> {
    let [nx, ny, nz] = grid.dims();
    let as_i32 = |v: usize| i32::try_from(v).map_err(|_| ParseError::new("grid too large for EXR"));
    let mut attrs = LayerAttributes::named("sdf_volume");
    attrs.other.insert(
        Text::from("rfta_dims"),
        AttributeValue::IntVec3((as_i32(nx)?, as_i32(ny)?, as_i32(nz)?)),
    );
    for (axis, name) in ["x", "y", "z"].iter().enumerate() {
        attrs.other.insert(
            Text::from(format!("rfta_origin_{name}").as_str()),
            AttributeValue::F64(grid.origin()[axis]),
        );
        attrs.other.insert(
            Text::from(format!("rfta_spacing_{name}").as_str()),
            AttributeValue::F64(grid.spacing()[axis]),
        );
    }
    let samples: Vec<f32> = values.iter().map(|&v| v as f32).collect();
    let channel = AnyChannel::new("sdf", FlatSamples::F32(samples));
    let layer = Layer::new(
        (nz, nx * ny),
        attrs,
        Encoding::SMALL_LOSSLESS,
        AnyChannels::sort(smallvec::smallvec![channel]),
    );
    let mut out = Cursor::new(Vec::new());
    Image::from_layer(layer)
        .write()
        .to_buffered(&mut out)
        .map_err(|e| ParseError::new(format!("writing OpenEXR failed: {e}")))?;
    Ok(out.into_inner())
}
