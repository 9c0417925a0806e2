"""Type stubs of the extension module behind the `rfta` package (use the package's functions)."""

from typing import Any, Callable, Optional, Sequence, Tuple

import numpy as np
import numpy.typing as npt

__version__: str

class NoSurfaceError(ValueError): ...

def reconstruct(
    values: npt.NDArray[np.float64],
    positions: Optional[npt.NDArray[np.float64]] = None,
    dims: Optional[Sequence[int]] = None,
    lo: Optional[Sequence[float]] = None,
    hi: Optional[Sequence[float]] = None,
    preset: str = "default",
    options: Optional[dict] = None,
    progress: Optional[Callable[[str, int, int], Any]] = None,
) -> Tuple[
    npt.NDArray[np.float64],
    npt.NDArray[np.int64],
    npt.NDArray[np.float64],
    npt.NDArray[np.float64],
    dict,
]: ...
def reconstruct_adaptive(
    sdf: Callable[[npt.NDArray[np.float64]], Any],
    lo: Sequence[float],
    hi: Sequence[float],
    budget: int,
    preset: str = "default",
    options: Optional[dict] = None,
    progress: Optional[Callable[[str, int, int], Any]] = None,
) -> Tuple[
    npt.NDArray[np.float64],
    npt.NDArray[np.int64],
    npt.NDArray[np.float64],
    npt.NDArray[np.float64],
    dict,
    dict,
    npt.NDArray[np.float64],
    npt.NDArray[np.float64],
]: ...
def page(
    vertices: npt.NDArray[np.float64],
    triangles: npt.NDArray[np.int64],
    values: npt.NDArray[np.float64],
    positions: Optional[npt.NDArray[np.float64]] = None,
    dims: Optional[Sequence[int]] = None,
    lo: Optional[Sequence[float]] = None,
    hi: Optional[Sequence[float]] = None,
    clamp: Optional[float] = None,
    title: str = "rfta",
    figures: Sequence[Tuple[str, str]] = ...,
) -> str: ...
def report_figures(report: str) -> list[Tuple[str, str]]: ...
def reconstruct_2d(
    values: npt.NDArray[np.float64],
    positions: npt.NDArray[np.float64],
    preset: str = "default",
    options: Optional[dict] = None,
) -> Tuple[
    npt.NDArray[np.float64],
    npt.NDArray[np.int64],
    npt.NDArray[np.float64],
    npt.NDArray[np.float64],
]: ...
def screened_poisson(
    points: npt.NDArray[np.float64],
    normals: npt.NDArray[np.float64],
    depth: Optional[int] = None,
    screening: Optional[float] = None,
    preset: str = "poissonrecon",
) -> Tuple[npt.NDArray[np.float64], npt.NDArray[np.int64]]: ...
def marching_cubes(
    values: npt.NDArray[np.float64],
    lo: Sequence[float],
    hi: Sequence[float],
    iso: float = 0.0,
) -> Tuple[npt.NDArray[np.float64], npt.NDArray[np.int64]]: ...
def signed_distance(
    points: npt.NDArray[np.float64],
    v: npt.NDArray[np.float64],
    f: npt.NDArray[np.int64],
) -> npt.NDArray[np.float64]: ...
def sample_sdf(
    v: npt.NDArray[np.float64],
    f: npt.NDArray[np.int64],
    dims: Sequence[int],
    lo: Sequence[float],
    hi: Sequence[float],
) -> npt.NDArray[np.float64]: ...
def read_sdf(
    path: str, grid: Optional[str] = None
) -> Tuple[
    npt.NDArray[np.float64],
    Optional[Tuple[int, int, int]],
    Optional[Tuple[float, float, float]],
    Optional[Tuple[float, float, float]],
    Optional[npt.NDArray[np.float64]],
    Optional[float],
    str,
]: ...
