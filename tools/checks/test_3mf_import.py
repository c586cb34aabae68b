"""3MF meshes in: files written by lib3mf (the 3MF Consortium's library) and by PrusaSlicer,
remeshed by pgvol, against the placed mesh computed here with numpy from the transforms the
test chose (or, for PrusaSlicer, from what it is known to do: put the part on the bed).

Distances are two-sided sampled Hausdorff distances (the largest distance from points sampled
on either surface to the other surface), in voxels of the remesh grid. The parts of each file
are kept apart by several voxels, so the union pgvol contours has the parts' own surfaces.
"""

from __future__ import annotations

import shutil
import zipfile
from pathlib import Path

import numpy as np
import pytest
import trimesh

import helpers

RES = 128
TOLERANCE_VOXELS = 0.5


def lib3mf_or_fail():
    try:
        import lib3mf
    except ImportError:
        pytest.fail("lib3mf is missing from the venv (pinned in tools/requirements.txt)")
    return lib3mf


def affine(rows) -> np.ndarray:
    """The 4x3 matrix of a 3MF transform, rows = images of x, y, z, then the translation."""
    return np.asarray(rows, dtype=np.float64).reshape(4, 3)


def place(mesh: trimesh.Trimesh, *matrices) -> trimesh.Trimesh:
    """`mesh` moved by the 3MF transforms in order (innermost first): row vectors times 4x3."""
    v = np.asarray(mesh.vertices, dtype=np.float64)
    for m in matrices:
        v = v @ m[:3] + m[3]
    return trimesh.Trimesh(vertices=v, faces=mesh.faces, process=False)


def lib3mf_transform(lib3mf, m: np.ndarray):
    t = lib3mf.Transform()
    for i in range(4):
        for j in range(3):
            t.Fields[i][j] = float(m[i, j])
    return t


def add_mesh(lib3mf, model, mesh: trimesh.Trimesh):
    obj = model.AddMeshObject()
    for v in mesh.vertices:
        p = lib3mf.Position()
        p.Coordinates[0], p.Coordinates[1], p.Coordinates[2] = (float(c) for c in v)
        obj.AddVertex(p)
    for f in mesh.faces:
        t = lib3mf.Triangle()
        t.Indices[0], t.Indices[1], t.Indices[2] = (int(i) for i in f)
        obj.AddTriangle(t)
    return obj


def sampled_hausdorff(a: trimesh.Trimesh, b: trimesh.Trimesh, count: int = 20000) -> float:
    worst = 0.0
    for src, dst, seed in ((a, b, 1), (b, a, 2)):
        points, _ = trimesh.sample.sample_surface(src, count, seed=seed)
        _, dist, _ = trimesh.proximity.closest_point(dst, points)
        worst = max(worst, float(dist.max()))
    return worst


def remesh_and_compare(pgvol: Path, part: Path, expected: trimesh.Trimesh, folder: Path) -> dict:
    out = folder / (part.stem + "-remeshed.ply")
    report = helpers.run_json([pgvol, "remesh", part, "-o", out, "--res", RES, "--json"])
    spacing = report["grid"]["spacing"]
    got = helpers.load_output(out)
    # Bounds first: a misplaced part fails here clearly, before the costly distance queries.
    bounds_off = float(np.abs(got.bounds - expected.bounds).max()) / spacing
    assert bounds_off <= 1.0, (
        f"{part.name}: bounds {bounds_off:.2f} voxels off; pgvol {got.bounds.tolist()}, "
        f"expected {expected.bounds.tolist()}"
    )
    distance = sampled_hausdorff(got, expected) / spacing
    assert distance <= TOLERANCE_VOXELS, (
        f"{part.name}: sampled Hausdorff distance {distance:.3f} voxels from the placed mesh "
        f"(limit {TOLERANCE_VOXELS}); bounds pgvol {got.bounds.tolist()}, "
        f"expected {expected.bounds.tolist()}"
    )
    return report


# Two parts that stay well apart after their component transforms: a box, and a sphere
# turned a quarter about z and moved 12 along -x.
BOX = trimesh.creation.box((10.0, 6.0, 4.0))
SPHERE = trimesh.creation.icosphere(subdivisions=3, radius=4.0)
BOX_IN_PART = affine([[1, 0, 0], [0, 1, 0], [0, 0, 1], [4, 0, 0]])
SPHERE_IN_PART = affine([[0, 1, 0], [-1, 0, 0], [0, 0, 1], [-12, 2, 1]])
# The build item: x -> z, z -> -x (a quarter turn about y), scaled 1.5, and moved.
ITEM = affine([[0, 0, 1.5], [0, 1.5, 0], [-1.5, 0, 0], [10, 20, 30]])


def expected_two_parts() -> trimesh.Trimesh:
    return trimesh.util.concatenate(
        [place(BOX, BOX_IN_PART, ITEM), place(SPHERE, SPHERE_IN_PART, ITEM)]
    )


def add_assembly(lib3mf, model, box, sphere):
    """The box and the sphere as components of one object placed by a build item."""
    assembly = model.AddComponentsObject()
    assembly.AddComponent(box, lib3mf_transform(lib3mf, BOX_IN_PART))
    assembly.AddComponent(sphere, lib3mf_transform(lib3mf, SPHERE_IN_PART))
    model.AddBuildItem(assembly, lib3mf_transform(lib3mf, ITEM))


