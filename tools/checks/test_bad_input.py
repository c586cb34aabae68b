"""Bad input makes `pgvol remesh` fail cleanly: non-zero exit, a message naming
the culprit, no panic, and nothing left behind in the output folder."""

from __future__ import annotations

import json
import struct
import subprocess
from pathlib import Path

import numpy as np
import pytest

import helpers

GOOD_OBJ = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n"


def _empty(folder: Path) -> Path:
    p = folder / "empty.obj"
    p.write_bytes(b"")
    return p


def _truncated_stl(folder: Path) -> Path:
    p = folder / "truncated.stl"
    tri = struct.pack("<12fH", *([0.0] * 3), 0, 0, 0, 1, 0, 0, 0, 1, 0, 0)
    # Header claims 100 triangles; only 10 follow, the last one cut short.
    p.write_bytes(b"binary stl".ljust(80, b" ") + struct.pack("<I", 100) + tri * 10 + tri[:20])
    return p


def _index_out_of_range(folder: Path) -> Path:
    p = folder / "bad-index.obj"
    p.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n")
    return p


def _nan_coordinate(folder: Path) -> Path:
    p = folder / "nan-coordinate.obj"
    p.write_text(GOOD_OBJ.replace("v 1 0 0", "v nan 0 0"))
    return p


def _unknown_extension(folder: Path) -> Path:
    p = folder / "mesh.xyz"
    p.write_text(GOOD_OBJ)
    return p


def _nonexistent(folder: Path) -> Path:
    return folder / "does-not-exist.obj"


def _device(folder: Path) -> Path:
    """An endless input: reading it whole would exhaust memory."""
    p = folder / "zero.obj"
    p.symlink_to("/dev/zero")
    return p


INPUT_CASES = {
    "empty-file": _empty,
    "truncated-binary-stl": _truncated_stl,
    "obj-index-out-of-range": _index_out_of_range,
    "obj-nan-coordinate": _nan_coordinate,
    "unknown-input-extension": _unknown_extension,
    "nonexistent-file": _nonexistent,
    "device-file": _device,
}


def _assert_clean_failure(r: helpers.Run, culprit: str, out_dir: Path):
    assert r.returncode != 0, "expected a non-zero exit\n" + r.describe()
    assert r.returncode > 0, f"killed by signal {-r.returncode}\n" + r.describe()
    assert "panicked" not in r.stderr and "panicked" not in r.stdout, "pgvol panicked\n" + r.describe()
    assert r.stderr.strip(), "no error message on stderr\n" + r.describe()
    assert culprit in r.stderr, f"stderr does not name {culprit!r}\n" + r.describe()
    left = sorted(p.name for p in out_dir.iterdir())
    assert not left, f"files left in the output folder: {left}"


@pytest.fixture
def dirs(tmp_path):
    inputs, outputs = tmp_path / "in", tmp_path / "out"
    inputs.mkdir()
    outputs.mkdir()
    return inputs, outputs


@pytest.mark.parametrize("case", list(INPUT_CASES))
def test_bad_input_fails_cleanly(case, dirs, pgvol):
    in_dir, out_dir = dirs
    src = INPUT_CASES[case](in_dir)
    r = helpers.run([pgvol, "remesh", src, "-o", out_dir / "out.glb", "--res", 16], timeout=120)
    _assert_clean_failure(r, src.name, out_dir)


def test_unknown_output_extension_fails_cleanly(dirs, pgvol):
    in_dir, out_dir = dirs
    src = in_dir / "tetra.obj"
    src.write_text(GOOD_OBJ)
    out = out_dir / "out.unknownext"
    r = helpers.run([pgvol, "remesh", src, "-o", out, "--res", 16], timeout=120)
    _assert_clean_failure(r, "unknownext", out_dir)


def test_wrong_flag_fails_cleanly(dirs, pgvol):
    in_dir, out_dir = dirs
    src = in_dir / "tetra.obj"
    src.write_text(GOOD_OBJ)
    r = helpers.run([pgvol, "remesh", src, "-o", out_dir / "out.glb", "--no-such-flag"], timeout=120)
    _assert_clean_failure(r, "--no-such-flag", out_dir)


