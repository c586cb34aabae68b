"""`pgvol encode` then `pgvol decode` with each contouring method and with the
bases and fits of the field crate: the decoded meshes are checked by trimesh and
manifold3d, and the .pgv file round-trips through `info` and `eval`."""

from __future__ import annotations

import json

import numpy as np
import pytest

import helpers
from helpers import REMESH_MESHES, EXPECTED_CLOSED

RES = 64
VOLUME_TOLERANCE = 0.01


@pytest.fixture(scope="session")
def encoded(pgvol, mesh_path, work_dir):
    cache = {}

    def _encode(name: str, *extra: str):
        key = (name, extra)
        if key not in cache:
            out = work_dir / "encode" / f"{name}{'-'.join(('',) + extra).replace('--', '')}.pgv"
            out.parent.mkdir(parents=True, exist_ok=True)
            helpers.run_ok([pgvol, "encode", mesh_path(name), "-o", out, "--res", RES, "-q", *extra])
            cache[key] = out
        return cache[key]

    return _encode


def decode(pgvol, pgv, method: str, suffix: str = ".glb"):
    out = pgv.with_name(f"{pgv.stem}-{method}{suffix}")
    helpers.run_ok([pgvol, "decode", pgv, "-o", out, "--method", method, "-q"])
    return out


@pytest.mark.parametrize("method", ["mc", "dc", "sn"])
@pytest.mark.parametrize("name", REMESH_MESHES)
def test_decoded_mesh_is_closed_manifold(name, method, pgvol, encoded, reference_mesh):
    mesh = helpers.load_output(decode(pgvol, encoded(name), method))
    assert mesh.is_watertight, f"{name}/{method}: not watertight ({helpers.edge_counts(mesh)})"
    assert mesh.is_winding_consistent, f"{name}/{method}: winding not consistent"
    status = helpers.manifold_status(mesh)
    assert helpers.manifold_ok(status), f"{name}/{method}: manifold3d rejects the output: {status}"
    if name in EXPECTED_CLOSED:
        ref = reference_mesh(name)
        err = helpers.rel_diff(mesh.volume, ref.volume)
        assert err <= VOLUME_TOLERANCE, f"{name}/{method}: volume off by {100 * err:.2f} %"
        # Genus is kept: the inputs are connected closed surfaces.
        assert mesh.euler_number == ref.euler_number, (
            f"{name}/{method}: Euler characteristic {mesh.euler_number} vs input {ref.euler_number}"
        )


def test_dual_contouring_keeps_sharp_edges_better(pgvol, encoded, mesh_path):
    pgv = encoded("fandisk")
    deviation = {}
    for method in ("mc", "dc"):
        out = decode(pgvol, pgv, method)
        report = helpers.run_json([pgvol, "compare", out, mesh_path("fandisk"), "--json", "--samples", 50000])
        deviation[method] = report["normal_deviation_mean_deg"]
    assert deviation["dc"] < deviation["mc"], deviation


@pytest.mark.parametrize(
    "extra",
    [("--basis", "bspline2"), ("--basis", "trilinear"), ("--basis", "pg", "--pg-n", "3", "--pg-r", "1.5")],
)
def test_other_bases_decode_to_closed_meshes(extra, pgvol, encoded, reference_mesh):
    pgv = encoded("spot", *extra)
    info = helpers.run_json([pgvol, "info", pgv, "--json"])
    assert info["header"]["grid"]["dims"] == [RES, RES, RES]
    mesh = helpers.load_output(decode(pgvol, pgv, "mc"))
    assert mesh.is_watertight
    err = helpers.rel_diff(mesh.volume, reference_mesh("spot").volume)
    assert err <= 0.02, f"{extra}: volume off by {100 * err:.2f} %"


def test_eval_matches_decoded_surface(pgvol, encoded, work_dir):
    pgv = encoded("fandisk")
    mesh = helpers.load_output(decode(pgvol, pgv, "mc"))
    rng = np.random.default_rng(3)
    picks = mesh.vertices[rng.choice(len(mesh.vertices), 200, replace=False)]
    points = work_dir / "encode" / "points.csv"
    points.write_text("x,y,z\n" + "".join(f"{x},{y},{z}\n" for x, y, z in picks))
    rows = helpers.run_json([pgvol, "eval", pgv, points, "--json"])["points"]
    assert len(rows) == 200
    values = np.array([r["value"] for r in rows])
    grads = np.array([r["gradient"] for r in rows])
    info = helpers.run_json([pgvol, "info", pgv, "--json"])
    spacing = info["header"]["grid"]["spacing"]
    # Marching cubes vertices sit on the zero set of the continuous field.
    assert np.abs(values).max() < 1e-3 * spacing, np.abs(values).max()
    # A signed distance has gradients of length close to one near the surface.
    lengths = np.linalg.norm(grads, axis=1)
    assert np.median(np.abs(lengths - 1)) < 0.05, np.median(lengths)


def test_every_json_report_times_its_run_the_same_way(tmp_path, pgvol):
    """`seconds` is an object with the total and the stages, in every command's --json."""
    knot = helpers.REPO_ROOT / "fixtures" / "torus-knot.obj"
    pgv = tmp_path / "knot.pgv"
    runs = {
        "encode": [pgvol, "encode", knot, "-o", pgv, "--res", 32],
        "decode": [pgvol, "decode", pgv, "-o", tmp_path / "k.glb"],
        "remesh": [pgvol, "remesh", knot, "-o", tmp_path / "r.glb", "--res", 32],
        "sdf": [pgvol, "sdf", knot, "-o", tmp_path / "k.nrrd", "--res", 24],
        "export": [pgvol, "export", pgv, "-o", tmp_path / "e.npy"],
        "offset": [pgvol, "offset", pgv, "-o", tmp_path / "o.glb", "--distance", 0.01],
        "slice": [pgvol, "slice", pgv, "-o", tmp_path / "s.json", "--layer-height", 0.5],
    }
    for name, args in runs.items():
        report = helpers.run_json(args + ["--json"])
        seconds = report.get("seconds")
        assert isinstance(seconds, dict), f"{name}: seconds is {seconds!r}"
        assert seconds.get("total", -1) >= 0, f"{name}: {seconds}"
        assert all(isinstance(v, (int, float)) and v >= 0 for v in seconds.values()), f"{name}: {seconds}"
        assert all(v <= seconds["total"] + 1e-6 for k, v in seconds.items()), f"{name}: {seconds}"
