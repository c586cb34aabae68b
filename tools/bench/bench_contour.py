"""Contouring speed against scikit-image and OpenVDB on the same grid, in one run.

    tools/.venv-bench/bin/python tools/bench/bench_contour.py [--mesh stanford-bunny] [--res 256] [--reps 5]

1. `pgvol sdf MESH --res N --band 4 --format npy` samples the signed distance on the pgvol grid
   (exact within 4 spacings of the surface, which is all contouring looks at).
2. scikit-image `marching_cubes(grid, 0)` on that numpy array.
3. OpenVDB (Debian's python3-openvdb, run under /usr/bin/python3 by this same script with
   `--vdb-worker`): a level set with a +-3 voxel band holding the same distances (meshToVolume's
   flood-fill sign fails on open meshes), then volumeToMesh (adaptivity 0), which visits only the
   band.
4. pgvol's `contour_grid` study on the same .npy: marching cubes with linear placement ("grid
   only"), marching cubes with root finding on the cubic B-spline interpolant of the grid (as
   `pgvol decode` places vertices), dual contouring and surface nets on that field.

Every timing is the best of --reps runs of the contouring call alone (no file I/O).
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
SYSTEM_PYTHON = "/usr/bin/python3"


def vdb_worker(mesh: str, grid_path: str, n: int, reps: int) -> None:
    """Runs under the system Python: OpenVDB's narrow-band level set of the same surface, and
    the time volumeToMesh takes on it.

    OpenVDB's own meshToVolume decides the sign by flood fill, which fails on open meshes such as
    the bunny, so the level set is built from pgvol's signed distances instead: values within 3
    voxels become the active band, the rest is filled with +-3 voxels by signedFloodFill, as
    meshToVolume would leave it.
    """
    import numpy as np

    sys.path.insert(0, str(HERE.parent))
    from objfile import read_obj

    try:
        import pyopenvdb as vdb
    except ImportError:  # newer builds name the module openvdb
        import openvdb as vdb

    verts, _ = read_obj(mesh)
    h = 1.1 * float((verts.max(0) - verts.min(0)).max()) / (n - 1)
    width = 3.0 * h
    values = np.load(grid_path).transpose(2, 1, 0)  # [i, j, k]
    band = np.where(np.abs(values) < width, values, width).astype(np.float32)
    grid = vdb.FloatGrid(background=width)
    grid.transform = vdb.createLinearTransform(voxelSize=h)
    grid.gridClass = vdb.GridClass.LEVEL_SET
    grid.copyFromArray(np.ascontiguousarray(band), ijk=(0, 0, 0), tolerance=0.0)
    grid.signedFloodFill()
    best, triangles = float("inf"), 0
    for _ in range(reps):
        start = time.perf_counter()
        _, tris, quads = grid.convertToPolygons(isovalue=0.0, adaptivity=0.0)
        best = min(best, time.perf_counter() - start)
        triangles = int(len(tris) + 2 * len(quads))
    print(json.dumps({"seconds": best, "triangles": triangles, "active": int(grid.activeVoxelCount())}))


def skimage_time(grid_path: Path, reps: int) -> dict:
    import numpy as np
    from skimage.measure import marching_cubes

    grid = np.load(grid_path)
    best, triangles = float("inf"), 0
    for _ in range(reps):
        start = time.perf_counter()
        _, faces, _, _ = marching_cubes(grid, 0.0)
        best = min(best, time.perf_counter() - start)
        triangles = len(faces)
    return {"seconds": best, "triangles": triangles}


def main() -> None:
    sys.path.insert(0, str(HERE))
    from common import mesh_file, pgvol_bin, run, run_json, REPO_ROOT, markdown_table

    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--mesh", default="stanford-bunny")
    ap.add_argument("--res", type=int, default=256)
    ap.add_argument("--reps", type=int, default=5)
    args = ap.parse_args()

    mesh = mesh_file(args.mesh)
    contour_grid = REPO_ROOT / "target" / "release" / "contour_grid"
    if not contour_grid.is_file():
        raise SystemExit(f"missing {contour_grid}: cargo build --release -p pgvol-studies --bin contour_grid")
    with tempfile.TemporaryDirectory() as tmp:
        grid_path = Path(tmp) / "grid.npy"
        proc, _ = run([pgvol_bin(), "sdf", mesh, "-o", grid_path, "--res", args.res, "--band", 4, "--format", "npy"])
        if proc.returncode != 0:
            raise SystemExit(proc.stderr)
        results = {}
        results["pgvol"], _ = run_json([contour_grid, grid_path, "--reps", args.reps, "--json"])
        try:
            results["skimage"] = skimage_time(grid_path, args.reps)
        except Exception as exc:  # a peer that is not installed shows as n/a
            results["skimage"] = {"error": str(exc)}
        try:
            results["openvdb"], _ = run_json(
                [SYSTEM_PYTHON, __file__, "--vdb-worker", mesh, grid_path, args.res, args.reps]
            )
        except Exception as exc:
            results["openvdb"] = {"error": str(exc)}

    load = os.getloadavg()[0]
    pg = results["pgvol"]
    mc = pg["mc_grid"]["seconds"]
    rows = []

    def row(name, entry):
        if "seconds" not in entry:
            rows.append([name, "n/a", "n/a", "", ""])
            return
        s = entry["seconds"]
        rows.append([name, f"{1e3 * s:.1f}", f"{entry['triangles']:,}", f"{mc / s:.2f}", f"{s / mc:.2f}"])

    row("pgvol marching cubes, grid only (linear placement)", pg["mc_grid"])
    row("pgvol marching cubes, root finding on the B-spline field", pg["mc_root_finding"])
    row("pgvol dual contouring (B-spline field)", pg["dc"])
    row("pgvol surface nets (B-spline field)", pg["sn"])
    row("scikit-image marching_cubes", results["skimage"])
    row("OpenVDB volumeToMesh on its +-3 band", results["openvdb"])
    print(f"{args.mesh}, {args.res}^3, best of {args.reps}, {pg['threads']} threads, load average {load:.2f}\n")
    print(markdown_table(["method", "ms", "triangles", "pgvol MC grid-only time / this", "this / pgvol MC grid-only"], rows))
    print("\n" + json.dumps(results))


if __name__ == "__main__":
    if len(sys.argv) > 1 and sys.argv[1] == "--vdb-worker":
        vdb_worker(sys.argv[2], sys.argv[3], int(sys.argv[4]), int(sys.argv[5]))
    else:
        main()