def test_good_tetrahedron_succeeds(dirs, pgvol):
    """Control for the cases above: the same small input without the defect works."""
    in_dir, out_dir = dirs
    src = in_dir / "tetra.obj"
    src.write_text(GOOD_OBJ)
    helpers.run_ok([pgvol, "remesh", src, "-o", out_dir / "out.glb", "--res", 16], timeout=120)
    assert (out_dir / "out.glb").is_file()


@pytest.mark.parametrize("command", ["compare", "sdf"])
def test_other_commands_name_missing_file(command, dirs, pgvol):
    in_dir, out_dir = dirs
    missing = in_dir / "does-not-exist.obj"
    if command == "compare":
        args = [pgvol, "compare", missing, missing, "--json"]
    else:
        args = [pgvol, "sdf", missing, "-o", out_dir / "grid.nrrd", "--res", 8, "--dense"]
    r = helpers.run(args, timeout=120)
    _assert_clean_failure(r, missing.name, out_dir)


def test_unwritable_standard_output_is_an_error_not_a_panic(dirs, pgvol):
    """A full disk behind standard output: an error and exit code 1, never a panic."""
    in_dir, _ = dirs
    src = in_dir / "tetra.obj"
    src.write_text(GOOD_OBJ)
    with open("/dev/full", "w") as full:
        proc = subprocess.run(
            [str(pgvol), "compare", str(src), str(src), "--samples", "100"],
            stdin=subprocess.DEVNULL,
            stdout=full,
            stderr=subprocess.PIPE,
            text=True,
            timeout=120,
        )
    assert proc.returncode == 1, proc.stderr
    assert "panicked" not in proc.stderr
    assert "standard output" in proc.stderr


def test_closed_pipe_is_an_error_not_a_panic(dirs, pgvol):
    """A reader that goes away (`pgvol compare A B | true`): exit code 1 with a message."""
    in_dir, _ = dirs
    src = in_dir / "tetra.obj"
    src.write_text(GOOD_OBJ)
    import os

    read_end, write_end = os.pipe()
    os.close(read_end)  # the reader is gone before pgvol writes anything
    proc = subprocess.Popen(
        [str(pgvol), "compare", str(src), str(src), "--samples", "100"],
        stdin=subprocess.DEVNULL,
        stdout=write_end,
        stderr=subprocess.PIPE,
    )
    os.close(write_end)
    _, err = proc.communicate(timeout=120)
    err = err.decode(errors="replace")
    assert proc.returncode == 1, err
    assert "panicked" not in err
    assert "standard output" in err


@pytest.fixture
def knot_pgv(tmp_path, pgvol):
    """The bundled torus knot encoded at 48³ with the default band of 4 spacings."""
    out = tmp_path / "knot.pgv"
    helpers.run_ok([pgvol, "encode", helpers.REPO_ROOT / "fixtures" / "torus-knot.obj", "-o", out, "--res", 48])
    return out


def test_decode_refuses_a_level_beyond_the_stored_band(knot_pgv, tmp_path, pgvol):
    info = helpers.run_json([pgvol, "info", knot_pgv, "--json"])
    band = float(info["header"]["metadata"]["band"])
    out = tmp_path / "level.glb"
    r = helpers.run([pgvol, "decode", knot_pgv, "-o", out, "--iso", band], timeout=120)
    assert r.returncode == 1, r.describe()
    assert "--band" in r.stderr and knot_pgv.name in r.stderr, r.describe()
    assert not out.exists()
    # A level well inside the band still decodes.
    helpers.run_ok([pgvol, "decode", knot_pgv, "-o", out, "--iso", band / 4])
    assert out.is_file()


def test_eval_reads_a_byte_order_mark_and_refuses_half_numbers(knot_pgv, tmp_path, pgvol):
    points = tmp_path / "bom.csv"
    points.write_bytes(b"\xef\xbb\xbf0,0,0\n1,0,0\n")
    rows = helpers.run_json([pgvol, "eval", knot_pgv, points, "--json"])["points"]
    assert len(rows) == 2, "the first row behind a byte-order mark was dropped"
    for text in ["0,0,0\n1,2,3a\n", "x,y,z\n3e19,0,0\n", "x,y,z\nnan,0,0\n"]:
        points.write_text(text)
        r = helpers.run([pgvol, "eval", knot_pgv, points], timeout=120)
        assert r.returncode == 1 and "line 2" in r.stderr, r.describe()


