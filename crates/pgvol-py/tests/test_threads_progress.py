"""The GIL is released while pgvol works, progress reaches the callback, and the callback or
Ctrl-C stops a long call."""

from __future__ import annotations

import subprocess
import sys
import textwrap
import threading
import time

import numpy as np
import pytest

import pgvol


@pytest.fixture(scope="module")
def bunny_field(bunny):
    return pgvol.Field.from_mesh(*bunny, res=128)


def test_python_threads_run_while_a_call_works(bunny, bunny_field):
    """A pure-Python loop on the main thread keeps running while another thread is inside
    pgvol: with the GIL held it could not run at all during the call."""
    f = bunny_field
    v = bunny[0]
    points = np.random.default_rng(0).uniform(v.min(0), v.max(0), (1_000_000, 3)).astype(np.float32)
    span = {}

    def work():
        span["start"] = time.perf_counter()
        f(points)
        f.eval_with_gradient(points)
        span["end"] = time.perf_counter()

    worker = threading.Thread(target=work)
    ticks = []
    worker.start()
    while worker.is_alive():
        ticks.append(time.perf_counter())
    worker.join()
    start, end = span["start"], span["end"]
    assert end - start > 0.05
    # Ticks all through the middle of the call, not only before and after it.
    middle = [t for t in ticks if start + 0.1 * (end - start) < t < end - 0.1 * (end - start)]
    assert len(middle) > 1000
    gaps = np.diff([start, *middle, end])
    assert gaps.max() < 0.5 * (end - start)


def test_pgvol_calls_in_two_threads_overlap(bunny, bunny_field, mesh_path):
    """While one thread evaluates a million points (on the worker pool), another completes
    whole calls that read a mesh (on its own thread): with the GIL held through a call, no
    call could start, let alone finish, inside the other."""
    f = bunny_field
    v = bunny[0]
    points = np.random.default_rng(1).uniform(v.min(0), v.max(0), (1_000_000, 3)).astype(np.float32)
    spot = mesh_path("spot")
    span = {}
    reads = []

    def evaluate():
        span["start"] = time.perf_counter()
        for _ in range(3):
            f.eval_with_gradient(points)
        span["end"] = time.perf_counter()

    worker = threading.Thread(target=evaluate)
    worker.start()
    while worker.is_alive():
        t0 = time.perf_counter()
        pgvol.read_mesh(spot)
        reads.append((t0, time.perf_counter()))
    worker.join()
    inside = [r for r in reads if span["start"] < r[0] and r[1] < span["end"]]
    assert len(inside) >= 3, (len(reads), span)


def test_encodes_in_two_threads_give_the_fields_of_one(bunny, spot):
    expected = [pgvol.Field.from_mesh(*m, res=96).to_bytes() for m in (bunny, spot)]
    results = {}

    def encode(i, mesh):
        results[i] = pgvol.Field.from_mesh(*mesh, res=96).to_bytes()

    threads = [threading.Thread(target=encode, args=(i, m)) for i, m in enumerate((bunny, spot))]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert [results[0], results[1]] == expected


def test_progress_reports_each_stage_from_0_to_1(spot):
    calls = []
    pgvol.Field.from_mesh(*spot, res=128, progress=lambda s, x: calls.append((s, x)))
    stages = [s for s, x in calls if x == 0.0]
    assert stages == ["distance", "fit"]
    for stage in stages:
        fractions = [x for s, x in calls if s == stage]
        assert fractions[0] == 0.0 and fractions[-1] == 1.0
        assert fractions == sorted(fractions)
    f = pgvol.Field.from_mesh(*spot, res=64)
    contour = []
    f.to_mesh(progress=lambda s, x: contour.append((s, x)))
    assert contour[0] == ("contour", 0.0) and contour[-1] == ("contour", 1.0)
    layers = []
    f.slice(0.1, progress=lambda s, x: layers.append(s))
    assert set(layers) == {"slice"}


def test_slicing_a_file_reports_its_layers_and_stops_when_asked(spot, tmp_path):
    path = tmp_path / "spot.pgv"
    pgvol.Field.from_mesh(*spot, res=64).save(path)
    calls = []
    layers = pgvol.slice_file(path, 0.02, progress=lambda s, x: calls.append((s, x)))
    assert len(layers) > 20
    assert calls[0] == ("slice", 0.0) and calls[-1] == ("slice", 1.0)

    def progress(stage, done):
        if done > 0.0:
            raise Stop("enough")

    with pytest.raises(Stop, match="enough"):
        pgvol.slice_file(path, 0.002, progress=progress)


class Stop(Exception):
    pass


def test_an_exception_in_the_callback_stops_the_call_and_propagates(spot):
    calls = []

    def progress(stage, done):
        calls.append((stage, done))
        if stage == "distance" and done == 1.0:
            raise Stop("enough")

    with pytest.raises(Stop, match="enough"):
        pgvol.Field.from_mesh(*spot, res=64, progress=progress)
    # The fit never started.
    assert calls[-1] == ("distance", 1.0)
    assert all(s == "distance" for s, _ in calls)


def test_ctrl_c_interrupts_a_long_call(mesh_path):
    """SIGINT during a long call without a callback raises KeyboardInterrupt from it, at the
    library's next check, well before the call would have finished."""
    script = textwrap.dedent(
        """
        import os, signal, sys, threading, time
        import pgvol
        # Python's own Ctrl-C handler, also where the process was started with SIGINT
        # ignored (a background job of a shell).
        signal.signal(signal.SIGINT, signal.default_int_handler)
        v, t = pgvol.read_mesh(sys.argv[1])
        t0 = time.perf_counter()
        pgvol.Field.from_mesh(v, t, res=192)
        full = time.perf_counter() - t0
        threading.Timer(0.05, lambda: os.kill(os.getpid(), signal.SIGINT)).start()
        t0 = time.perf_counter()
        try:
            pgvol.Field.from_mesh(v, t, res=192)
        except KeyboardInterrupt:
            print("interrupted", time.perf_counter() - t0, full)
        else:
            print("finished", time.perf_counter() - t0, full)
        """
    )
    r = subprocess.run(
        [sys.executable, "-c", script, str(mesh_path("stanford-bunny"))],
        capture_output=True, text=True, timeout=300,
    )
    assert r.returncode == 0, r.stderr
    word, elapsed, full = r.stdout.split()
    assert word == "interrupted", r.stdout
    assert float(elapsed) < float(full)
