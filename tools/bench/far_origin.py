"""Meshes far from the origin: the same meshes moved by 10^6 on every axis and by -3*10^7 along
y, remeshed and encoded/decoded by pgvol, against the same jobs at the origin. Accuracy is
measured against the moved input with trimesh (volume, Chamfer-L1 by closest points) and
pgvol compare (Hausdorff); time shows what the local frame costs.

Usage: python tools/bench/far_origin.py [--res 64 128] [--meshes cube torus-knot stanford-bunny]
       [--quick]   (one mesh at 48^3, for a check that the script runs)
Prints two tables: accuracy (independent of the machine's load) and seconds per job.
"""

from __future__ import annotations

import argparse
import tempfile
from pathlib import Path

import numpy as np
import trimesh

import common

SHIFTS = {
    "origin": np.zeros(3),
    "1e6 (x, y, z)": np.array([1e6, 1e6, 1e6]),
    "-3e7 (y)": np.array([0.0, -3e7, 0.0]),
}


def mesh_source(name: str, work: Path) -> Path:
    if name == "cube":
        path = work / "cube.obj"
        box = trimesh.creation.box(extents=(1.0, 1.0, 1.0))
        box.apply_translation([0.5, 0.5, 0.5])
        write_obj(path, box.vertices, box.faces)
        return path
    if name == "torus-knot":
        return common.REPO_ROOT / "fixtures" / "torus-knot.obj"
    return common.mesh_file(name)


def write_obj(path: Path, vertices, faces) -> None:
    with open(path, "w") as f:
        for p in np.asarray(vertices, np.float64):
            f.write("v %r %r %r\n" % tuple(float(c) for c in p))
        for t in np.asarray(faces):
            f.write("f %d %d %d\n" % tuple(t + 1))


def chamfer_pct(a: trimesh.Trimesh, b: trimesh.Trimesh, count: int = 20_000) -> float:
    """Chamfer-L1 (mean of the two mean closest-point distances) in % of b's diagonal."""
    rng_a, _ = trimesh.sample.sample_surface(a, count, seed=1)
    rng_b, _ = trimesh.sample.sample_surface(b, count, seed=2)
    d_ab = np.abs(trimesh.proximity.closest_point(b, rng_a)[1]).mean()
    d_ba = np.abs(trimesh.proximity.closest_point(a, rng_b)[1]).mean()
    return 100.0 * 0.5 * (d_ab + d_ba) / np.linalg.norm(b.extents)


def measure(pgvol: Path, source: Path, out: Path, shift: np.ndarray) -> dict:
    """Accuracy of `out` against `source`, both brought back to the origin in f64."""
    ref = common.load_mesh(source)
    got = common.load_mesh(out)
    ref.apply_translation(-shift)
    got.apply_translation(-shift)
    compare, _ = common.run_json([pgvol, "compare", source, out, "--json", "--samples", 100_000])
    return {
        "volume": got.volume / ref.volume - 1.0,
        "chamfer": chamfer_pct(got, ref),
        "hausdorff": compare["hausdorff_pct"],
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--res", type=int, nargs="+", default=[64, 128])
    ap.add_argument("--meshes", nargs="+", default=["cube", "torus-knot", "stanford-bunny"])
    ap.add_argument("--quick", action="store_true")
    args = ap.parse_args()
    if args.quick:
        args.res, args.meshes = [48], ["cube"]
    pgvol = common.pgvol_bin()
    rows, times = [], []
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        for name in args.meshes:
            base = common.load_mesh(mesh_source(name, work))
            for label, shift in SHIFTS.items():
                source = work / f"{name}-{label.split()[0]}.obj"
                write_obj(source, base.vertices + shift, base.faces)
                for res in args.res:
                    try:
                        out = work / "remesh.obj"
                        report, _ = common.run_json([pgvol, "remesh", source, "-o", out, "--res", res, "--json"])
                        remesh = measure(pgvol, source, out, shift)
                        pgv, dec = work / "f.pgv", work / "decode.obj"
                        enc, _ = common.run_json([pgvol, "encode", source, "-o", pgv, "--res", res, "--json"])
                        de, _ = common.run_json([pgvol, "decode", pgv, "-o", dec, "--json"])
                        decode = measure(pgvol, source, dec, shift)
                    except RuntimeError as e:
                        # A build that cannot handle the position (PGVOL_BIN of an older one).
                        rows.append([name, label, f"{res}³", common.short_reason(e), "", "", "", ""])
                        continue
                    rows.append([
                        name, label, f"{res}³",
                        remesh["hausdorff"], remesh["chamfer"], remesh["volume"] * 100,
                        decode["hausdorff"], decode["chamfer"],
                    ])
                    times.append([
                        name, label, f"{res}³", report["seconds"]["total"],
                        enc["seconds"]["total"] + de["seconds"]["total"],
                    ])
    print(common.markdown_table(
        ["mesh", "shift", "grid", "remesh Hausdorff %", "remesh Chamfer %", "remesh volume error %",
         "encode+decode Hausdorff %", "encode+decode Chamfer %"],
        rows,
    ))
    print()
    print(common.markdown_table(["mesh", "shift", "grid", "remesh s", "encode+decode s"], times))


if __name__ == "__main__":
    main()
