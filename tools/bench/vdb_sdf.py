"""OpenVDB narrow-band level set of a mesh on the pgvol grid.

Run with the system Python that has Debian's python3-openvdb module:
    /usr/bin/python3 vdb_sdf.py IN.npz OUT.npy
IN.npz holds vertices (float), faces (int), origin (3,), h (), n (), half_width ().
Writes the grid sampled at node (i, j, k) = origin + h*(i, j, k) as an (n, n, n)
float32 array indexed [i, j, k] (values beyond the band are +-background), and
prints {"seconds": level-set build time, "dense_seconds": copy-out time, "active": N}.
"""

import json
import sys
import time

import numpy as np

try:
    import pyopenvdb as vdb
except ImportError:  # newer builds name the module openvdb
    import openvdb as vdb


def main(src, dst):
    data = np.load(src)
    origin = np.asarray(data["origin"], dtype=np.float64)
    h = float(data["h"])
    n = int(data["n"])
    half_width = float(data["half_width"])
    # Index space: node (i, j, k) sits at world origin + h*(i, j, k); shift the mesh so
    # the grid origin is the world origin and use a uniform voxel size h.
    points = ((np.asarray(data["vertices"], dtype=np.float64) - origin)).astype(np.float32)
    tris = np.asarray(data["faces"], dtype=np.int32)
    xform = vdb.createLinearTransform(voxelSize=h)

    start = time.perf_counter()
    grid = vdb.FloatGrid.createLevelSetFromPolygons(points, triangles=tris, transform=xform, halfWidth=half_width)
    build = time.perf_counter() - start

    start = time.perf_counter()
    dense = np.zeros((n, n, n), dtype=np.float32)
    grid.copyToArray(dense, ijk=(0, 0, 0))
    copy = time.perf_counter() - start
    np.save(dst, dense)
    print(json.dumps({"seconds": build, "dense_seconds": copy, "active": int(grid.activeVoxelCount())}))


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])
