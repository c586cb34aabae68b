"""Wall-clock time of the editing commands against encoding the same mesh at the same grid, and
against a mesh Boolean by manifold3d when it is installed.

    tools/.venv-bench/bin/python tools/bench/bench_edit.py [--mesh bunny-capped] [--res 128,256]
        [--reps 1] [--json OUT.json] [--work DIR]

Per resolution N (the grid convention: cube of side 1.1 x the longest extent, N nodes per axis):
  * encode:        pgvol encode MESH -o X.pgv --res N
  * csg sharp:     pgvol csg union MESH BALL -o X.pgv --res N       (BALL: a sphere on the mesh's top)
  * csg rounded:   the same with --radius (2 % of the mesh's longest extent)
  * repair:        pgvol repair X.pgv --mask (a cube of side 15 % of the extent, under the top
                   centre of the mesh's box) --face -z
  * denoise:       pgvol repair X.pgv --mask (same) --denoise --coarse 30
  * blend liming:  pgvol blend liming of two planes with a cut over the mesh's box
  * manifold3d:    union of the mesh with an icosphere of the same ball (mesh Boolean; reference
                   for the Boolean's cost, not its output, which is a mesh, not a field).
Times are the whole process (start-up and file I/O included), best of --reps.
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import common  # noqa: E402


def best_time(args, reps: int) -> float:
    best = float("inf")
    for _ in range(reps):
        proc, wall = common.run(args)
        if proc.returncode != 0:
            raise RuntimeError(f"{' '.join(map(str, args[:3]))} exited {proc.returncode}: {proc.stderr.strip()[-300:]}")
        best = min(best, wall)
    return best


def manifold_union_seconds(mesh_path: Path, centre, radius: float, reps: int):
    try:
        import manifold3d
        import numpy as np
        import trimesh
    except ImportError as e:
        return None, common.short_reason(e)
    mesh = trimesh.load(mesh_path, force="mesh", process=True)
    ball = trimesh.creation.icosphere(subdivisions=5, radius=radius)
    ball.apply_translation(centre)

    def solid(m):
        return manifold3d.Manifold(manifold3d.Mesh(np.asarray(m.vertices, np.float32), np.asarray(m.faces, np.uint32)))

    best = float("inf")
    for _ in range(reps):
        start = time.perf_counter()
        out = (solid(mesh) + solid(ball)).to_mesh()
        best = min(best, time.perf_counter() - start)
        if len(out.tri_verts) == 0:
            return None, "manifold3d: empty result (the mesh is not a closed manifold)"
    return best, ""


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--mesh", default="bunny-capped")
    parser.add_argument("--res", default="128,256")
    parser.add_argument("--reps", type=int, default=1)
    parser.add_argument("--json", type=Path)
    parser.add_argument("--work", type=Path)
    args = parser.parse_args()
    pgvol = common.pgvol_bin()
    with tempfile.TemporaryDirectory(dir=args.work) as tmp:
        work = Path(tmp)
        mesh_path = common.source_mesh(args.mesh, work)
        vertices = common.load_mesh(mesh_path).vertices
        lo, hi = vertices.min(axis=0), vertices.max(axis=0)
        extent = float((hi - lo).max())
        top = [(lo[0] + hi[0]) / 2, (lo[1] + hi[1]) / 2, hi[2]]
        radius = 0.15 * extent
        ball = f"sphere:{top[0]},{top[1]},{top[2]},{radius}"
        blend_radius = 0.02 * extent
        half = 0.075 * extent
        mask = "--mask=" + ",".join(str(v) for v in [top[0] - half, top[1] - half, top[2] - 2 * half,
                                                      top[0] + half, top[1] + half, top[2]])
        box = f"--box={lo[0]},{lo[1]},{lo[2]},{hi[0]},{hi[1]},{hi[2]}"
        mid = (lo + hi) / 2
        planes = [f"plane:1,0,0,{mid[0]}", f"plane:0,1,0,{mid[1]}"]
        cut = f"plane:-1,-1,0,{-(mid[0] + mid[1]) + 0.2 * extent}"
        rows, records = [], []
        for n in [int(x) for x in args.res.split(",")]:
            pgv = work / f"enc{n}.pgv"
            cases = {
                "encode": [pgvol, "encode", mesh_path, "-o", pgv, "--res", n, "-q"],
                "csg sharp": [pgvol, "csg", "union", mesh_path, ball, "-o", work / "u.pgv", "--res", n, "-q"],
                "csg rounded": [pgvol, "csg", "union", mesh_path, ball, "-o", work / "r.pgv", "--res", n,
                                "--radius", blend_radius, "-q"],
                "repair": [pgvol, "repair", pgv, "-o", work / "f.pgv", mask, "--face=-z", "-q"],
                "denoise": [pgvol, "repair", pgv, "-o", work / "d.pgv", mask, "--denoise", "-q"],
                "blend liming": [pgvol, "blend", "liming", *planes, "--cut", cut, box, "-o", work / "l.pgv",
                                 "--res", n, "-q"],
            }
            times = {}
            for name, argv in cases.items():
                try:
                    times[name] = best_time(argv, args.reps)
                except Exception as e:  # one failing case does not stop the others
                    times[name] = None
                    print(f"{name} at {n}: {common.short_reason(e)}", file=sys.stderr)
            enc = times["encode"]
            for name, t in times.items():
                ratio = t / enc if (t and enc) else "n/a"
                rows.append([n, name, t if t is not None else "n/a", ratio])
                records.append({"res": n, "case": name, "seconds": t})
        m3d, why = manifold_union_seconds(mesh_path, top, radius, args.reps)
        rows.append(["-", "manifold3d mesh union", m3d if m3d is not None else f"n/a ({why})", "-"])
        records.append({"res": None, "case": "manifold3d mesh union", "seconds": m3d})
        print(common.markdown_table(["N", "operation", "s", "x encode"], rows))
        if args.json:
            args.json.write_text(json.dumps(records, indent=2))


if __name__ == "__main__":
    main()
