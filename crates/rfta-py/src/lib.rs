//! Python bindings of rfta: the extension module `rfta._rfta` behind the `rfta` Python package
//! (`python/rfta/__init__.py` holds the public API, the argument checks and the conversions of
//! numpy arrays; this module takes contiguous `float64` arrays only).
//!
//! Every long call runs without the GIL, so other Python threads go on; the reconstruction runs
//! on a worker thread while the calling thread waits, checks for Ctrl-C (`KeyboardInterrupt`)
//! and calls the progress callback, with the GIL, between waits. Errors become `ValueError` (bad
//! input; `NoSurfaceError`, a `ValueError`, when the samples describe no surface) or
//! `RuntimeError`, with the library's message; a panic becomes a `RuntimeError` too.
//!
//! Built by maturin (`pip install crates/rfta-py`); `cargo build -p rfta-py` builds the shared
//! library without linking libpython.

use std::sync::Mutex;

use numpy::{
    PyArray1, PyArrayMethods, PyReadonlyArray1, PyReadonlyArray2, PyReadonlyArray3,
    PyUntypedArrayMethods,
};
use pyo3::exceptions::{PyKeyboardInterrupt, PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyTuple};
use rfta_geom::glam::{DVec2, DVec3};
use rfta_geom::plane::{Grid2, SdfSamples2};
use rfta_geom::{OrientedPoints, TriMesh};

mod convert;
mod detach;

use convert::{faces, grid_of, in_grid_order, mesh_arrays, points, rows, samples_of};
use detach::detached;

pyo3::create_exception!(
    _rfta,
    NoSurfaceError,
    PyValueError,
    "The samples describe no surface (every value of one sign, and their spheres leave no room)."
);

/// The library's error as the Python exception a caller can act on.
fn error(e: rfta::Error) -> PyErr {
    use rfta::Error as E;
    match e {
        E::NoSurface { .. } => NoSurfaceError::new_err(e.to_string()),
        E::NotADistance(_) => {
            PyValueError::new_err(format!("{e} (check=False turns the check off)"))
        }
        E::InvalidParams(_)
        | E::OracleAnswer { .. }
        | E::TooLarge { .. }
        | E::TooFewPoints { .. }
        | E::ThreadPool { .. } => PyValueError::new_err(e.to_string()),
        E::Cancelled => PyKeyboardInterrupt::new_err("cancelled"),
        _ => PyRuntimeError::new_err(e.to_string()),
    }
}

/// The parameters: a preset, then the overrides in `options` (`rfta::Params`' serde names, the
/// one table of setting names; `None` values are left out).
fn params(preset: &str, options: Option<&Bound<'_, PyDict>>) -> PyResult<rfta::Params> {
    let p = rfta::Params::preset(preset).ok_or_else(|| {
        PyValueError::new_err(format!(
            "preset '{preset}' is not one of {}",
            rfta::PRESETS.map(|n| format!("'{n}'")).join(", ")
        ))
    })?;
    let mut given = serde_json::Map::new();
    for (key, value) in options.into_iter().flat_map(|o| o.iter()) {
        let key: String = key.extract()?;
        let json = if value.is_none() {
            continue;
        } else if let Ok(b) = value.extract::<bool>() {
            b.into()
        } else if let Ok(i) = value.extract::<u64>() {
            i.into()
        } else if let Ok(i) = value.extract::<i64>() {
            i.into()
        } else if let Ok(x) = value.extract::<f64>() {
            // JSON has no NaN or infinity (serde_json would make them null: no setting).
            serde_json::Number::from_f64(x)
                .ok_or_else(|| PyValueError::new_err(format!("{key}: {x} is not finite")))?
                .into()
        } else if let Ok(text) = value.extract::<String>() {
            // A named choice (`initial`); `with_options` says which names it takes.
            text.into()
        } else {
            return Err(PyValueError::new_err(format!(
                "{key}: {} is not a number, a bool or a name",
                value.repr()?
            )));
        };
        given.insert(key, json);
    }
    p.with_options(given).map_err(error)
}

