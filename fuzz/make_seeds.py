#!/usr/bin/env python3
"""Writes the seed corpus fuzz/corpus/<target>/: small valid inputs (the committed test meshes
and cases, a 5-tet cube in every format) and a few malformed ones. Run from anywhere:
    /usr/bin/python3 fuzz/make_seeds.py
The seeds are committed; rerun only to change them."""
import pathlib
import shutil
import struct

root = pathlib.Path(__file__).resolve().parent.parent
corpus = root / "fuzz" / "corpus"

NODES = [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0), (0, 0, 1), (1, 0, 1), (1, 1, 1), (0, 1, 1)]
TETS = [(1, 2, 4, 5), (2, 3, 4, 7), (2, 5, 6, 7), (4, 5, 7, 8), (2, 4, 5, 7)]  # 1-based
QUADS = [(1, 4, 3, 2), (5, 6, 7, 8), (1, 2, 6, 5), (2, 3, 7, 6), (3, 4, 8, 7), (4, 1, 5, 8)]
TRIS = [t for q in QUADS for t in ((q[0], q[1], q[2]), (q[0], q[2], q[3]))]


def put(target, name, data):
    d = corpus / target
    d.mkdir(parents=True, exist_ok=True)
    (d / name).write_bytes(data.encode() if isinstance(data, str) else data)


def msh22_ascii():
    s = "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n%d\n" % len(NODES)
    s += "".join("%d %g %g %g\n" % ((i + 1,) + p) for i, p in enumerate(NODES))
    s += "$EndNodes\n$Elements\n%d\n" % (len(TETS) + 1)
    s += "1 15 2 0 1 1\n"  # a point element, skipped
    s += "".join("%d 4 2 0 1 %d %d %d %d\n" % ((i + 2,) + t) for i, t in enumerate(TETS))
    return s + "$EndElements\n"


def msh41_ascii():
    n, e = len(NODES), len(TETS)
    s = "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n"
    s += "$Entities\n0 0 0 1\n1 0 0 0 1 1 1 0 0\n$EndEntities\n"
    s += "$Nodes\n1 %d 1 %d\n3 1 0 %d\n" % (n, n, n)
    s += "".join("%d\n" % (i + 1) for i in range(n))
    s += "".join("%g %g %g\n" % p for p in NODES)
    s += "$EndNodes\n$Elements\n1 %d 1 %d\n3 1 4 %d\n" % (e, e, e)
    s += "".join("%d %d %d %d %d\n" % ((i + 1,) + t) for i, t in enumerate(TETS))
    return s + "$EndElements\n"


def msh22_binary():
    b = b"$MeshFormat\n2.2 1 8\n" + struct.pack("<i", 1) + b"\n$EndMeshFormat\n"
    b += b"$Nodes\n%d\n" % len(NODES)
    b += b"".join(struct.pack("<i3d", i + 1, *p) for i, p in enumerate(NODES))
    b += b"\n$EndNodes\n$Elements\n%d\n" % len(TETS)
    b += struct.pack("<3i", 4, len(TETS), 2)
    b += b"".join(struct.pack("<7i", i + 1, 0, 1, *t) for i, t in enumerate(TETS))
    return b + b"\n$EndElements\n"


def msh41_binary():
    n, e = len(NODES), len(TETS)
    b = b"$MeshFormat\n4.1 1 8\n" + struct.pack("<i", 1) + b"\n$EndMeshFormat\n"
    b += b"$Nodes\n" + struct.pack("<4Q", 1, n, 1, n) + struct.pack("<3iQ", 3, 1, 0, n)
    b += b"".join(struct.pack("<Q", i + 1) for i in range(n))
    b += b"".join(struct.pack("<3d", *p) for p in NODES)
    b += b"\n$EndNodes\n$Elements\n" + struct.pack("<4Q", 1, e, 1, e) + struct.pack("<3iQ", 3, 1, 4, e)
    b += b"".join(struct.pack("<5Q", i + 1, *t) for i, t in enumerate(TETS))
    return b + b"\n$EndElements\n"


