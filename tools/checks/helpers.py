"""Shared helpers for the pgvol end-to-end checks.

Everything here is independent of pgvol's own code: meshes are read and measured
with trimesh / manifold3d so the checks act as an outside reference.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Sequence

import numpy as np
import pytest
import trimesh

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
import meshcap  # noqa: E402

REPO_ROOT = Path(__file__).resolve().parents[2]
# PGVOL_BIN may point the checks at another build of the binary.
PGVOL_BIN = Path(os.environ.get("PGVOL_BIN") or REPO_ROOT / "target" / "release" / "pgvol").resolve()
VALIDATOR = REPO_ROOT / "tools" / "validate_gltf.mjs"

# Meshes of the shared corpus remeshed by the checks, and the whole corpus.
REMESH_MESHES = ["stanford-bunny", "spot", "fandisk", "rocker-arm", "teapot", "suzanne"]
ALL_MESHES = REMESH_MESHES + ["cow"]
# Of REMESH_MESHES, the ones that are closed (watertight after merging equal vertices).
EXPECTED_CLOSED = {"spot", "fandisk", "rocker-arm"}

OUTPUT_FORMATS = [".glb", ".gltf", ".obj", ".stl", ".ply"]

# Generous per-command limit: a hung binary must not hang the whole suite.
COMMAND_TIMEOUT = int(os.environ.get("PGVOL_CHECK_TIMEOUT", "900"))


def shared_meshes_dir() -> Path:
    env = os.environ.get("PGVOL_SHARED_MESHES")
    if env:
        return Path(env).resolve()
    return (REPO_ROOT.parent / "shared" / "meshes").resolve()


def _tail(text: str, limit: int = 3000) -> str:
    text = text or ""
    return text if len(text) <= limit else "...\n" + text[-limit:]


@dataclass
class Run:
    args: list[str]
    returncode: int
    stdout: str
    stderr: str
    seconds: float

    def describe(self) -> str:
        return (
            f"command: {' '.join(self.args)}\n"
            f"exit code: {self.returncode}\n"
            f"--- stdout ---\n{_tail(self.stdout)}\n--- stderr ---\n{_tail(self.stderr)}"
        )


def run(args: Sequence[object], timeout: int = COMMAND_TIMEOUT, cwd: Path | None = None) -> Run:
    """Run a command with no stdin, capturing text output; a timeout fails the test."""
    argv = [str(a) for a in args]
    start = time.perf_counter()
    try:
        proc = subprocess.run(
            argv,
            stdin=subprocess.DEVNULL,
            capture_output=True,
            text=True,
            errors="replace",
            timeout=timeout,
            cwd=cwd,
        )
    except subprocess.TimeoutExpired as exc:
        pytest.fail(f"command timed out after {timeout} s: {' '.join(argv)}\n{_tail(str(exc.stderr or ''))}")
    return Run(argv, proc.returncode, proc.stdout, proc.stderr, time.perf_counter() - start)


def run_ok(args: Sequence[object], timeout: int = COMMAND_TIMEOUT) -> Run:
    r = run(args, timeout=timeout)
    if r.returncode != 0:
        pytest.fail("command failed\n" + r.describe())
    return r


def run_json(args: Sequence[object], timeout: int = COMMAND_TIMEOUT) -> dict:
    r = run_ok(args, timeout=timeout)
    try:
        value = json.loads(r.stdout)
    except json.JSONDecodeError as exc:
        pytest.fail(f"stdout is not one JSON object ({exc})\n" + r.describe())
    if not isinstance(value, dict):
        pytest.fail("stdout JSON is not an object\n" + r.describe())
    return value


# ---------------------------------------------------------------------------
# Loading meshes
# ---------------------------------------------------------------------------


def _positions_only(vertices, faces) -> trimesh.Trimesh:
    """A Trimesh with just positions and triangles, vertices merged by trimesh's default rules."""
    vertices = np.asarray(vertices, dtype=np.float64).reshape(-1, 3)
    faces = np.asarray(faces, dtype=np.int64).reshape(-1, 3)
    return trimesh.Trimesh(vertices=vertices, faces=faces, process=True)


def _load_obj_positions(path: Path) -> trimesh.Trimesh:
    # Read only geometry: materials / texture coordinates would split vertices
    # along UV seams and need an image library we do not want.
    with open(path, "rb") as fh:
        loaded = trimesh.exchange.obj.load_obj(fh, skip_materials=True)
    parts = list(loaded["geometry"].values()) if "geometry" in loaded else [loaded]
    verts, faces, offset = [], [], 0
    for part in parts:
        v = np.asarray(part["vertices"], dtype=np.float64).reshape(-1, 3)
        f = np.asarray(part["faces"], dtype=np.int64).reshape(-1, 3)
        verts.append(v)
        faces.append(f + offset)
        offset += len(v)
    if not verts:
        raise ValueError(f"{path}: no geometry")
    return _positions_only(np.vstack(verts), np.vstack(faces))


