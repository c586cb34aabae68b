"""Signed-distance-field timing: pgvol against peer libraries, on the pgvol grid.

Usage (normally through tools/bench/run.sh):
    python tools/bench/bench_sdf.py [--big] [--meshes stanford-bunny,fandisk]

Times in one run, per mesh and resolution (128, plus 256 with --big):
  * pgvol sdf --dense   (the seconds it reports, and the wall time of the command)
  * pysdf               (BVH build + queries)
  * libigl              signed_distance with the fast-winding-number sign
  * OpenVDB             meshToVolume narrow band (+-3 voxels), Debian's python3-openvdb
  * mesh2sdf            (optional; its own grid of the same size, timing only)
and then the sign disagreement of each method against libigl's fast winding
number at 64^3 on bunny / teapot / suzanne. Peers that are missing or fail are
reported as n/a with the reason.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import common  # noqa: E402

SYSTEM_PYTHON = os.environ.get("PGVOL_BENCH_SYSTEM_PYTHON", "/usr/bin/python3")
VDB_SCRIPT = Path(__file__).resolve().parent / "vdb_sdf.py"
VDB_HALF_WIDTH = 3.0


class NotAvailable(Exception):
    """A peer that cannot run here; the message says why."""


def install_note(package: str) -> str:
    log = Path(sys.prefix) / "install-failures" / f"{package}.log"
    if log.is_file():
        lines = [l for l in log.read_text(errors="replace").splitlines() if l.strip()]
        tail = " / ".join(lines[-2:])[-200:]
        return f"install failed ({tail})"
    return "not installed"


# ---------------------------------------------------------------------------
# Methods. Each returns (seconds, values or None, note); values are flat, x fastest,
# negative inside.
# ---------------------------------------------------------------------------


def reported_seconds(report: dict, wall: float) -> float:
    """The distance stage's seconds of a `pgvol sdf --json` report (its `seconds` holds the
    stages and their total), or the wall time when it has none."""
    seconds = report.get("seconds", wall)
    return float(seconds["sdf"] if isinstance(seconds, dict) else seconds)


def method_pgvol(mesh_path: Path, mesh, grid: common.Grid, work: Path):
    exe = common.pgvol_bin()
    if not exe.is_file():
        raise NotAvailable(f"binary missing at {exe} (cargo build --release)")
    out = work / "pgvol.nrrd"
    report, wall = common.run_json([exe, "sdf", mesh_path, "-o", out, "--res", grid.n, "--dense", "--json"])
    values = common.read_grid_x_fastest(out, grid.n)
    out.unlink(missing_ok=True)
    seconds = reported_seconds(report, wall)
    return seconds, values, f"reported {seconds:.3f} s, wall {wall:.3f} s"


def method_pgvol_band(mesh_path: Path, mesh, grid: common.Grid, work: Path):
    """The narrow band of +-3 voxels, the same band OpenVDB's row computes."""
    exe = common.pgvol_bin()
    if not exe.is_file():
        raise NotAvailable(f"binary missing at {exe} (cargo build --release)")
    out = work / "pgvol-band.nrrd"
    report, wall = common.run_json([exe, "sdf", mesh_path, "-o", out, "--res", grid.n, "--band", VDB_HALF_WIDTH, "--json"])
    values = common.read_grid_x_fastest(out, grid.n)
    out.unlink(missing_ok=True)
    seconds = reported_seconds(report, wall)
    return seconds, values, f"band +-3 voxels ({report.get('exact_nodes')} exact), {report.get('sign')} sign"


def method_pysdf(mesh_path, mesh, grid, work):
    try:
        from pysdf import SDF
    except Exception as exc:  # noqa: BLE001
        raise NotAvailable(f"{install_note('pysdf')}: {common.short_reason(exc)}") from None
    pts = grid.points().astype(np.float32)
    start = time.perf_counter()
    f = SDF(np.asarray(mesh.vertices, np.float32), np.asarray(mesh.faces, np.uint32))
    d = f(pts)
    seconds = time.perf_counter() - start
    return seconds, -np.asarray(d, np.float32), "build + query; sign by its own inside test"


