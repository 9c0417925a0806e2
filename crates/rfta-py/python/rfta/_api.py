"""The implementation of the ``rfta`` package's API; import it from ``rfta``."""

from __future__ import annotations

import json
import math
import warnings
from dataclasses import dataclass, field
from typing import Any, Callable, Optional, Sequence, Tuple, Union

import numpy as np

from . import _rfta
from ._rfta import NoSurfaceError

class RftaWarning(UserWarning):
    """What a reconstruction tells its caller beside the mesh (the report's ``warnings``):
    noisy or clamped values, samples the mesh disagrees with, cavities, thin handles. Filter it
    with ``warnings.filterwarnings("ignore", category=rfta.RftaWarning)``."""


def _host(sdf: Callable[[np.ndarray], Any]) -> Callable[[np.ndarray], Any]:
    """``sdf`` with its answer brought to the host: a tensor (PyTorch's, on any device, with or
    without gradients) as a numpy array; anything else as it is."""

    def ask(points: np.ndarray) -> Any:
        answer = sdf(points)
        if all(hasattr(answer, m) for m in ("detach", "cpu", "numpy")):
            answer = answer.detach().cpu().numpy()
        return answer

    return ask


def _warn(report: dict) -> None:
    for w in report.get("warnings", []):
        warnings.warn(f"rfta: {w}", RftaWarning, stacklevel=3)


Bounds = Union[float, Sequence[float], Sequence[Sequence[float]], None]
Progress = Callable[[str, int, int], Any]


def _finite(name: str, a: np.ndarray) -> None:
    bad = ~np.isfinite(a)
    if bad.any():
        first = np.unravel_index(int(np.argmax(bad)), a.shape)
        raise ValueError(
            f"{name} has {int(bad.sum())} value(s) that are NaN or infinite "
            f"(the first at index {tuple(int(i) for i in first)})"
        )


def _array(name: str, a: Any, ndim: int, dtype: Any = np.float64) -> np.ndarray:
    try:
        out = np.ascontiguousarray(a, dtype=dtype)
    except (TypeError, ValueError) as e:
        raise ValueError(f"{name} must be a numeric array: {e}") from None
    if out.ndim != ndim:
        raise ValueError(f"{name} must have {ndim} dimension(s), not shape {out.shape}")
    if dtype == np.float64:
        _finite(name, out)
    return out


def _rows(name: str, a: Any) -> np.ndarray:
    out = _array(name, a, 2)
    if out.shape[1] != 3:
        raise ValueError(f"{name} must have shape (n, 3), not {out.shape}")
    return out


def _faces(F: Any) -> np.ndarray:
    f = np.asarray(F)
    if not np.issubdtype(f.dtype, np.integer):
        raise ValueError(f"F must hold integer vertex indices, not {f.dtype}")
    f = np.ascontiguousarray(f, dtype=np.int64)
    if f.ndim != 2 or f.shape[1] != 3:
        raise ValueError(f"F must have shape (m, 3), not {f.shape}")
    return f


def _bounds(bounds: Bounds) -> Tuple[list, list]:
    """(lo, hi) corners from None ([-1, 1]^3), (lo, hi) scalars, two corners, or 6 numbers."""
    if bounds is None:
        return [-1.0] * 3, [1.0] * 3
    b = np.asarray(bounds, dtype=np.float64)
    if b.shape == (2,):
        lo, hi = [float(b[0])] * 3, [float(b[1])] * 3
    elif b.shape == (2, 3):
        lo, hi = [float(x) for x in b[0]], [float(x) for x in b[1]]
    elif b.shape == (6,):
        lo, hi = [float(x) for x in b[:3]], [float(x) for x in b[3:]]
    else:
        raise ValueError(
            "bounds must be (lo, hi), ((xmin, ymin, zmin), (xmax, ymax, zmax)) or 6 numbers, "
            f"not an array of shape {b.shape}"
        )
    if not all(math.isfinite(x) for x in lo + hi) or any(a >= c for a, c in zip(lo, hi)):
        raise ValueError(f"bounds must be finite with min < max on every axis: {lo} .. {hi}")
    return lo, hi


