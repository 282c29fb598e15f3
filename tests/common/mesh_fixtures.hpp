#pragma once
/// @file mesh_fixtures.hpp
/// @brief Small meshes built in tests.

#include <corocontact/core/tet_mesh.hpp>

#include <filesystem>
#include <string>

namespace coro::test {

/// The unit reference tet (0,0,0), (1,0,0), (0,1,0), (0,0,1).
TetMesh unit_tet();

/// A box mesh with interior nodes moved randomly by up to `jitter` of a cell (seeded).
TetMesh irregular_box(Index cells, double jitter, unsigned seed);

/// A fresh, empty directory under the system temp dir, named after `tag` and the process.
std::filesystem::path scratch_dir(const std::string& tag);

/// Writes `text` to `path` (creating parents) and returns `path`.
std::filesystem::path write_text(const std::filesystem::path& path, const std::string& text);

} // namespace coro::test