/// Reconstructs from samples: `values` (n,) at `positions` (n, 3), or on the grid `dims` over
/// `lo`..`hi` (C order) when `positions` is `None`. Positions that are exactly the points of a
/// grid, in any order, are treated as that grid. Returns `(V, F, P, N, report)`.
#[pyfunction]
#[pyo3(signature = (values, positions=None, dims=None, lo=None, hi=None, preset="default", options=None, progress=None))]
#[expect(clippy::too_many_arguments, reason = "the Python wrapper's keywords")]
fn reconstruct<'py>(
    py: Python<'py>,
    values: PyReadonlyArray1<'py, f64>,
    positions: Option<PyReadonlyArray2<'py, f64>>,
    dims: Option<[usize; 3]>,
    lo: Option<[f64; 3]>,
    hi: Option<[f64; 3]>,
    preset: &str,
    options: Option<&Bound<'py, PyDict>>,
    progress: Option<&Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyTuple>> {
    let params = params(preset, options)?;
    let samples = samples_of(values, positions, dims, lo, hi)?;
    let out = detached(py, progress, |progress, cancel| {
        rfta::reconstruct_cancellable(&samples, &params, progress, cancel)
    })?;
    PyTuple::new(
        py,
        reconstruction_items(py, &out, samples.as_grid().is_some())?,
    )
}

/// `(V, F, P, N, report)` of a reconstruction.
fn reconstruction_items<'py>(
    py: Python<'py>,
    out: &rfta::Reconstruction,
    grid: bool,
) -> PyResult<Vec<Bound<'py, PyAny>>> {
    let v_f = mesh_arrays(py, &out.mesh)?;
    Ok(vec![
        v_f.get_item(0)?,
        v_f.get_item(1)?,
        rows(py, &out.points.points)?.into_any(),
        rows(py, &out.points.normals)?.into_any(),
        report_dict(py, &out.report, grid)?.into_any(),
    ])
}

/// Reconstructs from an SDF that can be asked (`rfta::adaptive`): `sdf` takes an (n, 3)
/// float64 array and returns n values (anything `numpy.asarray` takes), asked over `lo`..`hi`
/// at most `budget` times. The callable runs with the GIL, on the worker thread, only while
/// it runs; an exception it raises is raised as itself; Ctrl-C stops between batches. Returns
/// `(V, F, P, N, report, adaptive, positions, values)`.
#[pyfunction]
#[pyo3(signature = (sdf, lo, hi, budget, preset="default", options=None, progress=None))]
#[expect(clippy::too_many_arguments, reason = "the Python wrapper's keywords")]
fn reconstruct_adaptive<'py>(
    py: Python<'py>,
    sdf: Py<PyAny>,
    lo: [f64; 3],
    hi: [f64; 3],
    budget: usize,
    preset: &str,
    options: Option<&Bound<'py, PyDict>>,
    progress: Option<&Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyTuple>> {
    let params = params(preset, options)?;
    let bounds = rfta_geom::Aabb::new(DVec3::from_array(lo), DVec3::from_array(hi));
    // The callable's own exception, kept to be raised as itself.
    let raised: Mutex<Option<PyErr>> = Mutex::new(None);
    let out = detached(py, progress, |progress, cancel| {
        let mut oracle = |points: &[DVec3]| -> Result<Vec<f64>, rfta::adaptive::OracleError> {
            Python::attach(|py| ask(py, &sdf, points)).map_err(|e| {
                let message = e.to_string();
                if let Ok(mut slot) = raised.lock() {
                    *slot = Some(e);
                }
                message.into()
            })
        };
        rfta::adaptive::reconstruct_adaptive(
            &mut oracle,
            bounds,
            rfta::adaptive::Budget::evaluations(budget),
            &params,
            progress,
            &mut |_| {},
            cancel,
        )
    });
    if let Some(e) = raised.lock().ok().and_then(|mut slot| slot.take()) {
        return Err(e);
    }
    let out = out?;
    let text =
        serde_json::to_string(&out.report).map_err(|e| PyRuntimeError::new_err(e.to_string()))?;
    let mut items = reconstruction_items(py, &out.reconstruction, false)?;
    items.extend([
        py.import("json")?.call_method1("loads", (text,))?,
        rows(py, &out.samples.positions())?.into_any(),
        PyArray1::from_slice(py, out.samples.values()).into_any(),
    ]);
    PyTuple::new(py, items)
}

/// One batch: the points as an (n, 3) float64 array, the answer through `numpy.asarray` as
/// float64, flattened.
fn ask(py: Python<'_>, sdf: &Py<PyAny>, points: &[DVec3]) -> PyResult<Vec<f64>> {
    let flat: Vec<f64> = points.iter().flat_map(|p| p.to_array()).collect();
    let array = PyArray1::from_vec(py, flat).reshape([points.len(), 3])?;
    let answer = sdf.bind(py).call1((array,))?;
    let numpy = py.import("numpy")?;
    let values = numpy
        .call_method1("asarray", (answer, "float64"))?
        .call_method1("reshape", (-1,))?;
    let values: PyReadonlyArray1<'_, f64> = values.extract()?;
    Ok(values.as_slice()?.to_vec())
}