def load_input(path: Path) -> trimesh.Trimesh:
    """Load a reference (input) mesh, keeping only positions and triangles."""
    path = Path(path)
    if not path.is_file():
        pytest.fail(f"input mesh is missing: {path}")
    if path.suffix.lower() == ".obj":
        return _load_obj_positions(path)
    mesh = trimesh.load(str(path), force="mesh")
    return _positions_only(mesh.vertices, mesh.faces)


def load_output(path: Path) -> trimesh.Trimesh:
    """Load a file written by pgvol with trimesh.load(..., force='mesh')."""
    path = Path(path)
    if not path.is_file():
        pytest.fail(f"pgvol reported success but wrote no file at {path}")
    try:
        mesh = trimesh.load(str(path), force="mesh")
    except Exception as exc:  # noqa: BLE001 - any loader error is a failed check
        pytest.fail(f"trimesh cannot load {path.name}: {type(exc).__name__}: {exc}")
    if not isinstance(mesh, trimesh.Trimesh) or len(mesh.faces) == 0:
        pytest.fail(f"{path.name}: trimesh found no triangles (got {type(mesh).__name__})")
    return _positions_only(mesh.vertices, mesh.faces)


# ---------------------------------------------------------------------------
# Measures
# ---------------------------------------------------------------------------


def manifold_mesh(mesh: trimesh.Trimesh):
    import manifold3d

    return manifold3d.Mesh(
        vert_properties=np.ascontiguousarray(mesh.vertices, dtype=np.float32),
        tri_verts=np.ascontiguousarray(mesh.faces, dtype=np.uint32),
    )


def manifold_status(mesh: trimesh.Trimesh):
    import manifold3d

    return manifold3d.Manifold(manifold_mesh(mesh)).status()


def manifold_ok(status) -> bool:
    import manifold3d

    return status == manifold3d.Error.NoError


def edge_counts(mesh: trimesh.Trimesh) -> dict:
    """Undirected edge statistics after trimesh's vertex merge."""
    edges = mesh.edges_sorted
    _, counts = np.unique(edges, axis=0, return_counts=True)
    boundary = trimesh.grouping.group_rows(edges, require_count=1)
    return {
        "edges": int(len(counts)),
        "boundary_edges": int(len(boundary)),
        "non_manifold_edges": int(np.count_nonzero(counts > 2)),
    }


def signed_volume(mesh: trimesh.Trimesh) -> float:
    """Sum of the signed volumes of the tetrahedra (origin, triangle): the divergence-theorem
    volume. Equals trimesh's `volume` for closed meshes; for open ones trimesh reports
    something else, while this stays the plain sum (relative to the coordinate origin)."""
    tri = np.asarray(mesh.triangles, dtype=np.float64)
    return float(np.einsum("ij,ij->i", tri[:, 0], np.cross(tri[:, 1], tri[:, 2])).sum() / 6.0)


def bbox_diagonal(mesh: trimesh.Trimesh) -> float:
    lo, hi = mesh.bounds
    return float(np.linalg.norm(hi - lo))


def one_sided_mean(src: trimesh.Trimesh, dst: trimesh.Trimesh, count: int, seed: int) -> float:
    """Mean distance from `count` area-uniform samples on src to the surface of dst."""
    points, _ = trimesh.sample.sample_surface(src, count, seed=seed)
    _, dist, _ = trimesh.proximity.closest_point(dst, points)
    return float(np.mean(dist))


def chamfer_l1(a: trimesh.Trimesh, b: trimesh.Trimesh, count: int, seed: int = 12345) -> tuple[float, float, float]:
    """(mean a->b, mean b->a, Chamfer-L1 = mean of the two)."""
    ab = one_sided_mean(a, b, count, seed)
    ba = one_sided_mean(b, a, count, seed + 1)
    return ab, ba, 0.5 * (ab + ba)


def rel_diff(value: float, reference: float) -> float:
    value, reference = float(value), float(reference)
    if reference == 0.0:
        return abs(value)
    return abs(value - reference) / abs(reference)



def cap_holes(mesh: trimesh.Trimesh) -> trimesh.Trimesh:
    """The mesh with each hole closed by a flat cap (see tools/meshcap.py)."""
    vertices, faces = meshcap.cap_holes(mesh.vertices, mesh.faces)
    return trimesh.Trimesh(vertices, faces, process=False)
