"""pgvol jobs split into parts that run as Dask tasks, with the single-process results.

Each function takes an optional ``client`` (a ``distributed.Client``). With one, the parts run
as tasks on its cluster; without one, the same part functions run one after another in this
process, so a machine without a cluster runs the same code path.

    >>> from dask.distributed import Client, LocalCluster
    >>> from pgvol import distributed
    >>> client = Client(LocalCluster(n_workers=2, threads_per_worker=1))
    >>> grid = distributed.encode_file("part.stl", "part.pgv", res=1024, client=client)
    >>> vertices, faces = distributed.decode("part.pgv", client=client)
    >>> layers = distributed.slice("part.pgv", 0.2, client=client)

- ``encode`` ships the mesh once to every worker (scattered with ``broadcast=True``), where
  the first task of a job builds the mesh's distance queries and keeps them for the job's
  other tasks. Each task samples and fits one box of fitting groups (8^3 bricks of 8^3 nodes)
  and returns its coefficient bricks; this process assembles the file, bit for bit the file
  of ``Field.from_mesh``. ``encode_file`` writes that file as the parts arrive, holding a
  window of them rather than the whole field.
- ``decode`` sends each task the coefficient bricks around its slab of cells (from a ``.pgv``
  path, the file's own compressed bricks of those slabs); the tasks' triangles are the
  single-process triangles, welded here at the seams.
- ``slice`` sends each task the bricks around its range of layers; from a ``.pgv`` path, the
  file's own compressed bricks of the slabs the range reaches, never the whole file at once.

Tasks are pure functions of their arguments, keyed by them: a task that fails is retried
(``retries``) and a task lost with its worker is run again by the scheduler, with the same
result. See docs/distributed.md in the repository.
"""

from __future__ import annotations

import hashlib
import os
import threading
import uuid
from collections import OrderedDict
from pathlib import Path
from typing import Any, Iterator

import numpy as np

from . import _pgvol
from ._pgvol import EncodeJob, Field, Grid, Layer

__all__ = ["encode", "encode_file", "decode", "slice", "plan_encode", "worker_count",
           "EncodeJob"]

# Retries of a failed task before the job fails: a worker lost with its tasks does not count
# (the scheduler reruns them), only an exception raised by the task.
RETRIES = 2

# Parts per worker thread when none are asked for: several per thread keep every thread busy
# while parts of unequal surface finish at different times.
PARTS_PER_THREAD = 4


def worker_count(client: Any) -> int:
    """Worker threads of ``client``'s cluster (1 without a client)."""
    if client is None:
        return 1
    info = client.scheduler_info()
    return max(1, sum(w.get("nthreads", 1) for w in info.get("workers", {}).values()))


def _parts(parts: int | None, client: Any) -> int:
    if parts is None:
        return 1 if client is None else PARTS_PER_THREAD * worker_count(client)
    if int(parts) < 1:
        raise ValueError(f"parts must be at least 1, got {parts}")
    return int(parts)


def _mesh_arrays(mesh: Any) -> tuple[np.ndarray, np.ndarray]:
    """(vertices, faces) of a path, a (vertices, faces) pair or a trimesh-like object."""
    if isinstance(mesh, (str, os.PathLike)):
        return _pgvol.read_mesh(Path(mesh))
    if hasattr(mesh, "vertices") and hasattr(mesh, "faces"):
        vertices, faces = mesh.vertices, mesh.faces
    else:
        vertices, faces = mesh
    return np.ascontiguousarray(vertices), np.ascontiguousarray(faces)


def _job_key(vertices: np.ndarray, faces: np.ndarray, options: dict) -> str:
    """A name for one encode: the mesh's bytes and the options."""
    h = hashlib.sha256()
    for a in (vertices, faces):
        h.update(f"{a.dtype.str}{a.shape}".encode())
        h.update(np.ascontiguousarray(a).tobytes())
    h.update(repr(sorted(options.items())).encode())
    return h.hexdigest()[:24]


# Per process, the distance queries of the encodes seen last (about 400 bytes per triangle
# each), so the tasks of one encode on one worker build them once. Two are kept so that a new
# job starting while the last one's tasks finish does not evict it.
_JOBS: OrderedDict[str, EncodeJob] = OrderedDict()
_JOBS_KEPT = 2
_JOBS_LOCK = threading.Lock()


