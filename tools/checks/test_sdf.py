"""`pgvol sdf --dense` writes the project grid (cube of side 1.1 x the longest bbox
extent, centred on the bbox, N nodes per axis, x fastest) holding the signed
distance, negative inside."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

import helpers

RES = 24
CHECKED_NODES = 3000


def grid_nodes(mesh: trimesh.Trimesh, n: int):
    lo, hi = mesh.bounds
    side = 1.1 * float(np.max(hi - lo))
    h = side / (n - 1)
    origin = 0.5 * (lo + hi) - 0.5 * side
    return origin, h


@pytest.mark.parametrize("name", ["fandisk", "spot"])
def test_dense_sdf_matches_reference(name, pgvol, mesh_path, reference_mesh, work_dir):
    import nrrd

    out = work_dir / "sdf" / f"{name}-{RES}.nrrd"
    out.parent.mkdir(parents=True, exist_ok=True)
    report = helpers.run_json([pgvol, "sdf", mesh_path(name), "-o", out, "--res", RES, "--dense", "--json"])
    assert report.get("samples") == RES**3, f"--json samples {report.get('samples')} != {RES**3}"
    for key in ("seconds", "samples_per_second"):
        assert key in report, f"sdf --json lacks {key!r}"

    data, header = nrrd.read(str(out))  # Fortran order: data[i, j, k] with i = x (fastest)
    assert data.dtype == np.float32, f"grid type {data.dtype}, expected float32"
    assert data.shape == (RES, RES, RES), f"grid shape {data.shape}"
    assert np.all(np.isfinite(data)), "dense grid has non-finite values"

    mesh = reference_mesh(name)
    origin, h = grid_nodes(mesh, RES)
    if "space origin" in header:
        assert np.allclose(np.asarray(header["space origin"], float), origin, atol=1e-5 * h * RES), header
    if "space directions" in header:
        dirs = np.asarray(header["space directions"], float)
        assert np.allclose(dirs, np.eye(3) * h, atol=1e-5 * h), header

    rng = np.random.default_rng(7)
    idx = rng.integers(0, RES, size=(CHECKED_NODES, 3))
    points = origin + h * idx
    got = data[idx[:, 0], idx[:, 1], idx[:, 2]].astype(np.float64)
    # trimesh: positive inside; pgvol: negative inside.
    expected = -trimesh.proximity.signed_distance(mesh, points)
    tol = 1e-4 * h * (RES - 1)
    err = np.abs(np.abs(got) - np.abs(expected))
    assert err.max() <= tol, f"{name}: |distance| off by up to {err.max():.3g} (tol {tol:.3g})"
    # Signs away from the surface (trimesh's inside test is unreliable right on it).
    far = np.abs(expected) > 0.5 * h
    wrong = np.count_nonzero(np.sign(got[far]) != np.sign(expected[far]))
    assert wrong == 0, f"{name}: {wrong} of {far.sum()} nodes have the wrong sign"