def _printer(verbose: bool, progress: Optional[Progress]) -> Optional[Progress]:
    if progress is not None and not callable(progress):
        raise ValueError("progress must be a callable (stage, done, of)")
    if not verbose:
        return progress

    def report(stage: str, done: int, of: int) -> None:
        if stage != "progress":
            print(f" --- rfta: {stage}", flush=True)
        if progress is not None:
            progress(stage, done, of)

    return report


@dataclass
class Samples:
    """SDF samples read from a file by ``read_sdf``; pass them to ``reconstruct`` as they are.

    Attributes
    ----------
    S : (nx, ny, nz) array, or (n,) with ``points``
        The values.
    bounds : ((x, y, z), (x, y, z)) or None
        The grid's first and last point (``reconstruct``'s ``bounds``); None for scattered samples.
    points : (n, 3) array or None
        Scattered sample positions.
    clamp : float or None
        The magnitude the file says its values are clamped at (an OpenVDB level set's background).
    description : str
        What was read (format, shape, for a level set its name, codec and voxel size).
    """

    S: np.ndarray
    bounds: Optional[Tuple[Tuple[float, float, float], Tuple[float, float, float]]]
    points: Optional[np.ndarray]
    clamp: Optional[float]
    description: str


def read_sdf(path: Any, grid: Optional[str] = None) -> Samples:
    """Reads SDF samples from a file: any format ``rfta reconstruct`` reads (``.npy`` grids with
    their sidecar, ``.exr``, OpenVDB ``.vdb`` level sets, ``.ply``/``.csv``/``.xyz`` scattered
    samples).

    An OpenVDB level set (the first in the file, or the one named ``grid``) reads as the dense
    grid of its narrow band: every voxel of the box around its active voxels and one voxel more
    on every side, inactive voxels at plus or minus the background value, which is the clamp::

        s = rfta.read_sdf("level_set.vdb")
        mesh = rfta.reconstruct(s)          # bounds and clamp from the file

    Raises ``OSError`` for a file that cannot be read and ``ValueError`` for a malformed one or a
    ``grid`` that is not a level set of the file (the message names the grids it holds).
    """
    values, dims, lo, hi, points, clamp, description = _rfta.read_sdf(str(path), grid)
    if dims is None:
        return Samples(values, None, points, clamp, description)
    return Samples(values.reshape(dims), (tuple(lo), tuple(hi)), None, clamp, description)


@dataclass
class Reconstruction:
    """A reconstructed mesh with its tangency points and the library's report."""

    vertices: np.ndarray
    """(n, 3) float64 vertex positions, in the samples' coordinates."""
    faces: np.ndarray
    """(m, 3) int64 triangles, outward-oriented."""
    points: np.ndarray
    """(p, 3) float64 final tangency points."""
    normals: np.ndarray
    """(p, 3) float64 unit normals of the tangency points."""
    report: dict = field(default_factory=dict)
    """What the reconstruction did: counts, agreement with the samples (``sign_errors``,
    ``entered``, ``gaps``; ``thin_loops``, the lengths in spacings of the loops around handles
    thinner than the samples resolve; ``cavities``, inward-facing components), ``warnings``,
    ``timings`` in seconds."""

    samples: Optional[tuple] = field(default=None, repr=False)
    """The samples it was made from (values, positions, grid), for ``to_html``."""

    adaptive: Optional[dict] = None
    """With ``sdf=``: the adaptive run's own report (``evaluations``, ``budget``,
    ``finest_spacing``, ``oracle_seconds`` and ``rfta_seconds`` apart, one entry per pass in
    ``passes``); ``None`` otherwise. The samples asked for are in ``samples``."""

    def __repr__(self) -> str:
        r = self.report
        genus = r.get("genus")
        parts = [
            f"{len(self.vertices)} vertices",
            f"{len(self.faces)} faces",
            f"genus {genus if genus is not None else 'undefined'}",
            f"{r.get('components', '?')} component(s)",
            "watertight" if r.get("watertight") else "NOT watertight",
            f"{r.get('sign_errors', '?')} samples on the wrong side",
            f"{r.get('entered', '?')} spheres entered",
            f"{len(r.get('warnings', []))} warning(s)",
        ]
        if self.adaptive is not None:
            parts.append(f"{self.adaptive.get('evaluations', '?')} evaluations")
        return f"Reconstruction({', '.join(parts)})"

    def to_html(self, path: Optional[str] = None, title: str = "rfta") -> str:
        """The mesh as one HTML page that opens without a network: an interactive 3D view with
        the samples on the wrong side, the spheres entered, thin handles, cavities and islands
        marked, marching cubes' mesh of the same grid as a layer, and the report's figures (as
        ``rfta reconstruct --html`` writes it). Written to ``path`` when given; returned."""
        if self.samples is None:
            raise ValueError("to_html needs the samples: a Reconstruction from rfta.reconstruct")
        values, positions, grid = self.samples
        figures = _rfta.report_figures(json.dumps(self.report))
        keywords = dict(positions=positions) if grid is None else dict(
            dims=list(grid[0]), lo=grid[1], hi=grid[2]
        )
        page = _rfta.page(
            self.vertices, self.faces.astype(np.int64), values,
            clamp=self.report.get("clamp"), title=title, figures=figures, **keywords,
        )
        if path is not None:
            with open(path, "w", encoding="utf-8") as f:
                f.write(page)
        return page

    def to_trimesh(self) -> Any:
        """The mesh as a ``trimesh.Trimesh`` (needs the ``trimesh`` package)."""
        try:
            import trimesh
        except ImportError:
            raise ImportError("to_trimesh needs trimesh: pip install trimesh") from None
        return trimesh.Trimesh(vertices=self.vertices, faces=self.faces, process=False)


