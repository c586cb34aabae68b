"""Bytes against Chamfer-L1: a sweep of resolutions for pgvol (.pgv, default settings), dense
float32 grids of signed distances and OpenVDB .vdb files (default and half float), each turned
into a mesh and compared with the input by `pgvol compare` (200,000 samples a side).

    tools/.venv-bench/bin/python tools/bench/bytes_curve.py [--meshes a,b] [--png OUT.png]
        [--json OUT.json] [-- extra pgvol encode arguments]

The open bunny is measured with its holes capped (tools/meshcap.py), since OpenVDB's sign needs a
closed surface. Prints markdown tables: the raw points, then for each .vdb file the pgvol error
at the same bytes and the pgvol bytes at the same error, interpolated log-log on pgvol's curve.
OpenVDB runs under the system Python with Debian's python3-openvdb (PGVOL_BENCH_SYSTEM_PYTHON).
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

from common import REPO_ROOT, pgvol_bin, source_mesh  # noqa: E402

PGV_RES = [40, 48, 64, 80, 96, 128, 160, 192, 256]
DENSE_RES = [32, 40, 48, 64, 80, 96, 128]
VDB_RES = [64, 96, 128, 192, 256]
SAMPLES = 200_000


def run(args) -> str:
    out = subprocess.run([str(a) for a in args], capture_output=True, text=True)
    if out.returncode != 0:
        raise SystemExit(f"failed: {' '.join(map(str, args))}\n{out.stderr}")
    return out.stdout


def chamfer(pgvol, mesh, reference) -> float:
    report = json.loads(run([pgvol, "compare", mesh, reference, "--samples", SAMPLES, "--json"]))
    return float(report["chamfer_l1_pct"])


def sweep(pgvol, mesh: Path, work: Path, extra) -> dict:
    points = {"pgvol": [], "dense-f32": [], "vdb": [], "vdb-half": []}
    for n in PGV_RES:
        pgv, out = work / "a.pgv", work / "a.glb"
        run([pgvol, "encode", mesh, "-o", pgv, "--res", n, "-q", *extra])
        run([pgvol, "decode", pgv, "-o", out, "-q"])
        points["pgvol"].append((n, pgv.stat().st_size, chamfer(pgvol, out, mesh)))
    for n in DENSE_RES:
        out = work / "d.glb"
        run([pgvol, "remesh", mesh, "-o", out, "--res", n, "--field", "decoded", "--basis", "trilinear", "-q"])
        points["dense-f32"].append((n, 4 * n**3, chamfer(pgvol, out, mesh)))
    system_python = os.environ.get("PGVOL_BENCH_SYSTEM_PYTHON", "/usr/bin/python3")
    script = REPO_ROOT / "tools" / "bench" / "vdb_file.py"
    for n in VDB_RES:
        try:
            info = json.loads(run([system_python, script, mesh, n, work / "v"]))
        except SystemExit as e:
            print(f"OpenVDB unavailable: {e}", file=sys.stderr)
            break
        c = chamfer(pgvol, work / "v.obj", mesh)
        points["vdb"].append((n, info["bytes"], c))
        points["vdb-half"].append((n, info["bytes_half"], c))
    return points


def loglog(x, xs, ys):
    """y at x on the piecewise log-log line through (xs, ys), xs increasing; None outside."""
    lx, lxs = np.log(x), np.log(xs)
    if lx < lxs[0] or lx > lxs[-1]:
        return None
    return float(np.exp(np.interp(lx, lxs, np.log(ys))))


def ratios(points) -> list[dict]:
    curve = sorted(points["pgvol"], key=lambda p: p[1])
    by_bytes_b = [p[1] for p in curve]
    by_bytes_c = [p[2] for p in curve]
    by_error = sorted(curve, key=lambda p: p[2])
    rows = []
    for kind in ("vdb", "vdb-half"):
        for n, b, c in points[kind]:
            ours_c = loglog(b, by_bytes_b, by_bytes_c)
            ours_b = loglog(c, [p[2] for p in by_error], [p[1] for p in by_error])
            rows.append({
                "file": kind, "res": n, "bytes": b, "chamfer": c,
                "pgvol_chamfer_at_bytes": ours_c, "error_ratio": None if ours_c is None else ours_c / c,
                "pgvol_bytes_at_chamfer": ours_b, "bytes_ratio": None if ours_b is None else ours_b / b,
            })
    return rows


def fmt(x, spec):
    return "n/a" if x is None else format(x, spec)


def plot(results: dict, path: Path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, len(results), figsize=(5 * len(results), 4.2), squeeze=False)
    styles = {"pgvol": ("o-", "pgvol .pgv"), "dense-f32": ("s--", "dense float32"),
              "vdb": ("^-", "OpenVDB .vdb"), "vdb-half": ("v:", "OpenVDB .vdb (half)")}
    for ax, (name, points) in zip(axes[0], results.items()):
        for kind, (style, label) in styles.items():
            if points[kind]:
                b = [p[1] / 1024 for p in points[kind]]
                c = [p[2] for p in points[kind]]
                ax.loglog(b, c, style, label=label, markersize=4)
        ax.set_title(name)
        ax.set_xlabel("file size (KiB)")
        ax.set_ylabel("Chamfer-L1 (% of diagonal)")
        ax.grid(True, which="both", alpha=0.3)
    axes[0][0].legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=90)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--meshes", default="bunny-capped,fandisk,spot")
    ap.add_argument("--png", type=Path)
    ap.add_argument("--json", type=Path)
    ap.add_argument("extra", nargs="*", help="extra arguments for pgvol encode")
    a = ap.parse_args()
    pgvol = pgvol_bin()
    results = {}
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        for name in a.meshes.split(","):
            print(f"{name} ...", file=sys.stderr)
            results[name] = sweep(pgvol, source_mesh(name, work), work, a.extra)
    print("| mesh | file | res | bytes | Chamfer-L1 % |\n|---|---|---|---|---|")
    for name, points in results.items():
        for kind, rows in points.items():
            for n, b, c in rows:
                print(f"| {name} | {kind} | {n} | {b:,} | {c:.5f} |")
    print("\n| mesh | .vdb file | res | bytes | Chamfer-L1 % | pgvol Chamfer-L1 at these bytes | ratio "
          "| pgvol bytes at this Chamfer-L1 | ratio |\n|---|---|---|---|---|---|---|---|---|")
    for name, points in results.items():
        for r in ratios(points):
            print(f"| {name} | {r['file']} | {r['res']} | {r['bytes']:,} | {r['chamfer']:.5f} "
                  f"| {fmt(r['pgvol_chamfer_at_bytes'], '.5f')} | {fmt(r['error_ratio'], '.2f')} "
                  f"| {fmt(r['pgvol_bytes_at_chamfer'], ',.0f')} | {fmt(r['bytes_ratio'], '.2f')} |")
    if a.json:
        a.json.write_text(json.dumps(results, indent=1))
    if a.png:
        plot(results, a.png)


if __name__ == "__main__":
    main()
