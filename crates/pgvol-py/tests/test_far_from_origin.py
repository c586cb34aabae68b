"""A mesh far from the origin through the package gives what it gives at the origin, moved
there: positions go in and come out as float64 world coordinates, and precision follows the
mesh's size rather than where it sits."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

import pgvol

SHIFT = np.array([1e6, -3e7, 2.5e5])


def unit_cube():
    box = trimesh.creation.box(extents=(1.0, 1.0, 1.0))
    return np.asarray(box.vertices, dtype=np.float64) + 0.5, np.asarray(box.faces, dtype=np.int64)


def test_a_far_cube_encodes_evaluates_and_contours_as_at_the_origin(tmp_path):
    vertices, faces = unit_cube()
    near = pgvol.Field.from_mesh(vertices, faces, res=32)
    far = pgvol.Field.from_mesh(vertices + SHIFT, faces, res=32)

    # Points around the surface, given in world coordinates.
    rng = np.random.default_rng(3)
    points = rng.uniform(-0.1, 1.1, size=(500, 3))
    np.testing.assert_allclose(far(points + SHIFT), near(points), atol=1e-5)
    values, gradients = far.eval_with_gradient(points + SHIFT)
    near_values, near_gradients = near.eval_with_gradient(points)
    np.testing.assert_allclose(values, near_values, atol=1e-5)
    np.testing.assert_allclose(gradients, near_gradients, atol=1e-4)
    assert np.array_equal(far.is_exact(points + SHIFT), near.is_exact(points))

    v, f = far.to_mesh()
    assert v.dtype == np.float64
    v0, f0 = near.to_mesh()
    assert v0.dtype == np.float32
    far_mesh = trimesh.Trimesh(v - SHIFT, f, process=False)
    assert abs(far_mesh.volume - trimesh.Trimesh(v0, f0, process=False).volume) < 1e-4
    stats = pgvol.compare((v, f), (vertices + SHIFT, faces), samples=20000)
    assert stats["hausdorff_pct"] < 0.5

    # The file keeps the frame: read back, the field is the same.
    path = tmp_path / "far.pgv"
    far.save(path)
    again = pgvol.Field.load(path)
    np.testing.assert_array_equal(again(points + SHIFT), far(points + SHIFT))


def test_far_meshes_round_trip_through_files_in_double_precision(tmp_path):
    vertices, faces = unit_cube()
    for ext in ("obj", "glb", "ply"):
        path = tmp_path / f"cube.{ext}"
        pgvol.write_mesh(path, vertices + SHIFT, faces)
        v, f = pgvol.read_mesh(path)
        assert v.dtype == np.float64
        # Every vertex is a cube corner, to float rounding at the cube's own size.
        d = np.abs(v[:, None, :] - (vertices + SHIFT)[None, :, :]).max(axis=2).min(axis=1)
        assert d.max() < 1e-6, ext
    # Near the origin the arrays stay float32, as they always were.
    pgvol.write_mesh(tmp_path / "near.obj", vertices, faces)
    v, _ = pgvol.read_mesh(tmp_path / "near.obj")
    assert v.dtype == np.float32


def test_stl_refuses_a_far_mesh_naming_the_precision_lost(tmp_path):
    vertices, faces = unit_cube()
    with pytest.raises(pgvol.OutputFileError, match=r"STL.*%.*OBJ"):
        pgvol.write_mesh(tmp_path / "cube.stl", vertices + SHIFT, faces)
    assert not (tmp_path / "cube.stl").exists()