def test_eval_flags_values_that_are_not_distances(knot_pgv, tmp_path, pgvol):
    info = helpers.run_json([pgvol, "info", knot_pgv, "--json"])
    g = info["header"]["grid"]
    lo = np.asarray(g["origin"], float)
    hi = lo + g["spacing"] * (np.asarray(g["dims"]) - 1)
    corner = lo + 0.01 * (hi - lo)
    outside_box = hi + 1.0
    points = tmp_path / "points.csv"
    points.write_text("".join(f"{x},{y},{z}\n" for x, y, z in [corner, outside_box]))
    # A corner of the grid cube is far from the knot's tube: beyond the band, so the value is
    # a clamp; beyond the box it is an extrapolation.
    rows = helpers.run_json([pgvol, "eval", knot_pgv, points, "--json"])["points"]
    assert [r["exact"] for r in rows] == [False, False], rows
    # Points on the decoded surface are within the band.
    surface = tmp_path / "k.glb"
    helpers.run_ok([pgvol, "decode", knot_pgv, "-o", surface])
    mesh = helpers.load_output(surface)
    points.write_text("".join(f"{x},{y},{z}\n" for x, y, z in mesh.vertices[:50]))
    rows = helpers.run_json([pgvol, "eval", knot_pgv, points, "--json"])["points"]
    assert all(r["exact"] for r in rows)


def test_repeated_faces_are_dropped_and_reported(dirs, pgvol):
    """A cube whose faces repeat 4,000 times is the cube: the repeats are dropped on reading."""
    in_dir, out_dir = dirs
    corners = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\n"
    faces = "f 1 3 2\nf 1 4 3\nf 5 6 7\nf 5 7 8\nf 1 2 6\nf 1 6 5\nf 2 3 7\nf 2 7 6\nf 3 4 8\nf 3 8 7\nf 4 1 5\nf 4 5 8\n"
    src = in_dir / "repeated.obj"
    src.write_text(corners + faces * 4000)
    out = out_dir / "cube.glb"
    r = helpers.run_ok([pgvol, "remesh", src, "-o", out, "--res", 32], timeout=120)
    assert "47988 repeated triangles" in r.stderr, r.describe()
    mesh = helpers.load_output(out)
    assert mesh.is_watertight
    assert abs(mesh.volume - 1.0) < 0.01, mesh.volume


@pytest.mark.parametrize("reversed_share", ["all", "half"])
def test_reversed_faces_give_the_same_solid(reversed_share, dirs, pgvol):
    """Every face, or every other face, wound the wrong way: the remesh is still the shape."""
    in_dir, out_dir = dirs
    original = helpers.shared_meshes_dir() / "spot.obj"
    lines = original.read_text().splitlines()
    faces_seen = 0
    flipped = []
    for line in lines:
        if line.startswith("f "):
            parts = line.split()
            if reversed_share == "all" or faces_seen % 2 == 0:
                parts = [parts[0], parts[1], parts[3], parts[2], *parts[4:]]
            faces_seen += 1
            line = " ".join(parts)
        flipped.append(line)
    src = in_dir / f"spot-{reversed_share}.obj"
    src.write_text("\n".join(flipped) + "\n")
    out = out_dir / "spot.glb"
    helpers.run_ok([pgvol, "remesh", src, "-o", out, "--res", 64], timeout=120)
    mesh = helpers.load_output(out)
    reference = helpers.load_input(original)
    assert mesh.is_watertight
    assert len(mesh.split(only_watertight=False)) == 1
    assert abs(mesh.volume / reference.volume - 1) < 0.01, (mesh.volume, reference.volume)


def _inside_out_cube(folder: Path) -> Path:
    """A unit cube with every face wound inward."""
    import trimesh

    cube = trimesh.creation.box()
    cube.faces = cube.faces[:, ::-1]
    path = folder / "cube-inside-out.obj"
    cube.export(path)
    return path


