"""Files shared with the command-line tool: .pgv files written by one are read by the other and
give the same field; meshes round-trip through every format; bytes and paths agree."""

from __future__ import annotations

import json

import numpy as np
import pytest
import trimesh

import pgvol
from conftest import REPO_ROOT, near_surface_points


def cli_eval(run_cli, pgv, points, tmp_path):
    """Values and gradients from `pgvol eval`, parsed back exactly (shortest round-trip)."""
    csv = tmp_path / "points.csv"
    np.savetxt(csv, points.astype(np.float32), delimiter=",", fmt="%.9g")
    out = tmp_path / "values.csv"
    run_cli("eval", pgv, csv, "-o", out, "-q")
    rows = np.loadtxt(out, delimiter=",", skiprows=1, dtype=np.float64)
    return rows[:, 3].astype(np.float32), rows[:, 4:7].astype(np.float32), rows[:, 7] == 1


def test_a_file_encoded_by_the_cli_loads_and_evaluates_identically(
    mesh_path, spot, spot_trimesh, run_cli, tmp_path
):
    pgv = tmp_path / "spot.pgv"
    run_cli("encode", mesh_path("spot"), "-o", pgv, "--res", 64, "-q")
    f = pgvol.Field.load(pgv)
    points = near_surface_points(spot_trimesh, 400, 0.2, seed=7).astype(np.float32)
    values, gradients, exact = cli_eval(run_cli, pgv, points, tmp_path)
    mine, my_gradients = f.eval_with_gradient(points)
    assert np.array_equal(mine, values)
    assert np.array_equal(my_gradients, gradients)
    assert np.array_equal(f.is_exact(points), exact)
    np.testing.assert_allclose(f(points), values, rtol=1e-6, atol=1e-7)
    # The same mesh encoded from Python with the same options gives the same bytes.
    assert pgvol.Field.from_mesh(*spot, res=64).to_bytes() == pgv.read_bytes()


def test_a_file_saved_from_python_decodes_with_the_cli(spot_field, run_cli, tmp_path):
    pgv = tmp_path / "from-python.pgv"
    spot_field.save(pgv)
    info = json.loads(run_cli("info", pgv, "--json").stdout)
    assert info["header"]["grid"]["dims"] == list(spot_field.grid.dims)
    assert info["header"]["basis"] == spot_field.basis
    assert float(info["header"]["metadata"]["band"]) == pytest.approx(spot_field.band)
    glb = tmp_path / "decoded.glb"
    run_cli("decode", pgv, "-o", glb, "--method", "dc", "-q")
    theirs = trimesh.load(glb, force="mesh", process=False)
    v, t = pgvol.Field.load(pgv).to_mesh(method="dc")
    assert len(theirs.faces) == len(t)
    np.testing.assert_allclose(np.sort(theirs.vertices, axis=0), np.sort(v, axis=0), atol=1e-6)


@pytest.mark.parametrize("precision", [None, "fixed", "q16", "f16", "f32"])
def test_saving_a_loaded_field_gives_the_same_file(precision, spot_field, spot_trimesh, tmp_path):
    """save then load keeps the field within the file's quantisation near the surface, and
    saving the loaded field again, as it was saved or with the defaults, writes the same bytes."""
    first, second = tmp_path / "first.pgv", tmp_path / "second.pgv"
    spot_field.save(first, precision=precision)
    loaded = pgvol.Field.load(first)
    loaded.save(second, precision=precision)
    assert second.read_bytes() == first.read_bytes()
    assert loaded.to_bytes() == first.read_bytes()
    assert pgvol.Field.from_bytes(loaded.to_bytes()).to_bytes() == first.read_bytes()
    points = near_surface_points(spot_trimesh, 1000, spot_field.exact_band, seed=12)
    exact = spot_field.is_exact(points)
    assert exact.mean() > 0.5
    error = np.abs(loaded(points) - spot_field(points))[exact].max()
    assert error < 0.01 * spot_field.grid.spacing
    if precision == "f32":
        assert error == 0
    dense = tmp_path / "dense.pgv"
    spot_field.save(dense, dense=True)
    assert pgvol.Field.load(dense).to_bytes(dense=True) == dense.read_bytes()


def test_dense_and_precise_files_round_trip_bit_exactly(spot_field, spot_trimesh, tmp_path):
    points = near_surface_points(spot_trimesh, 500, spot_field.exact_band, seed=8)
    expected = spot_field(points)
    dense = spot_field.to_bytes(dense=True)
    assert np.array_equal(pgvol.Field.from_bytes(dense)(points), expected)
    f32 = spot_field.to_bytes(precision="f32")
    assert np.array_equal(pgvol.Field.from_bytes(f32)(points), expected)
    # The default file quantises the coefficients and keeps only the bricks the band needs:
    # within the band, the values stay within a small part of a spacing.
    sparse = pgvol.Field.from_bytes(spot_field.to_bytes())
    exact = spot_field.is_exact(points)
    assert exact.mean() > 0.5
    assert np.abs(sparse(points) - expected)[exact].max() < 0.01 * spot_field.grid.spacing
    assert len(spot_field.to_bytes()) < len(f32) < len(dense)
    path = tmp_path / "spot.pgv"
    spot_field.save(path, dense=True)
    assert path.read_bytes() == dense
    loaded = pgvol.Field.load(str(path))
    assert loaded.grid == spot_field.grid and loaded.band == spot_field.band
    with pytest.raises(ValueError, match="unknown precision"):
        spot_field.to_bytes(precision="f8")


