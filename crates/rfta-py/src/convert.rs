//! Conversions between numpy arrays and rfta's types, with the checks that name what is wrong.

use numpy::{PyArray1, PyArrayMethods, PyReadonlyArray1, PyReadonlyArray2, PyUntypedArrayMethods};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyTuple;
use rfta_geom::glam::DVec3;
use rfta_geom::{Grid, SdfSamples, TriMesh};

/// `(n, 3)` rows as points.
pub(crate) fn points(a: &PyReadonlyArray2<'_, f64>, what: &str) -> PyResult<Vec<DVec3>> {
    let shape = a.shape();
    if shape[1] != 3 {
        return Err(PyValueError::new_err(format!(
            "{what} must have shape (n, 3), not {shape:?}"
        )));
    }
    let flat = a.as_slice()?;
    Ok(flat
        .chunks_exact(3)
        .map(|c| DVec3::new(c[0], c[1], c[2]))
        .collect())
}

/// `(m, 3)` integer rows as faces of a mesh with `n_vertices` vertices.
pub(crate) fn faces(a: &PyReadonlyArray2<'_, i64>, n_vertices: usize) -> PyResult<Vec<[u32; 3]>> {
    let shape = a.shape();
    if shape[1] != 3 {
        return Err(PyValueError::new_err(format!(
            "F must have shape (m, 3), not {shape:?}"
        )));
    }
    a.as_slice()?
        .chunks_exact(3)
        .map(|c| {
            let mut f = [0u32; 3];
            for (k, &v) in c.iter().enumerate() {
                f[k] = u32::try_from(v)
                    .ok()
                    .filter(|&i| (i as usize) < n_vertices)
                    .ok_or_else(|| {
                        PyValueError::new_err(format!(
                            "F holds index {v}, outside the {n_vertices} vertices"
                        ))
                    })?;
            }
            Ok(f)
        })
        .collect()
}

/// A mesh as numpy arrays `V (n, 3) float64`, `F (m, 3) int64`.
pub(crate) fn mesh_arrays<'py>(py: Python<'py>, mesh: &TriMesh) -> PyResult<Bound<'py, PyTuple>> {
    let v = rows(py, &mesh.vertices)?;
    let f: Vec<i64> = mesh.faces.iter().flat_map(|f| f.map(i64::from)).collect();
    let f = PyArray1::from_vec(py, f).reshape([mesh.faces.len(), 3])?;
    PyTuple::new(py, [v.into_any(), f.into_any()])
}

/// Points as an `(n, 3)` float64 array.
pub(crate) fn rows<'py>(
    py: Python<'py>,
    p: &[DVec3],
) -> PyResult<Bound<'py, numpy::PyArray2<f64>>> {
    let flat: Vec<f64> = p.iter().flat_map(|v| v.to_array()).collect();
    PyArray1::from_vec(py, flat).reshape([p.len(), 3])
}

pub(crate) fn grid_of(dims: [usize; 3], lo: [f64; 3], hi: [f64; 3]) -> PyResult<Grid> {
    Grid::from_bounds(dims, DVec3::from_array(lo), DVec3::from_array(hi))
        .map_err(|e| PyValueError::new_err(format!("bounds: {e}")))
}

/// `values` given at the positions `Grid::fit` or `Grid2::fit` placed at `index`, in the grid's
/// order.
pub(crate) fn in_grid_order(index: &[usize], values: &[f64]) -> Vec<f64> {
    let mut on_grid = vec![0.0; values.len()];
    for (&i, &v) in index.iter().zip(values) {
        on_grid[i] = v;
    }
    on_grid
}

/// The samples: `values` at `positions`, a grid when they are one (in any order), or on the
/// grid `dims` over `lo`..`hi` (C order).
pub(crate) fn samples_of(
    values: PyReadonlyArray1<'_, f64>,
    positions: Option<PyReadonlyArray2<'_, f64>>,
    dims: Option<[usize; 3]>,
    lo: Option<[f64; 3]>,
    hi: Option<[f64; 3]>,
) -> PyResult<SdfSamples> {
    let values = values.as_slice()?.to_vec();
    match (positions, dims, lo, hi) {
        (Some(p), None, None, None) => {
            let p = points(&p, "the positions")?;
            if p.len() != values.len() {
                return Err(PyValueError::new_err(format!(
                    "the positions are {} points but the values {}",
                    p.len(),
                    values.len()
                )));
            }
            match Grid::fit(&p) {
                Some((grid, index)) => SdfSamples::grid(grid, in_grid_order(&index, &values)),
                None => SdfSamples::scattered(p, values),
            }
        }
        (None, Some(dims), Some(lo), Some(hi)) => SdfSamples::grid(grid_of(dims, lo, hi)?, values),
        _ => {
            return Err(PyValueError::new_err(
                "give positions, or dims with lo and hi",
            ));
        }
    }
    .map_err(|e| PyValueError::new_err(e.to_string()))
}
