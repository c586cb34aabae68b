"""pgvol.distributed on a LocalCluster of two single-threaded worker processes, against the
single-process calls: the same .pgv bytes, the same triangles, the same layers, whatever the
number of tasks, when a worker is killed mid-run, and within the stated memory per worker."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import threading
import time

import numpy as np
import pytest
import trimesh

import pgvol
from pgvol import distributed

dask_distributed = pytest.importorskip("distributed", reason="dask distributed is required")
from dask.distributed import Client, LocalCluster  # noqa: E402

SHARED = ["stanford-bunny", "spot", "cow", "fandisk", "rocker-arm", "teapot", "suzanne"]

# The correctness target's resolution.
RES = 256

# A worker's peak grows by at most SLACK_FACTOR times the estimate of its largest part plus
# SLACK_BYTES (docs/distributed.md, memory per worker).
SLACK_FACTOR = 1.5
SLACK_BYTES = 64 << 20


def new_cluster() -> LocalCluster:
    return LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                        dashboard_address=":0", silence_logs=40)


@pytest.fixture(scope="module")
def client():
    with new_cluster() as cluster, Client(cluster) as c:
        yield c


def triangle_sets(a: tuple, b: tuple) -> tuple[np.ndarray, np.ndarray]:
    """The triangles of meshes `a` and `b` ((vertices, faces) pairs) as rows of vertex ids
    shared by both (vertices equal to the bit), each rotated to start at its smallest id
    (keeping the orientation) and sorted: equal for equal meshes in any order."""
    bits = [np.ascontiguousarray(v, dtype=np.float32).view(np.uint32).reshape(-1, 3)
            for v, _ in (a, b)]
    _, ids = np.unique(np.concatenate(bits), axis=0, return_inverse=True)
    ids = ids.ravel()
    out = []
    for (_, faces), offset in zip((a, b), (0, len(bits[0]))):
        tri = ids[np.asarray(faces, dtype=np.int64) + offset]
        first = np.argmin(tri, axis=1)
        rows = np.arange(len(tri))[:, None]
        tri = tri[rows, (first[:, None] + np.arange(3)) % 3]
        out.append(tri[np.lexsort(tri.T[::-1])])
    return out[0], out[1]


def reset_peak() -> int:
    """Resets this process's peak resident size to its current size (Linux: writing 5 to
    clear_refs), and returns that size in bytes."""
    with open("/proc/self/clear_refs", "w") as f:
        f.write("5")
    return peak_rss()


def peak_rss() -> int:
    """This process's peak resident size since the last reset, in bytes."""
    with open("/proc/self/status") as f:
        for line in f:
            if line.startswith("VmHWM:"):
                return int(line.split()[1]) * 1024
    raise AssertionError("no VmHWM in /proc/self/status")


def boundary_edges(vertices: np.ndarray, faces: np.ndarray) -> int:
    mesh = trimesh.Trimesh(vertices, faces, process=False)
    return len(trimesh.grouping.group_rows(mesh.edges_sorted, require_count=1))


@pytest.mark.parametrize("name", SHARED)
def test_encode_in_tasks_gives_the_single_process_file(client, mesh_path, name):
    mesh = pgvol.read_mesh(mesh_path(name))
    want = pgvol.Field.from_mesh(*mesh, res=RES).to_bytes()
    assert distributed.encode(mesh, res=RES, client=client, parts=8).to_bytes() == want
    if name == "stanford-bunny":
        # Two tasks, and one in this process: the same code path without a cluster. (On the
        # other meshes too in `tests/tests/distributed_parts.rs`, in Rust, at lower grids.)
        assert distributed.encode(mesh, res=RES, client=client, parts=2).to_bytes() == want
        assert distributed.encode(mesh, res=RES).to_bytes() == want


