"""Reach for the Arcs: triangle meshes from signed distance samples.

Sellán, Ren, Batty and Stein, "Reach For the Arcs: Reconstructing Surfaces from SDFs via Tangent
Points", SIGGRAPH 2024, implemented in Rust (the rfta repository, crates/rfta-py).

Two ways in:

- ``reach_for_the_arcs(U, S, ...)``: gpytoolbox's function, argument for argument, so that
  changing the import is the whole migration.
- ``reconstruct(S, bounds=..., preset="default", ...)``: a grid of values (or scattered samples)
  in, a ``Reconstruction`` (vertices, faces, tangency points, report) out.

Beside them: ``read_sdf`` (files: ``.npy``, ``.exr``, OpenVDB ``.vdb`` level sets, scattered
samples; its ``Samples`` go to ``reconstruct`` as they are), ``screened_poisson``,
``marching_cubes``, ``signed_distance``, ``sample_sdf``.

Arrays may be float32 or float64, in any memory layout; results are float64 vertices and int64
faces (the drop-in returns int32 faces, as gpytoolbox does). Long calls release the GIL (other Python threads run), stop on Ctrl-C between stages
(``KeyboardInterrupt``), and raise ``ValueError`` for bad input (``NoSurfaceError``, a
``ValueError``, when the samples describe no surface) or ``RuntimeError`` with the library's
message. Results do not depend on the thread count.
"""

from ._api import (
    NoSurfaceError,
    Reconstruction,
    RftaWarning,
    Samples,
    marching_cubes,
    reach_for_the_arcs,
    read_sdf,
    reconstruct,
    sample_sdf,
    screened_poisson,
    signed_distance,
)
from ._rfta import __version__

__all__ = [
    "NoSurfaceError",
    "Reconstruction",
    "RftaWarning",
    "Samples",
    "__version__",
    "marching_cubes",
    "reach_for_the_arcs",
    "read_sdf",
    "reconstruct",
    "sample_sdf",
    "screened_poisson",
    "signed_distance",
]

# The public objects say they are rfta's (help(), repr, pickling of a Reconstruction).
for _name in __all__:
    if _name != "__version__":
        globals()[_name].__module__ = __name__
del _name
