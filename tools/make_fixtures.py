#!/usr/bin/env python3
"""Writes the small meshes in fixtures/ (pure Python, deterministic).

- torus-knot.obj: a closed, consistently oriented tube around a (2,3) torus knot (genus 1).
- open-cup.obj: a cylinder without a lid (open, 1 boundary loop), for sign robustness.
"""
import math
import pathlib

ROOT = pathlib.Path(__file__).resolve().parent.parent / "fixtures"


def knot_point(t):
    p, q = 2, 3
    r = 2.0 + math.cos(q * t)
    return (r * math.cos(p * t), r * math.sin(p * t), -math.sin(q * t))


def sub(a, b):
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


def add(a, b):
    return (a[0] + b[0], a[1] + b[1], a[2] + b[2])


def scale(a, s):
    return (a[0] * s, a[1] * s, a[2] * s)


def dot(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def normalize(a):
    n = math.sqrt(dot(a, a))
    return scale(a, 1.0 / n)


def tube(curve, segments, sides, radius):
    """A closed tube: rotation-minimising frames by double reflection, twist spread evenly."""
    pts = [curve(2 * math.pi * i / segments) for i in range(segments)]
    tangents = [normalize(sub(pts[(i + 1) % segments], pts[i - 1])) for i in range(segments)]
    t0 = tangents[0]
    helper = (0.0, 0.0, 1.0) if abs(t0[2]) < 0.9 else (1.0, 0.0, 0.0)
    normals = [normalize(cross(cross(t0, helper), t0))]
    for i in range(segments):
        j = (i + 1) % segments
        v1 = sub(pts[j], pts[i])
        c1 = dot(v1, v1)
        r_l = sub(normals[i], scale(v1, 2 * dot(v1, normals[i]) / c1))
        t_l = sub(tangents[i], scale(v1, 2 * dot(v1, tangents[i]) / c1))
        v2 = sub(tangents[j], t_l)
        c2 = dot(v2, v2)
        n = sub(r_l, scale(v2, 2 * dot(v2, r_l) / c2)) if c2 > 1e-12 else r_l
        normals.append(normalize(n))
    # Close the frame: spread the angle between the transported and the first normal.
    end = normals[segments]
    b0 = cross(tangents[0], normals[0])
    twist = math.atan2(dot(end, b0), dot(end, normals[0]))
    verts = []
    for i in range(segments):
        n = normals[i]
        b = cross(tangents[i], n)
        shift = -twist * i / segments
        for k in range(sides):
            a = 2 * math.pi * k / sides + shift
            off = add(scale(n, math.cos(a) * radius), scale(b, math.sin(a) * radius))
            verts.append(add(pts[i], off))
    faces = []
    for i in range(segments):
        j = (i + 1) % segments
        for k in range(sides):
            l = (k + 1) % sides
            a, b, c, d = i * sides + k, j * sides + k, j * sides + l, i * sides + l
            faces.append((a, d, c))
            faces.append((a, c, b))
    return verts, faces


def signed_volume(verts, faces):
    return sum(dot(verts[a], cross(verts[b], verts[c])) for a, b, c in faces) / 6.0


def write_obj(path, verts, faces, comment):
    lines = [f"# {comment}"]
    lines += [f"v {x:.6f} {y:.6f} {z:.6f}" for x, y, z in verts]
    lines += [f"f {a + 1} {b + 1} {c + 1}" for a, b, c in faces]
    path.write_text("\n".join(lines) + "\n")


def cup(sides=48, rings=12, radius=1.0, height=1.5):
    verts = [(0.0, 0.0, 0.0)]
    for r in range(rings + 1):
        z = height * r / rings
        for k in range(sides):
            a = 2 * math.pi * k / sides
            verts.append((radius * math.cos(a), radius * math.sin(a), z))
    faces = []
    for k in range(sides):
        faces.append((0, 1 + (k + 1) % sides, 1 + k))
    for r in range(rings):
        for k in range(sides):
            l = (k + 1) % sides
            a, b = 1 + r * sides + k, 1 + r * sides + l
            c, d = a + sides, b + sides
            faces.append((a, b, d))
            faces.append((a, d, c))
    return verts, faces


def main():
    ROOT.mkdir(exist_ok=True)
    verts, faces = tube(knot_point, 240, 16, 0.45)
    if signed_volume(verts, faces) < 0:
        faces = [(a, c, b) for a, b, c in faces]
    write_obj(ROOT / "torus-knot.obj", verts, faces, "(2,3) torus knot tube, closed, written by tools/make_fixtures.py")
    verts, faces = cup()
    write_obj(ROOT / "open-cup.obj", verts, faces, "open cylinder (no lid), written by tools/make_fixtures.py")


if __name__ == "__main__":
    main()