# --- msh
put("msh", "cube5_v22.msh", msh22_ascii())
put("msh", "cube5_v41.msh", msh41_ascii())
put("msh", "cube5_v22_binary.msh", msh22_binary())
put("msh", "cube5_v41_binary.msh", msh41_binary())
shutil.copy(root / "tests/data/msh/cube_v22.msh", corpus / "msh" / "cube_v22.msh")
shutil.copy(root / "tests/data/msh/cube_v41.msh", corpus / "msh" / "cube_v41.msh")
put("msh", "bad_truncated.msh", msh22_ascii()[:200])
put("msh", "bad_huge_count.msh", "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n999999999999\n1 0 0 0\n$EndNodes\n")
put("msh", "bad_version.msh", msh22_ascii().replace("2.2 0 8", "3.0 0 8"))
put("msh", "bad_tag.msh", msh22_ascii().replace("4 2 0 1 1 2 4 5", "4 2 0 1 1 2 4 99"))
put("msh", "bad_binary_truncated.msh", msh41_binary()[:180])

# --- tetgen: .node, the separator line, .ele
SEP = "#--ele--\n"
node = "# cube\n%d 3 0 0\n" % len(NODES) + "".join("%d %g %g %g\n" % ((i + 1,) + p) for i, p in enumerate(NODES))
ele = "%d 4 0\n" % len(TETS) + "".join("%d %d %d %d %d\n" % ((i + 1,) + t) for i, t in enumerate(TETS))
put("tetgen", "cube5.tetgen", node + SEP + ele)
node0 = "%d 3 1 1\n" % len(NODES) + "".join("%d %g %g %g 0.5 1\n" % ((i,) + p) for i, p in enumerate(NODES))
ele0 = "%d 4 1\n" % len(TETS) + "".join("%d %d %d %d %d 7\n" % ((i,) + tuple(v - 1 for v in t)) for i, t in enumerate(TETS))
put("tetgen", "cube5_zero_based_attributes.tetgen", node0 + SEP + ele0)
put("tetgen", "bad_index.tetgen", node + SEP + ele.replace("2 4 5\n", "2 4 50\n", 1))
put("tetgen", "bad_count.tetgen", node.replace("8 3 0 0", "80000000000 3 0 0") + SEP + ele)
put("tetgen", "bad_no_ele.tetgen", node)

# --- surfaces
obj = "".join("v %g %g %g\n" % p for p in NODES) + "".join("f %d %d %d %d\n" % q for q in QUADS)
put("obj", "cube_quads.obj", obj)
put("obj", "cube_tris_slashes.obj", "# c\no cube\n" + "".join("v %g %g %g\nvt 0 0\nvn 0 0 1\n" % p for p in NODES)
    + "".join("f %d/1 %d//1 %d/1/1\n" % t for t in TRIS))
put("obj", "cube_negative.obj", "".join("v %g %g %g\n" % p for p in NODES)
    + "".join("f %d %d %d\n" % tuple(v - 9 for v in t) for t in TRIS))
shutil.copy(root / "tests/data/surface/cube_quads.obj", corpus / "obj" / "cube_quads_tests.obj")
put("obj", "bad_index.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 7\n")
put("obj", "bad_statement.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nfoo 1 2 3\nf 1 2 3\n")
put("obj", "bad_nan.obj", "v nan 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")

def stl_ascii():
    s = "solid cube\n"
    for t in TRIS:
        s += "facet normal 0 0 0\nouter loop\n" + "".join("vertex %g %g %g\n" % NODES[v - 1] for v in t)
        s += "endloop\nendfacet\n"
    return s + "endsolid cube\n"