def _job(key: str, mesh: tuple[np.ndarray, np.ndarray], options: dict) -> EncodeJob:
    with _JOBS_LOCK:
        job = _JOBS.get(key)
        if job is None:
            job = EncodeJob(mesh[0], mesh[1], **options)
            _JOBS[key] = job
            while len(_JOBS) > _JOBS_KEPT:
                _JOBS.popitem(last=False)
        _JOBS.move_to_end(key)
        return job


def _encode_part(job_key: str, mesh, options: dict, part: tuple) -> _pgvol.EncodedPart:
    """Task: the coefficient bricks of one box of fitting groups."""
    y0, y1, z0, z1 = part
    return _job(job_key, mesh, options).encode_part(y0, y1, z0, z1)


def _run(client: Any, function, calls: list[tuple], names: list[str], retries: int) -> list:
    """``function(*call)`` for every call, as tasks named ``names`` or here in order."""
    if client is None:
        return [function(*call) for call in calls]
    futures = [
        client.submit(function, *call, key=name, pure=False, retries=retries)
        for call, name in zip(calls, names)
    ]
    return client.gather(futures)


def plan_encode(mesh: Any, *, parts: int = 1, res: int | None = None,
                voxel: float | None = None, band: float = 4.0, basis: str = "bspline3",
                sign: str = "auto") -> list[dict]:
    """The parts of an encode: per part the fitting groups along y and z it covers and its
    estimated peak memory in bytes on a worker."""
    vertices, faces = _mesh_arrays(mesh)
    plan = _pgvol.plan_encode(vertices, faces, parts, res=res, voxel=voxel, band=band,
                              basis=basis, sign=sign)
    return [{"y": (y0, y1), "z": (z0, z1), "bytes": b} for y0, y1, z0, z1, b in plan]


class _EncodeRun:
    """What every run of one encode's parts shares: the mesh (shipped once to every worker),
    the options and the plan."""

    def __init__(self, mesh: Any, options: dict, client: Any, parts: int | None,
                 retries: int) -> None:
        self.vertices, self.faces = _mesh_arrays(mesh)
        self.options = options
        self.client = client
        self.retries = retries
        self.plan = _pgvol.plan_encode(self.vertices, self.faces, _parts(parts, client),
                                       **options)
        self.key = _job_key(self.vertices, self.faces, options)
        self.shipped: Any = (self.vertices, self.faces)
        if client is not None:
            # Once to every worker, not once per task.
            [self.shipped] = client.scatter([self.shipped], broadcast=True, hash=False)

    def _calls(self) -> tuple[list[tuple], list[str]]:
        boxes = [p[:4] for p in self.plan]
        calls = [(self.key, self.shipped, self.options, box) for box in boxes]
        names = [f"pgvol-encode-{self.key}-{'-'.join(map(str, box))}" for box in boxes]
        return calls, names

    def run(self) -> list[_pgvol.EncodedPart]:
        """Every part's result at once."""
        calls, names = self._calls()
        return _run(self.client, _encode_part, calls, names, self.retries)

    def in_order(self) -> Iterator[_pgvol.EncodedPart]:
        """The parts' results in plan order, each fetched when the writer asks for it and
        dropped here once handed over; the parts not fetched are cancelled when the writer
        stops early."""
        calls, names = self._calls()
        if self.client is None:
            for call in calls:
                yield _encode_part(*call)
            return
        futures: list[Any] = [
            self.client.submit(_encode_part, *call, key=name, pure=False,
                               retries=self.retries)
            for call, name in zip(calls, names)
        ]
        try:
            for i in range(len(futures)):
                result = futures[i].result()
                futures[i] = None
                yield result
        finally:
            left = [f for f in futures if f is not None]
            if left:
                self.client.cancel(left)


def encode(mesh: Any, *, res: int | None = None, voxel: float | None = None, band: float = 4.0,
           basis: str = "bspline3", sign: str = "auto", sharp: str = "off",
           sharp_angle: float | None = None, client: Any = None,
           parts: int | None = None, output: str | os.PathLike | None = None,
           retries: int = RETRIES) -> Field:
    """Encodes a mesh (a path, a (vertices, faces) pair or a trimesh) in parts: the same field,
    bit for bit, as ``Field.from_mesh`` with the interp fit. ``parts`` defaults to four per
    worker thread (one without a client); ``output`` saves the field as a ``.pgv``. The field
    is assembled here whole; ``encode_file`` writes the file holding a window of it.
    ``sharp="auto"`` stores the sharp-feature vertices as ``Field.from_mesh`` does: the parts
    compute coefficients only, and this process chooses the vertices against them."""
    options: dict[str, Any] = {
        "res": res, "voxel": voxel, "band": band, "basis": basis, "sign": sign,
        "sharp": sharp, "sharp_angle": sharp_angle,
    }
    job = _EncodeRun(mesh, options, client, parts, retries)
    results = job.run()
    field = _pgvol.assemble_encode(job.vertices, job.faces, [r.bricks for r in results],
                                   **options)
    if output is not None:
        field.save(output)
    return field