@pytest.mark.parametrize("ext", [".obj", ".stl", ".ply", ".glb", ".gltf"])
def test_meshes_round_trip_through_every_format_and_trimesh_reads_them(spot, tmp_path, ext):
    v, t = spot
    path = tmp_path / f"spot{ext}"
    pgvol.write_mesh(path, v, t)
    v2, t2 = pgvol.read_mesh(path)
    assert v2.dtype == np.float32 and t2.dtype == np.int32
    assert len(t2) == len(t)
    # Faces name the same corners (STL stores corners; reading welds them back).
    np.testing.assert_array_equal(np.sort(v2[t2].reshape(-1, 9), axis=0), np.sort(v[t].reshape(-1, 9), axis=0))
    theirs = trimesh.load(path, force="mesh", process=True)
    assert theirs.is_watertight
    assert theirs.volume == pytest.approx(trimesh.Trimesh(v, t, process=False).volume, rel=1e-5)


def test_read_mesh_matches_trimesh_on_the_shared_corpus(mesh_path):
    for name in ["spot", "fandisk", "stanford-bunny"]:
        v, t = pgvol.read_mesh(mesh_path(name))
        with open(mesh_path(name)) as text:
            (part,) = trimesh.exchange.obj.load_obj(text, skip_materials=True)["geometry"].values()
        theirs = trimesh.Trimesh(part["vertices"], part["faces"], process=True)
        assert len(t) == len(theirs.faces)
        np.testing.assert_allclose(v[t].min(axis=(0, 1)), theirs.bounds[0], atol=1e-6)
        np.testing.assert_allclose(v[t].max(axis=(0, 1)), theirs.bounds[1], atol=1e-6)
        assert trimesh.Trimesh(v, t).area == pytest.approx(theirs.area, rel=1e-5)


def test_vdb_level_sets_load_as_the_cli_encodes_them(run_cli, tmp_path):
    """An OpenVDB file (written by OpenVDB 10, see tools/fixtures/make_vdb_fixtures.cpp) loads
    to the field `pgvol encode` writes for it; a grid is chosen by name."""
    vdb = REPO_ROOT / "fixtures" / "vdb" / "several_grids.vdb"
    pgv = tmp_path / "moved.pgv"
    run_cli("encode", vdb, "-o", pgv, "-q")
    f = pgvol.Field.load(vdb)
    assert f.to_bytes() == pgv.read_bytes()
    # 'second': OpenVDB's sphere of radius 2.5 about (12, 12, 12), voxel size 1.
    second = pgvol.Field.from_vdb(vdb, grid="second")
    points = np.array([[12, 12, 14.5], [9.5, 12, 12], [12, 12, 12]], dtype=np.float32)
    values = second(points)
    assert np.all(np.abs(values[:2]) < 0.1) and values[2] < -2.0, values
    with pytest.raises(pgvol.InputFileError, match="'velocity'"):
        pgvol.Field.from_vdb(vdb, grid="nope")


def test_sharp_vertices_from_python_are_the_files_the_cli_writes(run_cli, tmp_path):
    # Turned so that every corner's cell is crossed at 64^3, where the stored vertices hold the
    # corners to 0.004 spacing (crates/pgvol/tests/sharp_encode.rs).
    box = trimesh.creation.box(extents=[1.0, 1.0, 1.0])
    turn = trimesh.transformations.rotation_matrix(0.5, [0, 1, 0])
    box.apply_transform(turn @ trimesh.transformations.rotation_matrix(0.5, [1, 0, 0]))
    box.export(tmp_path / "box.obj")
    pgv = tmp_path / "box.pgv"
    run_cli("encode", tmp_path / "box.obj", "-o", pgv, "--res", 64, "--sharp", "auto", "-q")
    vertices, faces = pgvol.read_mesh(tmp_path / "box.obj")
    sharp = pgvol.Field.from_mesh(vertices, faces, res=64, sharp="auto")
    assert sharp.to_bytes() == pgv.read_bytes()
    plain = pgvol.Field.from_mesh(vertices, faces, res=64)
    assert len(plain.to_bytes()) < len(sharp.to_bytes())
    h = sharp.grid.spacing

    def corner_gap(field, method):
        v, _ = field.to_mesh(method=method)
        return max(np.min(np.linalg.norm(v - c, axis=1)) for c in box.vertices) / h

    for method in ("dc", "sn"):
        near, far = corner_gap(sharp, method), corner_gap(plain, method)
        assert near < 0.1 and near < 0.5 * far, f"{method}: corners {near:.3f} against {far:.3f}"
    with pytest.raises(pgvol.ParameterError, match="sharp 'on'"):
        pgvol.Field.from_mesh(vertices, faces, res=32, sharp="on")
    with pytest.raises(pgvol.ParameterError, match="crease angle"):
        pgvol.Field.from_mesh(vertices, faces, res=32, sharp="auto", sharp_angle=0.0)