def _run(
    S: np.ndarray,
    positions: Optional[np.ndarray],
    grid: Optional[Tuple[Sequence[int], list, list]],
    preset: str,
    options: dict,
    progress: Optional[Progress],
) -> Tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, dict]:
    if grid is None:
        return _rfta.reconstruct(
            S, positions=positions, preset=preset, options=options, progress=progress
        )
    dims, lo, hi = grid
    return _rfta.reconstruct(
        S, dims=list(dims), lo=lo, hi=hi, preset=preset, options=options, progress=progress
    )


def reconstruct(
    S: Any = None,
    bounds: Bounds = None,
    preset: str = "default",
    *,
    points: Any = None,
    sdf: Optional[Callable[[np.ndarray], Any]] = None,
    budget: Optional[int] = None,
    rounds: Optional[int] = None,
    max_points_per_sphere: Optional[int] = None,
    seed: Optional[int] = None,
    clamp: Optional[float] = None,
    check: bool = True,
    depth: Optional[int] = None,
    screening: Optional[float] = None,
    owner_band: Optional[float] = None,
    raster_resolution: Optional[int] = None,
    min_island: Optional[float] = None,
    genus: Optional[int] = None,
    keep_cavities: bool = False,
    keep_thin_handles: bool = False,
    initial: Optional[str] = None,
    field: Optional[str] = None,
    simplify: bool = True,
    simplify_tolerance: Optional[float] = None,
    faces: Optional[int] = None,
    threads: Optional[int] = None,
    progress: Optional[Progress] = None,
    verbose: bool = False,
) -> Reconstruction:
    """Reconstructs a mesh from signed distance samples (negative inside).

    Parameters
    ----------
    S : (nx, ny, nz) array, or Samples
        The values on a grid: ``S[i, j, k]`` at ``linspace(lo, hi, n)`` on each axis (numpy's
        ``meshgrid(..., indexing="ij")``). Or, with ``points``, one value per point. Or what
        ``read_sdf`` read from a file, with its bounds or points and its clamp (``clamp`` given
        here overrides the file's).
    bounds : (lo, hi), ((xmin, ymin, zmin), (xmax, ymax, zmax)) or 6 numbers
        The grid's corner points (default [-1, 1]^3). Ignored with ``points``.
    preset : "default", "paper" or "fast"
        The paper's defaults (10 fine-tuning rounds; 3 on grids of more than 80 cells along
        their longest side), its Table 2 (20 rounds, 30 points per sphere), or gpytoolbox's
        defaults (3 rounds). The keywords below override it.
    points : (n, 3) array, optional
        Scattered sample positions (``S`` then has shape (n,)).
    sdf : callable, optional
        Instead of ``S``: the signed distance function itself, asked where the reconstruction
        needs it (adaptive sampling) over ``bounds``, at most ``budget`` times. It takes an
        (n, 3) float64 array of points, many at once (a few batches a pass), and returns their
        n values, as anything ``numpy.asarray`` takes or a PyTorch tensor on any device, with or
        without gradients (a model: ``lambda p: model(torch.from_numpy(p).to(device))``). An
        exception it raises reaches the caller as itself; a NaN, an
        infinite value or the wrong number of values raises ``ValueError`` naming the batch.
        Ctrl-C stops between batches.
    budget : int, optional
        With ``sdf``: the most evaluations (default 30000; at least 125).
    rounds, max_points_per_sphere, seed, clamp, depth, screening, owner_band,
    raster_resolution, min_island, genus, keep_cavities, keep_thin_handles, initial, threads
        ``rfta::Params``' settings of these names (its serde form, the one table of names).
        ``rfta reconstruct``'s options (``rfta reconstruct --help``) are the same with dashes
        (``--max-points-per-sphere``, ``--owner-band``), except ``screening``, which has no
        option (the CLI keeps the preset's), and ``threads`` (the global ``rfta --threads``).
        ``initial``: ``"gradient"`` (on grids, the default: the initial points from the samples'
        gradients) or ``"raster"`` (the paper's rasterized empty space).
    field : "auto", "distance", "level-set" or "bound"
        How the samples are read: as distances (the paper's spheres), as a level set whose zero
        set is the surface (grids only: a trained network's values, any field that is not a
        distance), as bounds on the distance (grids only: CSG trees of min and max, smooth
        blends: the spheres as empty space, the points on the zero set), or, by default, as a
        level set when a grid's values fall short of their zero set and as bounds when other
        spheres cover some of theirs. ``report["reach"]`` and ``report["spheres_covered"]`` say
        how far they reach and how many are covered, ``report["read_as"]`` (``"distances"``,
        ``"level-set"`` or ``"bounds"``) how they were read.
        With ``sdf``, the base grid decides: a level set is refined where its sign changes
        (as MISE does) and its finest grid read as one.
    simplify, simplify_tolerance, faces
        By default the mesh is simplified: edges collapsed while the surface stays within
        ``simplify_tolerance`` sample spacings (default 0.8 / N for samples N spacings
        across, within 0.008 to 0.06) of the unsimplified one, no sample
        changes side, no sphere is entered past the consistency check's margin and the topology
        stays the same; ``faces`` asks for at most that many faces (within one spacing unless
        a tolerance is given). ``simplify=False`` returns the mesh unsimplified (``rfta reconstruct
        --no-simplify``). ``report["faces_unsimplified"]`` and ``report["simplify_deviation"]``
        (spacings) say what it did.
    check : bool
        Refuse values that are not a signed distance (and detect a clamp); False to go on.
    progress : callable(stage, done, of), optional
        Called as stages start and about twice a second within a long stage.
    verbose : bool
        Print each stage as it starts.

    Returns
    -------
    Reconstruction
    """
    if sdf is not None or budget is not None:
        if sdf is None:
            raise ValueError("budget needs sdf: the function to ask")
        if S is not None or points is not None:
            raise ValueError("give either S (samples) or sdf (a function to ask), not both")
        if not callable(sdf):
            raise ValueError(f"sdf must be callable, not {type(sdf).__name__}")
        budget = 30000 if budget is None else int(budget)
        lo, hi = _bounds(bounds)
        options = dict(
            rounds=rounds, max_points_per_sphere=max_points_per_sphere, seed=seed,
            clamp=clamp, check=check, depth=depth, screening=screening,
            owner_band=owner_band, raster_resolution=raster_resolution,
            min_island=min_island, genus=genus, keep_cavities=keep_cavities,
            keep_thin_handles=keep_thin_handles, initial=initial, field=field, simplify=simplify,
            simplify_tolerance=simplify_tolerance, faces=faces, threads=threads,
        )
        V, F, P, N, report, adaptive, positions, values = _rfta.reconstruct_adaptive(
            _host(sdf), lo, hi, budget, preset=preset, options=options,
            progress=_printer(verbose, progress),
        )
        _warn(report)
        return Reconstruction(
            V, F, P, N, report, samples=(values, positions, None), adaptive=adaptive
        )
    if S is None:
        raise ValueError("give the samples S (or sdf, a function to ask)")
    if isinstance(S, Samples):
        bounds, points = S.bounds, S.points
        clamp = S.clamp if clamp is None else clamp
        S = S.S
    if points is None:
        S = _array("S", S, 3)
        lo, hi = _bounds(bounds)
        positions, grid = None, (S.shape, lo, hi)
    else:
        positions = _rows("points", points)
        S = _array("S", S, 1)
        grid = None
    options = dict(
        rounds=rounds,
        max_points_per_sphere=max_points_per_sphere,
        seed=seed,
        clamp=clamp,
        check=check,
        depth=depth,
        screening=screening,
        owner_band=owner_band,
        raster_resolution=raster_resolution,
        min_island=min_island,
        genus=genus,
        keep_cavities=keep_cavities,
        keep_thin_handles=keep_thin_handles,
        initial=initial,
        field=field,
        simplify=simplify,
        simplify_tolerance=simplify_tolerance,
        faces=faces,
        threads=threads,
    )
    V, F, P, N, report = _run(
        S.ravel(), positions, grid, preset, options, _printer(verbose, progress)
    )
    _warn(report)
    return Reconstruction(V, F, P, N, report, samples=(S.ravel(), positions, grid))


