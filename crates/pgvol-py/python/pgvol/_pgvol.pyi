"""Type stubs of the pgvol extension module."""

import os
from typing import (
    Any,
    Callable,
    Dict,
    Iterable,
    List,
    Literal,
    Optional,
    Sequence,
    Tuple,
    Union,
    final,
    overload,
)

import numpy as np
import numpy.typing as npt

__all__ = [
    "Field",
    "Grid",
    "Layer",
    "MaskReport",
    "Comparison",
    "MeshStats",
    "VertexDeviation",
    "DepthDifference",
    "ViewDifference",
    "PerturbReport",
    "PerturbLoop",
    "Refusals",
    "Cleanup",
    "Strays",
    "read_mesh",
    "write_mesh",
    "compare",
    "remesh",
    "signed_distance",
    "slice_file",
    "perturb",
    "set_memory_limit",
    "memory_limit",
    "__version__",
    "DEFAULT_RES",
    "MIN_RES",
    "MAX_RES",
    "ENCODE_BAND",
    "COMPARE_SAMPLES",
    "EncodeJob",
    "EncodedPart",
    "plan_encode",
    "assemble_encode",
    "write_encode_parts",
    "plan_decode",
    "decode_part_bricks",
    "decode_part",
    "plan_decode_file",
    "decode_file_part_bricks",
    "decode_file_part",
    "weld_parts",
    "plan_slice",
    "slice_part_bricks",
    "slice_part",
    "sharpen_layers",
    "plan_slice_file",
    "slice_file_part_bricks",
    "slice_file_part",
    "sharpen_file_layers",
    "write_layers",
]

__version__: str
DEFAULT_RES: int
MIN_RES: int
MAX_RES: int
ENCODE_BAND: float
COMPARE_SAMPLES: int

_PathLike = Union[str, "os.PathLike[str]"]
_Points = npt.ArrayLike
"""(N, 3) float32 or float64, any memory order."""
_Faces = npt.ArrayLike
"""(M, 3) int32, int64, uint32 or uint64 vertex indices, counter-clockwise seen from outside."""
_Progress = Callable[[str, float], Any]
"""Called as progress(stage, fraction): at the start of each stage (0.0), at most every 0.1 s
while it runs, and at its end (1.0). An exception it raises stops the call and propagates."""
_MeshLike = Union[Tuple[_Points, _Faces], Any]
"""A (vertices, faces) pair, or an object with .vertices and .faces (a trimesh.Trimesh)."""
_Vec3 = Tuple[float, float, float]
_PointsMethod = Literal["spline", "tangent", "rbf-wendland", "rbf-cubic"]
_Drain = Union[Sequence[float], Tuple[Sequence[float], Sequence[float], float]]
"""(x, y, z, dx, dy, dz, diameter) or ((x, y, z), (dx, dy, dz), diameter): a point inside the
cavity, the direction out through the wall, and the hole's diameter."""
_Mask = Union[Sequence[float], Tuple[Sequence[float], Sequence[float]]]
"""(x0, y0, z0, x1, y1, z1) or ((x0, y0, z0), (x1, y1, z1)): an axis-aligned box in model
units."""
_Face = Literal["+x", "-x", "+y", "-y", "+z", "-z"]
_Surface = Literal["gyroid", "schwarz-p", "primitive", "diamond", "neovius"]
_Segment = Tuple[_Vec3, _Vec3]

@final
class Grid:
    """Grid nodes: node (i, j, k) lies at origin + spacing * (i, j, k)."""

    def __new__(cls, origin: _Vec3, spacing: float, dims: Tuple[int, int, int]) -> "Grid": ...
    @property
    def origin(self) -> _Vec3:
        """The position of node (0, 0, 0)."""
    @property
    def spacing(self) -> float:
        """The distance between neighbouring nodes along every axis."""
    @property
    def dims(self) -> Tuple[int, int, int]:
        """Nodes along x, y and z."""
    @property
    def max_corner(self) -> _Vec3:
        """The position of the last node, origin + spacing * (dims - 1)."""
    def __eq__(self, other: object, /) -> bool: ...

@final
class Layer:
    """The closed contours of one layer plane."""

    def __new__(
        cls, height: float, loops: List[npt.NDArray[np.float32]], holes: List[bool]
    ) -> "Layer": ...

    @property
    def height(self) -> float:
        """Position of the plane along the slicing axis."""
    @property
    def loops(self) -> List[npt.NDArray[np.float32]]:
        """One (M, 2) float32 array of in-plane coordinates per closed loop: (y, z) for axis x,
        (z, x) for axis y, (x, y) for axis z."""
    @property
    def holes(self) -> List[bool]:
        """Per loop: a hole (clockwise) rather than an outer boundary (counter-clockwise)."""

@final
class MaskReport:
    """What a repair did inside one mask."""

    @property
    def nodes(self) -> int:
        """Grid nodes whose values were restored."""
    @property
    def iterations(self) -> int:
        """Iterations of the Laplace fill (0 when denoising)."""
    @property
    def coefficients(self) -> int:
        """Coefficients the local re-fit may have changed."""
    @property
    def fit_error(self) -> float:
        """The largest difference between the re-fitted field and the restored values at the
        mask's nodes."""

