"""Time of a gyroid infill of a hollowed mesh against the time of encoding the same mesh, on
the same grid: the lattice's speed target is an infill within twice the encode.

    .venv/bin/python tools/bench/bench_lattice.py [--mesh stanford-bunny] [--res 256]
        [--reps 3] [--json OUT.json] [--timeout 600] [--work DIR]

Per resolution N (grid: cube of side 1.1 x the longest extent, N nodes per axis), with E the
mesh's longest extent:
  * encode:      pgvol encode MESH -o X.pgv --res N
  * infill .pgv: pgvol shell MESH -o Y.pgv --res N --thickness E/50 --infill gyroid
                 --cell E/10 --infill-thickness 0.012 E   (volume fraction and area from the field)
  * infill .stl: the same to Y.stl (contoured, measured on the mesh, written)
Every command runs under /usr/bin/time -v; "s" is the wall clock of the whole process, the
shortest of --reps runs, "RSS" its largest peak. The infill's stage times and its report (volume
fraction, area, enclosed voids) come from its --json output.
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import common  # noqa: E402
from bench_scale import best_of  # noqa: E402


def extent(mesh: Path) -> float:
    return float(common.load_mesh(mesh).extents.max())


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--mesh", default="stanford-bunny")
    parser.add_argument("--res", default="256", help="comma-separated resolutions")
    parser.add_argument("--reps", type=int, default=3)
    parser.add_argument("--json", type=Path)
    parser.add_argument("--timeout", type=float, default=600)
    parser.add_argument("--work", type=Path)
    args = parser.parse_args(argv)

    exe = common.pgvol_bin()
    if not exe.is_file():
        raise SystemExit(f"no pgvol binary at {exe}; build it with cargo build --release")
    mesh = common.mesh_file(args.mesh)
    e = extent(mesh)
    wall, cell, sheet = e / 50, e / 10, 0.012 * e
    work = args.work or Path(tempfile.mkdtemp(prefix="pgvol-lattice-"))
    work.mkdir(parents=True, exist_ok=True)

    rows, records = [], []
    for res in [int(r) for r in args.res.split(",")]:
        encode = best_of([exe, "encode", mesh, "-o", work / "encoded.pgv", "--res", res, "--json", "-q"],
                         args.reps, args.timeout)
        infill = [exe, "shell", mesh, "--res", res, "--thickness", wall, "--infill", "gyroid", "--cell", cell,
                  "--infill-thickness", sheet, "--json", "-q", "-o"]
        as_pgv = best_of(infill + [work / "infill.pgv"], args.reps, args.timeout)
        as_stl = best_of(infill + [work / "infill.stl"], args.reps, args.timeout)
        record = {"mesh": args.mesh, "res": res, "wall": wall, "cell": cell, "sheet": sheet,
                  "encode": encode, "infill_pgv": as_pgv, "infill_stl": as_stl}
        records.append(record)
        failed = [name for name, r in [("encode", encode), ("infill .pgv", as_pgv), ("infill .stl", as_stl)]
                  if r["status"] != "ok"]
        if failed:
            notes = "; ".join(f"{n}: {r.get('note', r['status'])}" for n, r in
                              [("encode", encode), ("infill .pgv", as_pgv), ("infill .stl", as_stl)]
                              if r["status"] != "ok")
            rows.append([res, notes, "", "", "", "", "", "", ""])
            continue
        stl = as_stl["report"]
        stages = ", ".join(f"{k} {v:.2f}" for k, v in as_pgv["report"]["seconds"].items() if k != "total")
        rows.append([
            res, encode["seconds"], as_pgv["seconds"], as_pgv["seconds"] / encode["seconds"],
            as_stl["seconds"], as_stl["seconds"] / encode["seconds"],
            f"{100 * stl['solid']['fraction']:.2f} %", f"{stl['solid']['enclosed_voids']}",
            f"{max(encode['rss_mib'], 0):.0f} / {as_pgv['rss_mib']:.0f} / {as_stl['rss_mib']:.0f}",
        ])
        print(f"res {res}: infill .pgv stages (s): {stages}", file=sys.stderr)

    print(f"{args.mesh}: wall {wall:.4g}, gyroid cell {cell:.4g}, sheet {sheet:.4g} (extent {e:.4g})\n")
    print(common.markdown_table(
        ["res", "encode s", "infill .pgv s", "ratio", "infill .stl s", "ratio", "volume fraction",
         "enclosed voids", "RSS MiB (encode / .pgv / .stl)"],
        rows,
    ))
    if args.json:
        args.json.write_text(json.dumps(records, indent=2, default=str))
    return 0


if __name__ == "__main__":
    sys.exit(main())
