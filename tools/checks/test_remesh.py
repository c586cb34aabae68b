"""`pgvol remesh` on the shared corpus: the output is a valid closed manifold,
keeps the volume of closed inputs, and `pgvol compare` measures its distance to
the input as an independent trimesh computation does."""

from __future__ import annotations

import pytest

import helpers
from helpers import REMESH_MESHES, EXPECTED_CLOSED

# Samples per side for the reference Chamfer-L1: the relative standard error of
# each mean is ~1/sqrt(N) times the spread of the distances, well under 1 %.
REFERENCE_SAMPLES = 40_000
CHAMFER_TOLERANCE = 0.05
VOLUME_TOLERANCE = 0.02


def test_expected_inputs_are_closed(reference_mesh):
    closed = {name for name in REMESH_MESHES if reference_mesh(name).is_watertight}
    assert closed == EXPECTED_CLOSED, (
        f"closed inputs (trimesh, after merging equal vertices) are {sorted(closed)}, "
        f"expected {sorted(EXPECTED_CLOSED)}"
    )


@pytest.mark.parametrize("name", REMESH_MESHES)
def test_remesh_output_is_closed_manifold(name, remesh):
    out = remesh(name, ".glb")
    mesh = helpers.load_output(out)
    edges = helpers.edge_counts(mesh)
    assert mesh.is_watertight, f"{name}: output is not watertight ({edges})"
    assert mesh.is_winding_consistent, f"{name}: output winding is not consistent"
    status = helpers.manifold_status(mesh)
    assert helpers.manifold_ok(status), f"{name}: manifold3d rejects the output: {status}"
    assert mesh.volume > 0, f"{name}: output has non-positive volume {mesh.volume} (inside out?)"


@pytest.mark.parametrize("name", sorted(EXPECTED_CLOSED))
def test_remesh_keeps_volume_of_closed_inputs(name, remesh, reference_mesh):
    ref = reference_mesh(name)
    assert ref.is_watertight, f"{name}: input expected closed"
    out = helpers.load_output(remesh(name, ".glb"))
    err = helpers.rel_diff(out.volume, ref.volume)
    assert err <= VOLUME_TOLERANCE, (
        f"{name}: output volume {out.volume:.6g} vs input {ref.volume:.6g} "
        f"({100 * err:.2f} % > {100 * VOLUME_TOLERANCE:.0f} %)"
    )


@pytest.mark.parametrize("name", REMESH_MESHES)
def test_compare_chamfer_matches_reference(name, remesh, mesh_path, reference_mesh, pgvol):
    out_path = remesh(name, ".glb")
    report = helpers.run_json([pgvol, "compare", out_path, mesh_path(name), "--json", "--samples", 200000])
    for key in ("chamfer_l1", "mean_a_to_b", "mean_b_to_a", "diagonal", "chamfer_l1_pct"):
        assert key in report, f"compare --json lacks {key!r}: keys {sorted(report)}"

    out = helpers.load_output(out_path)
    ref = reference_mesh(name)
    ab, ba, chamfer = helpers.chamfer_l1(out, ref, REFERENCE_SAMPLES)

    detail = (
        f"{name}: pgvol chamfer_l1={report['chamfer_l1']:.6g} (a->b {report['mean_a_to_b']:.6g}, "
        f"b->a {report['mean_b_to_a']:.6g}); trimesh chamfer={chamfer:.6g} (a->b {ab:.6g}, b->a {ba:.6g})"
    )
    assert helpers.rel_diff(report["chamfer_l1"], chamfer) <= CHAMFER_TOLERANCE, detail
    assert helpers.rel_diff(report["mean_a_to_b"], ab) <= CHAMFER_TOLERANCE, "direction A->B: " + detail
    assert helpers.rel_diff(report["mean_b_to_a"], ba) <= CHAMFER_TOLERANCE, "direction B->A: " + detail

    # Internal consistency of the report.
    diag = helpers.bbox_diagonal(ref)
    assert helpers.rel_diff(report["diagonal"], diag) <= 1e-5, f"diagonal {report['diagonal']} vs B's bbox {diag}"
    mean_of_means = 0.5 * (report["mean_a_to_b"] + report["mean_b_to_a"])
    assert helpers.rel_diff(report["chamfer_l1"], mean_of_means) <= 1e-4, detail
    assert helpers.rel_diff(report["chamfer_l1_pct"], 100 * report["chamfer_l1"] / report["diagonal"]) <= 1e-4
    assert report["hausdorff"] >= max(report["mean_a_to_b"], report["mean_b_to_a"]) * (1 - 1e-6), report


def test_remesh_json_flag_prints_json(pgvol, mesh_path, work_dir):
    out = work_dir / "remesh-json" / "fandisk.glb"
    out.parent.mkdir(parents=True, exist_ok=True)
    report = helpers.run_json([pgvol, "remesh", mesh_path("fandisk"), "-o", out, "--res", 32, "--json"])
    assert report, "remesh --json printed an empty object"
    assert out.is_file(), "remesh --json wrote no output file"
