"""Lattices from Python: a gyroid sheet of a cube against the volume fraction of the same
implicit sampled with numpy, and an infill whose drains open the cavity's labyrinths."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

import pgvol

TAU = 2.0 * np.pi
SIDE, CELL, SHEET = 10.0, 5.0, 0.8


def gyroid_sheet(points, cell: float, thickness: float):
    """|f / |∇f|| − t/2 for the gyroid, the gradient in model units (docs/lattices.md)."""
    u = points * (TAU / cell)
    (sx, sy, sz), (cx, cy, cz) = np.sin(u), np.cos(u)
    f = sx * cy + sy * cz + sz * cx
    g = np.stack([cx * cy - sz * sx, cy * cz - sx * sy, cz * cx - sy * sz])
    d = f / (np.linalg.norm(g, axis=0) * (TAU / cell))
    return np.abs(d) - 0.5 * thickness


@pytest.fixture(scope="module")
def cube():
    box = trimesh.creation.box(bounds=[[0, 0, 0], [SIDE, SIDE, SIDE]])
    return pgvol.Field.from_mesh(np.asarray(box.vertices), np.asarray(box.faces), res=96, band=16)


def test_gyroid_sheet_volume_matches_the_sampled_implicit(cube):
    sheet = cube.lattice("gyroid", CELL, SHEET)
    assert sheet.metadata["operation"] == f"lattice gyroid cell {CELL:g} thickness {SHEET:g}"
    mesh = sheet.to_trimesh()
    assert mesh.is_watertight and mesh.is_winding_consistent
    n = 200
    c = (np.arange(n) + 0.5) * (SIDE / n)
    x, y = np.meshgrid(c, c, indexing="ij")
    inside = sum(
        np.count_nonzero(gyroid_sheet(np.stack([x, y, np.full_like(x, z)]), CELL, SHEET) < 0) for z in c
    )
    want = inside / n**3 * SIDE**3
    assert mesh.volume == pytest.approx(want, rel=0.01)


def test_infill_drains_and_refusals(cube):
    wall = 0.8
    sealed = cube.infill(wall, "gyroid", CELL, 0.6)
    # Points deep in each labyrinth of the sheet, drains from them out through the bottom.
    c = np.linspace(2.0, 8.0, 25)
    points = np.stack(np.meshgrid(c, c, c, indexing="ij")).reshape(3, -1)
    u = points * (TAU / CELL)
    f = np.sin(u[0]) * np.cos(u[1]) + np.sin(u[1]) * np.cos(u[2]) + np.sin(u[2]) * np.cos(u[0])
    drains = [(tuple(points[:, f.argmax()]), (0, 0, -1), 1.0), (tuple(points[:, f.argmin()]), (0, 0, -1), 1.0)]
    drained = cube.infill(wall, "gyroid", CELL, 0.6, drains=drains)
    closed_mesh, open_mesh = sealed.to_trimesh(), drained.to_trimesh()
    for m in (closed_mesh, open_mesh):
        assert m.is_watertight and m.is_winding_consistent
    # Sealed: the outer skin and the two labyrinths' surfaces; drained: the skin only, opened.
    assert voids(closed_mesh) >= 2 and voids(open_mesh) <= voids(closed_mesh) - 2
    with pytest.raises(ValueError, match="unknown surface"):
        cube.lattice("lidinoid", CELL, SHEET)
    with pytest.raises(ValueError, match="unknown lattice style"):
        cube.lattice("gyroid", CELL, SHEET, style="foam")
    with pytest.raises(ValueError, match="under half the cell"):
        cube.lattice("gyroid", CELL, 3.0)
    with pytest.raises(ValueError, match="needs a ramp"):
        cube.lattice("gyroid", CELL, SHEET, thickness_far=0.4)
    graded = cube.lattice("gyroid", CELL, SHEET, grade_linear=((0, 0, 0), (10, 0, 0)), thickness_far=0.4)
    assert graded.to_trimesh().volume < sheet_volume(cube)


def voids(mesh: trimesh.Trimesh) -> int:
    """Connected pieces of the surface enclosing negative volume: closed pockets."""
    labels = trimesh.graph.connected_component_labels(mesh.face_adjacency, node_count=len(mesh.faces))
    tri = mesh.triangles
    signed = np.einsum("ij,ij->i", tri[:, 0], np.cross(tri[:, 1], tri[:, 2])) / 6.0
    return int(np.count_nonzero(np.bincount(labels, weights=signed) < 0))


def sheet_volume(cube) -> float:
    return cube.lattice("gyroid", CELL, SHEET).to_trimesh().volume


def test_lattice_3mf_writes_the_implicit_package(cube, tmp_path):
    """The lattice as a 3MF implicit function: one level set over the package's implicit
    function, whose constants are the lattice's, over an image stack on the part's grid; an
    infill adds the wall and the drains."""
    import xml.etree.ElementTree as ET
    import zipfile

    ns = {"v": "http://schemas.3mf.io/3dmanufacturing/volumetric/2022/01",
          "i": "http://schemas.3mf.io/3dmanufacturing/implicit/2023/12"}
    path = tmp_path / "gyroid.3mf"
    grid = cube.lattice_3mf(path, "gyroid", CELL, SHEET)
    assert tuple(grid.dims) == tuple(cube.grid.dims)

    def model(p):
        with zipfile.ZipFile(p) as z:
            return ET.fromstring(z.read("3D/3dmodel.model"))

    root = model(path)
    levelset = root.findall(".//v:levelset", ns)
    assert len(levelset) == 1 and levelset[0].get("channel") == "shape"
    function = root.find(".//i:implicitfunction", ns)
    assert function.get("id") == levelset[0].get("functionid")
    # Constants are the f32 parameters written as f64.
    constants = {np.float32(c.get("value")) for c in function.findall("i:constant", ns)}
    assert set(np.float32([CELL, SHEET, 0.5])) <= constants
    assert len(function.findall("i:sin", ns)) == 3 and len(function.findall("i:functioncall", ns)) == 1
    stack = root.find(".//v:imagestack", ns)
    assert [int(stack.get(k)) for k in ("columncount", "rowcount", "sheetcount")] == list(grid.dims)

    drains = [((5.0, 5.0, 5.0), (0, 0, -1), 1.0)]
    infill = tmp_path / "infill.3mf"
    cube.lattice_3mf(infill, "diamond", CELL, 0.6, wall=0.8, drains=drains, grade_depth=1.2, thickness_far=1.0)
    filled = model(infill).find(".//i:implicitfunction", ns)
    constants = {np.float32(c.get("value")) for c in filled.findall("i:constant", ns)}
    assert set(np.float32([-0.8, 0.5])) <= constants  # the wall, the drain's radius
    assert len(filled.findall("i:functioncall", ns)) == 1

    with pytest.raises(pgvol.ParameterError, match="wall"):
        cube.lattice_3mf(tmp_path / "x.3mf", "gyroid", CELL, SHEET, drains=drains)
    with pytest.raises(pgvol.ParameterError, match="furlong"):
        cube.lattice_3mf(tmp_path / "x.3mf", "gyroid", CELL, SHEET, unit="furlong")  # type: ignore[arg-type]
    assert not (tmp_path / "x.3mf").exists()
