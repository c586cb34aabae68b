"""`pgvol points` and `pgvol contours` from the command line: the results are watertight by
trimesh and enclose the volume trimesh measures for the true mesh; clouds given as PLY with
normals, as text without them, and contours given as CLI and JSON layer files all work."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

import helpers

VOLUME_TOLERANCE = 0.02


def check_solid(path, reference):
    out = helpers.load_input(path)
    assert out.is_watertight, f"{path.name} is not watertight"
    ratio = out.volume / reference.volume
    assert abs(ratio - 1) < VOLUME_TOLERANCE, f"{path.name}: volume {ratio:.4f} of the mesh's"


@pytest.mark.parametrize("name", ["spot", "fandisk"])
def test_points_from_ply_with_normals_and_text_without(name, pgvol, reference_mesh, work_dir):
    mesh = reference_mesh(name)
    points, faces = trimesh.sample.sample_surface(mesh, 30_000, seed=3)
    normals = mesh.face_normals[faces]
    ply = work_dir / f"{name}-cloud.ply"
    header = (
        "ply\nformat ascii 1.0\n"
        f"element vertex {len(points)}\n"
        "property float x\nproperty float y\nproperty float z\n"
        "property float nx\nproperty float ny\nproperty float nz\nend_header\n"
    )
    body = "\n".join(" ".join(f"{v:.7g}" for v in row) for row in np.hstack([points, normals]))
    ply.write_text(header + body + "\n")
    out = work_dir / f"{name}-points.glb"
    report = helpers.run_json([pgvol, "points", ply, "-o", out, "--res", 80, "--json"])
    assert report["points"] == len(np.unique(points, axis=0))
    assert report["normals_estimated"] is False
    check_solid(out, mesh)

    xyz = work_dir / f"{name}-cloud.xyz"
    np.savetxt(xyz, points, fmt="%.7g")
    out = work_dir / f"{name}-points-estimated.stl"
    run = helpers.run_ok([pgvol, "points", xyz, "-o", out, "--res", 80, "--method", "rbf-wendland"])
    assert "estimated" in run.stderr
    check_solid(out, mesh)


@pytest.mark.parametrize("ext", [".cli", ".json", ".svg"])
def test_contours_rebuild_a_sliced_mesh(ext, pgvol, reference_mesh, mesh_path, work_dir):
    mesh = reference_mesh("spot")
    height = float(mesh.bounds[1][2] - mesh.bounds[0][2])
    layers = work_dir / f"spot-layers{ext}"
    helpers.run_ok([pgvol, "slice", mesh_path("spot"), "-o", layers, "--layer-height", height / 40])
    out = work_dir / f"spot-contours{ext}.glb"
    helpers.run_ok([pgvol, "contours", layers, "-o", out, "--res", 128])
    out_mesh = helpers.load_input(out)
    assert out_mesh.is_watertight
    # 40 layers lose the thin horns and ears' tips: a looser bound than for the points.
    assert abs(out_mesh.volume / mesh.volume - 1) < 0.05


def test_bad_clouds_are_refused_by_name(pgvol, work_dir):
    bad = work_dir / "bad.xyz"
    bad.write_text("0 0 0\n1 1\n")
    run = helpers.run([pgvol, "points", bad, "-o", work_dir / "bad.glb"])
    assert run.returncode != 0
    assert "bad.xyz" in run.stderr and "line 2" in run.stderr
    few = work_dir / "few.xyz"
    few.write_text("0 0 0\n1 0 0\n0 1 0\n")
    run = helpers.run([pgvol, "points", few, "-o", work_dir / "few.glb"])
    assert run.returncode != 0 and "at least 10" in run.stderr
