"""How soon a raising progress callback stops a long call from Python.

A mesh is encoded at a print resolution; the progress callback raises once the call has run
`--after` seconds, or with `--stage NAME` at the first report of that stage after its start
(for example "fit"). The figure is the time from that raise to the call's return (with the
stage that was running), over `--runs` runs.

Usage: python tools/bench/bench_cancel.py MESH [--res 1024] [--after 1.5 | --stage fit] [--runs 3]
"""

from __future__ import annotations

import argparse
import time

import numpy as np
import trimesh

import pgvol


class Stop(Exception):
    pass


def one_run(
    vertices: np.ndarray, faces: np.ndarray, res: int, after: float, at_stage: str | None
) -> tuple[float, str]:
    start = time.perf_counter()
    raised: dict[str, float | str] = {}

    def due(stage: str, fraction: float) -> bool:
        if at_stage is not None:
            return stage == at_stage and fraction > 0.0
        return time.perf_counter() - start >= after

    def progress(stage: str, fraction: float) -> None:
        if "at" not in raised and due(stage, fraction):
            raised["at"] = time.perf_counter()
            raised["stage"] = stage
            raise Stop()

    try:
        pgvol.Field.from_mesh(vertices, faces, res=res, progress=progress)
    except Stop:
        pass
    end = time.perf_counter()
    if "at" not in raised:
        return float("nan"), "finished before the raise"
    return end - float(raised["at"]), str(raised["stage"])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("mesh")
    parser.add_argument("--res", type=int, default=1024)
    parser.add_argument("--after", type=float, default=1.5)
    parser.add_argument("--stage", help="raise at this stage's first report instead")
    parser.add_argument("--runs", type=int, default=3)
    args = parser.parse_args()
    mesh = trimesh.load(args.mesh, force="mesh", process=False)
    vertices = np.asarray(mesh.vertices, dtype=np.float32)
    faces = np.asarray(mesh.faces, dtype=np.int64)
    print(f"| run | stage at the raise | raise → return (s) |")
    print(f"|---|---|---|")
    for run in range(args.runs):
        seconds, stage = one_run(vertices, faces, args.res, args.after, args.stage)
        print(f"| {run + 1} | {stage} | {seconds:.3f} |")


if __name__ == "__main__":
    main()