@final
class MeshStats:
    """Topology and size of a mesh."""

    @property
    def vertices(self) -> int:
        """Vertices referenced by at least one triangle."""
    @property
    def triangles(self) -> int: ...
    @property
    def edges(self) -> int:
        """Unique undirected edges."""
    @property
    def boundary_edges(self) -> int:
        """Edges used by exactly one triangle."""
    @property
    def non_manifold_edges(self) -> int:
        """Edges used by three or more triangles."""
    @property
    def watertight(self) -> bool:
        """Every edge used by exactly two triangles."""
    @property
    def winding_consistent(self) -> bool:
        """Every edge shared by two triangles is traversed once in each direction."""
    @property
    def euler_characteristic(self) -> int:
        """V - E + F."""
    @property
    def volume(self) -> float:
        """Signed volume by the divergence theorem; positive for outward-facing closed meshes."""
    @property
    def area(self) -> float: ...
    @property
    def components(self) -> int:
        """Connected components, where triangles sharing a vertex are connected."""

@final
class VertexDeviation:
    """Distances from the vertices of mesh A to mesh B, and the angles between their normals."""

    @property
    def vertices(self) -> int: ...
    @property
    def mean(self) -> float: ...
    @property
    def max(self) -> float: ...
    @property
    def normal_mean_deg(self) -> float:
        """Angle between A's vertex normal and B's normal at the closest point, in degrees."""
    @property
    def normal_max_deg(self) -> float: ...

@final
class ViewDifference:
    """The depth-buffer difference of one view."""

    @property
    def direction(self) -> Tuple[float, float, float]:
        """The view's depth direction."""
    @property
    def covered(self) -> int:
        """Pixels covered by either mesh."""
    @property
    def mean_abs(self) -> float:
        """Mean absolute depth difference over those pixels, in mesh units."""

@final
class DepthDifference:
    """Depth buffers of two meshes rendered from the same views, compared."""

    @property
    def views(self) -> List[ViewDifference]: ...
    @property
    def resolution(self) -> int:
        """Pixels per side of each view."""
    @property
    def mean_abs(self) -> float:
        """Mean absolute difference over every covered pixel of every view, in mesh units."""

@final
class Comparison:
    """Mesh ``a`` measured against reference mesh ``b``; ``_pct`` figures are percent of b's
    bounding-box diagonal."""

    @property
    def a(self) -> MeshStats: ...
    @property
    def b(self) -> MeshStats: ...
    @property
    def samples(self) -> int:
        """Samples drawn on each mesh."""
    @property
    def diagonal(self) -> float:
        """Bounding-box diagonal of b."""
    @property
    def hausdorff(self) -> float: ...
    @property
    def hausdorff_pct(self) -> float: ...
    @property
    def chamfer_l1(self) -> float: ...
    @property
    def chamfer_l1_pct(self) -> float: ...
    @property
    def mean_a_to_b(self) -> float: ...
    @property
    def mean_b_to_a(self) -> float: ...
    @property
    def normal_deviation_mean_deg(self) -> float:
        """Angle between the normals at each sample and at its closest point on the other mesh, pooled over both directions, in degrees."""
    @property
    def normal_deviation_p95_deg(self) -> float: ...
    @property
    def vertex_deviation(self) -> VertexDeviation: ...
    @property
    def vertex_deviation_mean_pct(self) -> float: ...
    @property
    def vertex_deviation_max_pct(self) -> float: ...
    @property
    def depth_buffer(self) -> DepthDifference:
        """Depth buffers from 14 views."""
    @property
    def depth_buffer_pct(self) -> float: ...

@final
class Refusals:
    """Seeds of the perturbation loop refused, by reason."""

    @property
    def too_few_points(self) -> int:
        """Fewer than ten vertices of the seed's sign within the trial radius."""
    @property
    def not_local(self) -> int:
        """No solve gave a local bump."""
    @property
    def no_gain(self) -> int:
        """The best bump did not lower the functional."""
    @property
    def probes(self) -> int:
        """The bump put more probes on the wrong side."""

@final
class PerturbLoop:
    """What the perturbation loop did; deviations in mesh units."""

    @property
    def functions(self) -> int:
        """Perturbations in the field: the loop's plus the clearing bumps."""
    @property
    def loop_functions(self) -> int:
        """Perturbations the loop added."""
    @property
    def sign_points(self) -> int:
        """Sign points given."""
    @property
    def wrong_side_of_base(self) -> int:
        """Sign points on the wrong side of the base quadric."""
    @property
    def wrong_side_before_clearing(self) -> int:
        """Sign points on the wrong side after the loop, before its clearing pass."""
    @property
    def wrong_side_after(self) -> int:
        """Sign points on the wrong side at the end."""
    @property
    def vertices(self) -> int: ...
    @property
    def diagonal(self) -> float:
        """The mesh's bounding-box diagonal."""
    @property
    def base_mean(self) -> float:
        """Mean vertex deviation estimate of the base quadric alone."""
    @property
    def base_max(self) -> float:
        """Largest vertex deviation estimate of the base quadric alone."""
    @property
    def mean(self) -> float:
        """Mean vertex deviation estimate after the last perturbation."""
    @property
    def max(self) -> float:
        """Largest vertex deviation estimate after the last perturbation."""
    @property
    def base_functional(self) -> float:
        """The functional the loop lowers (mean |M| over the vertices) for the base quadric."""
    @property
    def history(self) -> List[float]:
        """The functional after each accepted perturbation (never increasing)."""
    @property
    def base_exact(self) -> bool:
        """Whether the base quadric took the exact least-squares fit."""
    @property
    def trials(self) -> int:
        """Trial perturbations evaluated."""
    @property
    def seeds_set_aside(self) -> int: ...
    @property
    def exact_solves(self) -> int:
        """Perturbations whose ten-point system was solved exactly."""
    @property
    def descent_steps(self) -> int:
        """Descent steps taken on the chosen perturbations' coefficients."""
    @property
    def refusals(self) -> Refusals: ...
    @property
    def stop(self) -> str:
        """Why the loop ended: "tolerance", "max_functions", "no_improvement" or "cancelled"."""
    @property
    def seconds(self) -> float: ...