def test_a_file_written_as_parts_arrive_is_the_single_process_file(client, mesh_path, tmp_path):
    mesh = pgvol.read_mesh(mesh_path("stanford-bunny"))
    want = pgvol.Field.from_mesh(*mesh, res=RES).to_bytes()
    out = tmp_path / "bunny.pgv"
    for parts, where in [(8, client), (2, None)]:
        out.write_bytes(b"before")
        grid = distributed.encode_file(mesh, out, res=RES, client=where, parts=parts)
        assert out.read_bytes() == want, parts
        assert grid == pgvol.Field.from_bytes(want).grid
    # A mesh that fails in the parts leaves the file as it was.
    out.write_bytes(b"before")
    with pytest.raises(pgvol.ParameterError, match="pseudo-Gaussian"):
        distributed.encode_file(mesh, out, res=RES, basis="pg")
    assert out.read_bytes() == b"before"


def test_sharp_feature_vertices_in_parts_are_the_single_process_ones(client, mesh_path,
                                                                      tmp_path):
    mesh = pgvol.read_mesh(mesh_path("fandisk"))
    want = pgvol.Field.from_mesh(*mesh, res=RES, sharp="auto", sharp_angle=25).to_bytes()
    assert want != pgvol.Field.from_mesh(*mesh, res=RES).to_bytes()
    got = distributed.encode(mesh, res=RES, sharp="auto", sharp_angle=25, client=client,
                             parts=8)
    assert got.to_bytes() == want
    out = tmp_path / "fandisk.pgv"
    distributed.encode_file(mesh, out, res=RES, sharp="auto", sharp_angle=25, client=client,
                            parts=8)
    assert out.read_bytes() == want


def test_an_exception_in_the_parts_stops_the_write(mesh_path, tmp_path):
    from pgvol import _pgvol

    vertices, faces = pgvol.read_mesh(mesh_path("spot"))
    job = _pgvol.EncodeJob(vertices, faces, res=80)
    plan = _pgvol.plan_encode(vertices, faces, 2, res=80)

    def parts():
        yield job.encode_part(*plan[0][:4])
        raise KeyError("lost the second part")

    out = tmp_path / "spot.pgv"
    out.write_bytes(b"before")
    with pytest.raises(KeyError, match="lost the second part"):
        _pgvol.write_encode_parts(vertices, faces, parts(), out, res=80)
    assert out.read_bytes() == b"before"
    outcome, grid = _pgvol.write_encode_parts(
        vertices, faces, (job.encode_part(*p[:4]) for p in plan), out, res=80)
    assert outcome == "written"
    assert out.read_bytes() == pgvol.Field.from_mesh(vertices, faces, res=80).to_bytes()


def test_a_part_plan_really_splits(mesh_path):
    mesh = pgvol.read_mesh(mesh_path("spot"))
    plan = distributed.plan_encode(mesh, parts=8, res=RES)
    assert len(plan) == 8
    assert len({p["z"] for p in plan}) == 4 and len({p["y"] for p in plan}) == 2


def vertex_rows(vertices: np.ndarray, normals: np.ndarray) -> np.ndarray:
    """Each vertex's position and normal as the bits of six float32s, rows sorted: equal for
    meshes whose vertices carry the same normals, in any order."""
    rows = np.hstack([np.asarray(vertices, dtype=np.float32),
                      np.asarray(normals, dtype=np.float32)]).view(np.uint32)
    return rows[np.lexsort(rows.T[::-1])]


@pytest.mark.parametrize("name", ["stanford-bunny", "fandisk"])
def test_decode_in_tasks_gives_the_single_process_triangles_welded(client, mesh_path, name):
    field = pgvol.Field.from_mesh(*pgvol.read_mesh(mesh_path(name)), res=RES)
    v, f, n = field.to_mesh(method="mc", normals=True)
    for parts in (1, 2, 8):
        dv, df, dn = distributed.decode(field, client=None if parts == 1 else client,
                                        parts=parts, normals=True)
        assert len(dv) == len(v) and len(df) == len(f), parts
        got, want = triangle_sets((dv, df), (v, f))
        assert np.array_equal(got, want), parts
        # Each vertex carries the normal the single process gives it, seams included.
        assert np.array_equal(vertex_rows(dv, dn), vertex_rows(v, n)), parts
        assert boundary_edges(dv, df) == 0, parts
        assert trimesh.Trimesh(dv, df, process=False).is_watertight, parts
    assert len(distributed.decode(field, parts=2)) == 2


