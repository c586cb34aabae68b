"""Closing the holes of an open mesh with flat caps, for reference surfaces of open scans (the
Stanford bunny's five holes). numpy only, so every script in tools/ can use it."""

import numpy as np


def boundary_loops(faces):
    """Closed loops of boundary edges, each following its faces' orientation.

    A boundary edge is a directed face edge whose reverse no face has. Where several loops meet
    at one vertex the walk takes any unused outgoing edge, which still yields closed loops.
    """
    faces = np.asarray(faces, dtype=np.int64)
    directed = np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]])
    present = {(int(a), int(b)) for a, b in directed}
    outgoing = {}
    for a, b in present:
        if (b, a) not in present:
            outgoing.setdefault(a, []).append(b)
    loops = []
    while outgoing:
        start = next(iter(outgoing))
        loop, v = [], start
        while v in outgoing:
            loop.append(v)
            nxt = outgoing[v].pop()
            if not outgoing[v]:
                del outgoing[v]
            v = nxt
        loops.append(loop)
    return loops


def _ear_clip(uv):
    """Triangles (index triples into uv) of a simple counter-clockwise polygon, by ear clipping."""
    def cross(o, a, b):
        return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])

    def inside(p, a, b, c):
        return cross(a, b, p) >= 0 and cross(b, c, p) >= 0 and cross(c, a, p) >= 0

    left = list(range(len(uv)))
    triangles = []
    while len(left) > 3:
        for k in range(len(left)):
            i, j, l = left[k - 1], left[k], left[(k + 1) % len(left)]
            if cross(uv[i], uv[j], uv[l]) <= 0:
                continue
            if any(inside(uv[m], uv[i], uv[j], uv[l]) for m in left if m not in (i, j, l)):
                continue
            triangles.append((i, j, l))
            del left[k]
            break
        else:
            raise ValueError("hole boundary is not a simple polygon in its best-fit plane")
    triangles.append(tuple(left))
    return triangles


def cap_holes(vertices, faces):
    """(vertices, faces) with each hole closed by triangulating its boundary in the boundary's
    best-fit plane (ear clipping), so caps neither fold nor cross themselves. The cap runs
    against the boundary edges' direction so shared edges pair up. Suited to small, nearly flat
    holes such as the bunny's; raises ValueError for a boundary that is not simple in its plane."""
    vertices = np.asarray(vertices, dtype=np.float64)
    faces = np.asarray(faces, dtype=np.int64)
    new_faces = [faces]
    for loop in boundary_loops(faces):
        ring = np.asarray(loop[::-1])
        points = vertices[ring]
        centred = points - points.mean(axis=0)
        _, _, axes = np.linalg.svd(centred, full_matrices=False)
        uv = centred @ axes[:2].T
        area = 0.5 * np.sum(uv[:, 0] * np.roll(uv[:, 1], -1) - uv[:, 1] * np.roll(uv[:, 0], -1))
        if area < 0:
            uv[:, 1] = -uv[:, 1]
        new_faces.append(ring[np.asarray(_ear_clip(uv))])
    return vertices, np.concatenate(new_faces)


def write_obj(path, vertices, faces):
    with open(path, "w") as f:
        for p in vertices:
            f.write("v %r %r %r\n" % (float(p[0]), float(p[1]), float(p[2])))
        for t in faces:
            f.write(f"f {t[0] + 1} {t[1] + 1} {t[2] + 1}\n")