def igl_fwn(vertices, faces, points):
    import igl

    res = igl.signed_distance(
        np.asarray(points, np.float64),
        np.asarray(vertices, np.float64),
        np.asarray(faces, np.int64),
        sign_type=igl.SIGNED_DISTANCE_TYPE_FAST_WINDING_NUMBER,
    )
    s = res[0] if isinstance(res, (tuple, list)) else res
    return np.asarray(s, np.float32).reshape(-1)


def method_igl(mesh_path, mesh, grid, work):
    try:
        import igl  # noqa: F401
    except Exception as exc:  # noqa: BLE001
        raise NotAvailable(f"{install_note('libigl')}: {common.short_reason(exc)}") from None
    pts = grid.points()
    start = time.perf_counter()
    values = igl_fwn(mesh.vertices, mesh.faces, pts)
    return time.perf_counter() - start, values, "fast winding number sign"


def method_openvdb(mesh_path, mesh, grid, work):
    if not Path(SYSTEM_PYTHON).is_file():
        raise NotAvailable(f"{SYSTEM_PYTHON} missing")
    probe = subprocess.run(
        [SYSTEM_PYTHON, "-c", "import pyopenvdb"], capture_output=True, text=True, stdin=subprocess.DEVNULL
    )
    if probe.returncode != 0:
        probe = subprocess.run(
            [SYSTEM_PYTHON, "-c", "import openvdb"], capture_output=True, text=True, stdin=subprocess.DEVNULL
        )
        if probe.returncode != 0:
            raise NotAvailable("python3-openvdb not importable by the system python (apt-get install python3-openvdb)")
    src, dst = work / "vdb-in.npz", work / "vdb-out.npy"
    np.savez(
        src, vertices=mesh.vertices, faces=mesh.faces, origin=grid.origin, h=grid.h, n=grid.n,
        half_width=VDB_HALF_WIDTH,
    )
    proc, wall = common.run([SYSTEM_PYTHON, VDB_SCRIPT, src, dst])
    if proc.returncode != 0:
        raise NotAvailable(f"vdb script failed: {proc.stderr.strip()[-200:]}")
    info = json.loads(proc.stdout.strip().splitlines()[-1])
    dense = np.load(dst)  # [i, j, k]
    values = dense.ravel(order="F")
    src.unlink(missing_ok=True)
    dst.unlink(missing_ok=True)
    return float(info["seconds"]), values, f"band +-{VDB_HALF_WIDTH:g} voxels only ({info['active']} active)"


def method_mesh2sdf(mesh_path, mesh, grid, work):
    try:
        import mesh2sdf
    except Exception as exc:  # noqa: BLE001
        raise NotAvailable(f"{install_note('mesh2sdf')}: {common.short_reason(exc)}") from None
    # mesh2sdf wants the mesh inside [-1, 1]^3 and samples its own cell-centred grid.
    centre = 0.5 * (mesh.bounds[0] + mesh.bounds[1])
    scale = 2.0 / grid.side
    v = ((mesh.vertices - centre) * scale).astype(np.float32)
    start = time.perf_counter()
    mesh2sdf.compute(v, np.asarray(mesh.faces, np.int32), grid.n, fix=False, level=2.0 / grid.n)
    return time.perf_counter() - start, None, "own cell-centred grid, timing only"


METHODS = [
    ("pgvol sdf --dense", method_pgvol),
    ("pgvol sdf --band 3", method_pgvol_band),
    ("pysdf", method_pysdf),
    ("libigl (FWN sign)", method_igl),
    ("OpenVDB meshToVolume", method_openvdb),
    ("mesh2sdf", method_mesh2sdf),
]


