"""Whole-process time and peak memory of encode and decode against grid resolution, pgvol and
OpenVDB side by side in one run.

    .venv/bin/python tools/bench/bench_scale.py [--meshes bunny-capped,fandisk]
        [--res 128,256,512,1024[,2048]] [--json OUT.json] [--plot OUT.png] [--reps 1]
        [--mem-limit BYTES] [--timeout 3600] [--work DIR]

Per mesh and resolution N (grid: cube of side 1.1 x the longest extent, N nodes per axis):
  * pgvol encode MESH -o X.pgv --res N           pgvol decode X.pgv -o X.glb
  * OpenVDB (vdb_scale.py under the system Python with Debian's python3-openvdb):
    read OBJ + meshToVolume (+-3 voxel band, same voxel size and nodes) + write X.vdb, and
    read X.vdb + volumeToMesh (adaptivity 0) + write a binary PLY.
Every command runs under /usr/bin/time -v: "s" is the wall clock around the whole process (start-up
and file I/O included), RSS its "Maximum resident set size". Ratios are pgvol / OpenVDB.
A run whose memory would exceed --mem-limit (default: this machine's RAM) is skipped: pgvol
refuses by its own estimate (--max-memory), OpenVDB's is extrapolated from its smaller runs.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import re
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import common  # noqa: E402

HERE = Path(__file__).resolve().parent
VDB_SCRIPT = HERE / "vdb_scale.py"
TIME = "/usr/bin/time"
STAGES = [("pgvol", "encode"), ("pgvol", "decode"), ("OpenVDB", "encode"), ("OpenVDB", "decode")]


def timed(argv, timeout: float) -> dict:
    """One run under /usr/bin/time -v. Its own session, so a timeout ends the measured process
    too and not just `time` (which would leave it running and skew the next runs)."""
    argv = [TIME, "-v", *map(str, argv)]
    start = time.perf_counter()
    proc = subprocess.Popen(argv, stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True, start_new_session=True)
    try:
        out, err = proc.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, signal.SIGKILL)
        proc.communicate()
        return {"status": "timeout", "note": f"over {timeout:g} s"}
    seconds = time.perf_counter() - start

    def field(label):
        m = re.search(rf"^\s*{re.escape(label)}.*?: (.+)$", err, re.M)
        return m.group(1).strip() if m else None

    elapsed = field("Elapsed (wall clock) time")
    run = {
        "seconds": seconds,
        "rss_mib": int(field("Maximum resident set size") or 0) / 1024,
        # time -v's own figures: 10 ms resolution, so the wall clock above goes in the table.
        "elapsed_time_v": sum(float(x) * 60**i for i, x in enumerate(reversed(elapsed.split(":")))) if elapsed else None,
        "user_s": float(field("User time (seconds)") or "nan"),
        "sys_s": float(field("System time (seconds)") or "nan"),
    }
    # The tool's own stderr, and time's line when a signal (e.g. the OOM killer) ended it.
    body = re.sub(r"^Command exited with non-zero status \d+$", "", err.split("\tCommand being timed:")[0], flags=re.M)
    body = " ".join(body.split())
    if proc.returncode != 0:
        return {**run, "status": "failed", "note": body[-300:] or f"exit {proc.returncode}"}
    try:  # both tools print one JSON object on stdout
        run["report"] = json.loads(out)
    except ValueError:
        run["report"] = None
    return {**run, "status": "ok"}


def size(text: str) -> int:
    """Bytes from 24G, 512M or a plain number."""
    units = {"K": 2**10, "M": 2**20, "G": 2**30, "T": 2**40}
    unit = units.get(text[-1].upper())
    return int(float(text[:-1]) * unit) if unit else int(text)


def best_of(argv, reps: int, timeout: float) -> dict:
    """Shortest of reps runs (the least disturbed by other load), with the largest RSS seen."""
    runs = [timed(argv, timeout) for _ in range(reps)]
    ok = [r for r in runs if r["status"] == "ok"]
    if not ok:
        return runs[-1]
    best = min(ok, key=lambda r: r["seconds"])
    return {**best, "rss_mib": max(r["rss_mib"] for r in ok)}


def extrapolated_mib(runs: list[dict], tool: str, stage: str, mesh: str, res: int) -> float | None:
    """Peak RSS at res from the two largest runs below it, as a power of N clamped to [2, 3]:
    a narrow band and its mesh grow as N^2, a dense grid as N^3. None without an earlier run."""
    pts = sorted((r["res"], r["rss_mib"]) for r in runs
                 if (r["tool"], r["stage"], r["mesh"]) == (tool, stage, mesh) and r["status"] == "ok" and r["res"] < res)
    if not pts:
        return None
    (r1, m1), power = pts[-1], 3.0
    if len(pts) > 1:
        r0, m0 = pts[-2]
        power = min(3.0, max(2.0, math.log(m1 / m0) / math.log(r1 / r0)))
    return m1 * (res / r1) ** power


def measure(args, exe: Path, vdb_missing: str | None, work: Path, name: str, mesh: Path, res: int, runs: list[dict]):
    pgv, glb = work / f"{name}-{res}.pgv", work / f"{name}-{res}.glb"
    vdb, ply = work / f"{name}-{res}.vdb", work / f"{name}-{res}.ply"
    limit = ["--max-memory", args.mem_limit]
    commands = {
        ("pgvol", "encode"): ([exe, "encode", mesh, "-o", pgv, "--res", res, *limit, "-q", "--json"], pgv),
        ("pgvol", "decode"): ([exe, "decode", pgv, "-o", glb, *limit, "-q", "--json"], glb),
        ("OpenVDB", "encode"): ([common.SYSTEM_PYTHON, VDB_SCRIPT, "encode", mesh, res, vdb], vdb),
        ("OpenVDB", "decode"): ([common.SYSTEM_PYTHON, VDB_SCRIPT, "decode", vdb, ply], ply),
    }
    for tool, stage in STAGES:
        row = {"mesh": name, "res": res, "tool": tool, "stage": stage}
        encoded = next((r for r in runs if (r["mesh"], r["res"], r["tool"], r["stage"]) == (name, res, tool, "encode")), None)
        guess = extrapolated_mib(runs, tool, stage, name, res) if tool == "OpenVDB" else None
        if tool == "OpenVDB" and vdb_missing is not None:
            row.update(status="n/a", note=vdb_missing)
        elif stage == "decode" and encoded["status"] != "ok":
            row.update(status="skipped", note="no encoded file")
        elif guess is not None and guess * 2**20 > args.mem_limit:
            row.update(status="skipped", note=f"estimated {guess / 1024:.1f} GiB > {args.mem_limit / 2**30:.1f} GiB")
        else:
            print(f"  {name} {res}^3 {tool} {stage} ...", file=sys.stderr, flush=True)
            argv, out = commands[(tool, stage)]
            row.update(best_of(argv, args.reps, args.timeout))
            # pgvol's refusal by its own memory estimate is a skip, not a failure.
            if tool == "pgvol" and row["status"] == "failed" and "--max-memory" in row.get("note", ""):
                row["status"] = "skipped"
            if out.is_file():
                row["file_bytes"] = out.stat().st_size
        runs.append(row)
    for path in (pgv, glb, vdb, ply):  # a 2048^3 mesh runs to gigabytes
        path.unlink(missing_ok=True)


def table(runs: list[dict], resolutions: list[int], meshes: list[str]) -> str:
    get = {(r["mesh"], r["res"], r["tool"], r["stage"]): r for r in runs}

    def cell(r, key, scale=1.0):
        return f"{r[key] * scale:.3g}" if r["status"] == "ok" else r["status"]

    def ratio(a, b, key):
        return f"{a[key] / b[key]:.2f}" if a["status"] == b["status"] == "ok" else "n/a"

    rows = []
    for res in resolutions:
        for mesh in meshes:
            row = [res, mesh]
            for stage in ("encode", "decode"):
                p, v = get[(mesh, res, "pgvol", stage)], get[(mesh, res, "OpenVDB", stage)]
                row += [cell(p, "seconds"), cell(p, "rss_mib"), cell(v, "seconds"), cell(v, "rss_mib"),
                        ratio(p, v, "seconds"), ratio(p, v, "rss_mib")]
            for tool in ("pgvol", "OpenVDB"):
                r = get[(mesh, res, tool, "encode")]
                row.append(f"{r['file_bytes'] / 1024:,.0f}" if r["status"] == "ok" and "file_bytes" in r else r["status"])
            rows.append(row)
    header = ["res", "mesh"]
    for stage in ("encode", "decode"):
        header += [f"pgvol {stage} s", f"pgvol {stage} RSS MiB", f"OpenVDB {stage} s", f"OpenVDB {stage} RSS MiB",
                   f"{stage} time pgvol/VDB", f"{stage} RSS pgvol/VDB"]
    return common.markdown_table(header + [".pgv KiB", ".vdb KiB"], rows)


def plot(runs: list[dict], meshes: list[str], path: Path, title: str) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    colours = {("pgvol", "encode"): "C0", ("pgvol", "decode"): "C9", ("OpenVDB", "encode"): "C3", ("OpenVDB", "decode"): "C1"}
    markers = "os^vD*"
    fig, axes = plt.subplots(1, 2, figsize=(12, 4.8))
    for (tool, stage), colour in colours.items():
        for mesh, marker in zip(meshes, markers):
            pts = sorted((r["res"], r["seconds"], r["rss_mib"]) for r in runs
                         if (r["tool"], r["stage"], r["mesh"]) == (tool, stage, mesh) and r["status"] == "ok")
            if not pts:
                continue
            res, secs, rss = zip(*pts)
            style = dict(color=colour, marker=marker, ls="-" if stage == "encode" else "--", ms=4,
                         label=f"{tool} {stage}, {mesh}")
            axes[0].plot(res, secs, **style)
            axes[1].plot(res, rss, **style)
    resolutions = sorted({r["res"] for r in runs})
    for ax, ylabel in zip(axes, ["wall time of the process (s)", "peak RSS (MiB)"]):
        ax.set_xscale("log", base=2)
        ax.set_yscale("log")
        ax.set_xticks(resolutions, [str(n) for n in resolutions])
        ax.set_xlabel("grid resolution N (nodes per axis)")
        ax.set_ylabel(ylabel)
        ax.grid(True, which="both", alpha=0.3)
    axes[1].legend(fontsize=7, ncol=2)
    fig.suptitle(title, fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=100)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--meshes", default="bunny-capped,fandisk", help="shared meshes (comma separated); "
                    "bunny-capped is the Stanford bunny with its holes closed, as OpenVDB's sign needs")
    ap.add_argument("--res", default="128,256,512,1024", help="resolutions (comma separated), e.g. add 2048")
    ap.add_argument("--reps", type=int, default=1, help="runs per measurement; the shortest is kept")
    ap.add_argument("--mem-limit", type=size, default=os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES"),
                    help="memory a run may need (e.g. 24G), else it is skipped (default: this machine's RAM)")
    ap.add_argument("--timeout", type=float, default=3600, help="seconds per run")
    ap.add_argument("--json", type=Path, help="write every figure here")
    ap.add_argument("--plot", type=Path, help="write the log-log PNG here")
    ap.add_argument("--work", type=Path, help="directory for the files (default: a temporary one)")
    args = ap.parse_args(argv)

    exe = common.pgvol_bin()
    if not exe.is_file():
        raise SystemExit(f"missing {exe}: cargo build --release (or set PGVOL_BIN)")
    if not Path(TIME).is_file():
        raise SystemExit(f"missing {TIME}: apt-get install time")
    resolutions = sorted(int(n) for n in args.res.split(","))
    meshes = args.meshes.split(",")

    # Warm-up that also checks OpenVDB: both tools' files are then in the page cache for the first
    # timed run, as they are for the later ones.
    subprocess.run([exe, "--version"], capture_output=True)
    probe = subprocess.run([common.SYSTEM_PYTHON, "-c", f"import sys; sys.path.insert(0, {str(HERE)!r}); import vdb_scale"],
                           capture_output=True, text=True)
    vdb_missing = None if probe.returncode == 0 else (
        f"{common.SYSTEM_PYTHON} cannot import OpenVDB (apt-get install python3-openvdb): "
        + (probe.stderr.strip().splitlines() or [""])[-1])

    work = args.work or Path(tempfile.mkdtemp(prefix="pgvol-bench-scale-"))
    work.mkdir(parents=True, exist_ok=True)
    runs: list[dict] = []
    try:
        sources = {name: common.source_mesh(name, work) for name in meshes}
        for res in resolutions:
            for name in meshes:
                measure(args, exe, vdb_missing, work, name, sources[name], res, runs)
    finally:
        if not args.work:
            shutil.rmtree(work, ignore_errors=True)

    version = subprocess.run([exe, "--version"], capture_output=True, text=True).stdout.strip()
    vdb_version = next((r["report"].get("openvdb") for r in runs if r.get("report") and "openvdb" in r["report"]), "n/a")
    machine = {"cores": os.cpu_count(), "mem_bytes": args.mem_limit, "load_average": os.getloadavg()}
    title = (f"{version}, OpenVDB {vdb_version}; {machine['cores']} cores, limit {args.mem_limit / 2**30:.1f} GiB, "
             f"load {machine['load_average'][0]:.2f}; best of {args.reps}")
    print(f"# Encode / decode scaling, whole process ({title})\n")
    print(table(runs, resolutions, meshes))
    notes = [f"- {r['mesh']} {r['res']} {r['tool']} {r['stage']}: {r['status']}, {r['note']}"
             for r in runs if r["status"] != "ok" and r.get("note")]
    if notes:
        print("\n" + "\n".join(notes))
    if args.json:
        args.json.write_text(json.dumps({"pgvol": version, "openvdb": vdb_version, "machine": machine,
                                         "reps": args.reps, "runs": runs}, indent=1))
    if args.plot:
        plot(runs, meshes, args.plot, title)
    return 0


if __name__ == "__main__":
    sys.exit(main())
