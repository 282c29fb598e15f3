#pragma once
/// @file mesh_readers.hpp
/// @brief Tetrahedral mesh readers (and a writer for round trips).

#include <corocontact/core/tet_mesh.hpp>

#include <filesystem>

namespace coro {

/// Reads a tet mesh, choosing the format by extension: `.msh` (Gmsh 2.2 or 4.1, ASCII).
/// The mesh is returned as read: node order is the file's (MSH 4.1 node blocks joined in
/// file order, tags mapped to 0-based indices), elements other than 4-node tets skipped.
/// Call validate_and_orient() on the result.
/// @throws InputError naming the file, the line and what was expected, for a missing file,
///         an unknown extension, a malformed or truncated file, an unknown node tag
TetMesh read_tet_mesh(const std::filesystem::path& path);

/// Reads a Gmsh MSH file, version 2.2 or 4.1, ASCII.
/// @throws InputError as read_tet_mesh
TetMesh read_msh(const std::filesystem::path& path);

/// Writes a mesh as Gmsh MSH 2.2 ASCII (node tags 1..#V, tet elements of type 4).
/// @throws InputError if the file cannot be written
void write_msh22(const std::filesystem::path& path, const TetMesh& mesh);

} // namespace coro