def encode_file(mesh: Any, output: str | os.PathLike, *, res: int | None = None,
                voxel: float | None = None, band: float = 4.0, basis: str = "bspline3",
                sign: str = "auto", sharp: str = "off", sharp_angle: float | None = None,
                client: Any = None, parts: int | None = None,
                retries: int = RETRIES) -> Grid:
    """Encodes a mesh in parts straight to the ``.pgv`` file ``output``, bit for bit the file
    ``encode`` saves, written as the parts arrive in plan order: this process holds a window
    of slabs of coefficients, not the whole field, and of the coefficients near creases when
    ``sharp="auto"``. Returns the field's grid.

    When the automatic precision cannot be chosen a slab at a time (coefficients beyond the fixed precision's
    range, never seen on distance fields), the file is written by ``encode``, holding the
    whole field. ``output`` is replaced atomically and left as it was on failure."""
    options: dict[str, Any] = {
        "res": res, "voxel": voxel, "band": band, "basis": basis, "sign": sign,
        "sharp": sharp, "sharp_angle": sharp_angle,
    }
    job = _EncodeRun(mesh, options, client, parts, retries)
    outcome, grid = _pgvol.write_encode_parts(job.vertices, job.faces, job.in_order(), output,
                                              **options)
    if outcome == "whole":
        encode((job.vertices, job.faces), client=client, parts=parts, output=output,
               retries=retries, **options)
    return grid


def _field(source: Any) -> Field:
    return source if isinstance(source, Field) else Field.load(Path(source))


def _decode_part(bricks: bytes, cells: tuple[int, int], iso: float, normals: bool):
    """Task: the triangles of one slab of cells, with their vertices' normals if asked."""
    return _pgvol.decode_part(bricks, cells[0], cells[1], iso=iso, normals=normals)


def _decode_file_part(part: bytes, cells: tuple[int, int], iso: float, normals: bool):
    """Task: the triangles of one slab of cells, with their vertices' normals if asked, from
    its part of the file."""
    return _pgvol.decode_file_part(part, cells[0], cells[1], iso=iso, normals=normals)


def decode(source: Any, *, client: Any = None, parts: int | None = None, iso: float = 0.0,
           min_component: float | None = None, normals: bool = False,
           retries: int = RETRIES) -> tuple[np.ndarray, ...]:
    """Contours a field (a ``Field`` or a ``.pgv`` path) in parts by marching cubes on its own
    grid: (vertices, faces), the triangles of ``Field.to_mesh(method="mc")``, in another
    order, welded at the seams; with ``normals``, (vertices, faces, normals), each vertex with
    the normal ``to_mesh(normals=True)`` gives it. From a path to a sparse file each task gets
    the file's own bricks of its slabs, so this process never decodes the field."""
    count = _parts(parts, client)
    if not isinstance(source, Field):
        path = Path(source)
        plan = _pgvol.plan_decode_file(path, count)
        if plan is not None:
            ranges, spacing = plan
            pieces = _in_parts(client, "decode", ranges, _decode_file_part, (iso, normals),
                               lambda s, e: _pgvol.decode_file_part_bricks(path, s, e), retries)
            return _pgvol.weld_parts(pieces, spacing, iso=iso, min_component=min_component,
                                     normals=normals)
    field = _field(source)
    ranges = _pgvol.plan_decode(field, count)
    pieces = _in_parts(client, "decode", ranges, _decode_part, (iso, normals),
                       lambda s, e: _pgvol.decode_part_bricks(field, s, e), retries)
    return _pgvol.weld_parts(pieces, field.grid.spacing, iso=iso, min_component=min_component,
                             normals=normals)


def _slice_part(bricks: bytes, layers: tuple[int, int], layer_height: float, settings: dict,
                bounds) -> list[Layer]:
    """Task: the layers of one range, from its bricks; ``bounds`` is the field's."""
    return _pgvol.slice_part(bricks, bounds, layers[0], layers[1], layer_height, **settings)