@final
class Cleanup:
    """The pass clearing wrong nodes of the check grid away from the surface."""

    @property
    def wrong_before(self) -> int:
        """Checked points on the wrong side of the field before the pass."""
    @property
    def bumps(self) -> int:
        """Clearing bumps added."""
    @property
    def wrong_after(self) -> int:
        """Checked points still on the wrong side after it."""

@final
class Strays:
    """The passes removing stray pieces left on the check grid."""

    @property
    def pieces(self) -> int:
        """Stray pieces found before the passes."""
    @property
    def nodes(self) -> int:
        """Their nodes, each given a bump."""
    @property
    def against_mesh(self) -> int:
        """Of those, nodes on the mesh's side held by a stray piece (parts thinner than the grid)."""
    @property
    def rounds(self) -> int:
        """Passes that found stray pieces."""
    @property
    def pieces_left(self) -> int:
        """Stray pieces left after the last pass."""

@final
class PerturbReport:
    """What a conversion by the perturbation method did: the loop, then the two checks."""

    @property
    def perturbation(self) -> PerturbLoop: ...
    @property
    def cleanup(self) -> Cleanup: ...
    @property
    def strays(self) -> Strays: ...

@final
class Field:
    """A smooth implicit field: coefficients of a compactly supported basis on a grid.

    Near the surface its value is the signed distance (negative inside, positive outside, in
    the mesh's units); beyond ``exact_band`` it keeps the right sign with a clamped magnitude.
    Fields are immutable: operations return new ones. Every method that takes time releases
    the GIL.
    """

    @staticmethod
    def from_mesh(
        vertices: _Points,
        faces: _Faces,
        *,
        res: Optional[int] = None,
        voxel: Optional[float] = None,
        band: float = 4.0,
        basis: str = "bspline3",
        fit: Literal["interp", "iso", "wls"] = "interp",
        sign: Literal["auto", "winding", "pseudonormal", "parity"] = "auto",
        z_step: Optional[float] = None,
        sharp: Literal["off", "auto"] = "off",
        sharp_angle: Optional[float] = None,
        progress: Optional[_Progress] = None,
    ) -> "Field":
        """Encodes a triangle mesh.

        The grid is a cube of side 1.1 x the mesh's longest extent, centred on it, with ``res``
        nodes per axis (default 128) or spacing ``voxel``. Exact distances are sampled within
        ``band`` grid spacings of the surface (widen it for larger offsets and shells) and
        fitted with ``basis`` ("bspline3", "bspline2", "trilinear", "pg" or "pg-n<N>-r<R>").
        Vertices are welded and degenerate triangles dropped as when reading a file.
        ``sharp="auto"`` stores the exact vertices of the cells at creases turning by more than
        ``sharp_angle`` degrees (default 30), so that ``to_mesh(method="dc")`` (or "sn") on the file's own
        grid keeps them sharp, as ``pgvol encode --sharp auto`` and ``pgvol.distributed.encode``
        with the same options do.
        """
    @overload
    @staticmethod
    def from_points(
        points: _Points,
        normals: Optional[_Points] = None,
        *,
        res: Optional[int] = None,
        voxel: Optional[float] = None,
        method: _PointsMethod = "spline",
        band: float = 4.0,
        support: Optional[float] = None,
        sections: None = None,
        section_resolution: None = None,
        progress: Optional[_Progress] = None,
    ) -> "Field": ...
    @overload
    @staticmethod
    def from_points(
        points: _Points,
        normals: Optional[_Points] = None,
        *,
        res: Optional[int] = None,
        voxel: Optional[float] = None,
        method: _PointsMethod = "spline",
        band: float = 4.0,
        support: Optional[float] = None,
        sections: Tuple[Literal["x", "y", "z"], Sequence[float]],
        section_resolution: Optional[float] = None,
        progress: Optional[_Progress] = None,
    ) -> Tuple["Field", List[Layer]]:
        """A smooth closed surface through a point cloud: ``points`` (N, 3) with optional
        outward unit ``normals`` (N, 3), estimated and oriented when not given.

        The grid is a cube of side 1.1 x the cloud's longest extent with ``res`` nodes per
        axis (default 128) or spacing ``voxel``. ``method``: "spline" (least-squares B-spline
        fit), "tangent" (tangent-plane distance), "rbf-wendland" (compactly supported RBFs of
        radius ``support`` correcting the spline fit) or "rbf-cubic" (global r^3 RBF, at most
        2000 points). Node values are kept within ``band`` grid spacings of the points.

        With ``sections=(axis, heights)``, e.g. ``("z", [0.0, 0.5])``, returns ``(field,
        layers)``: cross-sections in the planes normal to ``axis`` at ``heights`` (within the
        grid's box), cut from the method's own field before it is resampled on the grid (for
        the RBF methods, the RBF interpolant), one Layer per distinct height, bottom first,
        sampled every ``section_resolution`` (default: the grid spacing). A plane that misses
        the surface gives a Layer without loops and a PgvolWarning.
        """
    @staticmethod
    def from_contours(
        layers: Union[Sequence[Layer], _PathLike],
        *,
        axis: Literal["x", "y", "z"] = "z",
        res: Optional[int] = None,
        voxel: Optional[float] = None,
        method: _PointsMethod = "spline",
        progress: Optional[_Progress] = None,
    ) -> "Field":
        """A closed solid through a stack of planar contours along ``axis``: Layers (as
        ``slice`` returns them) or a layer file (.json, .cli or .svg, as ``write_layers`` and
        ``pgvol slice`` write them), one layer per height, holes as clockwise loops.

        The grid is a cube of side 1.1 x the stack's longest extent with ``res`` nodes per axis
        (default 128) or spacing ``voxel``. ``method`` "spline" interpolates each plane's 2D
        signed distance across the planes by a cubic spline along the axis; the RBF methods
        fit points along the loops. The solid is closed half a layer (at least 2 grid
        spacings) beyond the outermost planes."""
    @staticmethod
    def from_trimesh(mesh: Any, **kwargs: Any) -> "Field":
        """Encodes a trimesh.Trimesh; the keywords are those of from_mesh."""
    @staticmethod
    def load(path: _PathLike) -> "Field":
        """Reads a .pgv file, or an OpenVDB .vdb level set (as from_vdb reads it)."""
    @staticmethod
    def from_vdb(path: _PathLike, grid: Optional[str] = None) -> "Field":
        """Fits an OpenVDB level set (the first float level set of a .vdb file, or the one
        named `grid`) on its own voxel grid, within its band."""
    @staticmethod
    def from_bytes(data: bytes) -> "Field":
        """Decodes the bytes of a .pgv file."""
    def save(
        self,
        path: _PathLike,
        *,
        dense: Optional[bool] = None,
        precision: Optional[Literal["f32", "f16", "q16", "fixed"]] = None,
    ) -> None:
        """Writes a .pgv file atomically: sparse compressed bricks around the surface by
        default (fields made by offset, shell, lattice or infill too), every coefficient as
        float32 with ``dense=True``. A field loaded from a file and saved with the same options
        gives the same bytes."""
    def to_bytes(
        self,
        *,
        dense: Optional[bool] = None,
        precision: Optional[Literal["f32", "f16", "q16", "fixed"]] = None,
    ) -> bytes:
        """The bytes save() would write."""
    def __call__(self, points: _Points) -> npt.NDArray[np.float32]:
        """Values at (N, 3) points: an (N,) float32 array, negative inside."""
    def eval_with_gradient(
        self, points: _Points
    ) -> Tuple[npt.NDArray[np.float32], npt.NDArray[np.float32]]:
        """Values (N,) and analytic gradients (N, 3), float32."""
    def is_exact(self, points: _Points) -> npt.NDArray[np.bool_]:
        """Whether each value is an exact distance: inside the grid's box and within
        exact_band of the surface."""
    def sample_grid(self, grid: Optional[Grid] = None) -> npt.NDArray[np.float32]:
        """The field at every node of ``grid`` (default: the field's own grid), as a float32
        array of shape (nx, ny, nz): ``a[i, j, k]`` is the value at
        ``origin + spacing * (i, j, k)``. The array is Fortran-ordered (x fastest in memory)."""
    def to_dense(self) -> npt.NDArray[np.float32]:
        """sample_grid() on the field's own grid."""
    @overload
    def to_mesh(
        self,
        *,
        method: Literal["mc", "sn", "dc"] = "mc",
        iso: float = 0.0,
        res: Optional[int] = None,
        min_component: Optional[float] = None,
        normals: Literal[False] = False,
        progress: Optional[_Progress] = None,
    ) -> Tuple[npt.NDArray[np.float32], npt.NDArray[np.int32]]:
        """Contours the level set ``iso`` into a watertight, manifold mesh: vertices (N, 3)
        float32 and faces (M, 3) int32, counter-clockwise seen from outside. ``method``:
        marching cubes, surface nets or dual contouring; ``res`` resamples the box with that
        many nodes along its longest side; pieces enclosing less than ``min_component``
        (default: 2 grid cells) are removed, ``0`` keeps every piece. With ``normals=True``,
        also the vertices' unit normals (N, 3) float32, those a file written by ``pgvol decode``
        stores: the field's gradient direction at each vertex for marching cubes on the
        field's own grid or on a resampled one, else weighted from the faces."""
    @overload
    def to_mesh(
        self,
        *,
        method: Literal["mc", "sn", "dc"] = "mc",
        iso: float = 0.0,
        res: Optional[int] = None,
        min_component: Optional[float] = None,
        normals: Literal[True],
        progress: Optional[_Progress] = None,
    ) -> Tuple[npt.NDArray[np.float32], npt.NDArray[np.int32], npt.NDArray[np.float32]]: ...
    def to_trimesh(self, **kwargs: Any) -> Any:
        """to_mesh() as a trimesh.Trimesh with to_mesh(normals=True)'s vertex normals (needs
        trimesh)."""
    def offset(self, distance: float) -> "Field":
        """The shape grown (distance > 0) or shrunk (distance < 0); |distance| must be below
        exact_band."""
    def resample(
        self,
        res: int = 128,
        *,
        bounds: Optional[Tuple[_Vec3, _Vec3]] = None,
        band: float = 4.0,
        progress: Optional[_Progress] = None,
    ) -> "Field":
        """This field sampled on a cube grid of ``res`` nodes per axis over its box (or over
        ``bounds``) and fitted again; node values within ``band`` grid spacings of the surface
        kept, clamped beyond."""
    @staticmethod
    def primitive(
        solid: str,
        *,
        res: int = 128,
        bounds: Optional[Tuple[_Vec3, _Vec3]] = None,
        band: float = 4.0,
        progress: Optional[_Progress] = None,
    ) -> "Field":
        """An analytic solid given as ``csg`` takes it (``"sphere:x,y,z,r"``, ``"box:..."``,
        ``"plane:..."``, ``"cylinder:..."``) as a field on a cube grid of ``res`` nodes over its
        box (``bounds`` for planes and cylinders), exact within ``band`` grid spacings."""
    def denoise(
        self,
        masks: Sequence[_Mask],
        *,
        coarse: int = 30,
        progress: Optional[_Progress] = None,
    ) -> "Field":
        """The field inside ``masks`` resampled with ``coarse`` samples along each mask's longest
        side and blended back: ``repair(masks, denoise=True)``."""
    def shell(
        self,
        thickness: float,
        *,
        side: Literal["inner", "outer", "centred"] = "inner",
        hollow: bool = False,
        drains: Optional[Sequence[_Drain]] = None,
        progress: Optional[_Progress] = None,
    ) -> "Field":
        """A wall of ``thickness`` on ``side`` of the surface, or with ``hollow=True`` the
        shape with a cavity ``thickness`` inside its surface and optional drain holes."""
    def lattice(
        self,
        surface: _Surface,
        cell: float,
        thickness: float,
        *,
        style: Literal["sheet", "strut"] = "sheet",
        grade_depth: Optional[float] = None,
        grade_linear: Optional[_Segment] = None,
        cell_far: Optional[float] = None,
        thickness_far: Optional[float] = None,
        progress: Optional[_Progress] = None,
    ) -> "Field":
        """The part cut by a triply periodic lattice of period ``cell``: ``style`` "sheet" (a
        wall of ``thickness``) or "strut" (a labyrinth bounded at the level ``thickness``).
        Grading: ``grade_depth`` (from the skin to that depth) or ``grade_linear`` (from one
        point to another), towards ``cell_far`` and ``thickness_far``."""
    def lattice_3mf(
        self,
        path: _PathLike,
        surface: _Surface,
        cell: float,
        thickness: float,
        *,
        style: Literal["sheet", "strut"] = "sheet",
        wall: Optional[float] = None,
        drains: Optional[Sequence[_Drain]] = None,
        grade_depth: Optional[float] = None,
        grade_linear: Optional[_Segment] = None,
        cell_far: Optional[float] = None,
        thickness_far: Optional[float] = None,
        unit: Literal[
            "micron", "millimeter", "centimeter", "inch", "foot", "meter"
        ] = "millimeter",
    ) -> Grid:
        """Writes the lattice (the parameters of ``lattice``) cut to this part, or with ``wall``
        the infill of the part hollowed to that wall with ``drains``, as a 3MF package: the part
        as the level set's image stack, the lattice as an implicit function of it. Returns the
        image stack's grid."""
    def infill(
        self,
        wall: float,
        surface: _Surface,
        cell: float,
        thickness: float,
        *,
        style: Literal["sheet", "strut"] = "sheet",
        drains: Optional[Sequence[_Drain]] = None,
        grade_depth: Optional[float] = None,
        grade_linear: Optional[_Segment] = None,
        cell_far: Optional[float] = None,
        thickness_far: Optional[float] = None,
        progress: Optional[_Progress] = None,
    ) -> "Field":
        """The shape hollowed to walls of ``wall`` thickness with the cavity filled by a
        lattice (the parameters of ``lattice``), and ``drains`` cut through wall and
        lattice."""
    def union(self, other: "Field", *, radius: Optional[float] = None) -> "Field":
        """This shape joined with ``other``: sharp, or rounded with ``radius`` (model units).

        The result is re-fitted in the cubic B-spline on a grid covering both shapes (grown by
        the radius) as fine as the finer of their grids, and is a distance within 4 spacings of
        its surface. Rounding reads exact distances up to the radius from each surface: each
        field's ``exact_band`` must reach it."""
    def intersection(self, other: "Field", *, radius: Optional[float] = None) -> "Field":
        """What this shape and ``other`` share, sharp or rounded with ``radius``; see
        ``union``."""
    def difference(self, other: "Field", *, radius: Optional[float] = None) -> "Field":
        """This shape less ``other``, sharp or rounded with ``radius``; see ``union``."""
    @staticmethod
    def csg(
        operands: Sequence[Union["Field", str, "os.PathLike[str]"]],
        op: Literal["union", "intersection", "difference"] = "union",
        *,
        radius: Optional[float] = None,
        res: int = 128,
        bounds: Optional[_Segment] = None,
        sign: Literal["auto", "winding", "pseudonormal", "parity"] = "auto",
        progress: Optional[_Progress] = None,
    ) -> "Field":
        """The Boolean ``op`` of two or more ``operands`` (for "difference", the first less the
        others), sharp or rounded with ``radius``.

        An operand is a Field, an analytic solid ("sphere:cx,cy,cz,r", "box:cx,cy,cz,hx,hy,hz",
        "plane:nx,ny,nz,d", "cylinder:px,py,pz,ax,ay,az,r") or the path of a .pgv or mesh
        file. The result is re-fitted in the cubic B-spline on a cube grid of ``res`` nodes per
        axis over ``bounds`` (default: the box of every bounded operand, grown by the radius;
        needed when every operand is a plane or cylinder). ``sign`` tells inside from outside
        in mesh files."""
    @staticmethod
    def blend(
        kind: Literal["liming", "spline", "ipatch"],
        primaries: Sequence[Union["Field", str, "os.PathLike[str]"]],
        *,
        cut: Optional[Union["Field", str, "os.PathLike[str]"]] = None,
        bound: Optional[Sequence[Union["Field", str, "os.PathLike[str]"]]] = None,
        lam: float = 0.5,
        weights: Optional[Sequence[float]] = None,
        through: Optional[Tuple[float, float, float]] = None,
        fit_points: Optional[Sequence[Tuple[float, float, float]]] = None,
        continuity: int = 1,
        res: int = 128,
        bounds: Optional[_Segment] = None,
        sign: Literal["auto", "winding", "pseudonormal", "parity"] = "auto",
        progress: Optional[_Progress] = None,
    ) -> "Field":
        """An algebraic blend of ``primaries`` (as ``csg``'s operands): "liming" (two primaries
        rounded where they meet by the cutting surface ``cut``), "spline" (a functional spline
        with one or more ``bound`` surfaces) or "ipatch" (one ``bound`` per primary, with
        ``weights`` w1..wn then w, or w1..wn and a point ``through``, or ``fit_points``;
        ``continuity`` the order of contact). ``lam`` is the Liming and spline parameter in
        (0, 1). Re-fitted on a cube grid of ``res`` nodes per axis over ``bounds`` (default:
        the bounded primaries' box)."""
    def __or__(self, other: "Field", /) -> "Field":
        """``a | b``: ``a.union(b)``."""
    def __and__(self, other: "Field", /) -> "Field":
        """``a & b``: ``a.intersection(b)``."""
    def __sub__(self, other: "Field", /) -> "Field":
        """``a - b``: ``a.difference(b)``."""
    # The reflected forms CPython derives from the same number slots: b.__ror__(a) is a | b.
    def __ror__(self, other: "Field", /) -> "Field": ...
    def __rand__(self, other: "Field", /) -> "Field": ...
    def __rsub__(self, other: "Field", /) -> "Field": ...
    @overload
    def repair(
        self,
        masks: Sequence[_Mask],
        *,
        face: Optional[_Face] = None,
        alpha: float = 1.0,
        denoise: bool = False,
        coarse: int = 30,
        reports: Literal[False] = False,
        progress: Optional[_Progress] = None,
    ) -> "Field": ...
    @overload
    def repair(
        self,
        masks: Sequence[_Mask],
        *,
        face: Optional[_Face] = None,
        alpha: float = 1.0,
        denoise: bool = False,
        coarse: int = 30,
        reports: Literal[True],
        progress: Optional[_Progress] = None,
    ) -> Tuple["Field", List[MaskReport]]:
        """The field restored inside axis-aligned ``masks``; coefficients whose support misses
        every mask stay bit-identical.

        With ``face`` ("+x", "-x", "+y", "-y", "+z" or "-z") a protrusion whose base crosses
        that face of each mask is removed and the surface continued across it; ``alpha`` is the
        field's normal derivative across the face (1, a distance's, continues the body; larger
        values lower and flatten the cap). With ``denoise=True`` the field inside each mask is
        resampled with ``coarse`` samples along its longest side (fewer smooth more). Give one
        of the two. The field must be an exact distance over the masks (encode with a band
        reaching the masks' largest side). With ``reports=True``, returns ``(field,
        reports)``, one MaskReport per mask."""
    def export(
        self,
        path: _PathLike,
        *,
        res: Optional[int] = None,
        coefficients: bool = False,
        unit: Literal[
            "micron", "millimeter", "centimeter", "inch", "foot", "meter"
        ] = "millimeter",
        band: float = 3.0,
        half: bool = False,
        vdb_compression: Literal["zip", "none"] = "zip",
    ) -> Grid:
        """Writes the field for other tools, the format by the extension of ``path``.

        ".nrrd" and ".npy": the field sampled on the stored grid, or with ``res`` nodes along
        the box's longest side; NRRD indexed (x, y, z) with the grid's origin and spacing,
        ``.npy`` float32 of shape (nz, ny, nx). ".3mf": a 3MF volumetric level set (a 16-bit
        PNG image stack) naming ``unit``. ".vdb": an OpenVDB FloatGrid level set named
        "surface", voxel (i, j, k) at node (i, j, k); nodes within ``band`` voxels of the
        surface are active, the others hold -band·spacing inside and +band·spacing outside;
        values as 16-bit floats with ``half=True``; value chunks zlib-compressed ("zip") or
        raw ("none"). With ``coefficients=True``, ".nrrd" holds the coefficients on the stored
        grid with the basis in its key/value fields, read back bit-exactly. Returns the grid
        written."""
    def slice(
        self,
        layer_height: float,
        *,
        axis: Literal["x", "y", "z"] = "z",
        first: Optional[float] = None,
        resolution: Optional[float] = None,
        tolerance: Optional[float] = None,
        progress: Optional[_Progress] = None,
    ) -> List[Layer]:
        """Layers of closed contours ``layer_height`` apart along ``axis``, the first half a
        layer above the bottom unless ``first`` is given. To slice a ``.pgv`` file without
        loading it whole, ``slice_file`` gives the same layers."""
    def view(
        self,
        path: _PathLike,
        *,
        section: Optional[Tuple[Literal["x", "y", "z"], float]] = None,
        iso: float = 0.0,
        colours: Optional[Dict[str, str]] = None,
        max_res: int = 256,
        title: Optional[str] = None,
        progress: Optional[_Progress] = None,
    ) -> None:
        """Writes the viewer page (.html), atomically: the surface, lit and turnable, and an
        axis-aligned section computed in the browser from the field, in one file that opens
        from disk. ``section`` is (axis, height) in the model's coordinates; ``colours`` maps
        "surface", "section" and "background" to "#rrggbb"; above ``max_res`` nodes per axis
        the page holds the surface and the field resampled onto a coarser grid."""
    def _repr_html_(self) -> str:
        """The viewer page in an iframe, as a notebook shows the field."""
    @property
    def grid(self) -> Grid:
        """The grid of the coefficients."""
    @property
    def basis(self) -> str:
        """"bspline3", "bspline2", "trilinear" or "pg-n<N>-r<R>"."""
    @property
    def fit(self) -> str:
        """How the coefficients were fitted: "interp", "iso" or "wls"."""
    @property
    def band(self) -> Optional[float]:
        """The recorded distance from the surface, in mesh units, within which the fitted
        samples were exact distances; None when not recorded."""
    @property
    def exact_band(self) -> float:
        """The distance from the surface within which values are exact distances."""
    @property
    def bounds(self) -> Tuple[_Vec3, _Vec3]:
        """The box of the source shape: (min corner, max corner)."""
    @property
    def metadata(self) -> Dict[str, str]:
        """The file header's key/value metadata."""

