"""Runs the same command lines with two pgvol binaries and compares every output file byte for byte.

A refactoring of the library or the command-line tool must not change what the commands write.
Each command line runs twice, once per binary, in its own empty folder holding the inputs; the
files each run leaves (fields, meshes, layer files, grids) must be identical, and so must the
exit status. Reports printed on stdout carry timings, so stdout is not compared.

Usage: python3 tools/compare_cli.py BEFORE_BINARY AFTER_BINARY [--mesh MESH]
The mesh defaults to fixtures/torus-knot.obj.
"""

from __future__ import annotations

import argparse
import filecmp
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent

# Each entry: a name and the arguments after the binary. `M` is the input mesh (copied in as
# m.obj); earlier entries' outputs are not visible to later ones, so each line makes its own.
SPHERE = "sphere:0,0,0,1"
COMMANDS: list[tuple[str, list[list[str]]]] = [
    ("encode-decode", [
        ["encode", "m.obj", "-o", "m.pgv", "--res", "64", "-q"],
        ["decode", "m.pgv", "-o", "m.ply", "-q"],
        ["decode", "m.pgv", "-o", "sn.obj", "--method", "sn", "-q"],
        ["decode", "m.pgv", "-o", "dc.stl", "--method", "dc", "-q"],
    ]),
    ("encode-dense", [["encode", "m.obj", "-o", "d.pgv", "--res", "48", "--dense-file", "-q"]]),
    ("remesh", [["remesh", "m.obj", "-o", "r.glb", "--res", "64", "-q"]]),
    ("sdf", [["sdf", "m.obj", "-o", "s.npy", "--res", "32", "-q"]]),
    ("export", [
        ["encode", "m.obj", "-o", "m.pgv", "--res", "48", "-q"],
        ["export", "m.pgv", "-o", "c.nrrd", "-q"],
        ["export", "m.pgv", "-o", "f.3mf", "-q"],
    ]),
    ("eval", [
        ["encode", "m.obj", "-o", "m.pgv", "--res", "48", "-q"],
        ["eval", "m.pgv", "pts.csv", "-o", "e.csv", "-q"],
    ]),
    ("slice", [
        ["slice", "m.obj", "-o", "l.json", "--layer-height", "0.05", "--res", "96", "-q"],
        ["encode", "m.obj", "-o", "m.pgv", "--res", "64", "-q"],
        ["slice", "m.pgv", "-o", "l.svg", "--layer-height", "0.05", "-q"],
    ]),
    ("offset", [
        ["offset", "m.obj", "-o", "o.ply", "--distance", "0.03", "--res", "64", "-q"],
        ["offset", "m.obj", "-o", "o.pgv", "--distance", "-0.02", "--res", "64", "-q"],
    ]),
    ("shell", [
        ["shell", "m.obj", "-o", "s.ply", "--thickness", "0.3", "--res", "96", "-q"],
        ["shell", "m.obj", "-o", "h.pgv", "--thickness", "0.3", "--hollow", "--res", "96", "-q"],
    ]),
    ("lattice", [["lattice", "m.obj", "-o", "g.ply", "--surface", "gyroid", "--cell", "1.5",
                  "--thickness", "0.3", "--res", "96", "-q"]]),
    ("csg", [
        ["csg", "union", SPHERE, "sphere:0,0,1,1", "-o", "u.ply", "--res", "48", "-q"],
        ["csg", "difference", "m.obj", SPHERE, "-o", "d.pgv", "--res", "48", "-q"],
        ["csg", "intersection", SPHERE, "box:0,0,1,0.8,0.8,0.8", "-o", "i.ply", "--res", "48",
         "--radius", "0.1", "-q"],
    ]),
    ("repair", [
        ["csg", "union", SPHERE, "sphere:0,0,1,0.3", "-o", "b.pgv", "--res", "48", "-q"],
        ["repair", "b.pgv", "-o", "f.ply", "--mask=-0.45,-0.45,0.75,0.45,0.45,1.45", "--face=-z",
         "--res", "48", "-q"],
    ]),
    ("blend", [["blend", "liming", "plane:1,0,0,0", "plane:0,1,0,0", "--cut", "plane:-1,-1,0,0.5",
                "--box", "-1,-1,-1,1,1,1", "-o", "b.ply", "-q"]]),
    ("points", [
        ["remesh", "m.obj", "-o", "p.ply", "--res", "48", "-q"],
        ["points", "p.ply", "-o", "pt.ply", "--res", "48", "-q"],
    ]),
    ("contours", [
        ["slice", "m.obj", "-o", "l.json", "--layer-height", "0.05", "--res", "96", "-q"],
        ["contours", "l.json", "-o", "c.ply", "--res", "64", "-q"],
    ]),
    ("perturb", [
        ["perturb", "m.obj", "-o", "p.pgv", "-q"],
        ["decode", "p.pgv", "-o", "p.ply", "-q"],
    ]),
]


def run_all(binary: Path, mesh: Path, folder: Path) -> dict[str, list[int]]:
    """Runs every command line with `binary`, each group in `folder/<group>`; returns exit codes."""
    codes: dict[str, list[int]] = {}
    for name, lines in COMMANDS:
        work = folder / name
        work.mkdir(parents=True)
        shutil.copy(mesh, work / "m.obj")
        (work / "pts.csv").write_text("0,0,0\n0.1,0.2,0.3\n1,1,1\n")
        codes[name] = []
        for line in lines:
            done = subprocess.run([str(binary), *line], cwd=work, capture_output=True, text=True)
            codes[name].append(done.returncode)
            if done.returncode != 0:
                print(f"{binary.name} {' '.join(line)}: {done.stderr.strip()}", file=sys.stderr)
    return codes


def compare(before: Path, after: Path) -> list[str]:
    """Paths (relative) whose bytes differ or that exist on one side only."""
    problems = []
    names = sorted({p.relative_to(before) for p in before.rglob("*") if p.is_file()}
                   | {p.relative_to(after) for p in after.rglob("*") if p.is_file()})
    for rel in names:
        a, b = before / rel, after / rel
        if not a.exists() or not b.exists():
            problems.append(f"{rel}: only {'after' if b.exists() else 'before'}")
        elif not filecmp.cmp(a, b, shallow=False):
            problems.append(f"{rel}: bytes differ")
    return problems


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("before", type=Path)
    parser.add_argument("after", type=Path)
    parser.add_argument("--mesh", type=Path, default=ROOT / "fixtures" / "torus-knot.obj")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        codes_before = run_all(args.before.resolve(), args.mesh, tmp / "before")
        codes_after = run_all(args.after.resolve(), args.mesh, tmp / "after")
        problems = [f"{name}: exit codes {codes_before[name]} before, {codes_after[name]} after"
                    for name in codes_before if codes_before[name] != codes_after[name]]
        problems += compare(tmp / "before", tmp / "after")
        files = sum(1 for p in (tmp / "after").rglob("*") if p.is_file())
        failures = sum(code != 0 for codes in codes_after.values() for code in codes)
    for line in problems:
        print(line)
    lines = sum(len(lines) for _, lines in COMMANDS)
    print(f"{lines} command lines, {files} files compared, {failures} commands failed, "
          f"{len(problems)} differences")
    return 1 if problems or failures else 0


if __name__ == "__main__":
    sys.exit(main())
