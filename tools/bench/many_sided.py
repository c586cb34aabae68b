"""A cylinder with many sides and polygon caps: its walls are needle triangles (2 long, 2*pi/N
wide) and its caps single N-gons, the input on which distance and winding-number queries are
hardest. pgvol remesh (default sign, and the pseudonormal sign the closed mesh allows) against
OpenVDB's meshToVolume + volumeToMesh (caps fan-triangulated by its reader), on the same grids.

Usage: python tools/bench/many_sided.py [--sides 50000] [--res 64 128 256] [--no-openvdb]
       [--quick]   (5,000 sides at 48^3, for a check that the script runs)
Prints one table: wall seconds of the whole process, pgvol's sampling and contouring seconds,
and the output's accuracy against the cylinder (pgvol compare: Hausdorff; trimesh: volume,
watertightness, pieces).
"""

from __future__ import annotations

import argparse
import math
import subprocess
import tempfile
from pathlib import Path

import common

HERE = Path(__file__).resolve().parent
VDB_SCRIPT = HERE / "vdb_scale.py"


def write_cylinder(path: Path, sides: int) -> float:
    """Radius 1, z from -1 to 1, caps as one face each (the bottom listed clockwise seen from
    above, so both face outward); returns the prism's exact volume."""
    with open(path, "w") as f:
        for z in (-1.0, 1.0):
            for i in range(sides):
                a = 2.0 * math.pi * i / sides
                f.write(f"v {math.cos(a):.9f} {math.sin(a):.9f} {z}\n")
        f.write("f " + " ".join(str(i + 1) for i in reversed(range(sides))) + "\n")
        f.write("f " + " ".join(str(sides + i + 1) for i in range(sides)) + "\n")
        for i in range(sides):
            j = (i + 1) % sides
            f.write(f"f {i + 1} {j + 1} {sides + j + 1} {sides + i + 1}\n")
    return 2.0 * sides / 2.0 * math.sin(2.0 * math.pi / sides)


def accuracy(pgvol: Path, source: Path, out: Path, volume: float) -> list[object]:
    mesh = common.load_mesh(out)
    compare, _ = common.run_json([pgvol, "compare", source, out, "--json", "--samples", 100_000])
    pieces = len(mesh.split(only_watertight=False))
    return [compare["hausdorff_pct"], 100.0 * (mesh.volume / volume - 1.0), bool(mesh.is_watertight), pieces]


def openvdb_available() -> bool:
    probe = subprocess.run(
        [common.SYSTEM_PYTHON, "-c", f"import sys; sys.path.insert(0, {str(HERE)!r}); import vdb_scale"],
        capture_output=True,
    )
    return probe.returncode == 0


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sides", type=int, default=50_000)
    ap.add_argument("--res", type=int, nargs="+", default=[64, 128, 256])
    ap.add_argument("--no-openvdb", action="store_true")
    ap.add_argument("--quick", action="store_true")
    args = ap.parse_args()
    if args.quick:
        args.sides, args.res = 5_000, [48]
    with_vdb = not args.no_openvdb and openvdb_available()
    pgvol = common.pgvol_bin()
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        source = work / "cylinder.obj"
        volume = write_cylinder(source, args.sides)
        for res in args.res:
            for label, extra in (("pgvol remesh", []), ("pgvol remesh --sign pseudonormal", ["--sign", "pseudonormal"])):
                out = work / "remesh.ply"
                report, wall = common.run_json([pgvol, "remesh", source, "-o", out, "--res", res, "--json", *extra])
                seconds = report["seconds"]
                rows.append([f"{res}³", label, wall, seconds["sdf"], seconds["contour"],
                             *accuracy(pgvol, source, out, volume)])
            if with_vdb:
                vdb, ply = work / "c.vdb", work / "vdb.ply"
                _, enc = common.run_json([common.SYSTEM_PYTHON, VDB_SCRIPT, "encode", source, res, vdb])
                _, dec = common.run_json([common.SYSTEM_PYTHON, VDB_SCRIPT, "decode", vdb, ply])
                rows.append([f"{res}³", "OpenVDB meshToVolume + volumeToMesh", enc + dec, "", "",
                             *accuracy(pgvol, source, ply, volume)])
    print(f"{args.sides:,} sides")
    print()
    print(common.markdown_table(
        ["grid", "job", "wall s", "sampling s", "contouring s", "Hausdorff %", "volume error %",
         "watertight", "pieces"],
        rows,
    ))


if __name__ == "__main__":
    main()
