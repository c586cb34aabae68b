"""Whole-process time and peak memory of encode and decode against grid resolution, pgvol and
OpenVDB side by side in one run.

    tools/.venv-bench/bin/python tools/bench/bench_scale.py [--meshes bunny-capped,fandisk,rocker-arm-1m]
        [--res 128,256,512,1024,2048,4096] [--json OUT.json] [--plot OUT.png] [--reps 1]
        [--mem-limit BYTES] [--timeout 3600] [--work DIR] [--no-chamfer]

Per mesh and resolution N (grid: cube of side 1.1 x the longest extent, centred on the bounding
box, N nodes per axis, so the voxel size is 1.1 x extent / (N - 1)):
  * pgvol encode MESH -o X.pgv --res N           pgvol decode X.pgv -o X.ply
  * OpenVDB through the C++ driver in vdb_driver/ (built here with make; Debian's libopenvdb-dev):
    vdb_driver encode MESH X.vdb --voxel H --origin ... --band 3   (read the OBJ, meshToLevelSet
    with a +-3 voxel band whose voxels are pgvol's nodes, write X.vdb), and
    vdb_driver decode X.vdb Y.ply   (read, volumeToMesh at 0 with adaptivity 0, write a PLY).
Both decodes write binary little-endian PLY. Every command runs under /usr/bin/time -v: "s" is the
wall clock around the whole process (start-up and file I/O included), RSS its "Maximum resident
set size". Ratios are pgvol / OpenVDB. The Chamfer column compares the two decoded meshes: the
mean distance from a sample of each one's vertices to the other's surface (the tangent plane at
the nearest vertex), both ways, in voxels; the two should agree within about a voxel.
A run whose memory would exceed --mem-limit (default: this machine's RAM) is skipped: pgvol
refuses by its own estimate (--max-memory), OpenVDB's is extrapolated from its smaller runs.
"rocker-arm-1m" is the rocker arm subdivided to 1,285,632 triangles (common.subdivide), and
"bunny-capped" the Stanford bunny with its holes closed, as OpenVDB's sign needs.
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

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import common  # noqa: E402

HERE = Path(__file__).resolve().parent
DRIVER_DIR = HERE / "vdb_driver"
DRIVER = DRIVER_DIR / "vdb_driver"
BAND = 3  # OpenVDB's half-width, voxels
TIME = "/usr/bin/time"
CHAMFER_SAMPLES = 100_000
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


def build_driver() -> str | None:
    """Builds vdb_driver (make, when its source is newer); None when it runs, else why not."""
    hint = "apt-get install g++ make libopenvdb-dev libboost-dev"
    if shutil.which("make") is None:
        return f"no make to build {DRIVER_DIR.name} ({hint})"
    proc = subprocess.run(["make", "-s", "-C", str(DRIVER_DIR)], capture_output=True, text=True)
    if proc.returncode != 0:
        last = (proc.stderr.strip().splitlines() or [""])[-1]
        return f"cannot build {DRIVER_DIR.name} ({hint}): {last[-200:]}"
    probe = subprocess.run([DRIVER, "version"], capture_output=True, text=True)
    return None if probe.returncode == 0 else f"{DRIVER} does not run: {probe.stderr.strip()[-200:]}"


PLY_TYPES = {"char": "i1", "int8": "i1", "uchar": "u1", "uint8": "u1", "short": "<i2", "int16": "<i2",
             "ushort": "<u2", "uint16": "<u2", "int": "<i4", "int32": "<i4", "uint": "<u4", "uint32": "<u4",
             "float": "<f4", "float32": "<f4", "double": "<f8", "float64": "<f8"}


def read_ply(path: Path):
    """Positions (float64) and triangles of a binary little-endian PLY whose faces all have three
    corners, as both tools write them."""
    with open(path, "rb") as fh:
        header = []
        while not header or header[-1] != "end_header":
            line = fh.readline()
            if not line:
                raise ValueError(f"{path}: no end_header")
            header.append(line.decode("ascii").strip())
        offset = fh.tell()
    if "format binary_little_endian 1.0" not in header:
        raise ValueError(f"{path}: not binary little-endian")
    elements = []  # (name, count, numpy fields)
    for words in (line.split() for line in header):
        if words[0] == "element":
            elements.append((words[1], int(words[2]), []))
        elif words[0] == "property" and words[1] == "list":
            elements[-1][2].append((words[4], [("n", PLY_TYPES[words[2]]), ("i", PLY_TYPES[words[3]], (3,))]))
        elif words[0] == "property":
            elements[-1][2].append((words[2], PLY_TYPES[words[1]]))
    vertices = faces = None
    for name, count, fields in elements:
        dtype = np.dtype(fields)
        records = np.fromfile(path, dtype=dtype, count=count, offset=offset)
        offset += dtype.itemsize * count
        if name == "vertex":
            vertices = np.stack([records["x"], records["y"], records["z"]], axis=1).astype(np.float64)
        elif name == "face":
            lists = records[fields[0][0]]
            if (lists["n"] != 3).any():
                raise ValueError(f"{path}: faces other than triangles")
            faces = np.ascontiguousarray(lists["i"])
    return vertices, faces


def surface_distances(points: np.ndarray, vertices: np.ndarray, faces: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Distance from each point to its nearest vertex, and to the tangent plane there (normal:
    the area-weighted sum of the normals of the faces around it), a close estimate of the
    distance to the surface when the mesh is finer than the distances measured."""
    from scipy.spatial import cKDTree

    nearest_d, nearest = cKDTree(vertices).query(points)
    needed = np.zeros(len(vertices), bool)
    needed[nearest] = True
    ring = faces[needed[faces].any(axis=1)]  # only the faces around the vertices used
    a, b, c = (vertices[ring[:, k]] for k in range(3))
    face_normals = np.cross(b - a, c - a)
    normals = np.zeros_like(vertices)
    for k in range(3):
        np.add.at(normals, ring[:, k], face_normals)
    n = normals[nearest]
    n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-300)
    plane_d = np.abs(np.einsum("ij,ij->i", points - vertices[nearest], n))
    return nearest_d, plane_d


