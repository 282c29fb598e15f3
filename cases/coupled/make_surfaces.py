#!/usr/bin/env python3
"""Writes the surfaces of the coupled case: ball_fine.obj (an icosphere of 2,562 vertices,
radius 0.5) and ramp.obj (a closed slab tilted by 15 degrees about z)."""
import math
import pathlib

HERE = pathlib.Path(__file__).parent


def icosphere(levels, radius):
    t = (1.0 + math.sqrt(5.0)) / 2.0
    vertices = [(-1, t, 0), (1, t, 0), (-1, -t, 0), (1, -t, 0), (0, -1, t), (0, 1, t), (0, -1, -t), (0, 1, -t),
                (t, 0, -1), (t, 0, 1), (-t, 0, -1), (-t, 0, 1)]
    vertices = [tuple(c / math.sqrt(sum(x * x for x in v)) for c in v) for v in vertices]
    faces = [(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9), (5, 11, 4), (11, 10, 2),
             (10, 7, 6), (7, 1, 8), (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8), (3, 8, 9), (4, 9, 5), (2, 4, 11),
             (6, 2, 10), (8, 6, 7), (9, 8, 1)]
    for _ in range(levels):
        cache = {}

        def middle(a, b):
            key = (min(a, b), max(a, b))
            if key not in cache:
                m = [(x + y) / 2 for x, y in zip(vertices[a], vertices[b])]
                n = math.sqrt(sum(c * c for c in m))
                vertices.append(tuple(c / n for c in m))
                cache[key] = len(vertices) - 1
            return cache[key]

        refined = []
        for a, b, c in faces:
            ab, bc, ca = middle(a, b), middle(b, c), middle(c, a)
            refined += [(a, ab, ca), (b, bc, ab), (c, ca, bc), (ab, bc, ca)]
        faces = refined
    return [tuple(radius * c for c in v) for v in vertices], faces


def write_obj(path, vertices, faces, comment):
    lines = [f"# {comment}"] + [f"v {x:.9g} {y:.9g} {z:.9g}" for x, y, z in vertices]
    lines += [f"f {a + 1} {b + 1} {c + 1}" for a, b, c in faces]
    path.write_text("\n".join(lines) + "\n")


def slab(x0, x1, y0, y1, z0, z1, degrees):
    corners = [(x, y, z) for z in (z0, z1) for y in (y0, y1) for x in (x0, x1)]
    a = math.radians(degrees)
    corners = [(x * math.cos(a) - y * math.sin(a), x * math.sin(a) + y * math.cos(a), z) for x, y, z in corners]
    # corner index = x + 2 y + 4 z; faces counter-clockwise seen from outside
    quads = [(0, 2, 3, 1), (4, 5, 7, 6), (0, 1, 5, 4), (2, 6, 7, 3), (0, 4, 6, 2), (1, 3, 7, 5)]
    faces = [f for a_, b, c, d in quads for f in ((a_, b, c), (a_, c, d))]
    return corners, faces


if __name__ == "__main__":
    vertices, faces = icosphere(4, 0.5)
    write_obj(HERE / "ball_fine.obj", vertices, faces, "icosphere, 4 subdivisions, radius 0.5 (make_surfaces.py)")
    vertices, faces = slab(-2.0, 2.0, -0.4, 0.0, -1.0, 1.0, -15.0)
    write_obj(HERE / "ramp.obj", vertices, faces, "slab tilted by -15 degrees about z (make_surfaces.py)")
