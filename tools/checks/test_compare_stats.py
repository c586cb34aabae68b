"""`pgvol compare MESH MESH --json`: the mesh statistics agree with trimesh and a
mesh is at distance ~0 from itself."""

from __future__ import annotations

import pytest

import helpers
from helpers import ALL_MESHES

STATS_KEYS = {
    "vertices", "triangles", "edges", "boundary_edges", "non_manifold_edges", "watertight",
    "winding_consistent", "euler_characteristic", "volume", "area", "components",
}


@pytest.fixture(scope="module")
def self_compare(pgvol, mesh_path):
    cache: dict[str, dict] = {}

    def _get(name: str) -> dict:
        if name not in cache:
            path = mesh_path(name)
            cache[name] = helpers.run_json([pgvol, "compare", path, path, "--json"])
        return cache[name]

    return _get


@pytest.mark.parametrize("side", ["a", "b"])
@pytest.mark.parametrize("name", ALL_MESHES)
def test_stats_match_trimesh(name, side, self_compare, reference_mesh):
    report = self_compare(name)
    assert side in report, f"compare --json lacks {side!r}: keys {sorted(report)}"
    stats = report[side]
    missing = STATS_KEYS - set(stats)
    assert not missing, f"{name}: stats lack {sorted(missing)}"

    ref = reference_mesh(name)
    edges = helpers.edge_counts(ref)
    problems = []

    def check_rel(key, expected, tol):
        if helpers.rel_diff(stats[key], expected) > tol:
            problems.append(f"{key}: pgvol {stats[key]!r} vs trimesh {expected!r} (rel tol {tol})")

    def check_eq(key, expected):
        if stats[key] != expected:
            problems.append(f"{key}: pgvol {stats[key]!r} vs trimesh {expected!r}")

    # For open meshes the volume is the plain signed sum relative to the coordinate origin.
    volume = helpers.signed_volume(ref)
    if ref.is_watertight:
        assert helpers.rel_diff(volume, ref.volume) < 1e-9, (volume, ref.volume)
    check_rel("volume", volume, 1e-4)
    check_rel("area", ref.area, 1e-5)
    check_eq("triangles", len(ref.faces))
    check_eq("edges", edges["edges"])
    check_eq("boundary_edges", edges["boundary_edges"])
    check_eq("non_manifold_edges", edges["non_manifold_edges"])
    check_eq("watertight", bool(ref.is_watertight))
    check_eq("euler_characteristic", int(ref.euler_number))
    assert not problems, f"{name} ({side}):\n  " + "\n  ".join(problems)


@pytest.mark.parametrize("name", ALL_MESHES)
def test_self_distance_is_zero(name, self_compare, reference_mesh):
    report = self_compare(name)
    diag = helpers.bbox_diagonal(reference_mesh(name))
    assert helpers.rel_diff(report["diagonal"], diag) <= 1e-5, f"diagonal {report['diagonal']} vs bbox {diag}"
    assert report["samples"] > 0, report
    for key in ("hausdorff", "chamfer_l1", "mean_a_to_b", "mean_b_to_a"):
        assert 0 <= report[key] < 1e-6 * diag, f"{name}: {key}={report[key]!r} for a mesh against itself (diag {diag})"


def test_text_report_keeps_small_figures_and_marks_open_volumes(pgvol, mesh_path, tmp_path):
    """A part in metres (the cow scaled by 1e-4) keeps its digits in the text report, where six
    decimals would print zeros; an open mesh's volume, which depends on the origin, is marked."""
    import trimesh

    small = tmp_path / "cow-small.obj"
    cow = trimesh.load(mesh_path("cow"), force="mesh", process=False)
    cow.apply_scale(1e-4)
    cow.export(small)
    text = helpers.run_ok([pgvol, "compare", small, small, "--samples", 2000]).stdout
    area = next(line for line in text.splitlines() if line.startswith("area")).split()[1:]
    assert all(abs(float(a) - cow.area) < 1e-3 * cow.area for a in area), (area, cow.area)
    assert "0.000000 " not in text.split("volume")[1], text
    suzanne = mesh_path("suzanne")
    text = helpers.run_ok([pgvol, "compare", suzanne, suzanne, "--samples", 2000]).stdout
    volume = next(line for line in text.splitlines() if line.startswith("volume"))
    assert volume.count("(open)") == 2, volume
