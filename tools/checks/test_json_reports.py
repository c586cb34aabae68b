"""Every command's `--json` report has one shape: its outputs, `warnings` (a list of strings,
empty when none; the same warnings standard error gets without --json) and `seconds` (an
object of stage times with their `total`)."""

from __future__ import annotations

import numpy as np
import trimesh

import helpers


def check_shape(name, report, outputs):
    warnings = report.get("warnings")
    assert isinstance(warnings, list), f"{name}: warnings is {warnings!r}"
    assert all(isinstance(w, str) for w in warnings), f"{name}: {warnings}"
    seconds = report.get("seconds")
    assert isinstance(seconds, dict), f"{name}: seconds is {seconds!r}"
    assert seconds.get("total", -1) >= 0, f"{name}: {seconds}"
    assert all(isinstance(v, (int, float)) and v >= 0 for v in seconds.values()), f"{name}: {seconds}"
    for key in outputs:
        assert key in report, f"{name}: no {key!r} in {sorted(report)}"


def test_every_json_report_has_outputs_warnings_and_seconds(tmp_path, pgvol):
    knot = helpers.REPO_ROOT / "fixtures" / "torus-knot.obj"
    pgv = tmp_path / "knot.pgv"
    layers = tmp_path / "layers.json"
    points = tmp_path / "points.csv"
    points.write_text("0,0,0\n0.1,0.2,0.3\n")
    runs = {
        "encode": ([pgvol, "encode", knot, "-o", pgv, "--res", 32], ["output", "grid", "fit"]),
        "decode": ([pgvol, "decode", pgv, "-o", tmp_path / "k.glb"], ["output", "triangles"]),
        "info": ([pgvol, "info", pgv], ["header", "bytes"]),
        "eval": ([pgvol, "eval", pgv, points], ["points"]),
        "export": ([pgvol, "export", pgv, "-o", tmp_path / "e.npy"], ["output", "grid"]),
        "remesh": ([pgvol, "remesh", knot, "-o", tmp_path / "r.glb", "--res", 32], ["output", "triangles"]),
        "sdf": ([pgvol, "sdf", knot, "-o", tmp_path / "k.nrrd", "--res", 24], ["grid", "samples"]),
        "compare": ([pgvol, "compare", tmp_path / "r.glb", knot, "--samples", 2000], ["hausdorff"]),
        "offset": ([pgvol, "offset", pgv, "-o", tmp_path / "o.glb", "--distance", 0.01], ["output", "triangles"]),
        "shell": ([pgvol, "shell", knot, "-o", tmp_path / "s.glb", "--thickness", 0.3, "--side", "outer",
                   "--res", 64], ["output", "triangles"]),
        "slice": ([pgvol, "slice", pgv, "-o", layers, "--layer-height", 0.2], ["output", "layers"]),
        "contours": ([pgvol, "contours", layers, "-o", tmp_path / "c.glb", "--res", 32], ["output", "layers"]),
        "csg": ([pgvol, "csg", "union", pgv, "sphere:0,0,0,0.5", "-o", tmp_path / "u.glb"], ["output", "triangles"]),
        "view": ([pgvol, "view", pgv, "-o", tmp_path / "v.html"], ["output", "bytes"]),
    }
    for name, (args, outputs) in runs.items():
        report = helpers.run_json(args + ["--json"])
        check_shape(name, report, outputs)
    # eval's values are in the report's points, one object per point.
    report = helpers.run_json(runs["eval"][0] + ["--json"])
    assert len(report["points"]) == 2 and {"value", "gradient", "exact"} <= set(report["points"][0])


def test_a_decode_that_removes_a_speck_says_so_in_its_json(tmp_path, pgvol):
    # A unit sphere, and beside it a sphere of 0.6 grid spacings around a node of the 33-node
    # grid of their box (spacing 2.2 / 32): a piece of under 2 cells, removed by default.
    h = 2.2 / 32
    node = -1.1 + 28 * h
    big = trimesh.creation.icosphere(subdivisions=4, radius=1.0)
    speck = trimesh.creation.icosphere(subdivisions=2, radius=0.6 * h)
    speck.apply_translation([node, node, node])
    both = trimesh.util.concatenate([big, speck])
    assert np.allclose(both.bounds, [[-1, -1, -1], [1, 1, 1]], atol=1e-3)
    mesh = tmp_path / "speck.obj"
    both.export(mesh)
    pgv = tmp_path / "speck.pgv"
    helpers.run_ok([pgvol, "encode", mesh, "-o", pgv, "--res", 33, "-q"])

    report = helpers.run_json([pgvol, "decode", pgv, "-o", tmp_path / "d.glb", "--json"])
    check_shape("decode", report, ["output", "triangles"])
    removed = [w for w in report["warnings"] if "removed 1 piece" in w]
    assert removed, report["warnings"]
    # Without --json the same warning goes to standard error; keeping every piece gives none.
    r = helpers.run_ok([pgvol, "decode", pgv, "-o", tmp_path / "d.glb"])
    assert "removed 1 piece" in r.stderr, r.describe()
    report = helpers.run_json([pgvol, "decode", pgv, "-o", tmp_path / "d.glb", "--json", "--min-component", 0])
    assert report["warnings"] == [], report["warnings"]
