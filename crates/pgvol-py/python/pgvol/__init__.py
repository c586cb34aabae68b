"""pgvol: triangle meshes to compact, smooth implicit fields and back, with NumPy arrays in
and out.

A :class:`Field` holds the coefficients of a compactly supported basis (the cubic B-spline by
default) on a grid; its value at a point is their weighted sum, the signed distance to the
surface near it (negative inside, positive outside, in the mesh's units), with an analytic
gradient.

    >>> import pgvol
    >>> v, t = pgvol.read_mesh("part.stl")
    >>> f = pgvol.Field.from_mesh(v, t, res=256)
    >>> d = f(points)                       # (N,) float32
    >>> v2, t2 = f.to_mesh(method="dc")     # a watertight mesh

See docs/python.md in the repository for the conventions, errors, threads and progress.
"""

from ._errors import (
    CancelledError,
    EmptyResultError,
    InputFileError,
    InternalError,
    MissingFileError,
    OutputFileError,
    ParameterError,
    PgvolError,
    PgvolWarning,
    ResourceLimitError,
)
from ._pgvol import (
    COMPARE_SAMPLES,
    DEFAULT_RES,
    ENCODE_BAND,
    MAX_RES,
    MIN_RES,
    Cleanup,
    Comparison,
    DepthDifference,
    Field,
    Grid,
    Layer,
    MaskReport,
    MeshStats,
    PerturbLoop,
    PerturbReport,
    Refusals,
    Strays,
    VertexDeviation,
    ViewDifference,
    __version__,
    compare,
    memory_limit,
    perturb,
    read_mesh,
    remesh,
    set_memory_limit,
    signed_distance,
    slice_file,
    write_mesh,
)

for _cls in (
    CancelledError,
    EmptyResultError,
    InputFileError,
    InternalError,
    MissingFileError,
    OutputFileError,
    ParameterError,
    PgvolError,
    PgvolWarning,
    ResourceLimitError,
):
    _cls.__module__ = __name__
del _cls

__all__ = [
    "COMPARE_SAMPLES",
    "DEFAULT_RES",
    "ENCODE_BAND",
    "MAX_RES",
    "MIN_RES",
    "CancelledError",
    "Cleanup",
    "Comparison",
    "DepthDifference",
    "EmptyResultError",
    "Field",
    "Grid",
    "InputFileError",
    "InternalError",
    "Layer",
    "MaskReport",
    "MeshStats",
    "MissingFileError",
    "OutputFileError",
    "ParameterError",
    "PerturbLoop",
    "PerturbReport",
    "PgvolError",
    "PgvolWarning",
    "Refusals",
    "ResourceLimitError",
    "Strays",
    "VertexDeviation",
    "ViewDifference",
    "__version__",
    "compare",
    "memory_limit",
    "perturb",
    "read_mesh",
    "remesh",
    "set_memory_limit",
    "signed_distance",
    "slice_file",
    "write_mesh",
]