def stl_binary(header=b"binary cube"):
    b = header.ljust(80, b"\0") + struct.pack("<I", len(TRIS))
    for t in TRIS:
        b += struct.pack("<3f", 0, 0, 0) + b"".join(struct.pack("<3f", *NODES[v - 1]) for v in t) + b"\0\0"
    return b

put("stl", "cube_ascii.stl", stl_ascii())
put("stl", "cube_binary.stl", stl_binary())
put("stl", "cube_binary_solid_header.stl", stl_binary(b"solid but binary"))
shutil.copy(root / "tests/data/surface/cube_ascii.stl", corpus / "stl" / "cube_ascii_tests.stl")
put("stl", "bad_binary_count.stl", stl_binary()[:84 + 50 * 3])
put("stl", "bad_ascii_truncated.stl", stl_ascii()[:300])
put("stl", "bad_huge_count.stl", b"x" * 80 + struct.pack("<I", 0xFFFFFFFF))

off = "OFF\n%d %d 0\n" % (len(NODES), len(QUADS)) + "".join("%g %g %g\n" % p for p in NODES) \
    + "".join("4 %d %d %d %d\n" % tuple(v - 1 for v in q) for q in QUADS)
put("off", "cube.off", off)
put("off", "cube_noheader.off", off[4:])
shutil.copy(root / "tests/data/surface/cube_colours.off", corpus / "off" / "cube_colours.off")
put("off", "cube_coff.off", "COFF\n3 1 0\n0 0 0 1 0 0 1\n1 0 0 0 1 0 1\n0 1 0 0 0 1 1\n3 0 1 2\n")
put("off", "bad_counts.off", "OFF\n99999999999 1 0\n0 0 0\n")
put("off", "bad_index.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 5\n")

# --- case files: the example cases and a few wrong ones
for toml in sorted((root / "cases").glob("*/*.toml")):
    put("case", toml.parent.name + "_" + toml.name, toml.read_text())
put("case", "bad_key.toml", "[simulation]\ndt = 0.01\nstepz = 3\n")
put("case", "bad_type.toml", "[simulation]\ndt = \"fast\"\n")
put("case", "bad_syntax.toml", "[simulation\ndt = 0.01\n")
put("case", "bad_range.toml", "[[body]]\nname = \"a\"\nshape = \"box\"\ncells = [0, 1, 1]\nyoung = -1\n")

# --- scene: cases whose bodies are built; cube.msh and cube.obj lie next to the case file
put("scene", "box_and_mesh.toml", """[simulation]
steps = 2
[contact]
enabled = true
[[body]]
name = "box"
shape = "box"
min = [0, 0, 0]
max = [1, 1, 1]
cells = [2, 2, 2]
[[body.fixed]]
min = [-1, -1, -1]
max = [0.1, 2, 2]
[[body.load]]
min = [0.9, -1, -1]
max = [2, 2, 2]
force = [0, -1, 0]
[[body]]
name = "cube"
mesh = "cube.msh"
surface = "cube.obj"
translate = [0, 1.5, 0]
scale = 0.5
rotate_axis = [0, 0, 1]
rotate_degrees = 30
[[obstacle]]
type = "plane"
point = [0, -1, 0]
normal = [0, 1, 0]
[[obstacle]]
type = "mesh"
mesh = "cube.obj"
""")
put("scene", "sphere.toml", """[[body]]
name = "ball"
shape = "sphere"
center = [0, 0, 0]
radius = 0.5
resolution = 4
""")
put("scene", "bad_duplicate_names.toml", "[[body]]\nname = \"a\"\nmesh = \"cube.msh\"\n[[body]]\nname = \"a\"\nmesh = \"cube.msh\"\n")
put("scene", "bad_missing_mesh.toml", "[[body]]\nname = \"a\"\nmesh = \"nothere.msh\"\n")
put("scene", "bad_empty_fixed.toml", "[[body]]\nname = \"a\"\nmesh = \"cube.msh\"\n[[body.fixed]]\nmin = [5, 5, 5]\nmax = [6, 6, 6]\n")