def reach_for_the_arcs(
    U: Any,
    S: Any,
    rng_seed: int = 3452,
    return_point_cloud: bool = False,
    fine_tune_iters: int = 3,
    batch_size: int = 10000,
    num_rasterization_spheres: int = 0,
    screening_weight: float = 10.0,
    rasterization_resolution: Optional[int] = None,
    max_points_per_sphere: int = 3,
    n_local_searches: Optional[int] = None,
    local_search_iters: int = 20,
    local_search_t: float = 0.01,
    tol: float = 1e-4,
    clamp_value: float = np.inf,
    force_cpu: bool = False,
    parallel: bool = False,
    verbose: bool = False,
):
    """gpytoolbox's ``reach_for_the_arcs``, argument for argument.

    Parameters
    ----------
    U : (n, 3) or (n, 2) array
        Sample positions: scattered, or the points of a grid in any order (a grid is recognised
        and reconstructed as one, which is more accurate and faster). 2D samples give closed
        polylines, as gpytoolbox's 2D mode.
    S : (n,) array
        The signed distance at each point, negative inside.
    rng_seed : int
        Seed of every random choice.
    return_point_cloud : bool
        Also return the tangency points and their normals.
    fine_tune_iters : int
        Fine-tuning rounds (the paper's k_max).
    batch_size : int
        Spheres per feasibility batch (0: all).
    num_rasterization_spheres : int
        No counterpart: rfta rasterizes every sphere (exact and fast); a non-zero value is
        ignored with a warning.
    screening_weight : float
        PoissonRecon's screening weight; rfta's solver needs 3 times the value for the same fit
        (docs/spsr.md), so it runs with ``3 * screening_weight``, halved for each Poisson depth
        beyond 9 as rfta's own screening is (fine grids: docs/faithfulness.md).
    rasterization_resolution : int, optional
        Cells per axis of the empty-space raster (default ``64 ceil(n^(1/3) / 16)``).
    max_points_per_sphere : int
        Tangency points per sphere at most (the paper's n_max).
    n_local_searches : int, optional
        No counterpart: rfta always uses the reference's default ``ceil(2 n^(1/3))``; another
        value is ignored with a warning.
    local_search_iters : int
        Moves of the feasibility local search.
    local_search_t : float
        Step of the local search and transport (the paper's tau).
    tol : float
        Tolerance of the inside tests.
    clamp_value : float
        The SDF was clamped at this magnitude (inf: not clamped; rfta also detects a clamp).
    force_cpu : bool
        Accepted; this package always rasterizes on the CPU.
    parallel : bool
        Use every core (the mesh does not depend on it); False runs on one thread.
    verbose : bool
        Print each stage as it starts.

    Returns
    -------
    V : (n, 3) float64 array
    F : (m, 3) int32 array (gpytoolbox's dtype)
    P, N : (p, 3) float64 arrays, with ``return_point_cloud``: tangency points and normals.

    Samples that describe no surface (all of one sign with spheres that leave no room for one)
    give V and F of shape (0, 3) ((0, 2) in 2D), as gpytoolbox does, and P and N empty arrays of
    the same shape where gpytoolbox returns None; a warning says why when ``verbose``.
    ``reconstruct`` raises ``NoSurfaceError`` instead. Every difference from gpytoolbox:
    crates/rfta-py/README.md.

    In 2D, ``V`` is (n, 2), ``F`` the (m, 2) edges of closed polylines (inside on the left of
    each edge), ``P`` and ``N`` (p, 2); ``screening_weight``, ``batch_size`` and the local
    search's arguments have no counterpart there (every point lies on the exact free arcs of
    its circle) and are ignored.
    """
    del force_cpu  # the CPU rasterizer always runs here
    U = _array("U", U, 2)
    if U.shape[1] not in (2, 3):
        raise ValueError(f"U must have shape (n, 3) or (n, 2), not {U.shape}")
    S = _array("S", S, 1)
    if S.shape[0] != U.shape[0]:
        raise ValueError(f"U has {U.shape[0]} points but S has {S.shape[0]} values")
    if num_rasterization_spheres:
        warnings.warn(
            "rfta rasterizes every sphere; num_rasterization_spheres is ignored", stacklevel=2
        )
    if n_local_searches is not None:
        warnings.warn(
            "rfta uses the reference's default n_local_searches = ceil(2 n^(1/3)); "
            "the value given is ignored",
            stacklevel=2,
        )
    options = dict(
        seed=int(rng_seed),
        rounds=int(fine_tune_iters),
        batch_size=int(batch_size),
        screening=3.0 * float(screening_weight),
        raster_resolution=rasterization_resolution,
        max_points_per_sphere=int(max_points_per_sphere),
        local_search_moves=int(local_search_iters),
        transport_step=float(local_search_t),
        tolerance=float(tol),
        clamp=None if not np.isfinite(clamp_value) else float(clamp_value),
        threads=None if parallel else 1,
        # gpytoolbox's mesh is the Poisson extraction's, every triangle: so is the drop-in's
        # (rfta.reconstruct simplifies).
        simplify=False,
    )
    d = U.shape[1]
    try:
        if d == 2:
            V, F, P, N = _rfta.reconstruct_2d(S, U, "default", options)
        else:
            V, F, P, N, _ = _run(S, U, None, "default", options, _printer(verbose, None))
    except NoSurfaceError as e:
        # gpytoolbox answers samples that describe no surface with an empty mesh.
        if verbose:
            warnings.warn(f"rfta: {e}; returning an empty mesh", stacklevel=2)
        V, F = np.zeros((0, d)), np.zeros((0, d), dtype=np.int32)
        P, N = np.zeros((0, d)), np.zeros((0, d))
    F = F.astype(np.int32)
    if return_point_cloud:
        return V, F, P, N
    return V, F


