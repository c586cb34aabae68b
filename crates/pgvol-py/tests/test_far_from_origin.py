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
    # The far surface is the origin's, moved: against each other and against their inputs.
    same = pgvol.compare((v, f), (v0.astype(np.float64) + SHIFT, f0), samples=20000)
    assert same.hausdorff_pct < 1e-3
    far_error = pgvol.compare((v, f), (vertices + SHIFT, faces), samples=20000)
    near_error = pgvol.compare((v0, f0), (vertices, faces), samples=20000)
    assert abs(far_error.hausdorff_pct - near_error.hausdorff_pct) < 1e-3

    # The file keeps the frame: read back, the far field is the origin's stored alike, moved.
    far.save(tmp_path / "far.pgv")
    near.save(tmp_path / "near.pgv")
    again = pgvol.Field.load(tmp_path / "far.pgv")
    near_again = pgvol.Field.load(tmp_path / "near.pgv")
    np.testing.assert_allclose(again(points + SHIFT), near_again(points), atol=1e-5)
    # Layers come as float32 arrays in the field's own frame, which a far field's is not: both
    # ways of slicing refuse it alike, and slice the near file.
    for slicing in (lambda p: pgvol.slice_file(p, 0.1), lambda p: pgvol.Field.load(p).slice(0.1)):
        with pytest.raises(pgvol.ParameterError, match="works only near the origin"):
            slicing(tmp_path / "far.pgv")
        assert len(slicing(tmp_path / "near.pgv")) == 10


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
