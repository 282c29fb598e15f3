#pragma once
/// @file mesh_readers.hpp
/// @brief Tetrahedral mesh readers (and a writer for round trips).

#include <corocontact/core/tet_mesh.hpp>

#include <filesystem>

namespace coro {

/// Reads a tet mesh, choosing the format by extension (case-insensitive):
/// - `.msh`: Gmsh 2.2 or 4.1, ASCII or binary (read_msh);
/// - `.vtu`, `.vtk`: VTK XML or legacy unstructured grid (read_vtk_mesh);
/// - `.node`, `.ele`: TetGen, both files with the same stem (read_tetgen).
///
/// The mesh is returned as read: node order is the file's, elements other than 4-node tets
/// skipped. Call validate_and_orient() on the result.
/// @throws InputError naming the file, the line (byte offset or element for binary data) and
///         what was expected, for a missing file, an unknown extension, a malformed or
///         truncated file, an unknown node
TetMesh read_tet_mesh(const std::filesystem::path& path);

/// Reads a Gmsh MSH file, version 2.2 or 4.1, ASCII (file-type 0) or binary (file-type 1, either
/// byte order, data-size 8). Node tags are mapped to 0-based indices in file order (MSH 4.1
/// node blocks joined in file order); elements other than the 4-node tet (type 4) are skipped.
/// Counts in the file are checked against what the file holds before anything is reserved.
/// @throws InputError as read_tet_mesh; binary data is located as "path: byte N"
TetMesh read_msh(const std::filesystem::path& path);

/// Reads a VTK unstructured grid: `.vtu` (XML, any encoding VTK reads) or legacy `.vtk`
/// (`DATASET UNSTRUCTURED_GRID`, ASCII or binary). All points are kept in file order; only
/// VTK_TETRA cells become tets. VTK's own error and warning output is captured, not printed.
/// @throws InputError naming the file when VTK reports any error or warning, when a declared
///         count exceeds what the file can hold, when a cell refers to a missing point, when a
///         coordinate is not finite, or when there is no VTK_TETRA cell
TetMesh read_vtk_mesh(const std::filesystem::path& path);

/// Reads a TetGen mesh from `stem.node` and `stem.ele` (`path` may name either; the other
/// extension is substituted). `.node`: `#points 3 #attributes #markers`, then `index x y z
/// [attributes] [marker]`; `.ele`: `#tets 4 #attributes`, then `index n0 n1 n2 n3
/// [attributes]`; `#` comments. The first point's index (0 or 1) sets the numbering, points
/// must be numbered consecutively. 10-node tets are rejected.
/// @throws InputError "path:line: expected ..., found ..." for a missing file of the pair, a
///         malformed or truncated file, a node index out of range, a repeated node in a tet
TetMesh read_tetgen(const std::filesystem::path& path);

/// Writes a mesh as Gmsh MSH 2.2 ASCII (node tags 1..#V, tet elements of type 4), whole or not
/// at all (core/atomic_file.hpp).
/// @throws OutputError naming the file and the system's reason if it cannot be written
void write_msh22(const std::filesystem::path& path, const TetMesh& mesh);

} // namespace coro
