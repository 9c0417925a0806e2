//! [`Mlp`]: the inexact evaluation's neural SDFs, as `tools/rfta-eval/inexact/train.py` writes
//! them: 3 -> 128 -> 128 -> 128 -> 128 -> 1, softplus (beta 10) between layers, every layer's
//! weights (inputs by outputs, row-major) then its biases, flat, float32, in one `.npy` file.

use std::path::Path;

use anyhow::{Context, Result, bail};
use rayon::prelude::*;
use rfta_geom::glam::DVec3;

/// The layer widths, input to output.
const WIDTHS: [usize; 6] = [3, 128, 128, 128, 128, 1];

/// Softplus' sharpness (PyTorch's `Softplus(beta)`).
const BETA: f32 = 10.0;

/// Points evaluated together (one matrix product per layer).
const BATCH: usize = 256;

struct Layer {
    inputs: usize,
    outputs: usize,
    /// `inputs x outputs`, row-major.
    weights: Vec<f32>,
    bias: Vec<f32>,
}

/// A trained network, evaluated in single precision as it was trained.
pub(crate) struct Mlp {
    layers: Vec<Layer>,
}

impl Mlp {
    /// The network in `path` (the layout in the module docs).
    pub(crate) fn load(path: &Path) -> Result<Self> {
        let bytes =
            std::fs::read(path).with_context(|| format!("cannot read {}", path.display()))?;
        let array =
            rfta_io::parse_npy(&bytes).map_err(|e| anyhow::anyhow!("{}: {e}", path.display()))?;
        let expected: usize = WIDTHS.windows(2).map(|w| w[0] * w[1] + w[1]).sum();
        if array.data.len() != expected {
            bail!(
                "{}: {} parameters, a {WIDTHS:?} network has {expected}",
                path.display(),
                array.data.len()
            );
        }
        let mut flat = array.data.iter().map(|&x| x as f32);
        let layers = WIDTHS
            .windows(2)
            .map(|w| Layer {
                inputs: w[0],
                outputs: w[1],
                weights: flat.by_ref().take(w[0] * w[1]).collect(),
                bias: flat.by_ref().take(w[1]).collect(),
            })
            .collect();
        Ok(Self { layers })
    }

    /// The network's values at `points`.
    pub(crate) fn values(&self, points: &[DVec3]) -> Vec<f64> {
        points
            .par_chunks(BATCH)
            .flat_map_iter(|chunk| self.batch(chunk))
            .collect()
    }

    fn batch(&self, points: &[DVec3]) -> Vec<f64> {
        let m = points.len();
        let mut h: Vec<f32> = points
            .iter()
            .flat_map(|p| p.to_array().map(|x| x as f32))
            .collect();
        let last = self.layers.len() - 1;
        for (l, layer) in self.layers.iter().enumerate() {
            let (i, o) = (layer.inputs, layer.outputs);
            let mut out = vec![0.0f32; m * o];
            for (row, x) in out.chunks_exact_mut(o).zip(h.chunks_exact(i)) {
                row.copy_from_slice(&layer.bias);
                for (&xk, w) in x.iter().zip(layer.weights.chunks_exact(o)) {
                    for (y, &wk) in row.iter_mut().zip(w) {
                        *y += xk * wk;
                    }
                }
                if l < last {
                    row.iter_mut().for_each(|y| *y = softplus(*y));
                }
            }
            h = out;
        }
        h.into_iter().map(f64::from).collect()
    }
}

/// `ln(1 + e^(beta x)) / beta`, without overflow.
fn softplus(x: f32) -> f32 {
    let z = BETA * x;
    if z > 20.0 { x } else { z.exp().ln_1p() / BETA }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A network whose unit 0 reads x and passes it through every softplus, the output bias
    /// 0.25, answers values worked by hand; files of the wrong size, not .npy or missing are
    /// errors.
    #[test]
    fn known_networks_answer_known_values() {
        let sizes: Vec<usize> = WIDTHS.windows(2).map(|w| w[0] * w[1] + w[1]).collect();
        let total: usize = sizes.iter().sum();
        let mut data = vec![0.0f64; total];
        *data.last_mut().expect("parameters") = 0.25;
        // First layer: unit 0 reads x with weight 1. Later layers: unit 0 passes unit 0 on.
        data[0] = 1.0;
        let mut at = sizes[0];
        for _ in 1..4 {
            data[at] = 1.0;
            at += sizes[1];
        }
        data[at] = 1.0; // the output reads unit 0
        let dir = std::env::temp_dir().join(format!("rfta-mlp-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("dir");
        let path = dir.join("net.npy");
        let mut bytes = Vec::new();
        rfta_io::write_npy_f64(&mut bytes, &[total], &data).expect("npy");
        std::fs::write(&path, bytes).expect("write");
        let net = Mlp::load(&path).expect("load");
        // Four softplus layers on x = 2 (each the identity beyond beta x = 20), then + 0.25.
        let v = net.values(&[DVec3::new(2.0, 5.0, -3.0), DVec3::new(-3.0, 0.0, 0.0)]);
        assert!((v[0] - 2.25).abs() < 1e-5, "{}", v[0]);
        // x = -3: softplus(-3) = ln(1 + e^-30) / 10, about 9.4e-15, then softplus of that
        // repeatedly: ln(2) / 10 = 0.0693 once the input is about zero, and onward.
        let s = |x: f64| (1.0 + (10.0 * x).exp()).ln() / 10.0;
        let expected = s(s(s(s(-3.0)))) + 0.25;
        assert!(
            (v[1] - expected).abs() < 1e-5,
            "{} against {expected}",
            v[1]
        );
        // A file of the wrong size, one that is not .npy, one that is missing: errors.
        let mut short = Vec::new();
        rfta_io::write_npy_f64(&mut short, &[total - 1], &data[1..]).expect("npy");
        std::fs::write(&path, short).expect("write");
        let err = Mlp::load(&path)
            .err()
            .map(|e| e.to_string())
            .unwrap_or_default();
        assert!(err.contains("parameters"), "{err}");
        std::fs::write(&path, b"not npy").expect("write");
        assert!(Mlp::load(&path).is_err());
        assert!(Mlp::load(&dir.join("missing.npy")).is_err());
        std::fs::remove_dir_all(&dir).ok();
    }
}