def screened_poisson(
    points: Any,
    normals: Any,
    depth: Optional[int] = None,
    screening: Optional[float] = None,
    preset: str = "poissonrecon",
):
    """Screened Poisson surface reconstruction (Kazhdan and Hoppe 2013) of oriented points.

    ``preset="poissonrecon"`` uses PoissonRecon's defaults (depth 8, screening 2),
    ``"rfta"`` the setting the reconstruction runs. Returns ``(V, F)``.
    """
    P, N = _rows("points", points), _rows("normals", normals)
    return _rfta.screened_poisson(P, N, depth=depth, screening=screening, preset=preset)


def marching_cubes(S: Any, bounds: Bounds = None, iso: float = 0.0):
    """Marching cubes of a grid of values over ``bounds`` (as ``reconstruct``). Returns (V, F)."""
    S = _array("S", S, 3)
    lo, hi = _bounds(bounds)
    return _rfta.marching_cubes(S, lo, hi, float(iso))


def signed_distance(points: Any, V: Any, F: Any) -> np.ndarray:
    """Distance from each point to the mesh (V, F), negative inside by winding number."""
    return _rfta.signed_distance(_rows("points", points), _rows("V", V), _faces(F))


def sample_sdf(V: Any, F: Any, res: int, bounds: Bounds = None) -> np.ndarray:
    """The exact signed distance of the mesh (V, F) on a (res + 1)^3 grid over ``bounds``
    (default [-1, 1]^3), as an array ``S[i, j, k]`` ready for ``reconstruct``."""
    res = int(res)
    if res < 1:
        raise ValueError("res must be at least 1 (the grid has res + 1 points per axis)")
    lo, hi = _bounds(bounds)
    dims = [res + 1] * 3
    flat = _rfta.sample_sdf(_rows("V", V), _faces(F), dims, lo, hi)
    return flat.reshape(dims)
