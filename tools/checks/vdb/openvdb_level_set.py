"""Run under the system Python, where pyopenvdb imports: a level set of a triangle mesh
written as OpenVDB writes it by default (Blosc), and OpenVDB's own mesh of it.

    python3 openvdb_level_set.py MESH.npz OUT.vdb REFERENCE.npz [--half]

MESH.npz holds `points` (n x 3 float) and `triangles` (m x 3 int); the voxel size is 1.1 x the
longest extent / 255 (a grid of about 256 voxels across) and the band the default 3 voxels
each side. REFERENCE.npz receives OpenVDB's volumeToMesh at isovalue 0 as `points`,
`triangles` and `quads`, and the voxel size as `voxel`.
"""

import sys

import numpy as np
import pyopenvdb as vdb


def main() -> None:
    mesh_path, out_vdb, out_ref = sys.argv[1:4]
    half = "--half" in sys.argv[4:]
    mesh = np.load(mesh_path)
    points = np.asarray(mesh["points"], dtype=np.float32)
    triangles = np.asarray(mesh["triangles"], dtype=np.int32)
    extent = float((points.max(axis=0) - points.min(axis=0)).max())
    voxel = 1.1 * extent / 255.0
    grid = vdb.FloatGrid.createLevelSetFromPolygons(
        points, triangles=triangles, transform=vdb.createLinearTransform(voxelSize=voxel)
    )
    grid.name = "surface"
    if half:
        grid.saveFloatAsHalf = True
    vdb.write(out_vdb, grids=[grid])
    ref_points, ref_triangles, ref_quads = grid.convertToPolygons(isovalue=0.0)
    np.savez(
        out_ref,
        points=ref_points,
        triangles=ref_triangles,
        quads=ref_quads,
        voxel=np.float64(voxel),
        active=np.int64(grid.activeVoxelCount()),
    )


if __name__ == "__main__":
    main()
