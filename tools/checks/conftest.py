"""Fixtures for the pgvol end-to-end checks.

Missing prerequisites (the release binary, the shared mesh corpus, a mesh of it)
make the checks FAIL with a message saying what is missing; they never skip.
"""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

import helpers


@pytest.fixture(scope="session")
def repo_root() -> Path:
    return helpers.REPO_ROOT


@pytest.fixture(scope="session")
def pgvol() -> Path:
    exe = helpers.PGVOL_BIN
    if not exe.is_file():
        pytest.fail(
            f"the pgvol binary is missing at {exe}; "
            "build it with `cargo build --release` (tools/test.sh does this)"
        )
    return exe


@pytest.fixture(scope="session")
def shared_meshes() -> Path:
    folder = helpers.shared_meshes_dir()
    if not folder.is_dir():
        pytest.fail(
            f"the shared mesh folder is missing: {folder} "
            "(set PGVOL_SHARED_MESHES or put the corpus at <repo>/../shared/meshes)"
        )
    return folder


@pytest.fixture(scope="session")
def mesh_path(shared_meshes):
    """mesh_path('spot') -> path of spot.obj in the shared corpus; fails if it is missing."""

    def _path(name: str) -> Path:
        path = shared_meshes / f"{name}.obj"
        if not path.is_file():
            pytest.fail(f"shared mesh {name!r} is missing: expected {path}")
        return path

    return _path


@pytest.fixture(scope="session")
def work_dir(tmp_path_factory) -> Path:
    """One scratch folder for the whole session (outputs are shared between checks)."""
    return tmp_path_factory.mktemp("pgvol-checks")


@pytest.fixture(scope="session")
def reference_mesh(mesh_path):
    """reference_mesh('spot') -> the input mesh loaded with trimesh (cached)."""
    cache: dict[str, object] = {}

    def _load(name: str):
        if name not in cache:
            cache[name] = helpers.load_input(mesh_path(name))
        return cache[name]

    return _load


@pytest.fixture(scope="session")
def remesh(pgvol, mesh_path, work_dir):
    """remesh('spot', '.glb') -> path of `pgvol remesh spot.obj -o OUT --res 64` (run once per key).

    A .gltf output goes into its own folder, since it may come with side files.
    """
    cache: dict[tuple, helpers.Run] = {}

    def _remesh(name: str, ext: str = ".glb", res: int = 64) -> Path:
        key = (name, ext, res)
        folder = work_dir / "remesh" / f"{name}-r{res}-{ext.lstrip('.')}"
        out = folder / f"{name}{ext}"
        if key not in cache:
            if folder.exists():
                shutil.rmtree(folder)
            folder.mkdir(parents=True)
            cache[key] = helpers.run([pgvol, "remesh", mesh_path(name), "-o", out, "--res", res])
        result = cache[key]
        if result.returncode != 0:
            pytest.fail(f"pgvol remesh failed for {name}{ext}\n" + result.describe())
        if not out.is_file():
            pytest.fail(f"pgvol remesh exited 0 but wrote no {out.name}\n" + result.describe())
        return out

    return _remesh
