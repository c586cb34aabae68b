"""Distributed encode on a Dask LocalCluster against the single-process sparse encode, and the
weak-scaling figures that predict larger clusters and grids.

    .venv/bin/python tools/bench/bench_distributed.py [--res 2048] [--workers 2]
        [--meshes stanford-bunny,rocker-arm-1m] [--worker-budget 1.1e9] [--json OUT.json]
        [--work DIR] [--skip-single] [--sharp off|auto]
    .venv/bin/python tools/bench/bench_distributed.py --identity [--res 256] [--parts 8]

(.venv is the test command's environment: it has the pgvol package, dask and distributed.)
Per mesh ("NAME-1m" is NAME subdivided at its edge midpoints until it has 1M triangles or more):
  * single process: `pgvol encode MESH -o single.pgv --res N` under /usr/bin/time -v (wall
    clock and peak RSS of the whole process);
  * distributed: pgvol.distributed.encode_file on a LocalCluster of --workers single-threaded
    worker processes, with the fewest parts (from 4 per worker up) whose largest estimated part fits
    --worker-budget; wall clock from the call to the written file, each worker's peak resident
    memory over the encode (VmHWM, reset before), the client's; the file compared byte for byte
    with the single-process one.
  * weak scaling: tasks in the graph, bytes shipped per task (the mesh once per worker, each
    task's returned bricks), scheduler overhead per task (1000 no-op tasks), per-task times from
    Dask's task stream split into the surface-free part (the band plan over the part's box,
    measured on the part with the least surface) and the surface part; and from them, predicted
    times and memory per worker for 8, 64 and 512 workers at 4096^3 and 8192^3.
With --identity: per shared mesh, encode, decode and slice in --parts parts against the
single-process calls (bytes, triangles, boundary edges, layers).
"""

from __future__ import annotations

import argparse
import json
import os
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import common  # noqa: E402

import numpy as np  # noqa: E402

TIME = "/usr/bin/time"


def reset_peak() -> int:
    """Resets this process's peak resident size (Linux clear_refs) and returns its size."""
    with open("/proc/self/clear_refs", "w") as f:
        f.write("5")
    return peak_rss()


def peak_rss() -> int:
    with open("/proc/self/status") as f:
        for line in f:
            if line.startswith("VmHWM:"):
                return int(line.split()[1]) * 1024
    return 0


def noop(x):
    return x


def mesh_arrays(name: str, work: Path):
    """(vertices, faces, path) of a shared mesh, or of one subdivided to 1M triangles."""
    import pgvol

    if name.endswith(common.SUBDIVIDED_SUFFIX):
        v, f = common.subdivide(*pgvol.read_mesh(common.mesh_file(name[: -len(common.SUBDIVIDED_SUFFIX)])))
        v, f = np.asarray(v, np.float32), np.asarray(f, np.int32)
        path = work / f"{name}.ply"
        pgvol.write_mesh(path, v, f)
        v, f = pgvol.read_mesh(path)
        return v, f, path
    path = common.mesh_file(name)
    v, f = pgvol.read_mesh(path)
    return v, f, path


def single_process(path: Path, res: int, out: Path, timeout: float, sharp: str) -> dict:
    argv = [TIME, "-v", str(common.pgvol_bin()), "encode", str(path), "-o", str(out),
            "--res", str(res), "--sharp", sharp, "--force"]
    start = time.perf_counter()
    r = subprocess.run(argv, capture_output=True, text=True, timeout=timeout)
    seconds = time.perf_counter() - start
    if r.returncode != 0:
        return {"status": "failed", "note": r.stderr.strip().splitlines()[-1:]}
    m = re.search(r"Maximum resident set size \(kbytes\): (\d+)", r.stderr)
    return {"status": "ok", "s": seconds, "rss": int(m.group(1)) * 1024 if m else None}


def choose_parts(mesh, res: int, workers: int, budget: float) -> tuple[int, list[dict]]:
    from pgvol import distributed

    parts = 4 * workers
    while True:
        plan = distributed.plan_encode(mesh, parts=parts, res=res)
        if max(p["bytes"] for p in plan) <= budget or len(plan) < parts:
            return parts, plan
        parts *= 2


def scheduler_overhead(client, n: int = 1000) -> float:
    start = time.perf_counter()
    client.gather(client.map(noop, range(n), pure=False))
    return (time.perf_counter() - start) / n


