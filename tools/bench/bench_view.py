"""The viewer page of a large file: how long `pgvol view` takes, how big the page is beside the
.pgv, and how long headless Chromium takes to open it to ready, one run (not a timed test).

    .venv/bin/python tools/bench/bench_view.py [--mesh bunny-capped] [--res 1024] [--max-res 256]
        [--json OUT.json] [--work DIR]

The mesh is encoded with pgvol's defaults (`pgvol encode MESH -o X.pgv --res N`, not timed),
then `pgvol view X.pgv -o X.html [--max-res M]` (wall seconds of the whole process), then the page
is opened in headless Chromium (tools/checks/chromium.py: SwiftShader WebGL, a fresh profile)
twice: as written, and at `#section=z:MID` (a section at the middle of the shape). Per opening:
the page's own time to ready (`data-ready-ms`: from the start of navigation to the first frame
drawn, parsing the inlined data and building the section included) and the wall time of the
whole Chromium process (start and exit included, an upper bound). Set PGVOL_BIN to use another
pgvol binary.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import common  # noqa: E402

sys.path.insert(0, str(common.REPO_ROOT / "tools" / "checks"))
import chromium  # noqa: E402


def run(*args) -> float:
    start = time.perf_counter()
    subprocess.run([str(a) for a in args], check=True, stdin=subprocess.DEVNULL)
    return time.perf_counter() - start


def measure(mesh: str, res: int, max_res: int | None, work: Path) -> dict:
    pgvol = common.pgvol_bin()
    source = common.source_mesh(mesh, work)
    pgv, page = work / f"{mesh}-{res}.pgv", work / f"{mesh}-{res}.html"
    run(pgvol, "encode", source, "-o", pgv, "--res", res, "-q")
    cap = [] if max_res is None else ["--max-res", max_res]
    view_seconds = run(pgvol, "view", pgv, "-o", page, *cap, "-q")
    info = json.loads(subprocess.run([str(pgvol), "info", str(pgv), "--json"], check=True,
                                     capture_output=True, text=True).stdout)
    lo, hi = info["header"]["source_bounds"]
    mid = round((lo[2] + hi[2]) / 2, 6)
    row = {
        "mesh": mesh, "res": res, "max_res": max_res, "pgv_bytes": pgv.stat().st_size,
        "page_bytes": page.stat().st_size, "view_seconds": view_seconds,
    }
    row["page_over_pgv"] = row["page_bytes"] / row["pgv_bytes"]
    for key, fragment in [("open", ""), ("section", f"section=z:{mid}")]:
        wall, state = chromium.seconds_to_ready(page, fragment)
        if state.get("status") != "ready":
            raise SystemExit(f"{page}#{fragment} did not open: {state}")
        row[f"{key}_ready_ms"] = int(state["ready-ms"])
        row[f"{key}_chromium_seconds"] = wall
        row["triangles"] = int(state["triangles"])
        if key == "section":
            row["section_area"] = float(state["section-area"])
    return row


def table(rows: list[dict]) -> str:
    lines = [
        "| mesh | N | cap | .pgv bytes | page bytes | page / .pgv | triangles | view s | "
        "ready ms | ready ms (section) | Chromium s | Chromium s (section) |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        lines.append(
            f"| {r['mesh']} | {r['res']} | {r['max_res'] or 'default'} | {r['pgv_bytes']:,} | "
            f"{r['page_bytes']:,} | {r['page_over_pgv']:.2f} | {r['triangles']:,} | "
            f"{r['view_seconds']:.2f} | {r['open_ready_ms']:,} | {r['section_ready_ms']:,} | "
            f"{r['open_chromium_seconds']:.1f} | {r['section_chromium_seconds']:.1f} |"
        )
    return "\n".join(lines)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--mesh", default="bunny-capped", help="shared mesh (or bunny-capped)")
    ap.add_argument("--res", default="1024", help="resolutions, nodes per axis (comma separated)")
    ap.add_argument("--max-res", type=int, help="the page's resolution cap (default: pgvol view's)")
    ap.add_argument("--json", type=Path, help="write the figures here")
    ap.add_argument("--work", type=Path, help="keep the files here (default: a temporary folder)")
    args = ap.parse_args(argv)
    if chromium.chromium_path() is None:
        raise SystemExit("chromium is missing (apt install chromium)")
    with tempfile.TemporaryDirectory() as tmp:
        work = args.work or Path(tmp)
        work.mkdir(parents=True, exist_ok=True)
        rows = [measure(args.mesh, int(n), args.max_res, work) for n in args.res.split(",")]
    if args.json:
        args.json.write_text(json.dumps(rows, indent=2))
    print(table(rows))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
