#!/usr/bin/env python3
"""Renders meshes side by side to a PNG with flat Lambert shading (matplotlib only).

usage: render_preview.py OUT.png MESH.obj[=TITLE] [MESH.obj[=TITLE] ...]
Used for the picture in the README: the input fixture next to its pgvol remesh.
"""
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from mpl_toolkits.mplot3d.art3d import Poly3DCollection  # noqa: E402
from objfile import read_obj  # noqa: E402


def draw(ax, verts, faces, title):
    tris = verts[faces]
    n = np.cross(tris[:, 1] - tris[:, 0], tris[:, 2] - tris[:, 0])
    n /= np.linalg.norm(n, axis=1, keepdims=True) + 1e-30
    light = np.array([0.4, -0.5, 0.75])
    light /= np.linalg.norm(light)
    shade = 0.25 + 0.75 * np.clip(n @ light, 0, 1)
    colors = np.outer(shade, [0.36, 0.55, 0.85])
    ax.add_collection3d(Poly3DCollection(tris, facecolors=colors, edgecolors="none"))
    lo, hi = verts.min(0), verts.max(0)
    c, r = (lo + hi) / 2, (hi - lo).max() / 2
    ax.set_xlim(c[0] - r, c[0] + r)
    ax.set_ylim(c[1] - r, c[1] + r)
    ax.set_zlim(c[2] - r, c[2] + r)
    ax.view_init(elev=35, azim=-60)
    ax.set_axis_off()
    ax.set_title(title, fontsize=12, y=0.88)


def main():
    out, items = sys.argv[1], sys.argv[2:]
    fig = plt.figure(figsize=(5 * len(items), 5), dpi=100)
    for k, item in enumerate(items):
        path, _, title = item.partition("=")
        verts, faces = read_obj(path)
        ax = fig.add_subplot(1, len(items), k + 1, projection="3d")
        draw(ax, verts, faces, title or path)
    fig.subplots_adjust(left=0, right=1, bottom=0, top=0.92, wspace=0)
    fig.savefig(out, bbox_inches="tight", pad_inches=0.05)


if __name__ == "__main__":
    main()