/// Reconstructs closed polylines from 2D samples: `values` (n,) at `positions` (n, 2), a grid
/// when they are one (in any order). Returns `(V, E, P, N)`: vertices (m, 2), edges (k, 2) with
/// the inside on the left, tangency points and normals (p, 2).
#[pyfunction]
#[pyo3(signature = (values, positions, preset="default", options=None))]
fn reconstruct_2d<'py>(
    py: Python<'py>,
    values: PyReadonlyArray1<'py, f64>,
    positions: PyReadonlyArray2<'py, f64>,
    preset: &str,
    options: Option<&Bound<'py, PyDict>>,
) -> PyResult<Bound<'py, PyTuple>> {
    let params = params(preset, options)?;
    let values = values.as_slice()?.to_vec();
    if positions.shape()[1] != 2 {
        return Err(PyValueError::new_err(format!(
            "U must have shape (n, 2), not {:?}",
            positions.shape()
        )));
    }
    let p: Vec<DVec2> = positions
        .as_slice()?
        .chunks_exact(2)
        .map(|c| DVec2::new(c[0], c[1]))
        .collect();
    if p.len() != values.len() {
        return Err(PyValueError::new_err(format!(
            "U has {} points but S has {} values",
            p.len(),
            values.len()
        )));
    }
    let samples = match Grid2::fit(&p) {
        Some((grid, index)) => SdfSamples2::grid(grid, in_grid_order(&index, &values)),
        None => SdfSamples2::scattered(p, values),
    }
    .map_err(|e| PyValueError::new_err(e.to_string()))?;
    let out = py
        .detach(|| rfta::plane::reconstruct(&samples, &params))
        .map_err(error)?;
    let flat = |v: &mut dyn Iterator<Item = f64>, n: usize| {
        PyArray1::from_vec(py, v.collect()).reshape([n, 2])
    };
    let c = &out.curve;
    let v = flat(
        &mut c.vertices.iter().flat_map(|v| v.to_array()),
        c.vertices.len(),
    )?;
    let e: Vec<i64> = c.edges.iter().flat_map(|e| e.map(i64::from)).collect();
    let e = PyArray1::from_vec(py, e).reshape([c.edges.len(), 2])?;
    let pts = flat(
        &mut out.points.iter().flat_map(|p| p.0.to_array()),
        out.points.len(),
    )?;
    let nrm = flat(
        &mut out.points.iter().flat_map(|p| p.1.to_array()),
        out.points.len(),
    )?;
    PyTuple::new(
        py,
        [v.into_any(), e.into_any(), pts.into_any(), nrm.into_any()],
    )
}

/// The HTML page of a reconstruction (`rfta_view`): the mesh `(V, triangles)` against its
/// samples (as for [`reconstruct`]), with `figures` (name, value) in its table.
#[pyfunction]
#[pyo3(signature = (vertices, triangles, values, positions=None, dims=None, lo=None, hi=None, clamp=None, title="rfta", figures=Vec::new()))]
#[expect(clippy::too_many_arguments, reason = "the Python wrapper's keywords")]
fn page(
    py: Python<'_>,
    vertices: PyReadonlyArray2<'_, f64>,
    triangles: PyReadonlyArray2<'_, i64>,
    values: PyReadonlyArray1<'_, f64>,
    positions: Option<PyReadonlyArray2<'_, f64>>,
    dims: Option<[usize; 3]>,
    lo: Option<[f64; 3]>,
    hi: Option<[f64; 3]>,
    clamp: Option<f64>,
    title: &str,
    figures: Vec<(String, String)>,
) -> PyResult<String> {
    let vertices = points(&vertices, "V")?;
    let faces = faces(&triangles, vertices.len())?;
    let mesh = TriMesh { vertices, faces };
    let samples = samples_of(values, positions, dims, lo, hi)?;
    py.detach(|| {
        let found = rfta_view::Found::of(&samples, &mesh, clamp).map_err(error)?;
        Ok(rfta_view::html(&rfta_view::reconstruction(
            title,
            &mesh,
            Some(&found),
            figures,
        )))
    })
}

