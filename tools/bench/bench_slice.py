"""Slicing a field at print resolution: pgvol slice as a whole process beside manifold3d slicing the
input mesh at the same heights, one run.

    .venv/bin/python tools/bench/bench_slice.py [--meshes bunny-capped,fandisk]
        [--res 256,1024,2048] [--json OUT.json] [--work DIR]

Per mesh and resolution N: the mesh is encoded once with pgvol's defaults (`pgvol encode MESH -o
X.pgv --res N`, not timed), then
  * pgvol: `pgvol slice X.pgv -o X.json --layer-height H` with H the grid spacing (one layer per
    node layer), under /usr/bin/time -v: wall seconds of the whole process (reading the file
    included) and its peak RSS;
  * the Python package, in this interpreter, as whole processes under /usr/bin/time -v too:
    `pgvol.slice_file(X.pgv, H)` (read slab by slab, as the command line reads it) and
    `pgvol.Field.load(X.pgv).slice(H)` (the whole volume decoded first), and
    `pgvol.distributed.slice(X.pgv, H, parts=8)` without a cluster (the parts one after another
    in the process, each from its own part of the file);
  * manifold3d: `Manifold.slice(z)` at the same heights in a Python loop (the mesh loaded before
    the clock starts), with each cross-section's area.
Area error is |pgvol − manifold3d| / manifold3d per layer, over the layers whose manifold3d area is
at least 1 % of the largest; the table gives its median. Ratios are pgvol / manifold3d.
Set PGVOL_BIN to time another pgvol binary.
"""

from __future__ import annotations

import argparse
import json
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import common  # noqa: E402


def timed(argv: list) -> dict:
    """Wall seconds and peak RSS (MiB) of one process under /usr/bin/time -v."""
    start = time.perf_counter()
    proc = subprocess.run(["/usr/bin/time", "-v", *map(str, argv)], capture_output=True, text=True)
    seconds = time.perf_counter() - start
    if proc.returncode != 0:
        raise SystemExit(f"{argv[1]} failed: {proc.stderr[-2000:]}")
    rss = re.search(r"Maximum resident set size \(kbytes\): (\d+)", proc.stderr)
    return {"s": seconds, "rss_mib": int(rss.group(1)) / 1024 if rss else None}


# The Python package's two ways to slice a file, each a whole process given the file and H.
PYTHON_STREAMED = "import sys, pgvol; pgvol.slice_file(sys.argv[1], float(sys.argv[2]))"
PYTHON_LOADED = "import sys, pgvol; pgvol.Field.load(sys.argv[1]).slice(float(sys.argv[2]))"
PYTHON_PARTS = (
    "import sys; from pgvol import distributed; "
    "distributed.slice(sys.argv[1], float(sys.argv[2]), parts=8)"
)


def loop_area(points) -> float:
    p = np.asarray(points, np.float64)
    if len(p) < 3:
        return 0.0
    x, y = p[:, 0], p[:, 1]
    return 0.5 * float(np.dot(x, np.roll(y, -1)) - np.dot(np.roll(x, -1), y))


def pgvol_layers(path: Path) -> tuple[list[float], list[float]]:
    """Heights and areas (holes subtracted) of a JSON layer file."""
    layers = json.loads(path.read_text())["layers"]
    heights = [float(l["height"]) for l in layers]
    areas = [sum(loop_area(lp["points"]) for lp in l["loops"]) for l in layers]
    return heights, areas


def manifold_areas(mesh_path: Path, heights: list[float]) -> tuple[float, list[float]]:
    """Seconds for Manifold.slice at every height, and the cross-sections' areas."""
    import manifold3d

    mesh = common.load_mesh(mesh_path)
    solid = manifold3d.Manifold(
        manifold3d.Mesh(
            vert_properties=np.asarray(mesh.vertices, np.float32),
            tri_verts=np.asarray(mesh.faces, np.uint32),
        )
    )
    if solid.status() != manifold3d.Error.NoError:
        raise SystemExit(f"manifold3d refuses {mesh_path.name}: {solid.status()}")
    start = time.perf_counter()
    sections = [solid.slice(h) for h in heights]
    seconds = time.perf_counter() - start
    return seconds, [s.area() for s in sections]