@pytest.mark.parametrize(
    "command, args, output",
    [
        ("remesh", ["--res", 32], "out.stl"),
        ("offset", ["--distance", 0.1, "--res", 32], "out.stl"),
        ("shell", ["--thickness", 0.1, "--res", 32], "out.stl"),
        ("slice", ["--layer-height", 0.25, "--res", 32], "out.json"),
    ],
)
def test_every_command_reading_a_mesh_takes_the_sign_method(command, args, output, dirs, pgvol):
    """`--sign` reaches the sampler: on an inside-out cube the default orients the faces first,
    while `pseudonormal` trusts them as given and turns the solid inside out."""
    in_dir, out_dir = dirs
    src = _inside_out_cube(in_dir)
    results = {}
    for sign in ["auto", "winding", "pseudonormal"]:
        out = out_dir / f"{sign}-{output}"
        r = helpers.run([pgvol, command, src, "-o", out, *args, "--sign", sign], timeout=120)
        results[sign] = out.read_bytes() if r.returncode == 0 else r.returncode
        assert r.returncode in (0, 1), r.describe()
    assert results["auto"] != results["pseudonormal"]
    if output.endswith(".stl"):
        solid = helpers.load_output(out_dir / f"auto-{output}")
        assert solid.is_watertight
        low = {"remesh": 0.99, "offset": 1.6, "shell": 0.3}[command]
        high = {"remesh": 1.01, "offset": 1.8, "shell": 0.6}[command]
        assert low < solid.volume < high, solid.volume


def test_csg_takes_the_sign_method_for_its_mesh_operands(dirs, pgvol):
    in_dir, out_dir = dirs
    src = _inside_out_cube(in_dir)
    outputs = {}
    for sign in ["auto", "pseudonormal"]:
        out = out_dir / f"{sign}.stl"
        r = helpers.run([pgvol, "csg", "union", src, "sphere:3,0,0,0.5", "-o", out, "--res", 48, "--sign", sign])
        assert r.returncode in (0, 1), r.describe()
        outputs[sign] = out.read_bytes() if r.returncode == 0 else r.returncode
    assert outputs["auto"] != outputs["pseudonormal"]
    solid = helpers.load_output(out_dir / "auto.stl")
    expected = 1.0 + 4.0 / 3.0 * np.pi * 0.5**3
    assert abs(solid.volume / expected - 1) < 0.03, solid.volume


def test_a_sign_method_for_a_pgv_input_is_refused(dirs, pgvol):
    in_dir, out_dir = dirs
    src = in_dir / "tetra.obj"
    src.write_text(GOOD_OBJ)
    pgv = out_dir / "tetra.pgv"
    helpers.run_ok([pgvol, "encode", src, "-o", pgv, "--res", 24])
    r = helpers.run([pgvol, "offset", pgv, "-o", out_dir / "o.stl", "--distance", 0.01, "--sign", "winding"])
    assert r.returncode == 1 and "mesh inputs" in r.stderr and str(pgv) in r.stderr, r.describe()


def test_a_missing_output_folder_is_named_before_any_work(dirs, pgvol):
    in_dir, out_dir = dirs
    src = in_dir / "tetra.obj"
    src.write_text(GOOD_OBJ)
    target = out_dir / "no-such-folder" / "out.glb"
    r = helpers.run([pgvol, "remesh", src, "-o", target, "--res", 16], timeout=120)
    assert r.returncode == 1, r.describe()
    assert f"{target}: the folder" in r.stderr and ".tmp" not in r.stderr, r.describe()


def test_replaced_outputs_keep_their_mode_and_read_only_ones_need_force(dirs, pgvol):
    import os
    import stat

    in_dir, out_dir = dirs
    src = in_dir / "tetra.obj"
    src.write_text(GOOD_OBJ)
    out = out_dir / "out.glb"
    out.write_bytes(b"old")
    os.chmod(out, 0o600)
    helpers.run_ok([pgvol, "remesh", src, "-o", out, "--res", 16])
    assert stat.S_IMODE(out.stat().st_mode) == 0o600
    os.chmod(out, 0o444)
    _refused_until_forced([pgvol, "remesh", src, "-o", out, "--res", 24], out, "read-only")
    assert stat.S_IMODE(out.stat().st_mode) == 0o444


