"""`pgvol points` and `pgvol contours` from the command line: the results are watertight by
trimesh and enclose the volume trimesh measures for the true mesh; clouds given as PLY with
normals, as text without them, and contours given as CLI and JSON layer files all work."""

from __future__ import annotations

import json

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


def distances_to_polylines(points: np.ndarray, loops: list[np.ndarray]) -> np.ndarray:
    """The distance from each 2D point to the nearest segment of the closed loops."""
    best = np.full(len(points), np.inf)
    for loop in loops:
        a = np.asarray(loop, dtype=np.float64)
        d = np.roll(a, -1, axis=0) - a
        length2 = np.maximum((d * d).sum(-1), 1e-30)
        for i in range(0, len(points), 2000):
            w = points[i : i + 2000, None, :] - a[None]
            t = np.clip((w * d[None]).sum(-1) / length2[None], 0.0, 1.0)
            dist = np.linalg.norm(w - t[..., None] * d[None], axis=-1).min(axis=1)
            best[i : i + 2000] = np.minimum(best[i : i + 2000], dist)
    return best


def test_sections_from_the_rbf_follow_the_mesh_sections(pgvol, reference_mesh, work_dir):
    """`--sections` cut from the RBF field lie on trimesh's sections of the true mesh, as
    closely as the sections `pgvol slice` cuts from the written volume."""
    mesh = reference_mesh("spot")
    points, faces = trimesh.sample.sample_surface(mesh, 20_000, seed=2)
    cloud = work_dir / "spot-sections.xyz"
    np.savetxt(cloud, np.hstack([points, mesh.face_normals[faces]]), fmt="%.7g")
    lo, hi = mesh.bounds
    heights = [round(float(lo[2] + f * (hi[2] - lo[2])), 5) for f in (0.2, 0.4, 0.5, 0.6, 0.8)]
    out = work_dir / "spot-sections.pgv"
    sections = "z:" + ",".join(str(h) for h in heights)
    args = ["--res", 64, "--method", "rbf-wendland", "--sections", sections, "--json"]
    report = helpers.run_json([pgvol, "points", cloud, "-o", out, *args])
    assert report["sections"]["output"] == str(work_dir / "spot-sections.sections.json")
    assert report["sections"]["empty"] == [] and report["warnings"] == []
    h = report["grid"]["spacing"]
    layers = json.loads((work_dir / "spot-sections.sections.json").read_text())["layers"]
    assert [layer["height"] for layer in layers] == pytest.approx(heights)
    for layer in layers:
        z = layer["height"]
        truth = mesh.section(plane_origin=[0, 0, z], plane_normal=[0, 0, 1])
        true_loops = [truth.vertices[e.points][:, :2] for e in truth.entities]
        # Loops of the true section wider than a grid spacing (the mesh's section has slivers).
        wide = [t for t in true_loops if np.ptp(t, axis=0).max() > h]
        ours = [np.asarray(loop["points"]) for loop in layer["loops"]]
        assert len(ours) == len(wide), f"z = {z}: {len(ours)} loops, the mesh has {len(wide)}"
        volume_layer = work_dir / "spot-sections-volume.json"
        helpers.run_ok([pgvol, "slice", out, "-o", volume_layer, "--layer-height", 1, "--first", z])
        resampled = json.loads(volume_layer.read_text())["layers"][0]["loops"]
        theirs = np.vstack([np.asarray(loop["points"]) for loop in resampled])
        d = distances_to_polylines(np.vstack(ours), true_loops) / h
        v = distances_to_polylines(theirs, true_loops) / h
        print(
            f"z = {z}: section from the RBF {d.mean():.3f} mean / {d.max():.3f} max grid "
            f"spacings from the mesh's; from the volume {v.mean():.3f} / {v.max():.3f}"
        )
        assert d.mean() < 0.05 and d.max() < 0.5, f"z = {z}"
