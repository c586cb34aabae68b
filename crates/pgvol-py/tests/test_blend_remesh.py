"""Blends and remeshing from Python: the same files and meshes as the command-line tool, and
surfaces checked with trimesh."""

from __future__ import annotations

import numpy as np
import trimesh

import pgvol

PLANES = ["plane:1,0,0,0", "plane:0,1,0,0"]
CUT = "plane:-1,-1,0,0.5"
BOX = ((-1.0, -1.0, -1.0), (1.0, 1.0, 1.0))


def test_a_liming_blend_is_the_file_the_cli_writes_and_rounds_the_edge(tmp_path, run_cli):
    field = pgvol.Field.blend("liming", PLANES, cut=CUT, bounds=BOX, res=48)
    out = tmp_path / "round.pgv"
    run_cli("blend", "liming", *PLANES, "--cut", CUT, "--box", "-1,-1,-1,1,1,1", "--res", 48,
            "-o", out, "-q")
    assert field.to_bytes() == out.read_bytes()
    # The wedge x <= 0, y <= 0 keeps its faces far from the edge and loses its sharp edge: a
    # point just inside the sharp corner is outside the rounded solid.
    inside_far, near_edge = field(np.array([(-0.6, -0.2, 0.0), (-0.03, -0.03, 0.0)]))
    assert inside_far < 0 < near_edge


def test_blend_refuses_what_it_cannot_build():
    for kwargs in [dict(kind="liming"), dict(kind="ipatch", bound=PLANES), dict(kind="swirl")]:
        kind = kwargs.pop("kind")
        try:
            pgvol.Field.blend(kind, PLANES, bounds=BOX, res=32, **kwargs)
        except ValueError as e:
            assert str(e)
        else:
            raise AssertionError(f"{kind} {kwargs} was accepted")


def test_remesh_gives_a_watertight_surface_close_to_the_input(tmp_path, run_cli):
    sphere = trimesh.creation.icosphere(subdivisions=3, radius=1.0)
    v, f = pgvol.remesh(sphere.vertices, sphere.faces, res=48)
    out = trimesh.Trimesh(v, f, process=False)
    assert out.is_watertight and out.is_winding_consistent
    radii = np.linalg.norm(out.vertices, axis=1)
    assert abs(radii.mean() - 1.0) < 0.01
    # The same surface as the command line's remesh of the same mesh file.
    mesh = tmp_path / "ball.obj"
    sphere.export(mesh)
    ply = tmp_path / "ball.ply"
    run_cli("remesh", mesh, "-o", ply, "--res", 48, "-q")
    cli = trimesh.load(ply, process=False)
    assert len(cli.faces) == len(out.faces)
    assert np.allclose(np.sort(cli.vertices, axis=0), np.sort(out.vertices, axis=0), atol=1e-5)
