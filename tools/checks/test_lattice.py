"""`pgvol lattice` and `pgvol shell --infill`: a gyroid sheet of a cube against the volume
fraction of the same implicit sampled finely with numpy, and the printability of the STL
(closed, manifold, no open edges) by trimesh and manifold3d."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

import helpers

TAU = 2.0 * np.pi
SIDE = 10.0
CELL = 5.0
THICKNESS = 0.6
RES = 128
FRACTION_TOLERANCE = 0.01


def gyroid(u):
    """The gyroid function and its gradient in phase coordinates (period 2π)."""
    (sx, sy, sz), (cx, cy, cz) = np.sin(u), np.cos(u)
    value = sx * cy + sy * cz + sz * cx
    gradient = np.stack([cx * cy - sz * sx, cy * cz - sx * sy, cz * cx - sy * sz])
    return value, gradient


def gyroid_sheet(points, cell: float, thickness: float):
    """The documented sheet field: |f / |∇f|| − t/2 with the gradient in model units and the
    distance-like value clamped to half a cell."""
    value, gradient = gyroid(points * (TAU / cell))
    norm = np.linalg.norm(gradient, axis=0) * (TAU / cell)
    clamp = 0.5 * cell
    far = norm * clamp <= np.abs(value)
    d = np.where(far, np.copysign(clamp, value), value / np.where(far, 1.0, norm))
    return np.abs(d) - 0.5 * thickness


def sampled_fraction(n: int = 320) -> float:
    """The fraction of the cube [0, SIDE]³ where the sheet field is negative, by the midpoint
    rule on n³ cells, a slab at a time."""
    centres = (np.arange(n) + 0.5) * (SIDE / n)
    x, y = np.meshgrid(centres, centres, indexing="ij")
    inside = 0
    for z in centres:
        points = np.stack([x, y, np.full_like(x, z)])
        inside += int(np.count_nonzero(gyroid_sheet(points, CELL, THICKNESS) < 0))
    return inside / n**3


@pytest.fixture(scope="module")
def cube_path(work_dir):
    path = work_dir / "lattice" / "cube.stl"
    path.parent.mkdir(parents=True, exist_ok=True)
    trimesh.creation.box(bounds=[[0, 0, 0], [SIDE, SIDE, SIDE]]).export(path)
    return path


def assert_printable(mesh: trimesh.Trimesh):
    """What a slicer needs of an STL: every edge shared by exactly two triangles, consistent
    winding, and a valid manifold for manifold3d."""
    counts = helpers.edge_counts(mesh)
    assert counts["boundary_edges"] == 0 and counts["non_manifold_edges"] == 0, counts
    assert mesh.is_watertight and mesh.is_winding_consistent
    assert helpers.manifold_ok(helpers.manifold_status(mesh)), helpers.manifold_status(mesh)


def test_gyroid_sheet_of_a_cube_matches_the_sampled_fraction(pgvol, cube_path, work_dir):
    out = work_dir / "lattice" / "cube-gyroid.stl"
    report = helpers.run_json([
        pgvol, "lattice", cube_path, "-o", out, "--surface", "gyroid", "--cell", CELL,
        "--thickness", THICKNESS, "--res", RES, "--json",
    ])
    mesh = helpers.load_output(out)
    assert_printable(mesh)
    fraction = mesh.volume / SIDE**3
    want = sampled_fraction()
    assert abs(fraction - want) <= FRACTION_TOLERANCE * want, (fraction, want)
    # The reported figures are the written solid's, against the contoured cube.
    solid = report["solid"]
    assert abs(solid["volume"] - mesh.volume) <= 1e-4 * mesh.volume, solid
    assert abs(solid["area"] - mesh.area) <= 1e-4 * mesh.area, solid
    assert abs(solid["part_volume"] - SIDE**3) <= 1e-3 * SIDE**3, solid
    assert solid["measured_on"] == "mesh" and solid["enclosed_voids"] == 0, solid


def test_infill_is_printable_and_its_drains_open_it(pgvol, cube_path, work_dir):
    """A hollowed cube filled with a gyroid: the sheet splits the cavity into two labyrinths,
    enclosed voids until one drain reaches into each; they come out through the bottom."""
    out = work_dir / "lattice" / "cube-infill.stl"
    base = [pgvol, "shell", cube_path, "-o", out, "--thickness", 0.8, "--infill", "gyroid",
            "--cell", CELL, "--infill-thickness", THICKNESS, "--res", RES, "--json", "-q"]
    sealed = helpers.run_json(base)["solid"]
    assert sealed["enclosed_voids"] >= 2, sealed
    # Points deep in each labyrinth: the gyroid field's extremes on a coarse grid.
    c = np.linspace(2.0, 8.0, 25)
    points = np.stack(np.meshgrid(c, c, c, indexing="ij")).reshape(3, -1)
    value, _ = gyroid(points * (TAU / CELL))
    drains = [points[:, value.argmax()], points[:, value.argmin()]]
    args = []
    for p in drains:
        args += ["--drain", ",".join(f"{x:.4f}" for x in [*p, 0, 0, -1, 1.0])]
    drained = helpers.run_json(base + args)["solid"]
    mesh = helpers.load_output(out)
    assert_printable(mesh)
    assert drained["enclosed_voids"] <= sealed["enclosed_voids"] - 2, (sealed, drained)
    assert drained["volume"] < sealed["volume"]
    # Walls 0.8 thick around a lattice: more than the lattice alone, less than the cube.
    assert 0.35 < drained["fraction"] < 0.9, drained


def test_bad_lattice_parameters_name_the_problem(pgvol, cube_path, work_dir):
    out = work_dir / "lattice" / "bad.stl"
    unknown = helpers.run([pgvol, "lattice", cube_path, "-o", out, "--surface", "lidinoid",
                           "--cell", CELL, "--thickness", THICKNESS])
    assert unknown.returncode != 0 and "gyroid" in unknown.stderr, unknown.describe()
    thin = helpers.run([pgvol, "lattice", cube_path, "-o", out, "--surface", "gyroid",
                        "--cell", CELL, "--thickness", 0.05, "--res", 64])
    assert thin.returncode == 1, thin.describe()
    assert "cube.stl" in thin.stderr and "two grid spacings" in thin.stderr, thin.describe()
    assert not out.exists()