def read_mesh(path: _PathLike) -> Tuple[npt.NDArray[np.float32], npt.NDArray[np.int32]]:
    """Reads an OBJ, glTF/GLB, STL, PLY or 3MF file (by extension; a 3MF build in millimetres),
    welding bit-identical vertices and dropping degenerate and repeated triangles."""

def write_mesh(
    path: _PathLike, vertices: _Points, faces: _Faces, normals: Optional[_Points] = None
) -> None:
    """Writes a GLB, glTF, OBJ, STL or PLY file (by extension), atomically. The vertex normals
    stored (STL stores none) are ``normals``, one finite (N, 3) row per vertex made unit length
    (a zero one takes a face's direction), where given; else weighted from the faces."""

def compare(
    a: _MeshLike, b: _MeshLike, *, samples: int = 200000, seed: int = 0
) -> Comparison:
    """Mesh ``a`` against reference ``b``: symmetric Hausdorff and Chamfer-L1 distances (also
    in percent of b's bounding-box diagonal), mean distances each way, normal deviation in
    degrees, the deviation of a's vertices and vertex normals from b (``vertex_deviation``), the
    mean depth-buffer difference over 14 views (``depth_buffer``, ``depth_buffer_pct``), and the
    topology statistics of both (``a``, ``b``)."""

