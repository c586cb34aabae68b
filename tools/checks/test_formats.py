"""`pgvol remesh` reads every input format and writes every output format."""

from __future__ import annotations

from pathlib import Path

import pytest
import trimesh

import helpers
from helpers import OUTPUT_FORMATS

VOLUME_TOLERANCE = 0.02
RES = 64

# name -> (file suffix, writer)
INPUT_FORMATS = {
    "obj": (".obj", lambda m, p: m.export(p, file_type="obj")),
    "stl-binary": (".stl", lambda m, p: m.export(p, file_type="stl")),
    "stl-ascii": (".stl", lambda m, p: m.export(p, file_type="stl_ascii")),
    "ply-binary": (".ply", lambda m, p: Path(p).write_bytes(trimesh.exchange.ply.export_ply(m, encoding="binary"))),
    "ply-ascii": (".ply", lambda m, p: Path(p).write_bytes(trimesh.exchange.ply.export_ply(m, encoding="ascii"))),
    "glb": (".glb", lambda m, p: m.export(p, file_type="glb")),
}


def _fixture_mesh(repo_root: Path) -> tuple[str, trimesh.Trimesh]:
    """The first closed fixtures/*.obj, or a generated icosphere when there is none."""
    for path in sorted((repo_root / "fixtures").glob("*.obj")):
        mesh = helpers.load_input(path)
        if mesh.is_watertight and mesh.volume > 0:
            return path.stem, mesh
    return "icosphere", trimesh.creation.icosphere(subdivisions=3, radius=1.0)


@pytest.fixture(scope="module")
def source(repo_root, tmp_path_factory):
    name, mesh = _fixture_mesh(repo_root)
    assert mesh.is_watertight, f"{name}: source mesh must be closed"
    folder = tmp_path_factory.mktemp("formats-in")
    inputs = {}
    for key, (suffix, write) in INPUT_FORMATS.items():
        path = folder / f"{name}-{key}{suffix}"
        write(mesh, str(path))
        inputs[key] = path
    return name, mesh, inputs


def _check_output(out: Path, volume: float, what: str):
    mesh = helpers.load_output(out)
    assert mesh.is_watertight, f"{what}: {out.name} is not watertight ({helpers.edge_counts(mesh)})"
    err = helpers.rel_diff(mesh.volume, volume)
    assert err <= VOLUME_TOLERANCE, (
        f"{what}: volume {mesh.volume:.6g} vs input {volume:.6g} ({100 * err:.2f} %)"
    )


@pytest.mark.parametrize("fmt", list(INPUT_FORMATS))
def test_reads_input_format(fmt, source, pgvol, tmp_path):
    name, mesh, inputs = source
    out = tmp_path / f"{name}.glb"
    helpers.run_ok([pgvol, "remesh", inputs[fmt], "-o", out, "--res", RES])
    _check_output(out, mesh.volume, f"input {fmt}")


@pytest.mark.parametrize("ext", OUTPUT_FORMATS)
def test_writes_output_format(ext, source, pgvol, tmp_path):
    name, mesh, inputs = source
    out = tmp_path / f"{name}{ext}"
    helpers.run_ok([pgvol, "remesh", inputs["obj"], "-o", out, "--res", RES])
    _check_output(out, mesh.volume, f"output {ext}")


def test_voxel_flag(source, pgvol, tmp_path):
    name, mesh, inputs = source
    h = float(max(mesh.extents)) * 1.1 / (RES - 1)
    out = tmp_path / f"{name}.glb"
    helpers.run_ok([pgvol, "remesh", inputs["obj"], "-o", out, "--voxel", f"{h:.9g}"])
    _check_output(out, mesh.volume, "--voxel")
