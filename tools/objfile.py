"""A minimal OBJ reader (positions and fan-triangulated faces) for the scripts in tools/, which
run under different Pythons and cannot rely on trimesh being installed."""

import numpy as np


def read_obj(path):
    """Vertices as float64 (n, 3) and triangles as int64 (m, 3); texture and normal indices are
    ignored, negative (relative) indices resolved."""
    verts, faces = [], []
    with open(path) as f:
        for line in f:
            parts = line.split()
            if not parts:
                continue
            if parts[0] == "v":
                verts.append([float(x) for x in parts[1:4]])
            elif parts[0] == "f":
                idx = [int(p.split("/")[0]) for p in parts[1:]]
                idx = [i - 1 if i > 0 else len(verts) + i for i in idx]
                faces.extend([idx[0], idx[k], idx[k + 1]] for k in range(1, len(idx) - 1))
    return np.array(verts, dtype=np.float64), np.array(faces, dtype=np.int64).reshape(-1, 3)