def _slice_file_part(part: bytes, layers: tuple[int, int], layer_height: float,
                     settings: dict) -> list[Layer]:
    """Task: the layers of one range, from its part of the file."""
    return _pgvol.slice_file_part(part, layers[0], layers[1], layer_height, **settings)


def slice(source: Any, layer_height: float, *, axis: str = "z", first: float | None = None,
          resolution: float | None = None, tolerance: float | None = None, client: Any = None,
          parts: int | None = None, retries: int = RETRIES) -> list[Layer]:
    """Slices a field (a ``Field`` or a ``.pgv`` path) in parts: the layers of
    ``Field.slice`` with the same arguments. From a path to a sparse file each task gets the
    file's own bricks of its slabs, so this process never decodes the field."""
    settings: dict[str, Any] = {
        "axis": axis, "first": first, "resolution": resolution, "tolerance": tolerance
    }
    count = _parts(parts, client)
    if not isinstance(source, Field):
        path = Path(source)
        plan = _pgvol.plan_slice_file(path, count, layer_height, **settings)
        if plan is not None:
            parts_layers = _in_parts(
                client, "slice", plan, _slice_file_part, (layer_height, settings),
                lambda s, e: _pgvol.slice_file_part_bricks(path, s, e, layer_height, **settings),
                retries)
            layers = [layer for part in parts_layers for layer in part]
            # The file's sharp section puts corners back, here where the layers are whole.
            return _pgvol.sharpen_file_layers(path, layers, layer_height, **settings)
    field = _field(source)
    ranges = _pgvol.plan_slice(field, count, layer_height, **settings)
    parts_layers = _in_parts(
        client, "slice", ranges, _slice_part, (layer_height, settings, field.bounds),
        lambda s, e: _pgvol.slice_part_bricks(field, s, e, layer_height, **settings), retries)
    layers = [layer for part in parts_layers for layer in part]
    return _pgvol.sharpen_layers(field, layers, layer_height, **settings)


def _in_parts(client: Any, job: str, ranges: list[tuple[int, int]], task, extra: tuple,
              bricks_of, retries: int) -> list:
    """``task(bricks, range, *extra)`` for every range, the results in plan order, as tasks
    named after ``job`` or here. Each part's bricks (``bricks_of(start, end)``) are made as the
    part is handed out and dropped here once used or scattered."""
    if client is None:
        return [task(bricks_of(s, e), (s, e), *extra) for s, e in ranges]
    key = uuid.uuid4().hex
    futures = []
    for s, e in ranges:
        [bricks] = client.scatter([bricks_of(s, e)], hash=False)
        futures.append(client.submit(task, bricks, (s, e), *extra,
                                     key=f"pgvol-{job}-{key}-{s}-{e}", pure=False,
                                     retries=retries))
    return client.gather(futures)


_EXAMPLES = """examples:
  python -m pgvol.distributed encode part.stl -o part.pgv --res 2048 --scheduler tcp://10.0.0.5:8786
  python -m pgvol.distributed encode part.stl -o part.pgv --res 1024 --local 2
  python -m pgvol.distributed decode part.pgv -o part.ply --scheduler tcp://10.0.0.5:8786
  python -m pgvol.distributed slice part.pgv -o layers.json --layer-height 0.2 --local 2
"""


def _connect(scheduler: str | None, local: int | None):
    """A client of the scheduler at ``scheduler``, of a new LocalCluster of ``local`` worker
    processes, or None (parts in this process); with what closes it."""
    if scheduler is None and local is None:
        return None, []
    from dask.distributed import Client, LocalCluster

    if scheduler is not None:
        client = Client(scheduler)
        return client, [client]
    cluster = LocalCluster(n_workers=local, threads_per_worker=1, processes=True,
                           dashboard_address=":0")
    client = Client(cluster)
    return client, [client, cluster]


