"""A unit cube far from the origin through the command-line tool: remesh, encode/decode, slice
and eval give what they give at the origin, moved there, measured with trimesh; the far GLB
passes the Khronos validator; STL and binary CLI, which hold single precision, are refused with
advice rather than written wrong."""

from __future__ import annotations

import json

import numpy as np
import pytest
import trimesh

import helpers
from test_validator import _assert_valid, validator  # noqa: F401 - the validator fixture

SHIFT = 1e6


def write_cube(path, shift):
    box = trimesh.creation.box(extents=(1.0, 1.0, 1.0))
    v = np.asarray(box.vertices, dtype=np.float64) + 0.5 + shift
    with open(path, "w") as f:
        for p in v:
            f.write("v %r %r %r\n" % tuple(float(c) for c in p))
        for t in box.faces:
            f.write("f %d %d %d\n" % tuple(t + 1))


@pytest.fixture(scope="module")
def cubes(tmp_path_factory):
    d = tmp_path_factory.mktemp("far")
    write_cube(d / "near.obj", 0.0)
    write_cube(d / "far.obj", SHIFT)
    return d


def test_far_remesh_and_decode_match_the_origin(pgvol, cubes, validator):  # noqa: F811
    near_ref = helpers.load_input(cubes / "near.obj")
    for how, make in [
        ("remesh", lambda src, out: helpers.run_ok([pgvol, "remesh", src, "-o", out, "--res", 48, "-q"])),
        ("decode", lambda src, out: (
            helpers.run_ok([pgvol, "encode", src, "-o", out.with_suffix(".pgv"), "--res", 48, "-q"]),
            helpers.run_ok([pgvol, "decode", out.with_suffix(".pgv"), "-o", out, "-q"]),
        )),
    ]:
        make(cubes / "near.obj", cubes / f"{how}-near.obj")
        make(cubes / "far.obj", cubes / f"{how}-far.glb")
        near = helpers.load_output(cubes / f"{how}-near.obj")
        far = helpers.load_output(cubes / f"{how}-far.glb")
        moved = far.copy()
        moved.apply_translation([-SHIFT] * 3)
        # At 1e6 single precision alone rounds by 0.03 (3 % of the cube): far below that.
        assert abs(moved.volume - near.volume) < 1e-4, how
        assert np.abs(moved.bounds - near.bounds).max() < 1e-5, how
        chamfer, _, _ = helpers.chamfer_l1(moved, near_ref, 20000)
        near_chamfer, _, _ = helpers.chamfer_l1(near, near_ref, 20000)
        assert chamfer < near_chamfer + 1e-5, how
        _assert_valid(validator, cubes / f"{how}-far.glb")


def test_far_info_eval_and_slice_are_in_world_coordinates(pgvol, cubes):
    pgv = cubes / "far.pgv"
    helpers.run_ok([pgvol, "encode", cubes / "far.obj", "-o", pgv, "--res", 48, "-q"])
    assert "frame offset" in helpers.run_ok([pgvol, "info", pgv]).stdout
    info = helpers.run_json([pgvol, "info", pgv, "--json"])
    assert np.abs(np.array(info["header"]["grid"]["offset"]) - (SHIFT + 0.5)).max() <= 1
    # A point 0.01 outside the face x = 1e6 + 1.
    points = cubes / "points.csv"
    points.write_text("x,y,z\n1000001.01,1000000.5,1000000.5\n")
    rows = helpers.run_ok([pgvol, "eval", pgv, points]).stdout.splitlines()
    x, y, z, value = (float(c) for c in rows[1].split(",")[:4])
    assert (x, y, z) == (1000001.01, 1000000.5, 1000000.5)
    assert abs(value - 0.01) < 2e-3
    layers = cubes / "far.json"
    helpers.run_ok([pgvol, "slice", pgv, "-o", layers, "--layer-height", 0.25, "-q"])
    heights = [layer["height"] for layer in json.loads(layers.read_text())["layers"]]
    assert heights and min(heights) > SHIFT and max(heights) < SHIFT + 1
    u = [p[0] for layer in json.loads(layers.read_text())["layers"] for lp in layer["loops"] for p in lp["points"]]
    assert abs(min(u) - SHIFT) < 0.02 and abs(max(u) - SHIFT - 1) < 0.02


def test_single_precision_outputs_refuse_a_far_shape_with_advice(pgvol, cubes):
    r = helpers.run([pgvol, "remesh", cubes / "far.obj", "-o", cubes / "far.stl", "--res", 24])
    assert r.returncode != 0 and not (cubes / "far.stl").exists()
    assert "STL" in r.stderr and "%" in r.stderr and "OBJ" in r.stderr
    r = helpers.run([pgvol, "slice", cubes / "far.obj", "-o", cubes / "far.cli", "--layer-height", 0.25,
                     "--binary", "--res", 24])
    assert r.returncode != 0 and not (cubes / "far.cli").exists()
    assert "binary CLI" in r.stderr and "ASCII" in r.stderr
