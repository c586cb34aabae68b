"""Fixtures for the tests of the pgvol Python package.

The meshes come from the shared corpus (`PGVOL_SHARED_MESHES`, or `../shared/meshes` beside
the repository) and the command-line tool from `target/release/pgvol` (`PGVOL_BIN`), as for
the end-to-end checks in tools/checks. A missing prerequisite fails the tests, it never skips
them.
"""

from __future__ import annotations

import os
import subprocess
from pathlib import Path

import numpy as np
import pytest
import trimesh

import pgvol

REPO_ROOT = Path(__file__).resolve().parents[3]


def shared_meshes_dir() -> Path:
    env = os.environ.get("PGVOL_SHARED_MESHES")
    if env:
        return Path(env).resolve()
    return (REPO_ROOT.parent / "shared" / "meshes").resolve()


@pytest.fixture(scope="session")
def mesh_path():
    """mesh_path("spot") -> the path of spot.obj in the shared corpus."""

    def _path(name: str) -> Path:
        path = shared_meshes_dir() / f"{name}.obj"
        if not path.is_file():
            pytest.fail(
                f"shared mesh {name!r} is missing: expected {path} "
                "(set PGVOL_SHARED_MESHES or put the corpus at <repo>/../shared/meshes)"
            )
        return path

    return _path


@pytest.fixture(scope="session")
def spot(mesh_path):
    """The cow 'spot': closed, manifold and consistently oriented (trimesh agrees)."""
    return pgvol.read_mesh(mesh_path("spot"))


@pytest.fixture(scope="session")
def bunny(mesh_path):
    """The Stanford bunny: 69k triangles, open at the bottom."""
    return pgvol.read_mesh(mesh_path("stanford-bunny"))


@pytest.fixture(scope="session")
def spot_field(spot):
    return pgvol.Field.from_mesh(*spot, res=96)


@pytest.fixture(scope="session")
def spot_trimesh(spot):
    mesh = trimesh.Trimesh(vertices=spot[0], faces=spot[1], process=False)
    assert mesh.is_watertight and mesh.is_winding_consistent
    return mesh


@pytest.fixture(scope="session")
def cli() -> Path:
    exe = Path(os.environ.get("PGVOL_BIN") or REPO_ROOT / "target" / "release" / "pgvol")
    if not exe.is_file():
        pytest.fail(f"the pgvol binary is missing at {exe}; build it with `cargo build --release`")
    return exe


@pytest.fixture(scope="session")
def run_cli(cli):
    def _run(*args, timeout: int = 300) -> subprocess.CompletedProcess:
        r = subprocess.run(
            [str(cli), *map(str, args)],
            capture_output=True,
            text=True,
            stdin=subprocess.DEVNULL,
            timeout=timeout,
        )
        if r.returncode != 0:
            pytest.fail(f"pgvol {' '.join(map(str, args))} failed:\n{r.stdout}\n{r.stderr}")
        return r

    return _run


def near_surface_points(mesh, n: int, spread: float, seed: int = 0) -> np.ndarray:
    """Area-uniform points on a trimesh moved along random directions by up to `spread`."""
    rng = np.random.default_rng(seed)
    points, _ = trimesh.sample.sample_surface(mesh, n, seed=seed)
    return points + rng.normal(0.0, spread / 3.0, points.shape)