def remesh(
    vertices: _Points,
    faces: _Faces,
    *,
    res: Optional[int] = None,
    voxel: Optional[float] = None,
    method: Literal["mc", "sn", "dc"] = "mc",
    field: str = "exact",
    min_component: Optional[float] = None,
    sign: Literal["auto", "winding", "pseudonormal", "parity"] = "auto",
    progress: Optional[_Progress] = None,
) -> Tuple[npt.NDArray[np.float32], npt.NDArray[np.int32]]:
    """A clean, watertight remesh: the mesh's field contoured on a cube grid of ``res`` nodes
    per axis (or spacing ``voxel``) by ``method``. ``field`` "exact" places vertices on the
    mesh's exact signed distance; a basis name ("bspline3", ...) on the coefficient volume an
    encode would give. Returns ``(vertices, faces)``."""

def slice_file(
    path: _PathLike,
    layer_height: float,
    *,
    axis: Literal["x", "y", "z"] = "z",
    first: Optional[float] = None,
    resolution: Optional[float] = None,
    tolerance: Optional[float] = None,
    progress: Optional[_Progress] = None,
) -> List[Layer]:
    """The layers of the ``.pgv`` file at ``path``, as ``Field.load(path).slice(...)`` gives
    them, read slab by slab as ``pgvol slice`` reads it: memory is a window of the volume rather
    than all of it, and no decoding of the whole file comes first."""