/// A report's figures for a page (`rfta_view::figures`), from its serde form as JSON: the
/// summary a person reads first, the warnings, then every figure.
#[pyfunction]
fn report_figures(report: &str) -> PyResult<Vec<(String, String)>> {
    let value: serde_json::Value =
        serde_json::from_str(report).map_err(|e| PyValueError::new_err(e.to_string()))?;
    Ok(rfta_view::figures(&value))
}

/// The report as a dict: `rfta::Report`'s serde form, and whether the samples were a grid.
fn report_dict<'py>(py: Python<'py>, r: &rfta::Report, grid: bool) -> PyResult<Bound<'py, PyDict>> {
    let text = serde_json::to_string(r).map_err(|e| PyValueError::new_err(e.to_string()))?;
    let d: Bound<'py, PyDict> = py
        .import("json")?
        .call_method1("loads", (text,))?
        .cast_into()?;
    d.set_item("grid", grid)?;
    Ok(d)
}

/// Screened Poisson reconstruction of oriented points (PoissonRecon's defaults, or the setting
/// the reconstruction runs with `preset="rfta"`). Returns `(V, F)`.
#[pyfunction]
#[pyo3(signature = (points, normals, depth=None, screening=None, preset="poissonrecon"))]
fn screened_poisson<'py>(
    py: Python<'py>,
    points: PyReadonlyArray2<'py, f64>,
    normals: PyReadonlyArray2<'py, f64>,
    depth: Option<u32>,
    screening: Option<f64>,
    preset: &str,
) -> PyResult<Bound<'py, PyTuple>> {
    let mut params = match preset {
        "poissonrecon" => rfta_spsr::SpsrParams::default(),
        "rfta" => rfta::Params {
            spsr_depth: depth,
            ..rfta::Params::default()
        }
        .spsr_params(None),
        other => {
            return Err(PyValueError::new_err(format!(
                "preset '{other}' is not one of 'poissonrecon', 'rfta'"
            )));
        }
    };
    if let Some(d) = depth {
        params.depth = d;
    }
    if let Some(s) = screening {
        params.screening = s;
    }
    let (p, n) = (
        self::points(&points, "points")?,
        self::points(&normals, "normals")?,
    );
    if p.len() != n.len() {
        return Err(PyValueError::new_err(format!(
            "{} points but {} normals",
            p.len(),
            n.len()
        )));
    }
    let cloud =
        OrientedPoints::new(p, n, None).map_err(|e| PyValueError::new_err(e.to_string()))?;
    let out = py
        .detach(|| rfta_spsr::reconstruct(&cloud, &params))
        .map_err(|e| match e {
            rfta_spsr::Error::DegenerateInput(_) | rfta_spsr::Error::InvalidParams(_) => {
                PyValueError::new_err(e.to_string())
            }
            _ => PyRuntimeError::new_err(e.to_string()),
        })?;
    mesh_arrays(py, &out.mesh)
}

/// Marching cubes of a grid of values (C order) over `lo`..`hi`. Returns `(V, F)`.
#[pyfunction]
#[pyo3(signature = (values, lo, hi, iso=0.0))]
fn marching_cubes<'py>(
    py: Python<'py>,
    values: PyReadonlyArray3<'py, f64>,
    lo: [f64; 3],
    hi: [f64; 3],
    iso: f64,
) -> PyResult<Bound<'py, PyTuple>> {
    let s = values.shape();
    let grid = grid_of([s[0], s[1], s[2]], lo, hi)?;
    let v = values.as_slice()?;
    let mesh = py.detach(|| rfta_mc::marching_cubes(&grid, v, iso));
    mesh_arrays(py, &mesh)
}

fn mesh_sdf(
    v: &PyReadonlyArray2<'_, f64>,
    f: &PyReadonlyArray2<'_, i64>,
) -> PyResult<rfta_mesh::MeshSdf> {
    let vertices = points(v, "V")?;
    let faces = faces(f, vertices.len())?;
    let mesh = TriMesh { vertices, faces };
    rfta_mesh::MeshSdf::new(&mesh).map_err(|e| PyValueError::new_err(e.to_string()))
}

/// Signed distance from each point to the mesh `(V, F)`, negative inside (by winding number).
#[pyfunction]
fn signed_distance<'py>(
    py: Python<'py>,
    points: PyReadonlyArray2<'py, f64>,
    v: PyReadonlyArray2<'py, f64>,
    f: PyReadonlyArray2<'py, i64>,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    let q = self::points(&points, "points")?;
    let index = mesh_sdf(&v, &f)?;
    let d = py.detach(|| index.signed_distances(&q));
    Ok(PyArray1::from_vec(py, d))
}