def run(mesh: str, res: int, work: Path) -> dict:
    pgvol = common.pgvol_bin()
    source = common.source_mesh(mesh, work)
    pgv = work / f"{mesh}-{res}.pgv"
    if not pgv.exists():
        subprocess.run([pgvol, "encode", source, "-o", pgv, "--res", str(res), "-q"], check=True)
    info = subprocess.run([pgvol, "info", pgv, "--json"], capture_output=True, text=True, check=True)
    spacing = float(json.loads(info.stdout)["header"]["grid"]["spacing"])
    out = work / f"{mesh}-{res}.json"
    ours = timed([pgvol, "slice", pgv, "-o", out, "--layer-height", repr(spacing), "-q"])
    heights, areas = pgvol_layers(out)
    streamed = timed([sys.executable, "-c", PYTHON_STREAMED, pgv, repr(spacing)])
    loaded = timed([sys.executable, "-c", PYTHON_LOADED, pgv, repr(spacing)])
    in_parts = timed([sys.executable, "-c", PYTHON_PARTS, pgv, repr(spacing)])
    peer_s, peer_areas = manifold_areas(source, heights)
    top = max(peer_areas) if peer_areas else 0.0
    errors = [abs(a - b) / b for a, b in zip(areas, peer_areas) if b >= 0.01 * top]
    return {
        "mesh": mesh,
        "res": res,
        "layers": len(heights),
        "file_mib": pgv.stat().st_size / 2**20,
        "pgvol_s": ours["s"],
        "pgvol_rss_mib": ours["rss_mib"],
        "python_slice_file_s": streamed["s"],
        "python_slice_file_rss_mib": streamed["rss_mib"],
        "python_load_slice_s": loaded["s"],
        "python_load_slice_rss_mib": loaded["rss_mib"],
        "python_parts_s": in_parts["s"],
        "python_parts_rss_mib": in_parts["rss_mib"],
        "manifold_s": peer_s,
        "ratio": ours["s"] / peer_s if peer_s > 0 else None,
        "median_area_error": float(np.median(errors)) if errors else None,
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--meshes", default="bunny-capped,fandisk")
    ap.add_argument("--res", default="256,1024,2048")
    ap.add_argument("--json", type=Path)
    ap.add_argument("--work", type=Path, help="keeps the encoded files between runs")
    args = ap.parse_args()
    work = args.work or Path(tempfile.mkdtemp(prefix="pgvol-slice-bench-"))
    work.mkdir(parents=True, exist_ok=True)
    rows = []
    print(
        "| mesh | grid | layers | .pgv | pgvol slice | peak RSS | manifold3d | ratio | median area error "
        "| Python slice_file | Python Field.load + slice | Python distributed.slice, 8 parts |"
    )
    print("|---|---|---|---|---|---|---|---|---|---|---|---|")
    for mesh in args.meshes.split(","):
        for res in (int(r) for r in args.res.split(",")):
            r = run(mesh, res, work)
            rows.append(r)
            print(
                f"| {mesh} | {res}³ | {r['layers']} | {r['file_mib']:.1f} MiB | {r['pgvol_s']:.2f} s | "
                f"{r['pgvol_rss_mib']:.0f} MiB | {r['manifold_s']:.3f} s | {r['ratio']:.1f}× | "
                f"{100 * r['median_area_error']:.3f} % | {r['python_slice_file_s']:.2f} s, "
                f"{r['python_slice_file_rss_mib']:.0f} MiB | {r['python_load_slice_s']:.2f} s, "
                f"{r['python_load_slice_rss_mib']:.0f} MiB | {r['python_parts_s']:.2f} s, "
                f"{r['python_parts_rss_mib']:.0f} MiB |",
                flush=True,
            )
    if args.json:
        args.json.write_text(json.dumps(rows, indent=1))


if __name__ == "__main__":
    main()