def signed_distance(
    vertices: _Points,
    faces: _Faces,
    *,
    res: Optional[int] = None,
    voxel: Optional[float] = None,
    band: Optional[float] = None,
    sign: Literal["auto", "winding", "pseudonormal", "parity"] = "auto",
    progress: Optional[_Progress] = None,
) -> Tuple[npt.NDArray[np.float32], Grid]:
    """The signed distance of a mesh sampled on a grid: a cube of side 1.1 x the mesh's longest
    extent, centred on it, with ``res`` nodes per axis (default 128) or spacing ``voxel``.
    Distances are exact everywhere, or with ``band`` only within that many grid spacings of the
    surface (elsewhere the sign and a clamped magnitude). Returns ``(values, grid)``: float32
    values of shape (nx, ny, nz), ``values[i, j, k]`` at ``origin + spacing * (i, j, k)``,
    negative inside, and the grid."""

def perturb(
    vertices: _Points,
    faces: _Faces,
    *,
    max_functions: int = 2000,
    tolerance: float = 0.001,
    descent_steps: int = 20,
    res: int = 128,
    list_path: Optional[_PathLike] = None,
    progress: Optional[_Progress] = None,
) -> Tuple[Field, PerturbReport]:
    """Converts a mesh by the perturbation method (docs/perturbation.md): a base quadric plus up
    to ``max_functions`` local bumps, until every vertex is within ``tolerance`` of the
    bounding-box diagonal, each refined by up to ``descent_steps`` descent steps on its
    coefficients (the paper's optimisation step), checked on the cube grid of ``res`` nodes per axis so that its
    contour there has the mesh's pieces and no stray ones. Returns the field resampled on that
    grid (metadata ``source = perturbation``) and the report: ``perturbation`` (the loop),
    ``cleanup`` and ``strays`` (the checks). With ``list_path``, also writes the function list
    there (a .pgv file that reads back as the same field)."""

