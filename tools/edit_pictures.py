"""Draws the pictures of docs/editing.md: 2D sections of fields before and after `pgvol csg`,
`pgvol repair` and `pgvol blend`, each made by the CLI and sampled with `pgvol eval`.

Usage: python tools/edit_pictures.py [--bin target/release/pgvol] [--out docs/images]
Needs numpy, trimesh and matplotlib (tools/bench/requirements.txt).
"""

from __future__ import annotations

import argparse
import subprocess
import tempfile
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import trimesh  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
SAMPLES = 160


def run(*args) -> None:
    subprocess.run([str(a) for a in args], check=True)


def section(pgvol: Path, pgv: Path, plane: str, lo, hi, work: Path) -> np.ndarray:
    """The field on a SAMPLES² grid of the plane 'xy' (z = 0) or 'xz' (y = 0) over [lo, hi]²."""
    u = np.linspace(lo, hi, SAMPLES)
    a, b = np.meshgrid(u, u)
    zero = np.zeros_like(a)
    pts = np.stack([a, b, zero] if plane == "xy" else [a, zero, b], axis=-1).reshape(-1, 3)
    pts_file, out_file = work / "points.csv", work / "values.csv"
    np.savetxt(pts_file, pts, delimiter=",", fmt="%.6f")
    run(pgvol, "eval", pgv, pts_file, "-o", out_file, "-q")
    values = np.loadtxt(out_file, delimiter=",", ndmin=2, skiprows=1)[:, 3]
    return values.reshape(SAMPLES, SAMPLES)


def panel(ax, field, lo, hi, title, before=None) -> None:
    extent = [lo, hi, lo, hi]
    ax.imshow(field < 0, origin="lower", extent=extent, cmap="Greys", vmin=0, vmax=2.5)
    u = np.linspace(lo, hi, SAMPLES)
    ax.contour(u, u, field, levels=np.linspace(-0.3, 0.3, 7), colors="tab:blue", linewidths=0.4)
    ax.contour(u, u, field, levels=[0], colors="k", linewidths=1.2)
    if before is not None:
        ax.contour(u, u, before, levels=[0], colors="tab:red", linewidths=1.0, linestyles="dashed")
    ax.set_title(title, fontsize=9)
    ax.set_xticks([])
    ax.set_yticks([])


def figure(path: Path, panels, lo, hi) -> None:
    fig, axes = plt.subplots(1, len(panels), figsize=(2.4 * len(panels), 2.5))
    for ax, (field, title, before) in zip(np.atleast_1d(axes), panels):
        panel(ax, field, lo, hi, title, before)
    fig.tight_layout()
    fig.savefig(path, dpi=72)
    plt.close(fig)
    print(path)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--bin", type=Path, default=ROOT / "target" / "release" / "pgvol")
    parser.add_argument("--out", type=Path, default=ROOT / "docs" / "images")
    args = parser.parse_args()
    pgvol = args.bin
    args.out.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)

        def make(name, *cli) -> Path:
            out = work / f"{name}.pgv"
            run(pgvol, *cli, "-o", out, "--res", 96, "-q")
            return out

        def sec(pgv, plane="xy", lo=-1.6, hi=1.6):
            return section(pgvol, pgv, plane, lo, hi, work)

        balls = ["sphere:-0.4,0,0,0.8", "sphere:0.5,0,0,0.6"]
        sharp = sec(make("sharp", "csg", "union", *balls))
        figure(
            args.out / "csg-radius.png",
            [(sharp, "union, sharp", None)]
            + [(sec(make(f"r{r}", "csg", "union", *balls, "--radius", r)), f"--radius {r}", sharp) for r in (0.2, 0.4)]
            + [(sec(make("diff", "csg", "difference", *balls, "--radius", 0.2)), "difference, --radius 0.2", None)],
            -1.6,
            1.6,
        )

        bumped = make("bumped", "csg", "union", "sphere:0,0,0,1", "sphere:0,0,1,0.3")
        mask = "--mask=-0.45,-0.45,0.75,0.45,0.45,1.45"
        before = sec(bumped, "xz")
        figure(
            args.out / "repair-alpha.png",
            [(before, "bumped sphere", None)]
            + [
                (sec(make(f"a{a}", "repair", bumped, mask, "--face=-z", "--alpha", a), "xz"), f"--alpha {a}", before)
                for a in (0.5, 0.9, 1.5)
            ],
            -1.6,
            1.6,
        )

        rng = np.random.default_rng(7)
        ball = trimesh.creation.icosphere(subdivisions=5)
        ball.vertices *= (1 + 0.015 * rng.standard_normal(len(ball.vertices)))[:, None]
        noisy_mesh = work / "noisy.ply"
        ball.export(noisy_mesh)
        noisy = make("noisy", "encode", noisy_mesh)
        dmask = "--mask=-0.6,-0.6,0.4,0.6,0.6,1.2"
        before = sec(noisy, "xz")
        figure(
            args.out / "repair-denoise.png",
            [(before, "noisy sphere", None)]
            + [
                (sec(make(f"d{c}", "repair", noisy, dmask, "--denoise", "--coarse", c), "xz"), f"--coarse {c}", before)
                for c in (30, 12)
            ],
            -1.6,
            1.6,
        )

        planes = ["plane:1,0,0,0", "plane:0,1,0,0"]
        box = "--box=-1,-1,-1,1,1,1"
        corner = sec(make("corner", "csg", "intersection", *planes, box), lo=-1, hi=0.5)
        figure(
            args.out / "blend-liming.png",
            [
                (sec(make(f"l{l}", "blend", "liming", *planes, "--cut", "plane:-1,-1,0,0.6", "--lambda", l, box), lo=-1, hi=0.5),
                 f"liming --lambda {l}", corner)
                for l in (0.2, 0.5, 0.8)
            ],
            -1,
            0.5,
        )
        bounds = ["--bound", "plane:1,0,0,1", "--bound", "plane:0,1,0,1"]
        figure(
            args.out / "blend-ipatch.png",
            [
                (sec(make(f"i{w}", "blend", "ipatch", *planes, *bounds, "--weights", f"1,1,{w}", box), lo=-1, hi=1),
                 f"ipatch w = {w}", None)
                for w in (-0.2, -1.0, -3.0)
            ],
            -1,
            1,
        )


if __name__ == "__main__":
    main()
