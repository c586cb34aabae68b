"""How thick the walls of a gyroid sheet are against the thickness asked for: the volume
fraction of {|f / |grad f|| <= t/2} (the sheet pgvol builds) against t times the gyroid's area
per volume, which a wall of exactly uniform thickness t would fill. Monte Carlo over one cell.

    .venv/bin/python tools/bench/lattice_wall.py [--samples 4000000]
"""

from __future__ import annotations

import argparse

import numpy as np


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--samples", type=int, default=4_000_000)
    args = parser.parse_args()
    u = np.random.default_rng(1).uniform(0, 2 * np.pi, (3, args.samples))
    (sx, sy, sz), (cx, cy, cz) = np.sin(u), np.cos(u)
    f = sx * cy + sy * cz + sz * cx
    norm = np.linalg.norm(np.stack([cx * cy - sz * sx, cy * cz - sx * sy, cz * cx - sy * sz]), axis=0)
    # Area per volume of the zero set, cell 1: E[delta(f) |grad f|] with the phase 2 pi x.
    eps = 0.02
    area = float(np.mean((np.abs(f) < eps) / (2 * eps) * norm)) * 2 * np.pi
    distance = f / norm / (2 * np.pi)
    print(f"gyroid area per volume: {area:.4f} / cell\n")
    print("| thickness / cell | volume fraction | t x area | ratio |")
    print("|---|---|---|---|")
    for t in [0.02, 0.06, 0.12, 0.18, 0.24]:
        got = float(np.mean(np.abs(distance) <= t / 2))
        print(f"| {t:.2f} | {got:.4f} | {t * area:.4f} | {got / (t * area):.3f} |")


if __name__ == "__main__":
    main()