def test_decode_of_a_file_in_tasks_reads_its_slabs_and_gives_its_triangles(
        client, mesh_path, tmp_path):
    from pgvol import _pgvol

    path = tmp_path / "fandisk.pgv"
    pgvol.Field.from_mesh(*pgvol.read_mesh(mesh_path("fandisk")), res=RES).save(path)
    field = pgvol.Field.load(path)
    v, f = field.to_mesh(method="mc")
    plan, spacing = _pgvol.plan_decode_file(path, 4)
    assert plan == _pgvol.plan_decode(field, 4) and spacing == field.grid.spacing
    triangles = 0
    for s, e in plan:
        part = _pgvol.decode_file_part_bricks(path, s, e)
        assert len(part) < path.stat().st_size
        got = _pgvol.decode_file_part(part, s, e)
        want = _pgvol.decode_part(_pgvol.decode_part_bricks(field, s, e), s, e)
        assert len(got[1]) == len(want[1])
        a, b = triangle_sets(got[:2], want[:2])
        assert np.array_equal(a, b), (s, e)
        assert np.array_equal(vertex_rows(got[0], got[2]), vertex_rows(want[0], want[2]))
        triangles += len(got[1])
    assert triangles >= len(f)
    for parts in (1, 3):
        dv, df = distributed.decode(path, client=None if parts == 1 else client, parts=parts)
        got, want = triangle_sets((dv, df), (v, f))
        assert np.array_equal(got, want), parts
        assert trimesh.Trimesh(dv, df, process=False).is_watertight, parts
    with pytest.raises(pgvol.InputFileError):
        _pgvol.decode_file_part(b"not a part", 0, 1)


def test_slice_in_tasks_gives_the_single_process_layers(client, mesh_path, tmp_path):
    field = pgvol.Field.from_mesh(*pgvol.read_mesh(mesh_path("stanford-bunny")), res=RES)
    path = tmp_path / "bunny.pgv"
    field.save(path)
    h = 2.7 * field.grid.spacing
    want = pgvol.Field.load(path).slice(h)
    for parts in (1, 3, 8):
        got = distributed.slice(path, h, client=None if parts == 1 else client, parts=parts)
        assert [l.height for l in got] == [l.height for l in want], parts
        for a, b in zip(got, want):
            assert a.holes == b.holes
            assert all(np.array_equal(x, y) for x, y in zip(a.loops, b.loops))


def test_slice_parts_of_a_file_carry_its_own_bricks_and_give_its_layers(mesh_path, tmp_path):
    from pgvol import _pgvol

    path = tmp_path / "spot.pgv"
    pgvol.Field.from_mesh(*pgvol.read_mesh(mesh_path("spot")), res=96).save(path)
    field = pgvol.Field.load(path)
    h = 1.5 * field.grid.spacing
    for axis in ("z", "x"):
        plan = _pgvol.plan_slice_file(path, 5, h, axis=axis)
        assert plan == _pgvol.plan_slice(field, 5, h, axis=axis) and len(plan) == 5
        want = field.slice(h, axis=axis)
        got = []
        for s, e in plan:
            part = _pgvol.slice_file_part_bricks(path, s, e, h, axis=axis)
            # The file's compressed bricks of a few slabs: less than the file, and less than
            # the coefficients (compressed as f32) the loaded field's parts get.
            assert len(part) < path.stat().st_size
            assert 3 * len(part) < 2 * len(_pgvol.slice_part_bricks(field, s, e, h, axis=axis))
            got += _pgvol.slice_file_part(part, s, e, h, axis=axis)
        assert [l.height for l in got] == [l.height for l in want]
        for a, b in zip(got, want):
            assert a.holes == b.holes
            assert all(np.array_equal(x, y) for x, y in zip(a.loops, b.loops, strict=True))
    # A dense file is not read by slabs: its parts come from the loaded field, alike.
    dense = tmp_path / "dense.pgv"
    field.save(dense, dense=True)
    assert _pgvol.plan_slice_file(dense, 3, h) is None
    want = field.slice(h)
    for source in (field, path, dense):
        got = distributed.slice(source, h, parts=3)
        assert [l.height for l in got] == [l.height for l in want]
        for a, b in zip(got, want):
            assert a.holes == b.holes
            assert all(np.array_equal(x, y) for x, y in zip(a.loops, b.loops, strict=True))
    with pytest.raises(pgvol.ParameterError, match="not among"):
        _pgvol.slice_file_part_bricks(path, 10**6, 10**6 + 1, h)
    with pytest.raises(pgvol.InputFileError):
        _pgvol.slice_file_part(b"not a part", 0, 1, h)
    cut = tmp_path / "cut.pgv"
    cut.write_bytes(path.read_bytes()[:1000])
    with pytest.raises(pgvol.InputFileError, match="cut.pgv"):
        distributed.slice(cut, h, parts=2)


