# Writes the bad-input corpus (run from this folder with /usr/bin/python3 make_corpus.py).
# Each file is listed in expected.tsv with the command to run, the exit code and a message
# substring that names the file and the line (or byte, or element). Files are derived from the
# good test meshes in ../msh, ../vtk, ../tetgen where that is the point (truncation, patched
# counts), otherwise written here by hand. Deterministic: no randomness beyond a fixed seed.
import os
import random
import struct

HERE = os.path.dirname(os.path.abspath(__file__))
DATA = os.path.dirname(HERE)


def read(rel):
    with open(os.path.join(DATA, rel), "rb") as f:
        return f.read()


def write(name, data):
    if isinstance(data, str):
        data = data.encode()
    with open(os.path.join(HERE, name), "wb") as f:
        f.write(data)


V22 = "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n"
NODES4 = "$Nodes\n4\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n$EndNodes\n"


def msh22(nodes, elements):
    return V22 + nodes + "$Elements\n%d\n%s$EndElements\n" % (len(elements), "".join(e + "\n" for e in elements))


# --- Gmsh MSH, ASCII -----------------------------------------------------------------------
cube22 = read("msh/cube_v22.msh")
write("msh_truncated_nodes.msh", cube22[: cube22.index(b"\n", 400) + 1])
cube41 = read("msh/cube_v41.msh")
write("msh41_truncated_elements.msh", cube41[: cube41.index(b"\n", len(cube41) - 300) + 1])
write("msh_garbage.msh", bytes(random.Random(6).randrange(256) for _ in range(512)))
write("msh_version3.msh", "$MeshFormat\n3.0 0 8\n$EndMeshFormat\n" + NODES4)
write("msh_header_count_too_large.msh", V22 + "$Nodes\n1000000000\n1 0 0 0\n2 1 0 0\n$EndNodes\n")
write("msh_nan_coordinate.msh", msh22("$Nodes\n4\n1 0 0 0\n2 1 0 0\n3 0 nan 0\n4 0 0 1\n$EndNodes\n",
                                      ["1 4 2 0 1 1 2 3 4"]))
write("msh_unknown_node.msh", msh22(NODES4, ["1 4 2 0 1 1 2 3 4", "2 4 2 0 1 1 2 3 9"]))
write("msh_repeated_node.msh", msh22(NODES4, ["1 4 2 0 1 1 2 3 4", "2 4 2 0 1 1 2 2 4"]))
write("msh_zero_volume.msh", msh22("$Nodes\n5\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n5 1 1 0\n$EndNodes\n",
                                   ["1 4 2 0 1 1 2 3 4", "2 4 2 0 1 1 2 3 5"]))
write("msh_no_tets.msh", msh22(NODES4, ["1 2 2 0 1 1 2 3", "2 2 2 0 1 1 2 4"]))
write("msh_empty.msh", "")
write("msh_duplicate_node_tag.msh", V22 + "$Nodes\n3\n1 0 0 0\n2 1 0 0\n1 0 1 0\n$EndNodes\n")
write("msh_three_node_tet.msh", msh22(NODES4, ["1 4 2 0 1 1 2 3"]))

# A tet listed twice, as Gmsh's MSH 2 writes a volume that belongs to two physical groups.
write("msh_duplicate_tet.msh", msh22("$Nodes\n5\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n5 1 1 1\n$EndNodes\n",
                                     ["1 4 2 1 1 1 2 3 4", "2 4 2 1 1 2 3 4 5", "3 4 2 2 1 1 2 4 3"]))
# Two tets on the same side of their shared face (the second folds back over the first).
write("msh_overlapping_tets.msh", msh22("$Nodes\n5\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n5 0.2 0.2 0.2\n$EndNodes\n",
                                        ["1 4 2 0 1 1 2 3 4", "2 4 2 0 1 1 2 3 5"]))