def main(argv: list[str] | None = None) -> int:
    """The command-line front end: ``python -m pgvol.distributed encode|decode|slice``."""
    import argparse
    import json
    import sys
    import time

    parser = argparse.ArgumentParser(
        prog="python -m pgvol.distributed",
        description="Run pgvol's encode, decode or slice in parts on a Dask cluster "
                    "(--scheduler), on a new local cluster (--local N) or in this process.",
        epilog=_EXAMPLES, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = parser.add_subparsers(dest="command", required=True)

    def common(p):
        where = p.add_mutually_exclusive_group()
        where.add_argument("--scheduler", metavar="ADDRESS",
                           help="a running Dask scheduler, e.g. tcp://HOST:8786")
        where.add_argument("--local", type=int, metavar="N",
                           help="start a LocalCluster of N single-threaded worker processes")
        p.add_argument("--parts", type=int, default=None,
                       help="number of parts (default: 4 per worker thread, 1 in process)")
        p.add_argument("-o", "--output", required=True, help="the file to write")
        p.add_argument("--json", action="store_true", help="print a JSON report")

    enc = sub.add_parser("encode", help="mesh -> .pgv, the file of `pgvol encode` bit for bit",
                         epilog=_EXAMPLES, formatter_class=argparse.RawDescriptionHelpFormatter)
    enc.add_argument("input", help="a mesh file (OBJ, glTF/GLB, STL, PLY)")
    size = enc.add_mutually_exclusive_group()
    size.add_argument("--res", type=int, help=f"nodes per axis (default {_pgvol.DEFAULT_RES})")
    size.add_argument("--voxel", type=float, help="grid spacing in mesh units")
    enc.add_argument("--band", type=float, default=_pgvol.ENCODE_BAND,
                     help="exact distances within this many spacings (default %(default)s)")
    enc.add_argument("--basis", default="bspline3", choices=["bspline3", "bspline2", "trilinear"],
                     help="basis (default %(default)s)")
    enc.add_argument("--sign", default="auto",
                     choices=["auto", "winding", "pseudonormal", "parity"],
                     help="inside/outside test (default %(default)s)")
    enc.add_argument("--sharp", default="off", choices=["off", "auto"],
                     help="store the vertices of cells at creases, as pgvol encode --sharp auto "
                          "(default %(default)s)")
    enc.add_argument("--sharp-angle", type=float, default=None, metavar="DEG",
                     help="crease angle for --sharp auto (default 30)")
    common(enc)

    dec = sub.add_parser("decode", help=".pgv -> mesh by marching cubes on the file's grid",
                         epilog=_EXAMPLES, formatter_class=argparse.RawDescriptionHelpFormatter)
    dec.add_argument("input", help="a .pgv file")
    dec.add_argument("--iso", type=float, default=0.0, help="level set (default 0)")
    dec.add_argument("--min-component", type=float, default=None,
                     help="remove pieces enclosing less than this volume (default 2 cells)")
    common(dec)

    sli = sub.add_parser("slice", help=".pgv -> layers (.svg, .cli or .json)",
                         epilog=_EXAMPLES, formatter_class=argparse.RawDescriptionHelpFormatter)
    sli.add_argument("input", help="a .pgv file")
    sli.add_argument("--layer-height", type=float, required=True, help="distance between layers")
    sli.add_argument("--axis", default="z", choices=["x", "y", "z"], help="(default z)")
    common(sli)

    args = parser.parse_args(argv)
    start = time.perf_counter()
    client, closers = _connect(args.scheduler, args.local)
    try:
        report: dict[str, Any] = {"command": args.command, "input": args.input,
                                  "output": args.output, "workers": worker_count(client)}
        if args.command == "encode":
            grid = encode_file(args.input, args.output, res=args.res, voxel=args.voxel,
                               band=args.band, basis=args.basis, sign=args.sign,
                               sharp=args.sharp, sharp_angle=args.sharp_angle, client=client,
                               parts=args.parts)
            report["grid"] = list(grid.dims)
        elif args.command == "decode":
            vertices, faces, normals = decode(args.input, client=client, parts=args.parts,
                                              iso=args.iso, min_component=args.min_component,
                                              normals=True)
            _pgvol.write_mesh(Path(args.output), vertices, faces, normals)
            report.update(vertices=len(vertices), triangles=len(faces))
        else:
            layers = slice(args.input, args.layer_height, axis=args.axis, client=client,
                           parts=args.parts)
            _pgvol.write_layers(Path(args.output), layers)
            report["layers"] = len(layers)
    except (_pgvol_errors(), ValueError, OSError) as e:
        print(f"error: {e}", file=sys.stderr)
        return 1
    finally:
        for c in closers:
            c.close()
    report["seconds"] = round(time.perf_counter() - start, 3)
    if args.json:
        print(json.dumps(report, indent=2))
    else:
        print(f"wrote {args.output} in {report['seconds']} s on {report['workers']} worker "
              f"thread(s)")
    return 0


def _pgvol_errors():
    from ._errors import PgvolError

    return PgvolError


if __name__ == "__main__":
    # Run from the importable module, so that tasks refer to its functions by name instead of
    # being pickled with this script's globals.
    from pgvol.distributed import main as _main

    raise SystemExit(_main())