def chamfer(a_ply: Path, b_ply: Path, voxel: float, samples: int = CHAMFER_SAMPLES) -> dict:
    """Symmetric Chamfer distance between two meshes, in voxels: the mean over both directions of
    the distance from up to `samples` vertices of one (chosen at random) to the other's surface."""
    a, b = read_ply(a_ply), read_ply(b_ply)
    rng = np.random.default_rng(0)
    out = {}
    for key, (src, dst) in {"pgvol_to_vdb": (a, b), "vdb_to_pgvol": (b, a)}.items():
        pts = src[0][rng.choice(len(src[0]), min(samples, len(src[0])), replace=False)]
        nearest_d, plane_d = surface_distances(pts, *dst)
        out[key] = {"mean": float(plane_d.mean() / voxel), "p99": float(np.quantile(plane_d, 0.99) / voxel),
                    "max": float(plane_d.max() / voxel), "mean_to_vertex": float(nearest_d.mean() / voxel)}
    out["chamfer_voxels"] = 0.5 * (out["pgvol_to_vdb"]["mean"] + out["vdb_to_pgvol"]["mean"])
    out["vertices"] = {"pgvol": len(a[0]), "OpenVDB": len(b[0])}
    out["triangles"] = {"pgvol": len(a[1]), "OpenVDB": len(b[1])}
    return out