def test_components_under_a_build_item_written_by_lib3mf(pgvol, work_dir):
    lib3mf = lib3mf_or_fail()
    wrapper = lib3mf.get_wrapper()
    model = wrapper.CreateModel()
    add_assembly(lib3mf, model, add_mesh(lib3mf, model, BOX), add_mesh(lib3mf, model, SPHERE))
    part = work_dir / "3mf-components.3mf"
    model.QueryWriter("3mf").WriteToFile(str(part))

    report = remesh_and_compare(pgvol, part, expected_two_parts(), work_dir)
    assert report["unit"] == "millimetre (as in the file)"
    assert report["input_triangles"] == len(BOX.faces) + len(SPHERE.faces)


def test_meshes_in_a_separate_model_part_written_by_lib3mf(pgvol, work_dir):
    lib3mf = lib3mf_or_fail()
    wrapper = lib3mf.get_wrapper()
    model = wrapper.CreateModel()
    objects_part = model.FindOrCreatePackagePart("/3D/Objects/parts.model")
    box = add_mesh(lib3mf, model, BOX)
    sphere = add_mesh(lib3mf, model, SPHERE)
    box.SetPackagePart(objects_part)
    sphere.SetPackagePart(objects_part)
    add_assembly(lib3mf, model, box, sphere)
    part = work_dir / "3mf-production.3mf"
    model.QueryWriter("3mf").WriteToFile(str(part))

    # The file must really hold its meshes in the other part, referenced by p:path.
    with zipfile.ZipFile(part) as package:
        names = package.namelist()
        assert "3D/Objects/parts.model" in names, names
        root = package.read("3D/3dmodel.model").decode()
        objects = package.read("3D/Objects/parts.model").decode()
    assert "<vertex" not in root and "<vertex" in objects
    assert 'p:path="/3D/Objects/parts.model"' in root

    remesh_and_compare(pgvol, part, expected_two_parts(), work_dir)


def test_inches_are_read_as_millimetres_and_reported(pgvol, work_dir):
    lib3mf = lib3mf_or_fail()
    wrapper = lib3mf.get_wrapper()
    model = wrapper.CreateModel()
    model.SetUnit(lib3mf.ModelUnit.Inch)
    sphere = add_mesh(lib3mf, model, SPHERE)
    model.AddBuildItem(sphere, lib3mf_transform(lib3mf, affine(np.vstack([np.eye(3), [1, 2, 3]]))))
    part = work_dir / "3mf-inch.3mf"
    model.QueryWriter("3mf").WriteToFile(str(part))

    expected = place(SPHERE, affine(np.vstack([np.eye(3), [1, 2, 3]])))
    expected.vertices *= 25.4
    report = remesh_and_compare(pgvol, part, expected, work_dir)
    assert report["unit"] == "inch -> millimetre x25.4", report["unit"]

    # On request the numbers stay as the file writes them, in inches.
    kept = work_dir / "3mf-inch-kept.ply"
    report = helpers.run_json(
        [pgvol, "remesh", part, "-o", kept, "--res", 64, "--mesh-units", "file", "--json"]
    )
    assert report["unit"] == "inch (as in the file, not converted)", report["unit"]
    in_inches = place(SPHERE, affine(np.vstack([np.eye(3), [1, 2, 3]])))
    off = np.abs(helpers.load_output(kept).bounds - in_inches.bounds).max()
    assert off <= report["grid"]["spacing"], (off, report["grid"])


def test_a_part_exported_by_prusaslicer(pgvol, mesh_path, work_dir):
    slicer = shutil.which("prusa-slicer")
    if slicer is None:
        pytest.skip("prusa-slicer is not installed (Debian package prusa-slicer)")
    source = mesh_path("spot")
    part = work_dir / "3mf-prusaslicer.3mf"
    helpers.run_ok([slicer, "--export-3mf", "-o", part, source])

    # PrusaSlicer keeps the part's shape and sets it on the bed: its lowest point at z = 0.
    reference = helpers.load_input(source)
    lift = -reference.bounds[0][2]
    expected = place(reference, affine(np.vstack([np.eye(3), [0, 0, lift]])))
    report = remesh_and_compare(pgvol, part, expected, work_dir)
    assert report["unit"] == "millimetre (as in the file)"


def test_hostile_3mf_files_are_refused_with_the_part_named(pgvol, work_dir):
    core = "http://schemas.microsoft.com/3dmanufacturing/core/2015/02"
    rels = (
        '<?xml version="1.0"?><Relationships xmlns="http://schemas.openxmlformats.org/package/'
        '2006/relationships"><Relationship Type="http://schemas.microsoft.com/3dmanufacturing/'
        '2013/01/3dmodel" Target="/3D/3dmodel.model" Id="r0"/></Relationships>'
    )
    cyclic = (
        f'<model xmlns="{core}"><resources>'
        '<object id="1"><components><component objectid="2"/></components></object>'
        '<object id="2"><components><component objectid="1"/></components></object>'
        '</resources><build><item objectid="1"/></build></model>'
    )
    cases = {
        "cycle": ({"_rels/.rels": rels, "3D/3dmodel.model": cyclic}, "refer back to themselves"),
        "missing": ({"_rels/.rels": rels}, "part /3D/3dmodel.model is missing"),
    }
    for label, (entries, message) in cases.items():
        path = work_dir / f"3mf-hostile-{label}.3mf"
        with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED) as package:
            for name, text in entries.items():
                package.writestr(name, text)
        r = helpers.run([pgvol, "remesh", path, "-o", work_dir / "never.ply", "--res", 32])
        assert r.returncode != 0, r.describe()
        assert path.name in r.stderr and message in r.stderr, r.describe()
