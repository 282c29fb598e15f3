#!/usr/bin/env python3
"""Writes ring.msh (a tet mesh of a ring with a square cross-section, Gmsh MSH 2.2 ASCII) and
ring.obj (its boundary surface, outward normals): small files to try `corocontact info` on, and
the body of ring.toml. Run it again after changing a number."""
import itertools
import math
import pathlib

AROUND, ACROSS, UP = 24, 2, 2          # cells around the ring, across its width, in height
INNER, OUTER, HEIGHT = 0.3, 0.5, 0.2   # radii and height [m]

HERE = pathlib.Path(__file__).resolve().parent


def node(i, j, k):
    """Index of grid node (i around, j across, k up); the ring closes: i wraps around."""
    return ((i % AROUND) * (ACROSS + 1) + j) * (UP + 1) + k


def position(i, j, k):
    angle = 2.0 * math.pi * i / AROUND
    r = INNER + (OUTER - INNER) * j / ACROSS
    return (r * math.cos(angle), HEIGHT * k / UP, -r * math.sin(angle))


def signed_volume(a, b, c, d):
    u = [b[m] - a[m] for m in range(3)]
    v = [c[m] - a[m] for m in range(3)]
    w = [d[m] - a[m] for m in range(3)]
    return (u[0] * (v[1] * w[2] - v[2] * w[1]) - u[1] * (v[0] * w[2] - v[2] * w[0])
            + u[2] * (v[0] * w[1] - v[1] * w[0])) / 6.0


def tets():
    """Six tets per cell around its main diagonal (Freudenthal), conforming between cells."""
    out = []
    for i, j, k in itertools.product(range(AROUND), range(ACROSS), range(UP)):
        for order in itertools.permutations(range(3)):
            corner = [0, 0, 0]
            path = [tuple(corner)]
            for axis in order:
                corner[axis] = 1
                path.append(tuple(corner))
            out.append([node(i + a, j + b, k + c) for a, b, c in path])
    return out


def main():
    points = [position(i, j, k) for i in range(AROUND) for j in range(ACROSS + 1) for k in range(UP + 1)]
    elements = tets()
    for t in elements:  # positive volumes, so the loader has nothing to reorient
        if signed_volume(*(points[v] for v in t)) < 0.0:
            t[2], t[3] = t[3], t[2]
    lines = ["$MeshFormat", "2.2 0 8", "$EndMeshFormat", "$Nodes", str(len(points))]
    lines += [f"{n + 1} {x:.17g} {y:.17g} {z:.17g}" for n, (x, y, z) in enumerate(points)]
    lines += ["$EndNodes", "$Elements", str(len(elements))]
    lines += [f"{e + 1} 4 2 1 1 " + " ".join(str(v + 1) for v in t) for e, t in enumerate(elements)]
    lines += ["$EndElements"]
    (HERE / "ring.msh").write_text("\n".join(lines) + "\n")

    # Boundary: faces of one tet only, oriented away from the tet's fourth vertex.
    count = {}
    for t in elements:
        for skip in range(4):
            face = [t[m] for m in range(4) if m != skip]
            count.setdefault(tuple(sorted(face)), []).append((face, t[skip]))
    faces = []
    for uses in count.values():
        if len(uses) == 1:
            face, opposite = uses[0]
            if signed_volume(*(points[v] for v in face), points[opposite]) > 0.0:
                face = [face[0], face[2], face[1]]
            faces.append(face)
    used = sorted({v for f in faces for v in f})
    new = {v: n for n, v in enumerate(used)}
    obj = ["# Boundary of ring.msh (make_ring.py): a closed surface of genus 1"]
    obj += ["v {:.17g} {:.17g} {:.17g}".format(*points[v]) for v in used]
    obj += ["f " + " ".join(str(new[v] + 1) for v in f) for f in faces]
    (HERE / "ring.obj").write_text("\n".join(obj) + "\n")
    print(f"ring.msh: {len(points)} nodes, {len(elements)} tets; ring.obj: {len(used)} vertices, {len(faces)} faces")


if __name__ == "__main__":
    main()
