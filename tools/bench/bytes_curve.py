"""Bytes against Chamfer-L1: a sweep of resolutions for pgvol (.pgv, default settings), dense
float32 grids of signed distances and OpenVDB .vdb files (default and half float), of function
budgets for the perturbation method (`pgvol perturb`), and of decimation ratios for quadric
decimation plus Draco (fast-simplification, then DracoPy at 14-bit positions), each turned into
a mesh and compared with the input by `pgvol compare` (200,000 samples a side). Each point also
carries the perturbation paper's three measures, from `pgvol compare INPUT OUTPUT`: the mean
distance of the input's vertices to the output (% of the diagonal), the mean angle between their
normals and the output's, and the mean depth-buffer difference over 14 views (%).

    tools/.venv-bench/bin/python tools/bench/bytes_curve.py [--meshes a,b] [--methods m,n]
        [--quick] [--png OUT.png] [--json OUT.json] [-- extra pgvol encode arguments]

Methods: pgvol, dense, vdb, perturb, draco (all by default). Perturbation bytes are given twice:
"perturb-list" is the size of the function-list .pgv file `pgvol perturb` writes by default
(encoding perturbation-f64), "perturb-pgv" the size of the coefficient volume it writes with
--resample 128; both contour to the same mesh, which `pgvol decode` makes from the list. --quick runs two points per method (a check that
everything runs, not a measurement).

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
PERTURB_FUNCTIONS = [50, 100, 200, 500, 1000, 2038]
PERTURB_RESAMPLE = 128
# Fraction of the triangles kept by quadric decimation before Draco.
DRACO_KEEP = [0.01, 0.02, 0.05, 0.1, 0.25, 0.5, 1.0]
DRACO_BITS = 14
SAMPLES = 200_000


def run(args) -> str:
    out = subprocess.run([str(a) for a in args], capture_output=True, text=True)
    if out.returncode != 0:
        raise SystemExit(f"failed: {' '.join(map(str, args))}\n{out.stderr}")
    return out.stdout


def chamfer(pgvol, mesh, reference) -> tuple:
    """Chamfer-L1 %, the paper's three measures of the input's vertices against `mesh`, and the
    pieces of `mesh`."""
    report = json.loads(run([pgvol, "compare", mesh, reference, "--samples", SAMPLES, "--json"]))
    paper = json.loads(run([pgvol, "compare", reference, mesh, "--samples", 1000, "--json"]))
    return (
        float(report["chamfer_l1_pct"]),
        float(paper["vertex_deviation_mean_pct"]),
        float(paper["vertex_deviation"]["normal_mean_deg"]),
        float(paper["depth_buffer_pct"]),
        int(report["a"]["components"]),
    )


def perturb_points(pgvol, mesh: Path, work: Path, budgets) -> dict:
    points = {"perturb-list": [], "perturb-pgv": []}
    for n in budgets:
        listed, pgv, out = work / "p-list.pgv", work / "p.pgv", work / "p.obj"
        report = json.loads(run([pgvol, "perturb", mesh, "-o", listed, "--max-functions", n,
                                 "--json"]))
        run([pgvol, "perturb", mesh, "-o", pgv, "--max-functions", n,
             "--resample", PERTURB_RESAMPLE, "-q"])
        # The list records the default 128-node grid, so its decode is that of the volume.
        run([pgvol, "decode", listed, "-o", out, "--min-component", 0, "-q"])
        functions = (report["perturbation"]["functions"] + report["cleanup"]["bumps"]
                     + report["strays"]["nodes"])
        m = chamfer(pgvol, out, mesh)
        points["perturb-list"].append((functions, listed.stat().st_size, *m))
        points["perturb-pgv"].append((functions, pgv.stat().st_size, *m))
    return points


def draco_points(pgvol, mesh: Path, work: Path, keeps) -> dict:
    import DracoPy
    import fast_simplification

    sys.path.insert(0, str(REPO_ROOT / "tools"))
    from meshcap import write_obj
    from objfile import read_obj

    v, f = read_obj(mesh)
    v, f = np.asarray(v, np.float32), np.asarray(f, np.int32)
    points = {"decimate+draco": []}
    for keep in keeps:
        if keep < 1.0:
            dv, df = fast_simplification.simplify(v, f, target_reduction=1.0 - keep)
        else:
            dv, df = v, f
        blob = DracoPy.encode(np.asarray(dv, np.float32), np.asarray(df, np.uint32),
                              quantization_bits=DRACO_BITS)
        back = DracoPy.decode(blob)
        out = work / "draco.obj"
        write_obj(out, np.asarray(back.points, np.float64).reshape(-1, 3),
                  np.asarray(back.faces, np.int64).reshape(-1, 3))
        points["decimate+draco"].append((len(df), len(blob), *chamfer(pgvol, out, mesh)))
    return points


def sweep(pgvol, mesh: Path, work: Path, extra, methods, quick) -> dict:
    pick = (lambda xs: [xs[len(xs) // 3], xs[-2]]) if quick else (lambda xs: xs)
    points = {"pgvol": [], "dense-f32": [], "vdb": [], "vdb-half": []}
    if "perturb" in methods:
        points.update(perturb_points(pgvol, mesh, work, pick(PERTURB_FUNCTIONS)))
    if "draco" in methods:
        points.update(draco_points(pgvol, mesh, work, pick(DRACO_KEEP)))
    for n in pick(PGV_RES) if "pgvol" in methods else []:
        pgv, out = work / "a.pgv", work / "a.glb"
        run([pgvol, "encode", mesh, "-o", pgv, "--res", n, "-q", *extra])
        run([pgvol, "decode", pgv, "-o", out, "-q"])
        points["pgvol"].append((n, pgv.stat().st_size, *chamfer(pgvol, out, mesh)))
    for n in pick(DENSE_RES) if "dense" in methods else []:
        out = work / "d.glb"
        run([pgvol, "remesh", mesh, "-o", out, "--res", n, "--field", "decoded", "--basis", "trilinear", "-q"])
        points["dense-f32"].append((n, 4 * n**3, *chamfer(pgvol, out, mesh)))
    system_python = os.environ.get("PGVOL_BENCH_SYSTEM_PYTHON", "/usr/bin/python3")
    script = REPO_ROOT / "tools" / "bench" / "vdb_file.py"
    for n in pick(VDB_RES) if "vdb" in methods else []:
        try:
            info = json.loads(run([system_python, script, mesh, n, work / "v"]))
        except SystemExit as e:
            print(f"OpenVDB unavailable: {e}", file=sys.stderr)
            break
        m = chamfer(pgvol, work / "v.obj", mesh)
        points["vdb"].append((n, info["bytes"], *m))
        points["vdb-half"].append((n, info["bytes_half"], *m))
    return points


def loglog(x, xs, ys):
    """y at x on the piecewise log-log line through (xs, ys), xs increasing; None outside."""
    lx, lxs = np.log(x), np.log(xs)
    if lx < lxs[0] or lx > lxs[-1]:
        return None
    return float(np.exp(np.interp(lx, lxs, np.log(ys))))


def ratios(points, kinds=("vdb", "vdb-half")) -> list[dict]:
    curve = sorted(points["pgvol"], key=lambda p: p[1])
    if len(curve) < 2:
        return []
    by_bytes_b = [p[1] for p in curve]
    by_bytes_c = [p[2] for p in curve]
    by_error = sorted(curve, key=lambda p: p[2])
    rows = []
    for kind in kinds:
        for n, b, c, *_ in points.get(kind, []):
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
              "vdb": ("^-", "OpenVDB .vdb"), "vdb-half": ("v:", "OpenVDB .vdb (half)"),
              "perturb-list": ("d-", "perturbation list"), "perturb-pgv": ("D:", "perturbation .pgv"),
              "decimate+draco": ("x-", "decimation + Draco")}
    for ax, (name, points) in zip(axes[0], results.items()):
        for kind, (style, label) in styles.items():
            if points.get(kind):
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
    ap.add_argument("--meshes", default="bunny-capped,fandisk,spot,cow")
    ap.add_argument("--methods", default="pgvol,dense,vdb,perturb,draco")
    ap.add_argument("--quick", action="store_true", help="two points per method, to check the run")
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
            results[name] = sweep(pgvol, source_mesh(name, work), work, a.extra,
                                  a.methods.split(","), a.quick)
    print("| mesh | file | res / functions / triangles | bytes | Chamfer-L1 % | vertex dev. % "
          "| normal dev. deg | depth-buffer diff. % | components |\n|---|---|---|---|---|---|---|---|---|")
    for name, points in results.items():
        for kind, rows in points.items():
            for n, b, c, v, nd, d, comp in rows:
                print(f"| {name} | {kind} | {n} | {b:,} | {c:.5f} | {v:.5f} | {nd:.2f} | {d:.4f} | {comp} |")
    print("\n| mesh | other file | res | bytes | Chamfer-L1 % | pgvol Chamfer-L1 at these bytes | ratio "
          "| pgvol bytes at this Chamfer-L1 | ratio |\n|---|---|---|---|---|---|---|---|---|")
    for name, points in results.items():
        for r in ratios(points, ("vdb", "vdb-half", "perturb-list", "decimate+draco")):
            print(f"| {name} | {r['file']} | {r['res']} | {r['bytes']:,} | {r['chamfer']:.5f} "
                  f"| {fmt(r['pgvol_chamfer_at_bytes'], '.5f')} | {fmt(r['error_ratio'], '.2f')} "
                  f"| {fmt(r['pgvol_bytes_at_chamfer'], ',.0f')} | {fmt(r['bytes_ratio'], '.2f')} |")
    if a.json:
        a.json.write_text(json.dumps(results, indent=1))
    if a.png:
        plot(results, a.png)


if __name__ == "__main__":
    main()