def test_slice_in_tasks_keeps_the_corners_of_a_sharp_file(client, run_cli, tmp_path):
    box = trimesh.creation.box(extents=[1.0, 1.0, 1.2])
    box.apply_transform(trimesh.transformations.rotation_matrix(0.5, [0, 0, 1]))
    box.export(tmp_path / "box.obj")
    path = tmp_path / "box.pgv"
    run_cli("encode", tmp_path / "box.obj", "-o", path, "--res", 64, "--sharp", "auto", "-q")
    field = pgvol.Field.load(path)
    h = field.grid.spacing
    want = field.slice(h)
    got = distributed.slice(path, h, client=client, parts=3)
    assert len(got) == len(want)
    for a, b in zip(got, want):
        assert a.height == b.height and a.holes == b.holes
        assert all(np.array_equal(x, y) for x, y in zip(a.loops, b.loops))
    # The corners come from the file's section: the parts' own layers are the smooth field's.
    from pgvol import _pgvol

    smooth = [layer for s, e in _pgvol.plan_slice(field, 3, h)
              for layer in _pgvol.slice_part(_pgvol.slice_part_bricks(field, s, e, h),
                                             field.bounds, s, e, h)]
    assert any(len(x) != len(y) or not np.array_equal(x, y)
               for a, b in zip(smooth, want) for x, y in zip(a.loops, b.loops))


def test_a_worker_killed_mid_run_changes_nothing(mesh_path):
    mesh = pgvol.read_mesh(mesh_path("stanford-bunny"))
    want = pgvol.Field.from_mesh(*mesh, res=RES).to_bytes()
    with new_cluster() as cluster, Client(cluster) as c:
        pids = c.run(os.getpid)
        out: dict = {}

        def run():
            try:
                out["field"] = distributed.encode(mesh, res=RES, client=c, parts=16)
            except BaseException as e:  # reported below
                out["error"] = e

        worker = threading.Thread(target=run)
        worker.start()

        def finished_parts(dask_scheduler=None):
            return sum(1 for k, ts in dask_scheduler.tasks.items()
                       if str(k).startswith("pgvol-encode") and ts.state == "memory")

        deadline = time.monotonic() + 120
        while c.run_on_scheduler(finished_parts) < 2 and worker.is_alive():
            assert time.monotonic() < deadline, "no part finished"
            time.sleep(0.02)
        # Kill the worker that holds results, so they and its running task are lost.
        victim = sorted(pids.items())[0][1]
        os.kill(victim, signal.SIGKILL)
        killed_mid_run = worker.is_alive()
        worker.join(timeout=300)
        assert "error" not in out, out.get("error")
        assert killed_mid_run, "the encode finished before the kill; use more parts"
        assert out["field"].to_bytes() == want
        assert victim not in c.run(os.getpid).values()


