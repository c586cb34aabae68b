"""`pgvol points` and `pgvol contours` against peers, in one run.

Usage (normally through tools/bench/run.sh points):
    python tools/bench/bench_points.py [--meshes a,b,...] [--points N] [--res N] [--quick]

Three tables, each row one mesh:
  1. Points with normals (N area-uniform samples, default 100k, triangle normals):
     pgvol points --method spline, tangent and rbf-wendland at --res (default 128), against Open3D's
     screened Poisson reconstruction, its depth chosen so its triangle count is nearest
     pgvol's. Wall time, peak RSS (both whole processes, /usr/bin/time -v), triangles,
     watertightness and Chamfer-L1 to the true mesh (pgvol compare, % of the diagonal).
  2. rbf-wendland (and spline) against scipy's RBFInterpolator (thin-plate spline, the same
     on- and off-surface constraints, the field sampled on a 64³ grid and contoured by
     scikit-image marching cubes) at 2 500, 5 000, 10 000 and 20 000 points. scipy's dense
     solve is over the constraints (two per point), (2n)² doubles and about (2n)³ operations:
     up to DENSE_MAX points it runs dense, above with `neighbors=` (a thin-plate fit to the
     nearest constraints of each evaluation point; 20 000 points dense would need 12.8 GB).
     pgvol alone at 1M points.
  3. Contours: the mesh sliced into 20 and 40 layers (pgvol slice, JSON), rebuilt by
     pgvol contours, against rasterising each layer, interpolating linearly between the
     layers and marching cubes (numpy and scikit-image), at the same grid; plus how far the
     input contours are from the rebuilt surface's slices at the same planes.
Peers run in a child process of this script (`--peer ...`) so their time and memory are
measured the same way as pgvol's. --quick: one mesh, 20k points, 64³, for a check.
--tables points,rbf,contours picks the tables (default all three).
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import common  # noqa: E402
from bench_scale import timed  # noqa: E402

DEFAULT_MESHES = "spot,fandisk"
# scipy evaluates its global RBF at every node: a coarser grid keeps it within minutes.
RBF_RES = 64
DENSE_MAX = 5_000
SCIPY_NEIGHBOURS = 64
TIMEOUT = 600.0
# scipy's fits at 10k and 20k points take minutes.
SCIPY_TIMEOUT = 900.0


def sample(mesh, n: int, seed: int = 1):
    import trimesh

    points, faces = trimesh.sample.sample_surface(mesh, n, seed=seed)
    return points.astype(np.float32), mesh.face_normals[faces].astype(np.float32)


def write_xyz(path: Path, points, normals=None) -> None:
    cols = points if normals is None else np.hstack([points, normals])
    np.savetxt(path, cols, fmt="%.7g")


def chamfer(exe: Path, out: Path, src: Path) -> float:
    report, _ = common.run_json([exe, "compare", out, src, "--json"])
    return float(report["chamfer_l1_pct"])


def mesh_facts(path: Path) -> tuple[int, bool]:
    m = common.load_mesh(path)
    return len(m.faces), bool(m.is_watertight)


# ---- peers, run as `bench_points.py --peer KIND ...` in a measured child process ----

def peer_poisson(cloud: Path, out: Path, depth: int) -> None:
    import open3d as o3d

    data = np.loadtxt(cloud, dtype=np.float64)
    pcd = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(data[:, :3]))
    pcd.normals = o3d.utility.Vector3dVector(data[:, 3:6])
    mesh, _ = o3d.geometry.TriangleMesh.create_from_point_cloud_poisson(pcd, depth=depth)
    o3d.io.write_triangle_mesh(str(out), mesh)


def grid_nodes(lo, hi, res: int):
    g = common.Grid((lo, hi), res)
    axis = g.origin[0] + g.h * np.arange(res), g.origin[1] + g.h * np.arange(res), g.origin[2] + g.h * np.arange(res)
    return g, axis


def contour_to(values, g, out: Path) -> None:
    import trimesh
    from skimage.measure import marching_cubes

    verts, faces, _, _ = marching_cubes(values, level=0.0, spacing=(g.h, g.h, g.h))
    trimesh.Trimesh(verts + g.origin, faces[:, ::-1], process=True).export(out)


def peer_scipy(cloud: Path, out: Path, res: int, neighbors: int | None = None) -> None:
    from scipy.interpolate import RBFInterpolator

    data = np.loadtxt(cloud, dtype=np.float64)
    p, n = data[:, :3], data[:, 3:6]
    lo, hi = p.min(0), p.max(0)
    eps = 0.5 * np.sqrt(((hi - lo) ** 2).sum()) / np.sqrt(len(p))
    # The constraints pgvol uses: each point at 0, one off-surface point per point at
    # +eps or -eps along its normal, alternating.
    side = np.where(np.arange(len(p)) % 2 == 0, 1.0, -1.0)
    centres = np.vstack([p, p + eps * side[:, None] * n])
    values = np.concatenate([np.zeros(len(p)), eps * side])
    rbf = RBFInterpolator(centres, values, kernel="thin_plate_spline", neighbors=neighbors)
    g, (x, y, z) = grid_nodes(lo, hi, res)
    X, Y, Z = np.meshgrid(x, y, z, indexing="ij")
    field = rbf(np.column_stack([X.ravel(), Y.ravel(), Z.ravel()])).reshape(X.shape)
    contour_to(field, g, out)


def peer_slices(layers_json: Path, out: Path, res: int) -> None:
    """Rasterise each layer (even-odd), signed 2D distance by scipy's EDT, linear
    interpolation between layers, marching cubes."""
    from matplotlib.path import Path as MplPath
    from scipy.ndimage import distance_transform_edt

    layers = json.loads(layers_json.read_text())["layers"]
    pts = np.array([p for l in layers for lp in l["loops"] for p in lp["points"]])
    heights = np.array([l["height"] for l in layers])
    lo = np.array([pts[:, 0].min(), pts[:, 1].min(), heights.min()])
    hi = np.array([pts[:, 0].max(), pts[:, 1].max(), heights.max()])
    g, (x, y, z) = grid_nodes(lo, hi, res)
    X, Y = np.meshgrid(x, y, indexing="ij")
    xy = np.column_stack([X.ravel(), Y.ravel()])
    sdf2 = []
    for l in layers:
        inside = np.zeros(len(xy), bool)
        for lp in l["loops"]:
            inside ^= MplPath(np.array(lp["points"])).contains_points(xy)
        inside = inside.reshape(X.shape)
        d = distance_transform_edt(~inside) - distance_transform_edt(inside)
        sdf2.append(d * g.h)
    sdf2 = np.array(sdf2)
    field = np.full((res, res, res), g.h * 4, np.float64)
    for k, zk in enumerate(z):
        if zk < heights[0] or zk > heights[-1]:
            continue
        i = min(np.searchsorted(heights, zk, side="right") - 1, len(heights) - 2)
        t = (zk - heights[i]) / max(heights[i + 1] - heights[i], 1e-12)
        field[:, :, k] = (1 - t) * sdf2[i] + t * sdf2[i + 1]
    contour_to(field, g, out)


# ---- the tables ----

def run_case(argv, timeout: float = TIMEOUT) -> dict:
    return timed([str(a) for a in argv], timeout)


def cell(run: dict, key: str, fmt: str) -> str:
    return format(run[key], fmt) if run.get("status") == "ok" else "n/a"


def points_table(exe, meshes, n, res, work) -> str:
    rows = []
    for name in meshes:
        src = common.mesh_file(name)
        mesh = common.load_mesh(src)
        cloud = work / f"{name}-{n}.xyz"
        write_xyz(cloud, *sample(mesh, n))
        results = {}
        for method in ["spline", "tangent", "rbf-wendland"]:
            out = work / f"{name}-{method}.glb"
            run = run_case([exe, "points", cloud, "-o", out, "--method", method, "--res", res, "--json"])
            if run["status"] == "ok":
                run["tris"], run["watertight"] = mesh_facts(out)
                run["chamfer"] = chamfer(exe, out, src)
            results[method] = run
        target = results["spline"].get("tris", 200_000)
        best = None
        for depth in [6, 7, 8, 9]:
            out = work / f"{name}-poisson-{depth}.ply"
            run = run_case([sys.executable, __file__, "--peer", "poisson", cloud, out, depth])
            if run["status"] != "ok":
                best = best or run
                continue
            run["tris"], run["watertight"] = mesh_facts(out)
            run["depth"] = depth
            if best is None or best.get("status") != "ok" or abs(run["tris"] - target) < abs(best["tris"] - target):
                best = run
                best["out"] = out
        if best and best.get("status") == "ok":
            best["chamfer"] = chamfer(exe, best["out"], src)
        results["poisson"] = best or {"status": "failed"}
        for label, r in [("pgvol spline", results["spline"]), ("pgvol tangent", results["tangent"]),
                         ("pgvol rbf-wendland", results["rbf-wendland"]),
                         (f"Open3D Poisson (depth {results['poisson'].get('depth', '?')})", results["poisson"])]:
            rows.append([name, label, cell(r, "seconds", ".2f"), cell(r, "rss_mib", ".0f"), r.get("tris", "n/a"),
                         r.get("watertight", "n/a"), cell(r, "chamfer", ".4f")])
    return common.markdown_table(["mesh", "method", "time (s)", "peak RSS (MiB)", "triangles", "watertight",
                                  "Chamfer-L1 (%)"], rows)


def rbf_table(exe, name, sizes, alone, res, work) -> str:
    src = common.mesh_file(name)
    mesh = common.load_mesh(src)
    rows = []
    for n in sizes + alone:
        cloud = work / f"{name}-rbf-{n}.xyz"
        write_xyz(cloud, *sample(mesh, n, seed=2))
        ours = {}
        for method in ["rbf-wendland", "spline"]:
            out = work / f"rbf-{n}-{method}.glb"
            run = run_case([exe, "points", cloud, "-o", out, "--method", method, "--res", res, "--json"])
            if run["status"] == "ok":
                run["chamfer"] = chamfer(exe, out, src)
            ours[method] = run
        theirs = {"status": "n/a"}
        if n in sizes:
            out = work / f"scipy-{n}.ply"
            kind = "scipy" if n <= DENSE_MAX else "scipy-local"
            theirs = run_case([sys.executable, __file__, "--peer", kind, cloud, out, res], SCIPY_TIMEOUT)
            theirs["mode"] = "dense" if n <= DENSE_MAX else f"{SCIPY_NEIGHBOURS} neighbours"
            if theirs["status"] == "ok":
                theirs["chamfer"] = chamfer(exe, out, src)
        w = ours["rbf-wendland"]
        rows.append([n, 2 * n, cell(w, "seconds", ".2f"), cell(w, "rss_mib", ".0f"), cell(w, "chamfer", ".4f"),
                     cell(ours["spline"], "seconds", ".2f"), cell(ours["spline"], "chamfer", ".4f"),
                     theirs.get("mode", "n/a"), cell(theirs, "seconds", ".2f"), cell(theirs, "rss_mib", ".0f"),
                     cell(theirs, "chamfer", ".4f")])
    return common.markdown_table(["points", "constraints", "rbf-wendland time (s)", "rbf-wendland RSS (MiB)",
                                  "rbf-wendland Chamfer-L1 (%)", "spline time (s)", "spline Chamfer-L1 (%)",
                                  "scipy solve", "scipy time (s)", "scipy RSS (MiB)", "scipy Chamfer-L1 (%)"], rows)


def contour_table(exe, meshes, res, work) -> str:
    rows = []
    for name in meshes:
        src = common.mesh_file(name)
        mesh = common.load_mesh(src)
        height = float(mesh.bounds[1][2] - mesh.bounds[0][2])
        for count in [20, 40]:
            layers = work / f"{name}-{count}.json"
            common.run_json([exe, "slice", src, "-o", layers, "--layer-height", height / count, "--json"])
            out = work / f"{name}-{count}-contours.glb"
            ours = run_case([exe, "contours", layers, "-o", out, "--res", res, "--json"])
            if ours["status"] == "ok":
                ours["tris"], ours["watertight"] = mesh_facts(out)
                ours["chamfer"] = chamfer(exe, out, src)
            base_out = work / f"{name}-{count}-baseline.ply"
            base = run_case([sys.executable, __file__, "--peer", "slices", layers, base_out, res])
            if base["status"] == "ok":
                base["tris"], base["watertight"] = mesh_facts(base_out)
                base["chamfer"] = chamfer(exe, base_out, src)
            ratio = (f"{ours['chamfer'] / base['chamfer']:.2f}"
                     if "chamfer" in ours and "chamfer" in base else "n/a")
            rows.append([name, count, cell(ours, "seconds", ".2f"), ours.get("watertight", "n/a"),
                         cell(ours, "chamfer", ".4f"), cell(base, "seconds", ".2f"), base.get("watertight", "n/a"),
                         cell(base, "chamfer", ".4f"), ratio])
    return common.markdown_table(["mesh", "layers", "pgvol time (s)", "watertight", "pgvol Chamfer-L1 (%)",
                                  "baseline time (s)", "baseline watertight", "baseline Chamfer-L1 (%)",
                                  "ratio"], rows)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--meshes", default=DEFAULT_MESHES)
    ap.add_argument("--contour-meshes", default="spot,fandisk,cow")
    ap.add_argument("--points", type=int, default=100_000)
    ap.add_argument("--res", type=int, default=128)
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--tables", default="points,rbf,contours")
    ap.add_argument("--peer", nargs=4, metavar=("KIND", "IN", "OUT", "ARG"))
    args = ap.parse_args(argv)
    if args.peer:
        kind, src, out, arg = args.peer
        peers = {
            "poisson": peer_poisson,
            "scipy": peer_scipy,
            "scipy-local": lambda c, o, r: peer_scipy(c, o, r, SCIPY_NEIGHBOURS),
            "slices": peer_slices,
        }
        peers[kind](Path(src), Path(out), int(arg))
        return 0
    exe = common.pgvol_bin()
    meshes = args.meshes.split(",")
    sizes, alone = [2_500, 5_000, 10_000, 20_000], [1_000_000]
    if args.quick:
        meshes, args.points, args.res, sizes, alone = meshes[:1], 20_000, 64, [1_000], [50_000]
    tables = args.tables.split(",")
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        if "points" in tables:
            print(f"### Points with normals ({args.points} samples, {args.res}^3)\n")
            print(points_table(exe, meshes, args.points, args.res, work))
        if "rbf" in tables:
            print(f"\n### rbf-wendland and scipy RBFInterpolator ({meshes[0]}, {RBF_RES}^3)\n")
            print(rbf_table(exe, meshes[0], sizes, alone, RBF_RES, work))
        if "contours" in tables:
            print(f"\n### Contours, 20 and 40 layers ({args.res}^3)\n")
            contour_meshes = meshes if args.quick else args.contour_meshes.split(",")
            print(contour_table(exe, contour_meshes, args.res, work))
    return 0


if __name__ == "__main__":
    sys.exit(main())