def timing_table(meshes: list[str], resolutions: list[int], work: Path) -> str:
    rows = []
    for name in meshes:
        path = common.mesh_file(name)
        mesh = common.load_mesh(path)
        for res in resolutions:
            grid = common.Grid(mesh.bounds, res)
            base_seconds = None
            base_values = None
            for label, fn in METHODS:
                print(f"  {name} {res}^3 {label} ...", file=sys.stderr, flush=True)
                try:
                    seconds, values, note = fn(path, mesh, grid, work)
                except NotAvailable as exc:
                    rows.append([name, res, label, "n/a", "n/a", "n/a", "n/a", str(exc)])
                    continue
                except Exception as exc:  # noqa: BLE001 - a peer's crash is a result, not our crash
                    rows.append([name, res, label, "n/a", "n/a", "n/a", "n/a", common.short_reason(exc)])
                    continue
                if label == "pgvol sdf --dense":
                    base_seconds, base_values = seconds, values
                ratio = f"{seconds / base_seconds:.2f}x" if base_seconds else "n/a"
                diff = "n/a"
                if values is not None and base_values is not None and label != "pgvol sdf --dense":
                    near = np.abs(base_values) <= 2.0 * grid.h  # inside every method's band
                    if near.any():
                        diff = f"{np.max(np.abs(np.abs(values[near]) - np.abs(base_values[near]))) / grid.h:.4f} h"
                rows.append([name, res, label, seconds, f"{grid.count / seconds:.3g}", ratio, diff, note])
    header = ["mesh", "res", "method", "seconds", "samples/s", "time vs pgvol", "max unsigned diff vs pgvol (|d|<=2h)", "note"]
    return common.markdown_table(header, rows)


def sign_table(meshes: list[str], res: int, work: Path) -> str:
    rows = []
    for name in meshes:
        path = common.mesh_file(name)
        mesh = common.load_mesh(path)
        grid = common.Grid(mesh.bounds, res)
        try:
            import igl  # noqa: F401

            ref = igl_fwn(mesh.vertices, mesh.faces, grid.points())
        except Exception as exc:  # noqa: BLE001
            rows.append([name, res, "all", "n/a", f"libigl reference unavailable: {common.short_reason(exc)}"])
            continue
        ref_inside = ref < 0
        for label, fn in METHODS:
            if label.startswith("libigl") or label == "mesh2sdf":
                continue
            try:
                _, values, note = fn(path, mesh, grid, work)
            except Exception as exc:  # noqa: BLE001
                rows.append([name, res, label, "n/a", common.short_reason(exc)])
                continue
            inside = values < 0
            differ = np.count_nonzero(inside != ref_inside)
            rows.append([name, res, label, f"{differ} ({100.0 * differ / grid.count:.3f} %)", note])
    header = ["mesh", "res", "method", "nodes whose sign differs from libigl FWN", "note"]
    return common.markdown_table(header, rows)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--big", action="store_true", help="also time 256^3")
    ap.add_argument("--meshes", default="stanford-bunny,fandisk", help="meshes to time (comma separated)")
    ap.add_argument("--sign-meshes", default="stanford-bunny,teapot,suzanne")
    ap.add_argument("--sign-res", type=int, default=64)
    ap.add_argument("--skip-signs", action="store_true")
    args, unknown = ap.parse_known_args(argv)  # run.sh passes the same flags to both benchmarks
    if unknown:
        print(f"bench_sdf: ignoring {' '.join(unknown)}", file=sys.stderr)

    resolutions = [128] + ([256] if args.big else [])
    work = Path(tempfile.mkdtemp(prefix="pgvol-bench-sdf-"))
    try:
        print(f"# SDF benchmark ({os.cpu_count()} cores; grid: cube 1.1 x longest extent, N nodes per axis)\n")
        print(timing_table(args.meshes.split(","), resolutions, work))
        if not args.skip_signs:
            print(f"\n## Sign disagreement against libigl fast winding number ({args.sign_res}^3)\n")
            print(sign_table(args.sign_meshes.split(","), args.sign_res, work))
    finally:
        shutil.rmtree(work, ignore_errors=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
