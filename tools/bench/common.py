"""Shared pieces of the pgvol benchmarks: paths, mesh loading, the grid convention."""

from __future__ import annotations

import json
import os
import subprocess
import time
from pathlib import Path

import numpy as np

REPO_ROOT = Path(__file__).resolve().parents[2]
# The Python with Debian's python3-openvdb module, which the benchmark venvs do not have.
SYSTEM_PYTHON = os.environ.get("PGVOL_BENCH_SYSTEM_PYTHON", "/usr/bin/python3")


def pgvol_bin() -> Path:
    return Path(os.environ.get("PGVOL_BIN") or REPO_ROOT / "target" / "release" / "pgvol").resolve()


def meshes_dir() -> Path:
    env = os.environ.get("PGVOL_SHARED_MESHES")
    return Path(env).resolve() if env else (REPO_ROOT.parent / "shared" / "meshes").resolve()


def mesh_file(name: str) -> Path:
    path = meshes_dir() / f"{name}.obj"
    if not path.is_file():
        raise SystemExit(f"missing mesh {name!r}: expected {path} (set PGVOL_SHARED_MESHES)")
    return path


# "NAME-1m" is the shared mesh NAME split at its edge midpoints until it has this many triangles
# or more (the rocker arm's 20,088 become 1,285,632).
SUBDIVIDED_SUFFIX = "-1m"
SUBDIVIDED_TRIANGLES = 1_000_000


def subdivide(vertices, faces, target: int = SUBDIVIDED_TRIANGLES):
    """Splits every triangle into four at its edge midpoints (trimesh) until there are at least
    target triangles."""
    import trimesh

    while len(faces) < target:
        vertices, faces = trimesh.remesh.subdivide(vertices, faces)
    return vertices, faces


def source_mesh(name: str, work: Path) -> Path:
    """A shared mesh by name, or one derived from it and written into work as OBJ:
    "bunny-capped" is the Stanford bunny with its holes closed (tools/meshcap.py), since OpenVDB's
    flood-fill sign needs a closed surface; "NAME-1m" is NAME subdivided (subdivide above)."""
    if name != "bunny-capped" and not name.endswith(SUBDIVIDED_SUFFIX):
        return mesh_file(name)
    import sys

    sys.path.insert(0, str(REPO_ROOT / "tools"))
    import meshcap
    from objfile import read_obj

    path = Path(work) / f"{name}.obj"
    if name == "bunny-capped":
        meshcap.write_obj(path, *meshcap.cap_holes(*read_obj(mesh_file("stanford-bunny"))))
    else:
        meshcap.write_obj(path, *subdivide(*read_obj(mesh_file(name[: -len(SUBDIVIDED_SUFFIX)]))))
    return path


def load_mesh(path: Path):
    """Positions and triangles only (vertices with equal positions merged), via trimesh."""
    import trimesh

    path = Path(path)
    if path.suffix.lower() == ".obj":
        with open(path, "rb") as fh:
            loaded = trimesh.exchange.obj.load_obj(fh, skip_materials=True)
        parts = list(loaded["geometry"].values()) if "geometry" in loaded else [loaded]
        verts, faces, offset = [], [], 0
        for part in parts:
            v = np.asarray(part["vertices"], dtype=np.float64).reshape(-1, 3)
            verts.append(v)
            faces.append(np.asarray(part["faces"], dtype=np.int64).reshape(-1, 3) + offset)
            offset += len(v)
        v, f = np.vstack(verts), np.vstack(faces)
    else:
        m = trimesh.load(str(path), force="mesh")
        v, f = m.vertices, m.faces
    return trimesh.Trimesh(vertices=np.asarray(v, np.float64), faces=np.asarray(f, np.int64), process=True)


class Grid:
    """The project grid: a cube of side 1.1 x the longest bbox extent, centred on the bbox,
    n nodes per axis, spacing side/(n-1), node (i,j,k) at origin + h*(i,j,k)."""

    def __init__(self, bounds, n: int):
        lo, hi = np.asarray(bounds[0], np.float64), np.asarray(bounds[1], np.float64)
        self.n = int(n)
        self.side = 1.1 * float(np.max(hi - lo))
        self.h = self.side / (self.n - 1)
        self.origin = 0.5 * (lo + hi) - 0.5 * self.side

    @property
    def count(self) -> int:
        return self.n**3

    def points(self) -> np.ndarray:
        """All nodes, x fastest: row i + n*(j + n*k) is node (i, j, k)."""
        ax = np.arange(self.n, dtype=np.float64) * self.h
        z, y, x = np.meshgrid(ax, ax, ax, indexing="ij")
        pts = np.stack([x.ravel(), y.ravel(), z.ravel()], axis=1)
        return pts + self.origin


def run(args, timeout: int = 3600) -> tuple[subprocess.CompletedProcess, float]:
    argv = [str(a) for a in args]
    start = time.perf_counter()
    proc = subprocess.run(argv, stdin=subprocess.DEVNULL, capture_output=True, text=True, timeout=timeout)
    return proc, time.perf_counter() - start


def run_json(args, timeout: int = 3600) -> tuple[dict, float]:
    proc, wall = run(args, timeout)
    if proc.returncode != 0:
        raise RuntimeError(f"{' '.join(map(str, args[:2]))} exited {proc.returncode}: {proc.stderr.strip()[-400:]}")
    return json.loads(proc.stdout), wall


def read_grid_x_fastest(path: Path, n: int) -> np.ndarray:
    """Read a pgvol grid file (NRRD or NPY) as a flat float32 array, x fastest."""
    path = Path(path)
    if path.suffix == ".npy":
        arr = np.load(path)
        # Shape (n, n, n) in C order indexed [k, j, i] keeps x fastest.
        return np.asarray(arr, dtype=np.float32).reshape(-1)
    import nrrd

    data, _ = nrrd.read(str(path))  # Fortran order: data[i, j, k], i = x
    if data.shape != (n, n, n):
        raise RuntimeError(f"grid shape {data.shape}, expected {(n, n, n)}")
    return np.asarray(data, dtype=np.float32).ravel(order="F")


def short_reason(exc: BaseException) -> str:
    text = f"{type(exc).__name__}: {exc}".strip().replace("\n", " ")
    return text if len(text) <= 160 else text[:157] + "..."


def markdown_table(header: list[str], rows: list[list[object]]) -> str:
    def fmt(v):
        if isinstance(v, float):
            return f"{v:.4g}"
        return str(v)

    lines = ["| " + " | ".join(header) + " |", "|" + "|".join("---" for _ in header) + "|"]
    lines += ["| " + " | ".join(fmt(v) for v in row) + " |" for row in rows]
    return "\n".join(lines)