def measure(args, exe: Path, vdb_missing: str | None, work: Path, name: str, mesh: Path, grid: common.Grid,
            runs: list[dict], checks: list[dict]):
    res = grid.n
    pgv, pgvol_ply = work / f"{name}-{res}.pgv", work / f"{name}-{res}-pgvol.ply"
    vdb, vdb_ply = work / f"{name}-{res}.vdb", work / f"{name}-{res}-openvdb.ply"
    limit = ["--max-memory", args.mem_limit]
    # Voxel (0, 0, 0) on pgvol's node (0, 0, 0): both tools sample the same points.
    placement = ["--voxel", repr(grid.h), "--origin", *map(repr, grid.origin.tolist()), "--band", BAND]
    commands = {
        ("pgvol", "encode"): ([exe, "encode", mesh, "-o", pgv, "--res", res, *limit, "-q", "--json"], pgv),
        ("pgvol", "decode"): ([exe, "decode", pgv, "-o", pgvol_ply, *limit, "-q", "--json"], pgvol_ply),
        ("OpenVDB", "encode"): ([DRIVER, "encode", mesh, vdb, *placement], vdb),
        ("OpenVDB", "decode"): ([DRIVER, "decode", vdb, vdb_ply], vdb_ply),
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
    check = {"mesh": name, "res": res, "voxel": grid.h}
    decoded = all(r["status"] == "ok" for r in runs if (r["mesh"], r["res"], r["stage"]) == (name, res, "decode"))
    if args.no_chamfer or not decoded:
        check["status"] = "skipped" if args.no_chamfer else "n/a"
    else:
        print(f"  {name} {res}^3 Chamfer ...", file=sys.stderr, flush=True)
        try:
            check.update(chamfer(pgvol_ply, vdb_ply, grid.h), status="ok")
        except (ImportError, MemoryError, ValueError) as exc:
            check.update(status="failed", note=common.short_reason(exc))
    checks.append(check)
    for path in (pgv, pgvol_ply, vdb, vdb_ply):  # a 4096^3 mesh runs to gigabytes
        path.unlink(missing_ok=True)


def table(runs: list[dict], checks: list[dict], resolutions: list[int], meshes: list[str]) -> str:
    get = {(r["mesh"], r["res"], r["tool"], r["stage"]): r for r in runs}
    compared = {(c["mesh"], c["res"]): c for c in checks}

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
            c = compared[(mesh, res)]
            row.append(f"{c['chamfer_voxels']:.3f}" if c["status"] == "ok" else c["status"])
            rows.append(row)
    header = ["res", "mesh"]
    for stage in ("encode", "decode"):
        header += [f"pgvol {stage} s", f"pgvol {stage} RSS MiB", f"OpenVDB {stage} s", f"OpenVDB {stage} RSS MiB",
                   f"{stage} time pgvol/VDB", f"{stage} RSS pgvol/VDB"]
    return common.markdown_table(header + [".pgv KiB", ".vdb KiB", "Chamfer voxels"], rows)


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
    ap.add_argument("--meshes", default="bunny-capped,fandisk,rocker-arm-1m",
                    help="shared meshes (comma separated); bunny-capped is the Stanford bunny with its holes "
                    "closed, as OpenVDB's sign needs, NAME-1m is NAME subdivided to 1M triangles or more")
    ap.add_argument("--res", "--sizes", default="128,256,512,1024,2048,4096",
                    help="resolutions, nodes per axis (comma separated)")
    ap.add_argument("--reps", type=int, default=1, help="runs per measurement; the shortest is kept")
    ap.add_argument("--mem-limit", type=size, default=os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES"),
                    help="memory a run may need (e.g. 24G), else it is skipped (default: this machine's RAM)")
    ap.add_argument("--timeout", type=float, default=3600, help="seconds per run")
    ap.add_argument("--no-chamfer", action="store_true", help="leave out the comparison of the decoded meshes")
    ap.add_argument("--json", type=Path, help="write every figure here (after each resolution)")
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

    # Also a warm-up: both tools' files are then in the page cache for the first timed run, as
    # they are for the later ones.
    subprocess.run([exe, "--version"], capture_output=True)
    vdb_missing = build_driver()
    version = subprocess.run([exe, "--version"], capture_output=True, text=True).stdout.strip()
    vdb_version = "n/a" if vdb_missing else json.loads(
        subprocess.run([DRIVER, "version"], capture_output=True, text=True).stdout)["openvdb"]
    machine = {"cores": os.cpu_count(), "mem_bytes": os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES"),
               "mem_limit": args.mem_limit}

    sys.path.insert(0, str(common.REPO_ROOT / "tools"))
    from objfile import read_obj

    work = args.work or Path(tempfile.mkdtemp(prefix="pgvol-bench-scale-"))
    work.mkdir(parents=True, exist_ok=True)
    runs: list[dict] = []
    checks: list[dict] = []
    try:
        sources = {name: common.source_mesh(name, work) for name in meshes}
        bounds = {}
        for name, path in sources.items():
            v, f = read_obj(path)
            bounds[name] = (v.min(axis=0), v.max(axis=0))
            machine.setdefault("triangles", {})[name] = len(f)
        for res in resolutions:
            for name in meshes:
                measure(args, exe, vdb_missing, work, name, sources[name], common.Grid(bounds[name], res), runs, checks)
            if args.json:  # a long run keeps what it has measured so far
                write_json(args.json, version, vdb_version, machine, args.reps, runs, checks)
    finally:
        if not args.work:
            shutil.rmtree(work, ignore_errors=True)

    machine["load_average"] = os.getloadavg()
    title = (f"{version}, OpenVDB {vdb_version} (C++); {machine['cores']} cores, "
             f"limit {args.mem_limit / 2**30:.1f} GiB, load {machine['load_average'][0]:.2f}; best of {args.reps}")
    print(f"# Encode / decode scaling, whole process ({title})\n")
    print(table(runs, checks, resolutions, meshes))
    notes = [f"- {r['mesh']} {r['res']} {r['tool']} {r['stage']}: {r['status']}, {r['note']}"
             for r in runs if r["status"] != "ok" and r.get("note")]
    notes += [f"- {c['mesh']} {c['res']} Chamfer: {c['status']}, {c['note']}" for c in checks if c.get("note")]
    if notes:
        print("\n" + "\n".join(notes))
    if args.json:
        write_json(args.json, version, vdb_version, machine, args.reps, runs, checks)
    if args.plot:
        plot(runs, meshes, args.plot, title)
    return 0


def write_json(path: Path, version: str, vdb_version: str, machine: dict, reps: int, runs: list[dict],
               checks: list[dict]) -> None:
    path.write_text(json.dumps({"pgvol": version, "openvdb": vdb_version, "machine": machine, "reps": reps,
                                "band_voxels": BAND, "runs": runs, "chamfer": checks}, indent=1))


if __name__ == "__main__":
    sys.exit(main())