def run_mesh(client, name: str, res: int, workers: int, budget: float, work: Path,
             skip_single: bool, timeout: float, sharp: str) -> dict:
    import pgvol
    from pgvol import distributed

    v, f, path = mesh_arrays(name, work)
    row: dict = {"mesh": name, "triangles": int(len(f)), "res": res, "workers": workers,
                 "sharp": sharp}
    single_out = work / f"{name}-{res}-single.pgv"
    if not skip_single:
        row["single"] = single_process(path, res, single_out, timeout, sharp)
    parts, plan = choose_parts((v, f), res, workers, budget)
    largest = max(plan, key=lambda p: p["bytes"])
    row.update(parts=len(plan), estimate_max_part=largest["bytes"],
               max_part_plan_nodes=part_plan_nodes(res, largest["y"], largest["z"]))
    out = work / f"{name}-{res}-dist.pgv"
    client.run(lambda: __import__("pgvol.distributed"))
    client.get_task_stream()  # starts recording
    base = client.run(reset_peak)
    client_base = reset_peak()
    start = time.perf_counter()
    distributed.encode_file((v, f), out, res=res, sharp=sharp, client=client, parts=parts)
    row["s"] = time.perf_counter() - start
    peaks = client.run(peak_rss)
    row["worker_peak"] = max(peaks.values())
    row["worker_growth"] = max(peaks[w] - base[w] for w in peaks)
    row["client_peak_growth"] = peak_rss() - client_base
    stream = [t for t in client.get_task_stream()
              if str(t.get("key", "")).startswith("pgvol-encode")]
    durations = [sum(s["stop"] - s["start"] for s in t["startstops"]
                     if s["action"] == "compute") for t in stream]
    row["task_seconds"] = {"n": len(durations), "sum": float(np.sum(durations)),
                           "max": float(np.max(durations)) if durations else 0.0}
    row["file_bytes"] = out.stat().st_size
    if single_out.exists():
        row["identical"] = out.read_bytes() == single_out.read_bytes()
    # Bytes per task: the mesh goes once to each worker; each task returns its bricks.
    # The surface-free work of a task (the band plan: a pass over the triangles, flags and
    # far-region signs over the part's box), as the time of the part with the least surface,
    # at R and R/2, with the nodes its plan covers: a + c x nodes.
    for key, n in (("", res), ("_half", res // 2)):
        job = distributed.EncodeJob(v, f, res=n)
        least = min(distributed.plan_encode((v, f), parts=len(plan), res=n),
                    key=lambda p: p["bytes"])
        t0 = time.perf_counter()
        r = job.encode_part(*least["y"], *least["z"])
        row[f"plan_task{key}_s"] = time.perf_counter() - t0
        row[f"least_part_plan_nodes{key}"] = part_plan_nodes(n, least["y"], least["z"])
        del job
    row["mesh_bytes"] = int(v.nbytes + f.nbytes)
    row["returned_bytes_per_task"] = (row["file_bytes"] * 1.0) / len(plan)
    row["smallest_part_returned"] = len(r.bricks)
    return row


# The geometry of a part's band plan (crates/pgvol/src/distributed/encode_parts.rs and
# pgvol-sdf's sampling): fitting groups of 64 nodes, and the plan covers a part's groups
# widened by one group on each side (the fit's 2-brick reach, rounded out to whole region
# tiles of 64 nodes) along y and z, and the whole grid along x, at 3 bytes per 64 nodes.
GROUP_NODES = 64
PLAN_BYTES_PER_NODE = 3 / 64
BYTES_PER_TRIANGLE = 500  # JOB_BYTES_PER_TRIANGLE


def part_plan_nodes(res: int, y: tuple[int, int], z: tuple[int, int]) -> int:
    """Nodes the band plan of the part of groups `y`, `z` covers on a res^3 grid."""
    groups = -(-res // GROUP_NODES)

    def span(r):
        lo, hi = max(r[0] - 1, 0), min(r[1] + 1, groups)
        return min(hi * GROUP_NODES, res) - lo * GROUP_NODES

    return res * span(y) * span(z)


def largest_part(res: int, tasks: int) -> tuple[tuple[int, int], tuple[int, int]]:
    """The groups of the thickest interior part plan_encode cuts a res^3 grid into for `tasks`
    parts: z slabs, each cut along y when there are more parts than slabs."""
    groups = -(-res // GROUP_NODES)
    slabs = min(tasks, groups)
    per_slab = min(-(-tasks // slabs), groups)
    gz, gy = -(-groups // slabs), -(-groups // per_slab)
    mid = lambda g: (min(1, groups - g), min(1, groups - g) + g)  # noqa: E731
    return mid(gy), mid(gz)


def predict_memory(row: dict, n: int, tasks: int) -> dict:
    """Memory per worker at n^3 with `tasks` parts: the mesh's distance queries, the largest
    part's plan flags, and its band: the measured run's band per part (its largest part's
    estimate less the other two terms) times its parts, scaled by area ((n/R)^2) and shared by
    the tasks."""
    R, P = row["res"], row["parts"]
    mesh_bytes = row["triangles"] * BYTES_PER_TRIANGLE
    band_at_r = row["estimate_max_part"] - row["max_part_plan_nodes"] * PLAN_BYTES_PER_NODE \
        - mesh_bytes
    y, z = largest_part(n, tasks)
    plan_nodes = part_plan_nodes(n, y, z)
    band = max(band_at_r, 0.0) * P * (n / R) ** 2 / tasks
    return {"plan_nodes": plan_nodes, "mesh_bytes": mesh_bytes,
            "plan_bytes": plan_nodes * PLAN_BYTES_PER_NODE, "band_bytes": band,
            "worker_bytes": mesh_bytes + plan_nodes * PLAN_BYTES_PER_NODE + band}


def tasks_for(row: dict, n: int, workers: int, budget: float) -> int:
    """The tasks predict() assumes at n^3 on `workers` workers."""
    most = (-(-n // GROUP_NODES)) ** 2
    tasks = min(max(4 * workers, row["parts"]), most)
    while tasks < most and predict_memory(row, n, tasks)["worker_bytes"] > budget:
        tasks = min(2 * tasks, most)
    return tasks


def predict(row: dict, overhead: float, budget: float) -> list[dict]:
    """Weak scaling on paper, from one measured run at resolution R with P parts:
    - a task's time = a + c x (its plan's nodes) + surface work / tasks: a is the pass over
      the triangles, c the plan's flags and far-region signs per node (both from the task with
      the least surface at R and R/2, whose plans cover different node counts), and the
      surface work ~ N^2 (band bricks);
    - tasks: from 4 per worker (and at least the measured P), doubled until the predicted
      memory per worker fits `budget` or every part is one column of groups;
    - time = tasks x (task time + overhead) / workers + assembly on the client (~ N^2,
      taken as the measured wall clock less the tasks' share);
    - memory per worker: predict_memory."""
    R, P, W = row["res"], row["parts"], row["workers"]
    plan_s, half_s = row["plan_task_s"], row["plan_task_half_s"]
    nodes, half_nodes = row["least_part_plan_nodes"], row["least_part_plan_nodes_half"]
    c = max(plan_s - half_s, 0.0) / max(nodes - half_nodes, 1)
    a = max(plan_s - c * nodes, 0.0)
    surface = max(row["task_seconds"]["sum"] - P * plan_s, 0.0)
    tasks_wall = row["task_seconds"]["sum"] / W
    assembly = max(row["s"] - tasks_wall, 0.0)
    out = []
    for n in (4096, 8192):
        k2 = (n / R) ** 2
        for workers in (8, 64, 512):
            tasks = tasks_for(row, n, workers, budget)
            memory = predict_memory(row, n, tasks)
            time_s = tasks * (a + c * memory["plan_nodes"] + surface * k2 / tasks + overhead) \
                / workers + assembly * k2
            out.append({"res": n, "workers": workers, "tasks": tasks,
                        "predicted_s": time_s, **memory,
                        "returned_bytes_per_task": row["file_bytes"] * k2 / tasks,
                        "mesh_bytes_per_worker": row["mesh_bytes"]})
    return out


def identity(res: int, parts: int) -> None:
    """Per shared mesh: encode, decode and slice in `parts` parts (in this process: the same
    part functions the tasks run) against the single-process calls; every decoded piece kept,
    so the comparison covers specks too."""
    import pgvol
    import trimesh
    from pgvol import distributed

    def triangles(f, ids):
        tri = ids[np.asarray(f, np.int64)]
        first = np.argmin(tri, axis=1)
        tri = tri[np.arange(len(tri))[:, None], (first[:, None] + np.arange(3)) % 3]
        return tri[np.lexsort(tri.T[::-1])]

    rows = []
    for name in SHARED:
        mesh = pgvol.read_mesh(common.mesh_file(name))
        whole = pgvol.Field.from_mesh(*mesh, res=res)
        same_file = distributed.encode(mesh, res=res, parts=parts).to_bytes() == whole.to_bytes()
        v, f = whole.to_mesh(method="mc", min_component=0.0)
        dv, df = distributed.decode(whole, parts=parts, min_component=0.0)
        bits = [np.ascontiguousarray(x, np.float32).view(np.uint32).reshape(-1, 3)
                for x in (dv, v)]
        _, ids = np.unique(np.concatenate(bits), axis=0, return_inverse=True)
        ids = ids.ravel()
        a = triangles(df, ids[:len(bits[0])])
        b = triangles(f, ids[len(bits[0]):])
        same_mesh = a.shape == b.shape and np.array_equal(a, b)
        out = trimesh.Trimesh(dv, df, process=False)
        boundary = len(trimesh.grouping.group_rows(out.edges_sorted, require_count=1))
        h = 2.7 * whole.grid.spacing
        layers, got = whole.slice(h), distributed.slice(whole, h, parts=parts)
        same_layers = len(layers) == len(got) and all(
            x.height == y.height and x.holes == y.holes
            and all(np.array_equal(p, q) for p, q in zip(x.loops, y.loops))
            for x, y in zip(layers, got))
        rows.append([name, len(f), same_file, same_mesh, boundary, len(layers), same_layers])
    print(common.markdown_table(
        ["mesh", "triangles (decoded)", f"identical .pgv ({parts} parts)",
         "identical triangles", "boundary edges", "layers", "identical layers"], rows))


def gb(x) -> str:
    return "n/a" if x is None else f"{x / 1e9:.2f} GB"


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--res", type=int, default=2048)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--meshes", default="stanford-bunny,rocker-arm-1m")
    ap.add_argument("--worker-budget", type=float, default=1.1e9,
                    help="largest estimated part, bytes (default 1.1e9: the measured growth "
                         "ran up to 1.17x the estimate, and the target is 1.5 GB per worker)")
    ap.add_argument("--json", type=Path)
    ap.add_argument("--work", type=Path)
    ap.add_argument("--skip-single", action="store_true")
    ap.add_argument("--timeout", type=float, default=3600)
    ap.add_argument("--identity", action="store_true",
                    help="only compare encode, decode and slice in --parts parts with the "
                         "single-process calls on the seven shared meshes at --res")
    ap.add_argument("--parts", type=int, default=8)
    ap.add_argument("--sharp", default="off", choices=["off", "auto"],
                    help="sharp-feature vertices, as pgvol encode --sharp (default off)")
    args = ap.parse_args()
    if args.identity:
        identity(args.res, args.parts)
        return 0

    from dask.distributed import Client, LocalCluster

    work = args.work or Path(tempfile.mkdtemp(prefix="pgvol-bench-dist-"))
    work.mkdir(parents=True, exist_ok=True)
    rows = []
    with LocalCluster(n_workers=args.workers, threads_per_worker=1, processes=True,
                      dashboard_address=":0", silence_logs=40, memory_limit=0) as cluster, \
            Client(cluster) as client:
        overhead = scheduler_overhead(client)
        for name in args.meshes.split(","):
            row = run_mesh(client, name, args.res, args.workers, args.worker_budget, work,
                           args.skip_single, args.timeout, args.sharp)
            row["overhead_per_task_s"] = overhead
            row["predictions"] = predict(row, overhead, args.worker_budget)
            rows.append(row)
            print(json.dumps(row, indent=1), file=sys.stderr, flush=True)

    print(common.markdown_table(
        ["mesh", "triangles", "grid", "single s", "single RSS", f"{args.workers} workers s",
         "parts", "peak per worker", "growth per worker", "estimate (largest part)",
         "client growth", "identical .pgv"],
        [[r["mesh"], r["triangles"], f"{r['res']}³",
          f"{r['single']['s']:.1f}" if r.get("single", {}).get("status") == "ok" else "n/a",
          gb(r.get("single", {}).get("rss")), f"{r['s']:.1f}", r["parts"], gb(r["worker_peak"]),
          gb(r["worker_growth"]), gb(r["estimate_max_part"]), gb(r["client_peak_growth"]),
          r.get("identical", "n/a")] for r in rows]))
    print()
    print(common.markdown_table(
        ["mesh", "tasks", "task s (sum / max)", "surface-free part of a task s",
         "mesh shipped per worker", "bricks returned per task", "scheduler overhead per task"],
        [[r["mesh"], r["task_seconds"]["n"],
          f"{r['task_seconds']['sum']:.1f} / {r['task_seconds']['max']:.1f}",
          f"{r['plan_task_s']:.2f} (at {r['res'] // 2}³: {r['plan_task_half_s']:.2f})",
          f"{r['mesh_bytes'] / 1e6:.1f} MB",
          f"{r['returned_bytes_per_task'] / 1e6:.2f} MB",
          f"{r['overhead_per_task_s'] * 1e3:.2f} ms"] for r in rows]))
    print()
    print(common.markdown_table(
        ["mesh", "grid", "workers", "tasks", "predicted s", "memory per worker",
         "(mesh + plan + band)", "bricks returned per task"],
        [[r["mesh"], f"{p['res']}³", p["workers"], p["tasks"], f"{p['predicted_s']:.0f}",
          gb(p["worker_bytes"]),
          " + ".join(f"{p[k] / 1e9:.2f}" for k in ("mesh_bytes", "plan_bytes", "band_bytes")),
          f"{p['returned_bytes_per_task'] / 1e6:.2f} MB"]
         for r in rows for p in r["predictions"]]))
    if args.json:
        args.json.write_text(json.dumps(rows, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