def test_worker_memory_stays_within_the_stated_bound(mesh_path):
    """The growth of each worker's peak resident memory over the encode is at most the
    estimate of its largest part with the slack docs/distributed.md states (the allocator's
    per-thread arenas and Dask's buffers), and that estimate falls as the parts get
    smaller."""
    mesh = pgvol.read_mesh(mesh_path("stanford-bunny"))
    res, parts = 384, 16
    plan = distributed.plan_encode(mesh, parts=parts, res=res)
    bound = max(p["bytes"] for p in plan)
    two = max(p["bytes"] for p in distributed.plan_encode(mesh, parts=2, res=res))
    assert bound < 0.6 * two
    with new_cluster() as cluster, Client(cluster) as c:
        c.run(lambda: __import__("pgvol.distributed"))
        before = c.run(reset_peak)
        distributed.encode(mesh, res=res, client=c, parts=parts)
        after = c.run(peak_rss)
    for worker, rss in before.items():
        growth = after[worker] - rss
        assert growth <= SLACK_FACTOR * bound + SLACK_BYTES, (worker, growth, bound)


def test_command_line_front_end_writes_the_single_process_file(mesh_path, tmp_path):
    out = tmp_path / "spot.pgv"
    r = subprocess.run(
        [sys.executable, "-m", "pgvol.distributed", "encode", str(mesh_path("spot")),
         "-o", str(out), "--res", "96", "--local", "2", "--json"],
        capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    assert '"workers": 2' in r.stdout
    want = pgvol.Field.from_mesh(*pgvol.read_mesh(mesh_path("spot")), res=96).to_bytes()
    assert out.read_bytes() == want
    sharp = subprocess.run(
        [sys.executable, "-m", "pgvol.distributed", "encode", str(mesh_path("fandisk")),
         "-o", str(out), "--res", "96", "--sharp", "auto", "--sharp-angle", "25", "--local", "1"],
        capture_output=True, text=True, timeout=300)
    assert sharp.returncode == 0, sharp.stderr
    want = pgvol.Field.from_mesh(*pgvol.read_mesh(mesh_path("fandisk")), res=96, sharp="auto",
                                 sharp_angle=25).to_bytes()
    assert out.read_bytes() == want
    bad = subprocess.run(
        [sys.executable, "-m", "pgvol.distributed", "encode", str(tmp_path / "none.obj"),
         "-o", str(out), "--res", "96"], capture_output=True, text=True, timeout=300)
    assert bad.returncode == 1 and "none.obj" in bad.stderr


def test_command_line_decode_writes_the_vertices_and_normals_of_pgvol_decode(
        mesh_path, run_cli, tmp_path):
    pgv = tmp_path / "fandisk.pgv"
    run_cli("encode", mesh_path("fandisk"), "-o", pgv, "--res", 96, "-q")
    single, parted = tmp_path / "single.ply", tmp_path / "parted.ply"
    run_cli("decode", pgv, "-o", single, "-q")
    r = subprocess.run(
        [sys.executable, "-m", "pgvol.distributed", "decode", str(pgv), "-o", str(parted),
         "--parts", "3", "--local", "1"], capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    a, b = (trimesh.load(p, process=False) for p in (single, parted))
    assert "vertex_normals" in b._cache.cache, "the PLY holds no normals"
    assert len(a.faces) == len(b.faces) and len(a.vertices) == len(b.vertices)
    assert np.array_equal(vertex_rows(b.vertices, b.vertex_normals),
                          vertex_rows(a.vertices, a.vertex_normals))


def test_options_that_cannot_be_split_are_refused(mesh_path, spot_field):
    mesh = pgvol.read_mesh(mesh_path("spot"))
    with pytest.raises(pgvol.ParameterError, match="pseudo-Gaussian"):
        distributed.encode(mesh, res=64, basis="pg")
    with pytest.raises(ValueError, match="at least 1"):
        distributed.encode(mesh, res=64, parts=0)


def test_an_encoded_part_pickles_whole():
    import pickle

    from pgvol import _pgvol

    sphere = trimesh.creation.icosphere(subdivisions=3)
    job = _pgvol.EncodeJob(sphere.vertices, sphere.faces, res=32)
    part = job.encode_part(0, 1, 0, 1)
    back = pickle.loads(pickle.dumps(part))
    assert isinstance(back, _pgvol.EncodedPart)
    assert len(part.bricks) > 0 and back.bricks == part.bricks
    assert back.exact_nodes == part.exact_nodes > 0