def set_memory_limit(limit: Optional[int]) -> None:
    """Sets the largest estimated peak memory in bytes a call may start with; None restores the
    default, the memory available when the call starts."""

def memory_limit() -> Optional[int]:
    """The memory limit in force, in bytes."""

# Jobs in parts, for pgvol.distributed (see docs/distributed.md).

@final
class EncodedPart:
    """One part of an encode in parts: its coefficient bricks and the nodes it sampled exactly."""

    def __new__(cls, bricks: bytes, exact_nodes: int) -> "EncodedPart": ...
    @property
    def bricks(self) -> bytes:
        """The coefficient bricks and sides of the part's box, as slab bytes."""
    @property
    def exact_nodes(self) -> int:
        """Nodes of the part's stored sample bricks within the band."""

@final
class EncodeJob:
    """The distance queries of a mesh for encoding any of its parts."""

    def __new__(
        cls,
        vertices: _Points,
        faces: Any,
        *,
        res: Optional[int] = None,
        voxel: Optional[float] = None,
        band: float = 4.0,
        basis: str = "bspline3",
        sign: str = "auto",
        sharp: Literal["off", "auto"] = "off",
        sharp_angle: Optional[float] = None,
    ) -> "EncodeJob": ...
    def encode_part(self, y0: int, y1: int, z0: int, z1: int) -> EncodedPart: ...
    def part_bytes(self, y0: int, y1: int, z0: int, z1: int) -> int: ...

