"""`pgvol slice`, `pgvol offset` and `pgvol shell` on the shared meshes, checked against
manifold3d's exact cross-sections and its manifold test."""

from __future__ import annotations

import json

import manifold3d
import numpy as np
import pytest

import helpers

SLICE_RES = 256
AREA_TOLERANCE = 0.01


def loop_area(points) -> float:
    p = np.asarray(points, dtype=np.float64)
    x, y = p[:, 0], p[:, 1]
    return 0.5 * float(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1)))


@pytest.mark.parametrize("name", ["fandisk", "spot"])
def test_slices_match_manifold_cross_sections(name, pgvol, mesh_path, reference_mesh, work_dir):
    ref = reference_mesh(name)
    lo, hi = ref.bounds
    height = float(hi[2] - lo[2])
    layer = height / 60
    out = work_dir / "ops" / f"{name}.json"
    out.parent.mkdir(parents=True, exist_ok=True)
    helpers.run_ok([pgvol, "slice", mesh_path(name), "-o", out, "--layer-height", layer, "--res", SLICE_RES, "-q"])
    layers = json.loads(out.read_text())["layers"]

    # Layer count and heights exactly as asked: first at half a layer, then every layer height.
    expected = int(np.floor((height - layer / 2) / layer + 1e-6)) + 1
    assert len(layers) == expected, (len(layers), expected)
    for i, l in enumerate(layers):
        assert abs(l["height"] - (lo[2] + layer / 2 + i * layer)) < 1e-4 * height

    solid = manifold3d.Manifold(helpers.manifold_mesh(ref))
    compared = same_count = 0
    for l in layers:
        section = solid.slice(l["height"])
        want = section.area()
        # Skip layers near horizontal faces or tips, where a tiny change in height changes a lot.
        if want < 0.02 * (hi[0] - lo[0]) * (hi[1] - lo[1]):
            continue
        got = sum(loop_area(loop["points"]) for loop in l["loops"])
        assert abs(got - want) <= AREA_TOLERANCE * want, f"{name} z={l['height']:.5f}: area {got} vs {want}"
        for loop in l["loops"]:
            assert (loop_area(loop["points"]) < 0) == loop["hole"], "outer loops CCW, holes CW"
        compared += 1
        same_count += len(l["loops"]) == section.num_contour()
    assert compared >= 0.8 * len(layers) - 4
    assert same_count >= 0.95 * compared, f"{name}: loop counts agree on {same_count} of {compared} layers"


@pytest.mark.parametrize("fraction", [0.05, -0.05])
def test_offsets_are_closed_manifolds(fraction, pgvol, mesh_path, reference_mesh, work_dir):
    ref = reference_mesh("fandisk")
    distance = fraction * helpers.bbox_diagonal(ref)
    out = work_dir / "ops" / f"fandisk-offset-{fraction}.glb"
    out.parent.mkdir(parents=True, exist_ok=True)
    helpers.run_ok([pgvol, "offset", mesh_path("fandisk"), "-o", out, "--distance", distance, "--res", 96, "-q"])
    mesh = helpers.load_output(out)
    assert mesh.is_watertight and mesh.is_winding_consistent
    assert helpers.manifold_ok(helpers.manifold_status(mesh)), helpers.manifold_status(mesh)
    if fraction > 0:
        assert mesh.volume > ref.volume
    else:
        assert 0 < mesh.volume < ref.volume


def test_hollowed_part_has_an_inner_cavity(pgvol, mesh_path, reference_mesh, work_dir):
    ref = reference_mesh("spot")
    wall = 0.02 * helpers.bbox_diagonal(ref)
    out = work_dir / "ops" / "spot-hollow.glb"
    helpers.run_ok([pgvol, "shell", mesh_path("spot"), "-o", out, "--thickness", wall, "--hollow", "--res", 96, "-q"])
    mesh = helpers.load_output(out)
    assert mesh.is_watertight and mesh.is_winding_consistent
    assert helpers.manifold_ok(helpers.manifold_status(mesh)), helpers.manifold_status(mesh)
    # Two nested surfaces: the outer skin and the inward-facing cavity.
    assert mesh.body_count == 2 or len(mesh.split(only_watertight=False)) == 2
    assert 0 < mesh.volume < 0.5 * ref.volume


def test_sparse_file_decodes_like_the_dense_one(pgvol, mesh_path, work_dir):
    folder = work_dir / "ops"
    sparse, dense = folder / "bunny.pgv", folder / "bunny-dense.pgv"
    helpers.run_ok([pgvol, "encode", mesh_path("stanford-bunny"), "-o", sparse, "--res", 64, "-q"])
    helpers.run_ok([pgvol, "encode", mesh_path("stanford-bunny"), "-o", dense, "--res", 64, "--dense-file", "-q"])
    info = helpers.run_json([pgvol, "info", sparse, "--json"])
    assert info["bricks_stored"] < info["bricks_total"]
    assert sparse.stat().st_size < 0.5 * dense.stat().st_size
    chamfer = {}
    for f in (sparse, dense):
        out = f.with_suffix(".glb")
        helpers.run_ok([pgvol, "decode", f, "-o", out, "-q"])
        chamfer[f.name] = helpers.run_json(
            [pgvol, "compare", out, mesh_path("stanford-bunny"), "--json", "--samples", 50000]
        )["chamfer_l1"]
    a, b = chamfer.values()
    assert abs(a - b) <= 0.01 * b, chamfer