def _refused_until_forced(command: list, kept: Path, says: str):
    """`command` fails saying `says` and `--force`, leaving `kept` as it was; with `--force` it
    replaces `kept`."""
    before = kept.read_bytes()
    r = helpers.run(command, timeout=120)
    assert r.returncode == 1 and says in r.stderr and "--force" in r.stderr, r.describe()
    assert kept.read_bytes() == before
    helpers.run_ok([*command, "--force"])
    assert kept.read_bytes() != before


def test_an_output_that_is_the_input_needs_force(dirs, pgvol):
    in_dir, _ = dirs
    src = in_dir / "tetra.obj"
    src.write_text(GOOD_OBJ)
    # The same file by another spelling of its path is refused too.
    other = in_dir / "." / "tetra.obj"
    pgv = in_dir / "t.pgv"
    helpers.run_ok([pgvol, "encode", src, "-o", pgv, "--res", 16])
    _refused_until_forced([pgvol, "offset", pgv, "-o", pgv, "--distance", 0.01], pgv, "is also the input")
    _refused_until_forced([pgvol, "remesh", src, "-o", other, "--res", 16], src, "is also the input")


def test_a_level_set_lost_to_speck_removal_says_so(knot_pgv, tmp_path, pgvol):
    """When the speck limit removes every piece, the refusal names the limit rather than
    calling the field empty; with the default limit the same file decodes."""
    out = tmp_path / "o.obj"
    r = helpers.run([pgvol, "decode", knot_pgv, "-o", out, "--min-component", "1e30", "-q"])
    assert r.returncode == 1 and "every piece of the level set" in r.stderr, r.describe()
    assert "1.000e30" in r.stderr and not out.exists(), r.describe()
    helpers.run_ok([pgvol, "decode", knot_pgv, "-o", out, "-q"])


def test_eval_refuses_an_endless_points_file(knot_pgv, tmp_path, pgvol):
    points = tmp_path / "points.csv"
    points.symlink_to("/dev/zero")
    r = helpers.run([pgvol, "eval", knot_pgv, points], timeout=60)
    assert r.returncode == 1 and "not a regular file" in r.stderr, r.describe()


def test_a_terminated_write_leaves_no_temporary_and_keeps_the_old_file(tmp_path, pgvol):
    import signal
    import time

    out = tmp_path / "grid.nrrd"
    out.write_bytes(b"old")
    knot = helpers.REPO_ROOT / "fixtures" / "torus-knot.obj"
    # A banded grid is quick to sample and slow to write (256 MB), so the signal lands mid-write.
    proc = subprocess.Popen(
        [str(pgvol), "sdf", str(knot), "-o", str(out), "--res", "400", "--band", "3", "-q"],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
    )
    deadline = time.monotonic() + 120
    caught = False
    while proc.poll() is None and time.monotonic() < deadline:
        if any(p.name.endswith(".tmp") for p in tmp_path.iterdir()):
            proc.send_signal(signal.SIGTERM)
            caught = True
            break
        time.sleep(0.005)
    proc.communicate(timeout=120)
    if not caught:
        pytest.skip("the write finished before the signal could be sent")
    assert proc.returncode == 130
    assert [p.name for p in tmp_path.iterdir()] == ["grid.nrrd"]
    assert out.read_bytes() == b"old"


def test_specks_are_removed_by_default_and_kept_on_request(tmp_path, pgvol):
    import trimesh

    # A unit tetrahedron and one of side 0.1 (about two grid cells at 64³) far from it.
    lines = []
    for s, at in [(1.0, 0.0), (0.1, 2.0)]:
        for p in [(0, 0, 0), (1, 0, 0), (0, 1, 0), (0, 0, 1)]:
            lines.append("v " + " ".join(str(at + s * c) for c in p))
    for base in (0, 4):
        for f in [(1, 3, 2), (1, 2, 4), (1, 4, 3), (2, 3, 4)]:
            lines.append("f " + " ".join(str(base + i) for i in f))
    src = tmp_path / "speck.obj"
    src.write_text("\n".join(lines) + "\n")
    out = tmp_path / "out.glb"

    default = helpers.run_ok([pgvol, "remesh", src, "-o", out, "--res", 64])
    assert "removed 1 piece" in default.stderr, default.describe()
    assert len(trimesh.load(out, force="mesh").split(only_watertight=False)) == 1
    helpers.run_ok([pgvol, "remesh", src, "-o", out, "--res", 64, "--min-component", 0])
    assert len(trimesh.load(out, force="mesh").split(only_watertight=False)) == 2
    r = helpers.run([pgvol, "remesh", src, "-o", out, "--min-component=-1"])
    assert r.returncode != 0 and "at least 0" in r.stderr, r.describe()


