"""OpenVDB's counterparts of `pgvol encode` and `pgvol decode`, one whole process each, for
bench_scale.py to time from outside.

Run with the system Python that has Debian's python3-openvdb module:
    /usr/bin/python3 vdb_scale.py encode MESH.obj N OUT.vdb
    /usr/bin/python3 vdb_scale.py decode IN.vdb OUT.ply
encode: reads the OBJ, builds meshToVolume with a +-3 voxel band on the pgvol grid (cube of
side 1.1 x the longest extent, centred on the bounding box, N nodes per axis, so the same voxel
size and node positions as `pgvol encode --res N`) and writes it (default compression).
decode: reads the .vdb, runs volumeToMesh (adaptivity 0) and writes a binary PLY of triangles.
Each prints one JSON line with its in-process phase times, so interpreter start-up and imports
can be told apart from the work.
"""

import json
import os
import sys
import time

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
from objfile import read_obj  # noqa: E402

try:
    import pyopenvdb as vdb
except ImportError:  # newer builds name the module openvdb
    import openvdb as vdb

HALF_WIDTH = 3.0


def encode(mesh, n, out):
    t0 = time.perf_counter()
    verts, faces = read_obj(mesh)
    lo, hi = verts.min(0), verts.max(0)
    side = 1.1 * float((hi - lo).max())
    h = side / (n - 1)
    origin = 0.5 * (lo + hi) - 0.5 * side
    # Index (i, j, k) at origin + h*(i, j, k): OpenVDB's voxels coincide with pgvol's nodes.
    xform = vdb.createLinearTransform([[h, 0, 0, 0], [0, h, 0, 0], [0, 0, h, 0], [*origin, 1.0]])
    t1 = time.perf_counter()
    grid = vdb.FloatGrid.createLevelSetFromPolygons(
        verts.astype(np.float32), triangles=faces.astype(np.int32), transform=xform, halfWidth=HALF_WIDTH
    )
    grid.name = "surface"
    t2 = time.perf_counter()
    vdb.write(out, grids=[grid])
    t3 = time.perf_counter()
    return {"read": t1 - t0, "build": t2 - t1, "write": t3 - t2, "active": int(grid.activeVoxelCount()),
            "bytes": os.path.getsize(out)}


def decode(src, out):
    t0 = time.perf_counter()
    grid = vdb.read(src, "surface")
    t1 = time.perf_counter()
    points, tris, quads = grid.convertToPolygons(isovalue=0.0, adaptivity=0.0)
    t2 = time.perf_counter()
    # Quads split in two so both tools write triangle meshes, and every face reversed, since
    # volumeToMesh winds them inward; numpy writes, no per-face Python loop.
    quads = np.asarray(quads, np.int32).reshape(-1, 4)
    faces = np.concatenate([np.asarray(tris, np.int32).reshape(-1, 3)[:, ::-1], quads[:, [0, 2, 1]], quads[:, [0, 3, 2]]])
    rec = np.empty(len(faces), dtype=[("n", "u1"), ("v", "<i4", (3,))])
    rec["n"], rec["v"] = 3, faces
    with open(out, "wb") as f:
        f.write((f"ply\nformat binary_little_endian 1.0\nelement vertex {len(points)}\n"
                 "property float x\nproperty float y\nproperty float z\n"
                 f"element face {len(faces)}\nproperty list uchar int vertex_indices\nend_header\n").encode())
        f.write(np.ascontiguousarray(points, "<f4").tobytes())
        f.write(rec.tobytes())
    t3 = time.perf_counter()
    return {"read": t1 - t0, "mesh": t2 - t1, "write": t3 - t2, "triangles": int(len(faces)),
            "bytes": os.path.getsize(out)}


if __name__ == "__main__":
    mode, args = sys.argv[1], sys.argv[2:]
    result = encode(args[0], int(args[1]), args[2]) if mode == "encode" else decode(args[0], args[1])
    print(json.dumps({**result, "openvdb": ".".join(map(str, vdb.LIBRARY_VERSION))}))
