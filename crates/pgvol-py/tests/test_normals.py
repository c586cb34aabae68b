"""Vertex normals from Python: marching cubes gives the field's gradient directions, the other
methods normals weighted from the faces; write_mesh stores the normals it is given, made unit
length, and trimesh reads back what was written."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

import pgvol


def unit_lengths(normals: np.ndarray) -> np.ndarray:
    return np.linalg.norm(normals.astype(np.float64), axis=1)


def written_normals(path) -> tuple[np.ndarray, np.ndarray]:
    """The vertices and vertex normals trimesh reads from a PLY or GLB file, in file order."""
    loaded = trimesh.load(path, process=False)
    mesh = loaded if isinstance(loaded, trimesh.Trimesh) else next(iter(loaded.geometry.values()))
    assert "vertex_normals" in mesh._cache.cache, "the file holds no vertex normals"
    return np.asarray(mesh.vertices), np.asarray(mesh.vertex_normals)


def test_marching_cubes_normals_are_the_fields_gradient_directions(spot_field):
    v, f = spot_field.to_mesh()
    v2, f2, n = spot_field.to_mesh(normals=True)
    assert np.array_equal(v, v2) and np.array_equal(f, f2)
    assert n.dtype == np.float32 and n.shape == v.shape
    assert np.abs(unit_lengths(n) - 1).max() < 1e-6
    _, gradients = spot_field.eval_with_gradient(v)
    directions = gradients / np.linalg.norm(gradients, axis=1, keepdims=True)
    assert np.sum(directions * n, axis=1).min() > 0.9999
    # Resampled, the vertices lie on another grid and their normals follow the field there.
    v, _, n = spot_field.to_mesh(res=48, normals=True)
    _, gradients = spot_field.eval_with_gradient(v)
    directions = gradients / np.linalg.norm(gradients, axis=1, keepdims=True)
    assert np.sum(directions * n, axis=1).min() > 0.9999


@pytest.mark.parametrize("method", ["sn", "dc"])
def test_other_methods_give_normals_weighted_from_the_faces(spot_field, method):
    v, f, n = spot_field.to_mesh(method=method, normals=True)
    assert np.abs(unit_lengths(n) - 1).max() < 1e-6
    # trimesh weighs by corner angle only, pgvol by angle and area: close, not equal.
    theirs = trimesh.Trimesh(v, f, process=False).vertex_normals
    agreement = np.sum(theirs * n, axis=1)
    assert np.median(agreement) > 0.9999 and np.percentile(agreement, 1) > 0.95


@pytest.mark.parametrize("ext", [".ply", ".glb"])
def test_written_normals_are_the_given_ones_made_unit(spot_field, tmp_path, ext):
    v, f, n = spot_field.to_mesh(normals=True)
    path = tmp_path / f"spot{ext}"
    pgvol.write_mesh(path, v, f, n)
    read_vertices, read_normals = written_normals(path)
    assert np.array_equal(read_vertices.astype(np.float32), v)
    assert np.array_equal(read_normals.astype(np.float32), n)
    # Lengths other than 1 are normalised; a zero normal takes one of its faces' directions.
    scaled = (n * 3).astype(np.float64)
    scaled[0] = 0
    pgvol.write_mesh(path, v, f, scaled)
    _, read_normals = written_normals(path)
    np.testing.assert_allclose(read_normals[1:], n[1:], atol=1e-6)
    faces_of_first = f[np.any(f == 0, axis=1)]
    face_normals = trimesh.Trimesh(v, faces_of_first, process=False).face_normals
    assert np.abs(face_normals @ read_normals[0] - 1).min() < 1e-5
    # Without normals, the writer weighs them from the faces as before.
    pgvol.write_mesh(path, v, f)
    _, weighted = written_normals(path)
    assert not np.array_equal(weighted.astype(np.float32), n)
    assert np.median(np.sum(weighted * n, axis=1)) > 0.999


def test_wrong_normals_are_refused_with_what_would_work(spot_field, tmp_path):
    v, f, n = spot_field.to_mesh(normals=True)
    path = tmp_path / "spot.ply"
    with pytest.raises(pgvol.ParameterError, match="one per vertex"):
        pgvol.write_mesh(path, v, f, n[:-1])
    bad = n.copy()
    bad[5, 1] = np.nan
    with pytest.raises(pgvol.ParameterError, match="finite"):
        pgvol.write_mesh(path, v, f, bad)
    with pytest.raises(pgvol.ParameterError, match="shape"):
        pgvol.write_mesh(path, v, f, n[:, :2])
    assert not path.exists()


def test_to_trimesh_carries_the_fields_normals(spot_field):
    _, _, n = spot_field.to_mesh(normals=True)
    mesh = spot_field.to_trimesh()
    assert np.array_equal(np.asarray(mesh.vertex_normals, dtype=np.float32), n)