def _flat_sheet(folder: Path) -> Path:
    """A flat square of 8 x 8 cells in z = 0: an open sheet with no thickness."""
    p = folder / "sheet.obj"
    n = 8
    lines = [f"v {i / n} {j / n} 0" for j in range(n + 1) for i in range(n + 1)]
    for j in range(n):
        for i in range(n):
            a = j * (n + 1) + i + 1
            lines += [f"f {a} {a + 1} {a + n + 2}", f"f {a} {a + n + 2} {a + n + 1}"]
    p.write_text("\n".join(lines) + "\n")
    return p


@pytest.mark.parametrize(
    "case",
    ["intersection", "difference", "repair", "encode", "perturb", "slice"],
)
def test_empty_results_are_errors_not_files(case, dirs, pgvol):
    """An operation whose result has nothing inside fails and writes nothing, saying why."""
    inputs, outputs = dirs
    sheet = _flat_sheet(inputs)
    ball = inputs / "ball.pgv"
    if case == "repair":
        helpers.run_ok([pgvol, "csg", "union", "sphere:0,0,0,1", "sphere:0.5,0,0,1", "-o", ball, "--res", 32, "-q"])
    args, reason = {
        "intersection": (["csg", "intersection", "sphere:0,0,0,1", "sphere:3,0,0,1", "-o", outputs / "x.pgv"], "do not overlap"),
        "difference": (["csg", "difference", "sphere:0,0,0,1", "sphere:0,0,0,1", "-o", outputs / "x.pgv"], "cover all of the first"),
        "repair": (["repair", ball, "-o", outputs / "x.pgv", "--mask=-9,-9,-9,9,9,9", "--face", "+z"], "masks around only the parts"),
        "encode": (["encode", sheet, "-o", outputs / "x.pgv", "--res", 32], "all its vertices lie in one plane"),
        "perturb": (["perturb", sheet, "-o", outputs / "x.pgv", "--max-functions", 20, "--resample", 32], "all its vertices lie in one plane"),
        "slice": (["slice", sheet, "-o", outputs / "x.svg", "--layer-height", 0.1, "--res", 32], "no layer holds a contour"),
    }[case]
    r = helpers.run([pgvol, *args, "-q"])
    _assert_clean_failure(r, reason, outputs)
    if case != "slice":
        assert "be empty" in r.stderr or "is empty" in r.stderr, r.describe()


def test_clouds_of_coincident_points_say_so_once(dirs, pgvol):
    inputs, outputs = dirs
    for name, text, says in [
        ("one.xyz", "0 0 0\n", "a single point"),
        ("same.xyz", "0.5 0.5 0.5\n" * 1000, "all 1000 points coincide"),
    ]:
        cloud = inputs / name
        cloud.write_text(text)
        r = helpers.run([pgvol, "points", cloud, "-o", outputs / "x.pgv", "-q"])
        _assert_clean_failure(r, says, outputs)
        assert "at least 10 distinct points" in r.stderr and "bounding box" not in r.stderr, r.describe()
    # A library message that includes its cause's sentence prints that sentence once.
    tetra = inputs / "tetra.obj"
    tetra.write_text(GOOD_OBJ)
    r = helpers.run([pgvol, "encode", tetra, "-o", outputs / "x.pgv", "--voxel", 1e-6, "-q"])
    _assert_clean_failure(r, "cannot make the grid", outputs)
    assert r.stderr.count("more than the limit") == 1, r.describe()