/// The exact signed distance of the mesh `(V, F)` on the grid `dims` over `lo`..`hi`, as a flat
/// C-order array.
#[pyfunction]
fn sample_sdf<'py>(
    py: Python<'py>,
    v: PyReadonlyArray2<'py, f64>,
    f: PyReadonlyArray2<'py, i64>,
    dims: [usize; 3],
    lo: [f64; 3],
    hi: [f64; 3],
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    let grid = grid_of(dims, lo, hi)?;
    let index = mesh_sdf(&v, &f)?;
    let values = py.detach(|| index.signed_distance_grid(&grid, &|| {}));
    Ok(PyArray1::from_vec(py, values))
}

/// SDF samples from a file, any format `rfta reconstruct` reads (`grid` names the level set of
/// an OpenVDB file): `(values, dims, lo, hi, points, clamp, description)`, with `dims`, `lo` and
/// `hi` (the first and last grid point) for a grid, `points` for scattered samples, `clamp` what
/// the file says its values are clamped at (an OpenVDB level set's background). A missing or
/// unreadable file is an `OSError`, a malformed one a `ValueError`.
#[pyfunction]
#[pyo3(signature = (path, grid=None))]
fn read_sdf<'py>(
    py: Python<'py>,
    path: std::path::PathBuf,
    grid: Option<&str>,
) -> PyResult<Bound<'py, PyTuple>> {
    let read = py.detach(|| match grid {
        Some(_) => rfta_io::read_vdb(&path, grid, None),
        None => rfta_io::read_sdf(&path, None),
    });
    let raw = read.map_err(|e| match e {
        rfta_io::Error::Io { .. } => pyo3::exceptions::PyOSError::new_err(e.to_string()),
        _ => PyValueError::new_err(e.to_string()),
    })?;
    let values = PyArray1::from_vec(py, raw.values);
    let none = || py.None();
    let (dims, lo, hi, positions) = match &raw.layout {
        rfta_geom::Layout::Grid(g) => {
            let b = g.bounds();
            (
                g.dims().into_pyobject(py)?.into_any().unbind(),
                b.min.to_array().into_pyobject(py)?.into_any().unbind(),
                b.max.to_array().into_pyobject(py)?.into_any().unbind(),
                none(),
            )
        }
        rfta_geom::Layout::Scattered(p) => {
            (none(), none(), none(), rows(py, p)?.into_any().unbind())
        }
    };
    PyTuple::new(
        py,
        [
            values.into_any().unbind(),
            dims,
            lo,
            hi,
            positions,
            raw.clamp.into_pyobject(py)?.into_any().unbind(),
            raw.description.into_pyobject(py)?.into_any().unbind(),
        ],
    )
}

#[pymodule]
fn _rfta(m: &Bound<'_, PyModule>) -> PyResult<()> {
    // The global pool at most one thread per core, whatever RAYON_NUM_THREADS asks (rayon
    // would start that many and panic where they cannot start). An error here (the threads
    // refused) leaves rayon's own start, which reports it as it can.
    let _ = rfta::start_global_pool(None);
    // What one input may take once read or made dense (an OpenVDB level set's box): a quarter
    // of the memory the process can use now, as the CLI has it.
    if let Some(bytes) = rfta::available_memory() {
        rfta_io::set_read_limit(bytes / 4);
    }
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add("NoSurfaceError", m.py().get_type::<NoSurfaceError>())?;
    m.add_function(wrap_pyfunction!(reconstruct, m)?)?;
    m.add_function(wrap_pyfunction!(reconstruct_adaptive, m)?)?;
    m.add_function(wrap_pyfunction!(reconstruct_2d, m)?)?;
    m.add_function(wrap_pyfunction!(page, m)?)?;
    m.add_function(wrap_pyfunction!(report_figures, m)?)?;
    m.add_function(wrap_pyfunction!(screened_poisson, m)?)?;
    m.add_function(wrap_pyfunction!(marching_cubes, m)?)?;
    m.add_function(wrap_pyfunction!(signed_distance, m)?)?;
    m.add_function(wrap_pyfunction!(sample_sdf, m)?)?;
    m.add_function(wrap_pyfunction!(read_sdf, m)?)?;
    Ok(())
}