def plan_encode(
    vertices: _Points,
    faces: Any,
    parts: int,
    *,
    res: Optional[int] = None,
    voxel: Optional[float] = None,
    band: float = 4.0,
    basis: str = "bspline3",
    sign: str = "auto",
    sharp: Literal["off", "auto"] = "off",
    sharp_angle: Optional[float] = None,
) -> List[Tuple[int, int, int, int, int]]: ...
def assemble_encode(
    vertices: _Points,
    faces: Any,
    bricks: List[bytes],
    *,
    res: Optional[int] = None,
    voxel: Optional[float] = None,
    band: float = 4.0,
    basis: str = "bspline3",
    sign: str = "auto",
    sharp: Literal["off", "auto"] = "off",
    sharp_angle: Optional[float] = None,
) -> Field: ...
def write_encode_parts(
    vertices: _Points,
    faces: Any,
    parts: Iterable[EncodedPart],
    path: _PathLike,
    *,
    res: Optional[int] = None,
    voxel: Optional[float] = None,
    band: float = 4.0,
    basis: str = "bspline3",
    sign: str = "auto",
    sharp: Literal["off", "auto"] = "off",
    sharp_angle: Optional[float] = None,
) -> Tuple[Literal["written", "whole"], Grid]: ...
def plan_decode(field: Field, parts: int) -> List[Tuple[int, int]]: ...
def decode_part_bricks(field: Field, start: int, end: int) -> bytes: ...
def decode_part(
    bricks: bytes, start: int, end: int, *, iso: float = 0.0, normals: bool = True
) -> Tuple[npt.NDArray[Any], ...]: ...
def plan_decode_file(
    path: _PathLike, parts: int
) -> Optional[Tuple[List[Tuple[int, int]], float]]: ...
def decode_file_part_bricks(path: _PathLike, start: int, end: int) -> bytes: ...
def decode_file_part(
    part: bytes, start: int, end: int, *, iso: float = 0.0, normals: bool = True
) -> Tuple[npt.NDArray[Any], ...]: ...
def weld_parts(
    pieces: List[Any],
    spacing: float,
    *,
    iso: float = 0.0,
    min_component: Optional[float] = None,
    normals: bool = True,
) -> Tuple[npt.NDArray[Any], ...]: ...
def plan_slice(
    field: Field,
    parts: int,
    layer_height: float,
    *,
    axis: str = "z",
    first: Optional[float] = None,
    resolution: Optional[float] = None,
    tolerance: Optional[float] = None,
) -> List[Tuple[int, int]]: ...
def slice_part_bricks(
    field: Field,
    start: int,
    end: int,
    layer_height: float,
    *,
    axis: str = "z",
    first: Optional[float] = None,
    resolution: Optional[float] = None,
    tolerance: Optional[float] = None,
) -> bytes: ...
def slice_part(
    bricks: bytes,
    bounds: Tuple[_Vec3, _Vec3],
    start: int,
    end: int,
    layer_height: float,
    *,
    axis: str = "z",
    first: Optional[float] = None,
    resolution: Optional[float] = None,
    tolerance: Optional[float] = None,
) -> List[Layer]: ...
def sharpen_layers(
    field: Field,
    layers: List[Layer],
    layer_height: float,
    *,
    axis: str = "z",
    first: Optional[float] = None,
    resolution: Optional[float] = None,
    tolerance: Optional[float] = None,
) -> List[Layer]: ...
def plan_slice_file(
    path: _PathLike,
    parts: int,
    layer_height: float,
    *,
    axis: str = "z",
    first: Optional[float] = None,
    resolution: Optional[float] = None,
    tolerance: Optional[float] = None,
) -> Optional[List[Tuple[int, int]]]: ...
def slice_file_part_bricks(
    path: _PathLike,
    start: int,
    end: int,
    layer_height: float,
    *,
    axis: str = "z",
    first: Optional[float] = None,
    resolution: Optional[float] = None,
    tolerance: Optional[float] = None,
) -> bytes: ...
def slice_file_part(
    part: bytes,
    start: int,
    end: int,
    layer_height: float,
    *,
    axis: str = "z",
    first: Optional[float] = None,
    resolution: Optional[float] = None,
    tolerance: Optional[float] = None,
) -> List[Layer]: ...
def sharpen_file_layers(
    path: _PathLike,
    layers: List[Layer],
    layer_height: float,
    *,
    axis: str = "z",
    first: Optional[float] = None,
    resolution: Optional[float] = None,
    tolerance: Optional[float] = None,
) -> List[Layer]: ...
def write_layers(
    path: _PathLike, layers: List[Layer], *, binary: bool = False, units_mm: float = 1.0
) -> None: ...
