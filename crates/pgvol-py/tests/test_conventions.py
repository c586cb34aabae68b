"""Array conventions: dtypes, memory orders and shapes accepted or refused, the axis order of
sampled volumes, arrays handed over without a copy; errors as exception classes."""

from __future__ import annotations

import pickle

import numpy as np
import pytest
import trimesh

import pgvol


@pytest.fixture(scope="module")
def small_mesh():
    box = trimesh.creation.box(extents=(2.0, 1.0, 0.5))
    return np.asarray(box.vertices), np.asarray(box.faces)


@pytest.fixture(scope="module")
def small_field(small_mesh):
    return pgvol.Field.from_mesh(*small_mesh, res=24)


def test_vertex_and_face_dtypes_and_orders_give_the_same_field(small_mesh, small_field):
    v, t = small_mesh
    reference = small_field.to_bytes(dense=True)
    wide = np.zeros((len(v), 6))
    wide[:, ::2] = v
    variants = [
        (v.astype(np.float32), t.astype(np.int32)),
        (np.asfortranarray(v), np.asfortranarray(t.astype(np.int64))),
        (v.astype(np.float64), t.astype(np.uint32)),
        (wide[:, ::2], t.astype(np.uint64)),  # a strided view
        (v.tolist(), t.tolist()),
    ]
    for vertices, faces in variants:
        f = pgvol.Field.from_mesh(vertices, faces, res=24)
        assert f.to_bytes(dense=True) == reference


def test_point_dtypes_orders_and_strides_give_the_same_values(small_field):
    rng = np.random.default_rng(0)
    points = rng.uniform(-1.2, 1.2, (500, 3))
    expected = small_field(points.astype(np.float32))
    wide = np.zeros((500, 6))
    wide[:, ::2] = points
    for p in [
        points,
        np.asfortranarray(points),
        np.asfortranarray(points.astype(np.float32)),
        wide[:, ::2],  # a strided view
        points[::-1][::-1],
        points.tolist(),
    ]:
        assert np.array_equal(small_field(p), expected)
        values, gradients = small_field.eval_with_gradient(p)
        assert np.array_equal(values, expected)
        assert gradients.shape == (500, 3)
    assert small_field(np.empty((0, 3))).shape == (0,)


@pytest.mark.parametrize(
    "points, message",
    [
        (np.zeros((4, 2)), r"points must have shape \(N, 3\), got \(4, 2\)"),
        (np.zeros(3), r"points must have shape \(N, 3\), got \(3\)"),
        (np.zeros((2, 3, 3)), r"got \(2, 3, 3\)"),
        (np.zeros((4, 3), dtype=np.int64), "points must be float32 or float64, got int64"),
        (np.zeros((4, 3), dtype=np.float16), "got float16"),
        (np.zeros((4, 3), dtype=">f8"), "points must be float32 or float64"),
        ("not points", r"must have shape \(N, 3\)"),
    ],
)
def test_bad_points_are_value_errors_that_say_why(small_field, points, message):
    with pytest.raises(ValueError, match=message) as info:
        small_field(points)
    assert isinstance(info.value, pgvol.ParameterError)
    assert info.value.kind == "bad parameter" and info.value.path is None
    with pytest.raises(ValueError, match=message):
        small_field.eval_with_gradient(points)


def test_bad_meshes_are_value_errors_that_say_why(small_mesh):
    v, t = small_mesh
    cases = [
        (v[:, :2], t, r"vertices must have shape \(N, 3\)"),
        (v, t[:, :2], r"faces must have shape \(N, 3\)"),
        (v, t.astype(np.float64), "faces must be int32, int64, uint32 or uint64, got float64"),
        (v.astype(np.int32), t, "vertices must be float32 or float64, got int32"),
        (v, np.where(t == 0, -1, t), "vertex index -1 is out of range"),
        (v, np.where(t == 0, 99, t), "refers to vertex 99 but the mesh has 8 vertices"),
        (np.where(v > 0, np.nan, v), t, "NaN"),
        (v, t[:0], "no triangles"),
    ]
    for vertices, faces, message in cases:
        with pytest.raises(pgvol.ParameterError, match=message):
            pgvol.Field.from_mesh(vertices, faces, res=16)


