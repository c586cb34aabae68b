#!/usr/bin/env python3
"""Draws the pictures of docs/lattices.md: the four periodic surfaces as sheets cut to a cube
(3D, flat shading) and sections of a part before and after the lattice operations.

usage: lattice_pictures.py OUT_DIR [surfaces] [sections]
(runs target/release/pgvol; needs numpy, matplotlib, trimesh)
Writes lattice-surfaces.png and lattice-sections.png into OUT_DIR.
"""
import json
import subprocess
import sys
import tempfile
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import trimesh  # noqa: E402
from matplotlib.patches import PathPatch  # noqa: E402
from matplotlib.path import Path as MplPath  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
PGVOL = ROOT / "target" / "release" / "pgvol"
SPOT = ROOT.parent / "shared" / "meshes" / "spot.obj"
sys.path.insert(0, str(ROOT / "tools"))
from render_preview import draw  # noqa: E402


def pgvol(*args):
    subprocess.run([str(PGVOL), *map(str, args), "-q"], check=True)


def small_png(path: Path):
    """The picture again with a palette of 64 colours: a third of the bytes, no visible change."""
    from PIL import Image

    Image.open(path).convert("RGB").quantize(64).save(path, optimize=True)


def surfaces(work: Path, out: Path):
    cube = work / "cube.stl"
    trimesh.creation.box(bounds=[[0, 0, 0], [10, 10, 10]]).export(cube)
    fig = plt.figure(figsize=(16, 4.4), dpi=80)
    for k, name in enumerate(["gyroid", "schwarz-p", "diamond", "neovius"]):
        mesh_path = work / f"{name}.obj"
        pgvol("lattice", cube, "-o", mesh_path, "--surface", name, "--cell", 5, "--thickness", 0.9, "--res", 72)
        mesh = trimesh.load(mesh_path, force="mesh")
        ax = fig.add_subplot(1, 4, k + 1, projection="3d")
        draw(ax, np.asarray(mesh.vertices), np.asarray(mesh.faces), "")
        ax.set_title(f"{name} sheet", fontsize=12, y=1.0)
    fig.subplots_adjust(left=0, right=1, bottom=0, top=0.92, wspace=0)
    fig.savefig(out / "lattice-surfaces.png", bbox_inches="tight", pad_inches=0.05)
    small_png(out / "lattice-surfaces.png")


def section(pgv: Path, work: Path, height: float):
    """The loops of the layer at `height` along z, by `pgvol slice`."""
    out = work / (pgv.stem + ".json")
    pgvol("slice", pgv, "-o", out, "--layer-height", 100, "--first", height)
    return json.loads(out.read_text())["layers"][0]["loops"]


def fill(ax, loops, title, box):
    verts, codes = [], []
    for loop in loops:
        p = np.asarray(loop["points"])
        verts += [*p, p[0]]
        codes += [MplPath.MOVETO] + [MplPath.LINETO] * (len(p) - 1) + [MplPath.CLOSEPOLY]
    ax.add_patch(PathPatch(MplPath(verts, codes), facecolor=(0.36, 0.55, 0.85), edgecolor="black", lw=0.3))
    (x0, y0), (x1, y1) = box
    ax.set_xlim(x0, x1)
    ax.set_ylim(y0, y1)
    ax.set_aspect("equal")
    ax.set_axis_off()
    ax.set_title(title, fontsize=11)


def sections(work: Path, out: Path):
    z, res = 0.0, 256
    part = work / "spot.pgv"
    pgvol("encode", SPOT, "-o", part, "--res", res, "--band", 16)
    cases = [(part, [], "part")]
    runs = [
        ("lattice", ["lattice", SPOT, "--surface", "gyroid", "--cell", 0.25, "--thickness", 0.03],
         "gyroid sheet ∩ part\ncell 0.25, thickness 0.03"),
        ("strut", ["lattice", SPOT, "--surface", "diamond", "--style", "strut", "--cell", 0.3, "--thickness", -0.03],
         "diamond strut ∩ part\ncell 0.3, level −0.03"),
        ("infill", ["shell", SPOT, "--thickness", 0.04, "--infill", "gyroid", "--cell", 0.25,
                    "--infill-thickness", 0.02, "--drain", f"0,0,{z + 0.1},0,0,-1,0.08"],
         "shell 0.04 + gyroid infill 0.02\nwith a drain (centre)"),
        ("graded", ["shell", SPOT, "--thickness", 0.04, "--infill", "gyroid", "--cell", 0.25,
                    "--infill-thickness", 0.05, "--grade-depth", 0.2, "--thickness-far", 0.015],
         "infill graded with depth\n0.05 at the skin → 0.015 at 0.2"),
    ]
    for name, args, title in runs:
        path = work / f"{name}.pgv"
        pgvol(*args, "-o", path, "--res", res)
        cases.append((path, [], title))
    fig, axes = plt.subplots(1, len(cases), figsize=(3.2 * len(cases), 5.2), dpi=90)
    loops = [section(path, work, z) for path, _, _ in cases]
    points = np.concatenate([np.asarray(loop["points"]) for loop in loops[0]])
    box = (points.min(axis=0) - 0.02, points.max(axis=0) + 0.02)
    for ax, (_, _, title), layer in zip(axes, cases, loops):
        fill(ax, layer, title, box)
    fig.suptitle(f"spot, section z = {z}, {res}³ grid", fontsize=12)
    fig.savefig(out / "lattice-sections.png", bbox_inches="tight", pad_inches=0.05)
    small_png(out / "lattice-sections.png")


def main():
    out = Path(sys.argv[1])
    out.mkdir(parents=True, exist_ok=True)
    only = sys.argv[2:] or ["surfaces", "sections"]
    with tempfile.TemporaryDirectory() as tmp:
        if "surfaces" in only:
            surfaces(Path(tmp), out)
        if "sections" in only:
            sections(Path(tmp), out)


if __name__ == "__main__":
    main()
