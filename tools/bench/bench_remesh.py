"""`pgvol remesh` timing and accuracy against a dense SDF + marching cubes baseline.

Usage (normally through tools/bench/run.sh):
    python tools/bench/bench_remesh.py [--big] [--meshes a,b,...]

For each mesh and resolution (64 and 128, plus 256 with --big):
  * pgvol remesh MESH -o OUT.glb --res N --field decoded (the encode/decode pipeline in one
    go): wall time, triangles, Chamfer-L1 to the input
  * baseline: pgvol sdf --dense at the same grid, then scikit-image marching cubes
    at level 0: time (sdf + contouring), triangles, Chamfer-L1 to the input
Chamfer-L1 comes from `pgvol compare OUT INPUT --json` and is shown in % of the
input's bounding-box diagonal.
"""

from __future__ import annotations

import argparse
import os
import shutil
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import common  # noqa: E402

DEFAULT_MESHES = "stanford-bunny,spot,fandisk,rocker-arm,teapot,suzanne"


def chamfer_pct(exe: Path, out: Path, src: Path) -> tuple[float, float]:
    report, _ = common.run_json([exe, "compare", out, src, "--json"])
    return float(report["chamfer_l1_pct"]), float(report["hausdorff_pct"])


def pgvol_remesh(exe: Path, src: Path, res: int, work: Path):
    out = work / f"{src.stem}-{res}.glb"
    proc, wall = common.run([exe, "remesh", src, "-o", out, "--res", res, "--field", "decoded"])
    if proc.returncode != 0:
        raise RuntimeError(f"remesh exited {proc.returncode}: {proc.stderr.strip()[-300:]}")
    mesh = common.load_mesh(out)
    ch, hd = chamfer_pct(exe, out, src)
    return wall, len(mesh.faces), ch, hd, bool(mesh.is_watertight)


def dense_mc(exe: Path, src: Path, mesh, res: int, work: Path):
    from skimage.measure import marching_cubes
    import trimesh

    grid = common.Grid(mesh.bounds, res)
    field = work / f"{src.stem}-{res}.nrrd"
    start = time.perf_counter()
    common.run_json([exe, "sdf", src, "-o", field, "--res", res, "--dense", "--json"])
    values = common.read_grid_x_fastest(field, res).reshape((res, res, res), order="F")  # [i, j, k]
    verts, faces, _, _ = marching_cubes(values, level=0.0, spacing=(grid.h, grid.h, grid.h))
    seconds = time.perf_counter() - start
    verts = verts + grid.origin
    out_mesh = trimesh.Trimesh(verts, faces, process=True)
    if out_mesh.volume < 0:  # orient outward whatever skimage's convention
        out_mesh.invert()
    out = work / f"{src.stem}-{res}-mc.ply"
    out_mesh.export(out)
    ch, hd = chamfer_pct(exe, out, src)
    field.unlink(missing_ok=True)
    return seconds, len(out_mesh.faces), ch, hd, bool(out_mesh.is_watertight)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--big", action="store_true", help="also run at 256^3")
    ap.add_argument("--meshes", default=DEFAULT_MESHES)
    ap.add_argument("--res", default="64,128", help="comma-separated resolutions")
    args, unknown = ap.parse_known_args(argv)  # run.sh passes the same flags to both benchmarks
    if unknown:
        print(f"bench_remesh: ignoring {' '.join(unknown)}", file=sys.stderr)

    exe = common.pgvol_bin()
    if not exe.is_file():
        print(f"pgvol binary missing at {exe}; run cargo build --release", file=sys.stderr)
        return 1
    resolutions = [int(r) for r in args.res.split(",")] + ([256] if args.big else [])
    work = Path(tempfile.mkdtemp(prefix="pgvol-bench-remesh-"))
    rows = []
    try:
        for name in args.meshes.split(","):
            src = common.mesh_file(name)
            mesh = common.load_mesh(src)
            for res in resolutions:
                print(f"  {name} {res}^3 ...", file=sys.stderr, flush=True)
                for label, fn in (
                    ("pgvol remesh", lambda: pgvol_remesh(exe, src, res, work)),
                    ("dense sdf + skimage MC", lambda: dense_mc(exe, src, mesh, res, work)),
                ):
                    try:
                        seconds, tris, ch, hd, closed = fn()
                    except Exception as exc:  # noqa: BLE001
                        rows.append([name, res, label, "n/a", "n/a", "n/a", "n/a", "n/a", common.short_reason(exc)])
                        continue
                    rows.append([name, res, label, seconds, tris, f"{ch:.4f}", f"{hd:.3f}", "yes" if closed else "no", ""])
    finally:
        shutil.rmtree(work, ignore_errors=True)

    print(f"# Remesh benchmark ({os.cpu_count()} cores)\n")
    header = ["mesh", "res", "method", "seconds", "triangles", "Chamfer-L1 % diag", "Hausdorff % diag", "watertight", "note"]
    print(common.markdown_table(header, rows))
    return 0


if __name__ == "__main__":
    sys.exit(main())