def test_bad_options_are_value_errors(small_mesh, small_field):
    v, t = small_mesh
    for kwargs, message in [
        ({"res": 3}, f"res must be from 4 to {pgvol.MAX_RES}"),
        ({"res": 16, "voxel": 0.1}, "not both"),
        ({"res": None, "voxel": -1.0}, "voxel must be a positive number"),
        ({"basis": "cubic"}, "unknown basis 'cubic'"),
        ({"fit": "lsq"}, "unknown fit"),
        ({"sign": "maybe"}, "unknown sign"),
        ({"band": 1.0}, "band must be at least 2"),
        ({"z_step": 0.5}, "z_step applies to fit='iso' only"),
        ({"progress": 5}, "progress must be a callable"),
    ]:
        with pytest.raises(ValueError, match=message):
            pgvol.Field.from_mesh(v, t, **{"res": 16, **kwargs})
    with pytest.raises(ValueError, match="unknown method 'marching'"):
        small_field.to_mesh(method="marching")
    with pytest.raises(ValueError, match="exact distance only within"):
        small_field.offset(1.0)
    with pytest.raises(ValueError, match="reaches beyond the field's grid"):
        small_field.offset(10.0)
    with pytest.raises(ValueError, match="level set 5 is empty|reaches beyond the field's grid"):
        small_field.to_mesh(iso=5.0)
    for res in (0, 3):
        with pytest.raises(pgvol.ParameterError, match=f"at least 4 nodes along the longest side, got {res}"):
            small_field.to_mesh(res=res)
    with pytest.raises(ValueError, match="unknown axis"):
        small_field.slice(0.1, axis="w")
    with pytest.raises(ValueError, match="layer height must be a positive number"):
        small_field.slice(-0.1)


def test_sampled_volumes_are_indexed_x_y_z_on_an_asymmetric_grid(small_field):
    grid = pgvol.Grid(origin=(-1.0, -0.4, -0.3), spacing=0.1, dims=(5, 7, 9))
    a = small_field.sample_grid(grid)
    assert a.shape == (5, 7, 9) and a.dtype == np.float32
    # a[i, j, k] is the field at origin + spacing * (i, j, k).
    i, j, k = np.meshgrid(np.arange(5), np.arange(7), np.arange(9), indexing="ij")
    nodes = np.stack([i, j, k], axis=-1).reshape(-1, 3) * 0.1 + np.array(grid.origin)
    expected = small_field(nodes.astype(np.float32)).reshape(5, 7, 9)
    np.testing.assert_allclose(a, expected, rtol=0, atol=1e-6)
    # x varies fastest in memory, as in every pgvol array and file.
    assert a.flags.f_contiguous
    assert a[1, 0, 0] != a[0, 1, 0] or a[0, 1, 0] != a[0, 0, 1]
    own = small_field.to_dense()
    assert own.shape == small_field.grid.dims
    assert np.array_equal(own, small_field.sample_grid(small_field.grid))


def test_sampled_volumes_match_the_cli_npy_export(small_field, tmp_path, run_cli):
    """The command-line export writes (nz, ny, nx) in C order: the same memory, transposed."""
    path = tmp_path / "box.pgv"
    small_field.save(path)
    run_cli("export", path, "-o", tmp_path / "box.npy")
    exported = np.load(tmp_path / "box.npy")
    assert exported.shape == tuple(reversed(small_field.grid.dims))
    np.testing.assert_array_equal(pgvol.Field.load(path).to_dense(), exported.T)


def test_returned_arrays_are_handed_over_without_a_copy(small_field):
    points = np.zeros((10, 3))
    arrays = [small_field(points), *small_field.eval_with_gradient(points), small_field.to_dense()]
    arrays += list(small_field.to_mesh())
    for a in arrays:
        # Owned by the Rust vector they were built in, not by a NumPy copy of it.
        assert not a.flags.owndata and a.base is not None
        assert type(a.base).__name__ == "PySliceContainer"
        assert a.flags.writeable


def test_output_dtypes_and_shapes(small_field):
    v, t = small_field.to_mesh()
    assert v.dtype == np.float32 and v.ndim == 2 and v.shape[1] == 3
    assert t.dtype == np.int32 and t.ndim == 2 and t.shape[1] == 3
    assert t.min() == 0 and t.max() == len(v) - 1


def test_missing_files_are_file_not_found_errors_with_the_path(tmp_path):
    missing = tmp_path / "nowhere.pgv"
    with pytest.raises(FileNotFoundError) as info:
        pgvol.Field.load(missing)
    e = info.value
    assert isinstance(e, pgvol.MissingFileError) and isinstance(e, pgvol.InputFileError)
    assert e.kind == "input file" and e.path == str(missing) and e.filename == str(missing)
    assert str(e).startswith(str(missing) + ": ")
    with pytest.raises(FileNotFoundError):
        pgvol.read_mesh(tmp_path / "nowhere.obj")


