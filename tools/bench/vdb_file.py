"""OpenVDB level-set file of a mesh on the pgvol grid, and its mesh.

Run with the system Python that has Debian's python3-openvdb module:
    /usr/bin/python3 vdb_file.py MESH.obj N OUT_PREFIX
Builds meshToVolume with a +-3 voxel band on the pgvol grid (cube of side 1.1 x the longest
extent, N nodes per axis), writes OUT_PREFIX.vdb (default compression) and OUT_PREFIX-half.vdb
(saved as half float), meshes the level set with volumeToMesh (adaptivity 0) into
OUT_PREFIX.obj, and prints {"bytes": ..., "bytes_half": ..., "triangles": ...}.
"""

import json
import os
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
from objfile import read_obj  # noqa: E402

try:
    import pyopenvdb as vdb
except ImportError:  # newer builds name the module openvdb
    import openvdb as vdb


def main(mesh, n, prefix):
    verts, faces = read_obj(mesh)
    lo, hi = verts.min(0), verts.max(0)
    side = 1.1 * float((hi - lo).max())
    h = side / (n - 1)
    xform = vdb.createLinearTransform(voxelSize=h)
    grid = vdb.FloatGrid.createLevelSetFromPolygons(verts.astype(np.float32), triangles=faces.astype(np.int32), transform=xform, halfWidth=3.0)
    grid.name = "surface"
    vdb.write(prefix + ".vdb", grids=[grid])
    grid.saveFloatAsHalf = True
    vdb.write(prefix + "-half.vdb", grids=[grid])
    points, tris, quads = grid.convertToPolygons(isovalue=0.0, adaptivity=0.0)
    with open(prefix + ".obj", "w") as f:
        for p in points:
            f.write(f"v {p[0]} {p[1]} {p[2]}\n")
        for t in tris:
            f.write(f"f {t[0] + 1} {t[1] + 1} {t[2] + 1}\n")
        for q in quads:
            f.write(f"f {q[0] + 1} {q[1] + 1} {q[2] + 1} {q[3] + 1}\n")
    print(json.dumps({
        "bytes": os.path.getsize(prefix + ".vdb"),
        "bytes_half": os.path.getsize(prefix + "-half.vdb"),
        "triangles": int(len(tris) + 2 * len(quads)),
    }))


if __name__ == "__main__":
    main(sys.argv[1], int(sys.argv[2]), sys.argv[3])
