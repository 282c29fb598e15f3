#pragma once
// Private to io/: the binary Gmsh MSH reader (versions 2.2 and 4.1, file-type 1).

#include <corocontact/core/tet_mesh.hpp>

#include <string>
#include <string_view>

namespace coro::detail {

/// Reads a binary MSH file whose `$MeshFormat` line says file-type 1, from its whole content.
/// Messages say "path: byte N: expected ..., found ..." and name the node, element or block.
/// Every count is checked against the bytes left before anything is read or reserved.
/// @param[in] path  the file name, for messages
/// @param[in] data  the file's bytes, starting with `$MeshFormat`
/// @throws InputError for a malformed, truncated or inconsistent file
TetMesh read_msh_binary(const std::string& path, std::string_view data);

} // namespace coro::detail
