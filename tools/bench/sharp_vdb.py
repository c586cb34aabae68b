"""Sharp edges at equal bytes: pgvol's dual contouring with the sharp section against OpenVDB's
volumeToMesh of a level set stored in as many bytes.

For each part, `pgvol encode P --res N --sharp auto` gives the file's bytes; OpenVDB's level set
(meshToVolume, a +-3 voxel band, saved as half floats, the smaller of its two files) is built on
the same kind of grid (a cube of side 1.1 x the longest extent) with the resolution whose file
comes closest to those bytes (two secant steps on bytes ~ resolution^2), and meshed with
volumeToMesh (adaptivity 0). Both meshes are measured against the input with `pgvol compare
--samples 50000`: mean normal deviation in degrees (volumeToMesh's faces turned outward first),
Hausdorff in spacings of pgvol's grid.

Usage: python tools/bench/sharp_vdb.py [--res 128] [--parts a,b,...]
OpenVDB runs under the system Python with Debian's python3-openvdb (tools/bench/vdb_file.py).
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import common  # noqa: E402
from bench_sharp import compare, part_path  # noqa: E402

PARTS = "plate-three-holes,boxes-45,hex-nut,fandisk,rocker-arm"
VDB_FILE = Path(__file__).resolve().parent / "vdb_file.py"


def openvdb(src: Path, res: int, prefix: Path) -> dict:
    out = subprocess.run(
        [common.SYSTEM_PYTHON, str(VDB_FILE), str(src), str(res), str(prefix)],
        check=True,
        capture_output=True,
        text=True,
    )
    return json.loads(out.stdout.strip().splitlines()[-1])


def flipped(obj: Path) -> Path:
    """The OBJ with every face's winding reversed: volumeToMesh winds its polygons the other way
    round from the input's outward convention, and the normal deviation is oriented."""
    out = obj.with_name(obj.stem + "-outward.obj")
    with obj.open() as src, out.open("w") as dst:
        for line in src:
            if line.startswith("f "):
                line = "f " + " ".join(reversed(line.split()[1:])) + "\n"
            dst.write(line)
    return out


def at_bytes(src: Path, target: int, start: int, work: Path) -> tuple[int, dict, Path]:
    """OpenVDB's resolution whose half-float file is closest to `target` bytes."""
    tried: dict[int, dict] = {}
    res = start
    for _ in range(3):
        if res in tried:
            break
        tried[res] = openvdb(src, res, work / f"vdb-{res}")
        res = max(8, round(res * (target / tried[res]["bytes_half"]) ** 0.5))
    best = min(tried, key=lambda r: abs(tried[r]["bytes_half"] - target))
    return best, tried[best], flipped(work / f"vdb-{best}.obj")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--res", type=int, default=128)
    parser.add_argument("--parts", default=PARTS)
    args = parser.parse_args()
    exe = common.pgvol_bin()
    print(
        "| part | pgvol bytes | DC + sharp: normals, Hausdorff | OpenVDB resolution | "
        "OpenVDB bytes | volumeToMesh: normals, Hausdorff |"
    )
    print("|---|---|---|---|---|---|")
    for name in args.parts.split(","):
        with tempfile.TemporaryDirectory() as tmp:
            work = Path(tmp)
            src = part_path(name, work)
            pgv = work / "auto.pgv"
            info, _ = common.run_json(
                [exe, "encode", src, "-o", pgv, "--res", args.res, "--sharp", "auto", "--json"]
            )
            spacing = float(info["grid"]["spacing"])
            out = work / "dc.ply"
            common.run_json([exe, "decode", pgv, "-o", out, "--method", "dc", "--json"])
            normals, hausdorff = compare(exe, src, out)
            res, vdb, vdb_mesh = at_bytes(src, int(info["bytes"]), args.res, work)
            vdb_normals, vdb_hausdorff = compare(exe, src, vdb_mesh)
            print(
                f"| {name} | {info['bytes']} | {normals:.2f}, {hausdorff / spacing:.2f} "
                f"| {res} | {vdb['bytes_half']} | {vdb_normals:.2f}, "
                f"{vdb_hausdorff / spacing:.2f} |",
                flush=True,
            )


if __name__ == "__main__":
    main()
