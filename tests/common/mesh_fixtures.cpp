#include "mesh_fixtures.hpp"

#include <corocontact/core/primitives.hpp>

#include <fstream>
#include <random>
#include <unistd.h>

namespace coro::test {

TetMesh unit_tet()
{
    TetMesh mesh;
    mesh.rest_positions.resize(4, 3);
    mesh.rest_positions << 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1;
    mesh.tets.resize(1, 4);
    mesh.tets << 0, 1, 2, 3;
    return mesh;
}

TetMesh irregular_box(Index cells, double jitter, unsigned seed)
{
    TetMesh mesh = make_box(Vec3::Zero(), Vec3::Ones(), {cells, cells, cells});
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> offset(-jitter / cells, jitter / cells);
    for (Index v = 0; v < mesh.num_vertices(); ++v) {
        const auto p = mesh.rest_positions.row(v);
        const bool interior = (p.array() > 1e-12).all() && (p.array() < 1.0 - 1e-12).all();
        if (interior)
            for (int d = 0; d < 3; ++d)
                mesh.rest_positions(v, d) += offset(rng);
    }
    return mesh;
}

std::filesystem::path scratch_dir(const std::string& tag)
{
    const auto dir = std::filesystem::temp_directory_path() /
                     ("coro_test_" + tag + "_" + std::to_string(::getpid()));
    std::filesystem::remove_all(dir);
    std::filesystem::create_directories(dir);
    return dir;
}

std::filesystem::path write_text(const std::filesystem::path& path, const std::string& text)
{
    std::filesystem::create_directories(path.parent_path());
    std::ofstream(path, std::ios::binary) << text;
    return path;
}

} // namespace coro::test