write("msh_huge_coordinate.msh", msh22("$Nodes\n4\n1 0 0 0\n2 1e300 0 0\n3 0 1e300 0\n4 0 0 1e300\n$EndNodes\n",
                                       ["1 4 2 0 1 1 2 3 4"]))
write("msh_tiny.msh", msh22("$Nodes\n4\n1 0 0 0\n2 1e-120 0 0\n3 0 1e-120 0\n4 0 0 1e-120\n$EndNodes\n",
                            ["1 4 2 0 1 1 2 3 4"]))

# --- Gmsh MSH, binary ----------------------------------------------------------------------
bin22 = read("msh/cube_v22_bin.msh")
write("msh22_bin_truncated.msh", bin22[: len(bin22) // 2])
bin41 = read("msh/cube_v41_bin.msh")
write("msh41_bin_truncated.msh", bin41[: len(bin41) * 3 // 4])
at = bin41.index(b"$Nodes\n") + 7 + 8
write("msh41_bin_count_too_large.msh", bin41[:at] + struct.pack("<Q", 1 << 40) + bin41[at + 8:])
at = bin22.index(b"$Nodes\n") + 7
at = bin22.index(b"\n", at) + 1 + 4  # first node: int tag, then x
write("msh22_bin_nan.msh", bin22[:at] + struct.pack("<d", float("inf")) + bin22[at + 8:])
at = bin22.index(b"2.2 1 8\n") + 8
write("msh22_bin_bad_byte_order.msh", bin22[:at] + struct.pack("<i", 256 + 7) + bin22[at + 4:])

# --- TetGen --------------------------------------------------------------------------------
write("tetgen_missing_node.ele", "1 4 0\n1 1 2 3 4\n")
UNIT = "4 3 0 0\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n"
write("tetgen_quadratic.node", UNIT)
write("tetgen_quadratic.ele", "1 10 0\n1 1 2 3 4 1 2 3 4 1 2\n")
write("tetgen_index_out_of_range.node", UNIT)
write("tetgen_index_out_of_range.ele", "# one tet\n1 4 0\n1 1 2 3 7\n")
node = read("tetgen/cube.1.node")
write("tetgen_truncated.node", node[: node.index(b"\n", len(node) // 2) + 1])
write("tetgen_truncated.ele", read("tetgen/cube.1.ele"))

# --- VTK -----------------------------------------------------------------------------------
write("vtu_garbage.vtu", "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\"><Piece NumberOf")
vtu = read("vtk/cube_appended.vtu")
write("vtu_truncated.vtu", vtu[: len(vtu) * 2 // 3])
vtu_ascii = read("vtk/cube_ascii.vtu")
write("vtu_count_too_large.vtu", vtu_ascii.replace(b'NumberOfPoints="76"', b'NumberOfPoints="760000000000"'))
legacy = read("vtk/cube_gmsh.vtk")
write("vtk_truncated.vtk", legacy[: len(legacy) // 2])
write("vtk_polydata.vtk", "# vtk DataFile Version 2.0\np\nASCII\nDATASET POLYDATA\nPOINTS 3 float\n0 0 0 1 0 0 0 1 0\n")
write("vtk_duplicate_tet.vtk", "# vtk DataFile Version 2.0\ntwice\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS 4 double\n"
      "0 0 0 1 0 0 0 1 0 0 0 1\nCELLS 2 10\n4 0 1 2 3\n4 3 2 1 0\nCELL_TYPES 2\n10\n10\n")
write("vtk_no_tets.vtk", "# vtk DataFile Version 2.0\ntri\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS 3 double\n"
      "0 0 0 1 0 0 0 1 0\nCELLS 1 4\n3 0 1 2\nCELL_TYPES 1\n5\n")

# --- Surfaces (read through case files) ------------------------------------------------------
stl = read("surface/cube_binary_solid.stl")
write("stl_wrong_count.stl", stl[:80] + struct.pack("<I", struct.unpack("<I", stl[80:84])[0] + 5) + stl[84:])
write("obj_index_zero.obj", "v 0.2 0.2 0.2\nv 0.8 0.2 0.2\nv 0.2 0.8 0.2\nf 0 1 2\n")
write("off_truncated.off", "OFF\n8 12 0\n0 0 0\n1 0 0\n")

# --- Case files ----------------------------------------------------------------------------
BODY = "[[body]]\nname = \"block\"\nshape = \"box\"\nmin = [0.0, 0.0, 0.0]\nmax = [1.0, 1.0, 1.0]\n"
SIM = "[simulation]\ndt = 0.01\nsteps = 2\n\n"
write("case_misspelled_key.toml", SIM + BODY + "yuong = 1e5\n")
write("case_misspelled_section.toml", "[simulaton]\ndt = 0.01\n\n" + BODY)
write("case_negative_dt.toml", "[simulation]\ndt = -0.01\nsteps = 2\n\n" + BODY)
write("case_poisson_half.toml", SIM + BODY + "poisson = 0.5\n")
write("case_wrong_type.toml", "[simulation]\ndt = 0.01\nsteps = \"ten\"\n\n" + BODY)
write("case_bad_choice.toml", SIM + "[contact]\nmode = \"exactly\"\n\n" + BODY)
write("case_missing_mesh.toml", SIM + "[[body]]\nname = \"a\"\nmesh = \"does_not_exist.msh\"\n")
write("case_directory_mesh.toml", SIM + "[[body]]\nname = \"a\"\nmesh = \"folder.msh\"\n")
write("case_duplicate_body.toml", SIM + BODY + "\n" + BODY.replace("0.0, 0.0, 0.0", "2.0, 0.0, 0.0")
      .replace("1.0, 1.0, 1.0", "3.0, 1.0, 1.0"))
write("case_empty.toml", "")
write("case_garbage.toml", bytes(random.Random(7).randrange(256) for _ in range(300)))
write("case_syntax_error.toml", SIM + "[[body]\nname = \"a\"\n")
write("case_bad_mesh.toml", SIM + "[[body]]\nname = \"flat\"\nmesh = \"msh_zero_volume.msh\"\n")
write("case_bad_binary_mesh.toml", SIM + "[[body]]\nname = \"cut\"\nmesh = \"msh22_bin_truncated.msh\"\n")
write("case_unknown_mesh_extension.toml", SIM + "[[body]]\nname = \"a\"\nmesh = \"mesh.ply\"\n")
write("case_stl_wrong_count.toml", SIM + BODY + "\n[[obstacle]]\ntype = \"mesh\"\nmesh = \"stl_wrong_count.stl\"\n")
write("case_obj_index_zero.toml", SIM + BODY + "surface = \"obj_index_zero.obj\"\n")
write("case_off_truncated.toml", SIM + BODY + "\n[[obstacle]]\ntype = \"mesh\"\nmesh = \"off_truncated.off\"\n")
write("case_empty_fixed_box.toml", SIM + BODY + "[[body.fixed]]\nmin = [5.0, 5.0, 5.0]\nmax = [6.0, 6.0, 6.0]\n")
write("case_inverted_box.toml", SIM + BODY.replace("max = [1.0, 1.0, 1.0]", "max = [-1.0, 1.0, 1.0]"))

# Values whose products leave the range of double, and sizes beyond what can be numbered or held.
write("case_young_huge.toml", SIM + BODY + "young = 1e300\n")
write("case_density_tiny.toml", SIM + BODY + "density = 1e-300\n")
write("case_dt_tiny.toml", "[simulation]\ndt = 1e-300\nsteps = 2\n\n" + BODY)
write("case_gravity_huge.toml", "[simulation]\ndt = 0.01\nsteps = 2\ngravity = [0.0, -1e300, 0.0]\n\n" + BODY)
write("case_contact_stiffness_huge.toml", SIM + "[contact]\nenabled = true\nstiffness = 1e300\n\n" + BODY)
# Values inside double's range whose stiffness-to-mass ratio dt²(λ+2μ)/(ρh²) loses the mass in the step.
write("case_density_light.toml", "[simulation]\ndt = 0.01\nsteps = 2\ngravity = [0.0, -9.81, 0.0]\n\n" + BODY +
      "density = 1e-20\n")
write("case_young_stiff.toml", SIM + BODY + "young = 1e110\n[[body.fixed]]\nmax = [0.1, 1e9, 1e9]\n")
write("case_far_from_origin.toml", SIM + BODY + "translate = [1e12, 0.0, 0.0]\n")
write("case_translate_huge.toml", SIM + BODY + "translate = [1e300, 0.0, 0.0]\n")
write("case_tolerance_one.toml", SIM + "[solver]\ntolerance = 1.0\n\n" + BODY)
write("case_parts_per_thread.toml", SIM + "[solver]\nparts_per_thread = 2147483647\n\n" + BODY)
write("case_cells_overflow.toml", SIM + BODY + "cells = [2000, 2000, 2000]\n")
write("case_cells_memory.toml", SIM + BODY + "cells = [1000, 1000, 300]\n")
write("case_sphere_overflow.toml", SIM + "[[body]]\nname = \"ball\"\nshape = \"sphere\"\nresolution = 100000\n")
write("case_mesh_duplicate_tet.toml", SIM + "[[body]]\nname = \"twice\"\nmesh = \"msh_duplicate_tet.msh\"\n")
# Output names: too long, or taken by another block of the frame.
write("case_name_too_long.toml", SIM + BODY.replace('"block"', '"' + "b" * 129 + '"'))
write("case_name_obstacle.toml", SIM + BODY.replace('"block"', '"obstacle0"') +
      "\n[[obstacle]]\ntype = \"mesh\"\nmesh = \"surface_cube.obj\"\n")
write("case_name_surface.toml", SIM + BODY + "surface = \"surface_cube.obj\"\n\n" +
      BODY.replace('"block"', '"block_surface"').replace("0.0, 0.0, 0.0", "2.0, 0.0, 0.0")
      .replace("1.0, 1.0, 1.0", "3.0, 1.0, 1.0"))
# An embedded surface far from its body's tets; a body that starts behind a plane.
write("case_surface_far.toml", SIM + BODY + "surface = \"surface_far.obj\"\n")
write("case_plane_behind.toml", SIM + "[contact]\nenabled = true\n\n" + BODY +
      "\n[[obstacle]]\ntype = \"plane\"\npoint = [0.0, 2.0, 0.0]\nnormal = [0.0, 1.0, 0.0]\n")
write("case_plane_point_huge.toml", SIM + BODY + "\n[[obstacle]]\ntype = \"plane\"\npoint = [0.0, -1e200, 0.0]\n")
CUBE_OBJ = ("v {0} {0} {0}\nv {1} {0} {0}\nv {1} {1} {0}\nv {0} {1} {0}\nv {0} {0} {1}\nv {1} {0} {1}\nv {1} {1} {1}\n"
            "v {0} {1} {1}\nf 1 4 3\nf 1 3 2\nf 5 6 7\nf 5 7 8\nf 1 2 6\nf 1 6 5\nf 2 3 7\nf 2 7 6\nf 3 4 8\n"
            "f 3 8 7\nf 4 1 5\nf 4 5 8\n")
write("surface_cube.obj", CUBE_OBJ.format(0.1, 0.9))
write("surface_far.obj", CUBE_OBJ.format(10.1, 10.9))
write("surface_huge.obj", CUBE_OBJ.format(2.0, 1e300))
write("case_obstacle_huge.toml", SIM + BODY + "\n[[obstacle]]\ntype = \"mesh\"\nmesh = \"surface_huge.obj\"\n")

# A directory where a mesh or case file is expected (git keeps them through a README).
for folder in ("folder.msh", "folder.toml"):
    os.makedirs(os.path.join(HERE, folder), exist_ok=True)
    write(os.path.join(folder, "README.md"), "A directory where a file is expected (bad-input corpus).\n")
