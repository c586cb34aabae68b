"""The Python package against the command-line tool and peer Python libraries, in one run.

    PYTHON tools/bench/bench_python.py [--mesh stanford-bunny] [--res 256] [--points 1000000]
                                       [--trimesh-points 2000] [--reps 3] [--json out.json]

PYTHON is any Python with the package installed (`pip install ./crates/pgvol-py`), numpy, scipy,
trimesh and rtree; pysdf is measured when it imports (`pip install pysdf==0.1.9`, which builds
from source with Debian's libeigen3-dev and CPATH=/usr/include/eigen3).

1. Batched evaluation: --points uniform random points in the bounding box of the mesh, through
   a --res field: `f(points)` (values) and `f.eval_with_gradient(points)`; pysdf's
   `SDF(vertices, faces)(points)` on the same points (exact distances from its own BVH, built
   once outside the timing); trimesh's `proximity.signed_distance` on the first
   --trimesh-points of them, its time extrapolated linearly to all of them. Best of --reps, the
   points already in memory as float32 (pysdf and trimesh: as they take them).
2. Overhead of the bindings: `Field.from_mesh(v, t, res=N)` and `f.to_mesh()` in this process
   against the stage times the CLI reports for the same job (`pgvol encode --json`: sdf + fit;
   `pgvol decode --json`: the contouring call), and the CLI's whole-process wall time with its
   file I/O (the CLI contours the field read back from its sparse file).

The machine may be shared: figures are single runs (best of --reps) and move with its load.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

from common import mesh_file, pgvol_bin  # noqa: E402

import pgvol  # noqa: E402


def best(fn, reps: int) -> tuple[float, object]:
    """The shortest wall time of `reps` calls of fn, and the last result."""
    times, out = [], None
    for _ in range(reps):
        t0 = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t0)
    return min(times), out


def cli_json(*args) -> tuple[dict, float]:
    t0 = time.perf_counter()
    r = subprocess.run(
        [str(pgvol_bin()), *map(str, args), "--json"], capture_output=True, text=True, check=True
    )
    return json.loads(r.stdout), time.perf_counter() - t0


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--mesh", default="stanford-bunny")
    ap.add_argument("--res", type=int, default=256)
    ap.add_argument("--points", type=int, default=1_000_000)
    ap.add_argument("--trimesh-points", type=int, default=2000)
    ap.add_argument("--reps", type=int, default=3)
    ap.add_argument("--json", type=Path)
    a = ap.parse_args()

    path = mesh_file(a.mesh)
    v, t = pgvol.read_mesh(path)
    results: dict = {
        "mesh": a.mesh,
        "triangles": int(len(t)),
        "res": a.res,
        "points": a.points,
        "cpus": os.cpu_count(),
        "machine": platform.platform(),
    }

    # 2. Encode and contour in process, against the CLI's own stage times.
    encode_s, f = best(lambda: pgvol.Field.from_mesh(v, t, res=a.res), a.reps)
    contour_s, (mv, mt) = best(lambda: f.to_mesh(), a.reps)
    with tempfile.TemporaryDirectory() as tmp:
        pgv = Path(tmp) / "x.pgv"
        cli_encode = [cli_json("encode", path, "-o", pgv, "--res", a.res, "--force") for _ in range(a.reps)]
        cli_decode = [cli_json("decode", pgv, "-o", Path(tmp) / "x.ply", "--force") for _ in range(a.reps)]
    enc_stages = min(r["seconds"]["sdf"] + r["seconds"]["fit"] for r, _ in cli_encode)
    enc_wall = min(w for _, w in cli_encode)
    # `seconds` holds each stage's time and the total; the contouring call is `contour`.
    dec_stage = min(r["seconds"]["contour"] for r, _ in cli_decode)
    dec_wall = min(w for _, w in cli_decode)
    results["encode"] = {
        "python_from_mesh": encode_s,
        "cli_sdf_plus_fit": enc_stages,
        "cli_process_wall": enc_wall,
    }
    results["contour"] = {
        "python_to_mesh": contour_s,
        "cli_contour": dec_stage,
        "cli_process_wall": dec_wall,
        "triangles": int(len(mt)),
    }

    # 1. Batched evaluation over the mesh's bounding box.
    rng = np.random.default_rng(0)
    lo, hi = v.min(axis=0), v.max(axis=0)
    points = rng.uniform(lo, hi, (a.points, 3)).astype(np.float32)
    values_s, values = best(lambda: f(points), a.reps)
    grad_s, _ = best(lambda: f.eval_with_gradient(points), a.reps)
    exact = f.is_exact(points)
    results["eval"] = {
        "pgvol_values": values_s,
        "pgvol_values_and_gradients": grad_s,
        "exact_fraction": float(exact.mean()),
    }

    try:
        import pysdf
    except ImportError as e:
        results["eval"]["pysdf"] = f"n/a ({e})"
    else:
        sdf = pysdf.SDF(v.astype(np.float32), t.astype(np.uint32))
        pysdf_s, theirs = best(lambda: sdf(points), a.reps)
        # pysdf is positive inside: flip it; compare where pgvol's value is a distance.
        diff = np.abs(values - (-np.asarray(theirs)))[exact]
        results["eval"]["pysdf"] = pysdf_s
        results["eval"]["pysdf_vs_pgvol_max_abs_in_band"] = float(diff.max())
        results["eval"]["pysdf_vs_pgvol_p99_abs_in_band"] = float(np.percentile(diff, 99))

    import trimesh

    mesh = trimesh.Trimesh(v, t, process=False)
    sub = points[: a.trimesh_points].astype(np.float64)
    tri_s, _ = best(lambda: trimesh.proximity.signed_distance(mesh, sub), 1)
    results["eval"]["trimesh_subset"] = {"points": len(sub), "seconds": tri_s}
    results["eval"]["trimesh_extrapolated"] = tri_s * a.points / len(sub)

    grid = f.grid
    results["field"] = {"dims": grid.dims, "spacing": grid.spacing, "band": f.band}
    print(json.dumps(results, indent=2, default=str))
    if a.json:
        a.json.write_text(json.dumps(results, indent=2, default=str))

    e = results["eval"]
    n = a.points
    print()
    print(f"| {a.mesh}, {a.res}³, {n:,} points | seconds | ns per point |")
    print("|---|---|---|")
    rows = [
        ("pgvol `f(points)`", e["pgvol_values"]),
        ("pgvol `f.eval_with_gradient(points)`", e["pgvol_values_and_gradients"]),
    ]
    if isinstance(e.get("pysdf"), float):
        rows.append(("pysdf `SDF(v, t)(points)`", e["pysdf"]))
    rows.append(
        (f"trimesh `signed_distance` ({a.trimesh_points} points, extrapolated)", e["trimesh_extrapolated"])
    )
    for name, s in rows:
        print(f"| {name} | {s:.3f} | {s / n * 1e9:.0f} |")
    print()
    print("| job | Python, in process | CLI, its stages | CLI, whole process |")
    print("|---|---|---|---|")
    enc, con = results["encode"], results["contour"]
    print(f"| encode {a.res}³ | {enc['python_from_mesh']:.3f} | {enc['cli_sdf_plus_fit']:.3f} | {enc['cli_process_wall']:.3f} |")
    print(f"| contour (mc) | {con['python_to_mesh']:.3f} | {con['cli_contour']:.3f} | {con['cli_process_wall']:.3f} |")


if __name__ == "__main__":
    main()