def test_malformed_inputs_and_unwritable_outputs_name_the_file(small_field, tmp_path):
    bad = tmp_path / "bad.pgv"
    bad.write_bytes(b"this is not a pgv file")
    with pytest.raises(pgvol.InputFileError) as info:
        pgvol.Field.load(bad)
    assert not isinstance(info.value, FileNotFoundError)
    assert info.value.path == str(bad) and info.value.kind == "input file"
    # Bytes are a value, not a file: junk is a ValueError saying so, never a missing file.
    with pytest.raises(pgvol.ParameterError, match="not a readable .pgv file") as info:
        pgvol.Field.from_bytes(b"garbage")
    assert isinstance(info.value, ValueError) and not isinstance(info.value, FileNotFoundError)
    out = tmp_path / "no-such-folder" / "x.pgv"
    with pytest.raises(pgvol.OutputFileError) as info:
        small_field.save(out)
    assert info.value.path == str(out) and info.value.kind == "output file"
    with pytest.raises(pgvol.OutputFileError, match="expected a .pgv file name"):
        small_field.save(tmp_path / "x.txt")
    with pytest.raises(pgvol.OutputFileError, match="unknown extension"):
        pgvol.write_mesh(tmp_path / "x.xyz", *small_field.to_mesh())


def test_a_sheet_without_thickness_is_an_empty_result_saying_so():
    """A flat open sheet encloses nothing: an EmptyResultError (a ValueError), not a field."""
    n = 8
    v = np.array([(i / n, j / n, 0.0) for j in range(n + 1) for i in range(n + 1)], np.float32)
    faces = []
    for j in range(n):
        for i in range(n):
            a = j * (n + 1) + i
            faces += [(a, a + 1, a + n + 2), (a, a + n + 2, a + n + 1)]
    with pytest.raises(pgvol.EmptyResultError, match="no thickness|all its vertices lie in one plane") as info:
        pgvol.Field.from_mesh(v, np.array(faces, np.int32), res=24)
    assert isinstance(info.value, ValueError) and info.value.kind == "empty result"


def test_jobs_beyond_the_memory_limit_are_memory_errors(small_mesh):
    pgvol.set_memory_limit(1 << 20)
    try:
        assert pgvol.memory_limit() == 1 << 20
        with pytest.raises(MemoryError) as info:
            pgvol.Field.from_mesh(*small_mesh, res=512)
        assert isinstance(info.value, pgvol.ResourceLimitError)
        assert info.value.kind == "resource limit"
    finally:
        pgvol.set_memory_limit(None)
    assert pgvol.memory_limit() != 1 << 20


def test_errors_and_fields_pickle(small_field):
    e = pgvol.ParameterError("bad thing", "bad parameter", None)
    again = pickle.loads(pickle.dumps(e))
    assert type(again) is pgvol.ParameterError and str(again) == "bad thing"
    f = pickle.loads(pickle.dumps(small_field))
    points = np.random.default_rng(1).uniform(-1, 1, (100, 3))
    assert np.array_equal(f(points), small_field(points))


def test_properties(small_field):
    f = small_field
    assert f.basis == "bspline3" and f.fit == "interp"
    assert f.grid.dims == (24, 24, 24)
    assert f.grid.spacing == pytest.approx(2.0 * 1.1 / 23, rel=1e-6)
    assert f.band == pytest.approx(4 * f.grid.spacing, rel=1e-5)
    assert 0 < f.exact_band < f.band
    lo, hi = f.bounds
    np.testing.assert_allclose(lo, (-1.0, -0.5, -0.25))
    np.testing.assert_allclose(hi, (1.0, 0.5, 0.25))
    assert f.metadata["band"]
    assert "Field(basis=bspline3, dims=(24, 24, 24)" in repr(f)
    assert pgvol.Grid((0, 0, 0), 1.0, (2, 3, 4)) == pgvol.Grid((0, 0, 0), 1.0, (2, 3, 4))
    for basis in ["bspline2", "trilinear", "pg", "pg-n2-r1.25"]:
        g = pgvol.Field.from_mesh(*trimesh_box(), res=16, basis=basis)
        assert g.basis == {"pg": "pg-n3-r1.5"}.get(basis, basis)


def trimesh_box():
    box = trimesh.creation.box(extents=(2.0, 1.0, 0.5))
    return box.vertices, box.faces
