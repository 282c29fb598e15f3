// Plane obstacles in the frames: a finite patch of each plane under the scene.

#include <corocontact/io/case_reader.hpp>
#include <corocontact/io/scene_loader.hpp>
#include <corocontact/io/scene_output.hpp>

#include "mesh_fixtures.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <string>

namespace coro {
namespace {

namespace fs = std::filesystem;

const char* CASE = R"([[body]]
name = "block"
shape = "box"
min = [-1.0, 2.0, 0.5]
max = [3.0, 2.5, 1.5]
cells = [4, 1, 1]

[[obstacle]]
type = "plane"
point = [0.0, 0.0, 0.0]
normal = [0.0, 1.0, 0.0]

[[obstacle]]
type = "plane"
point = [5.0, 1.0, -2.0]
normal = [-1.0, 2.0, 3.0]
)";

const FrameBlock& block_named(const std::vector<FrameBlock>& blocks, const std::string& name)
{
    const auto it = std::find_if(blocks.begin(), blocks.end(), [&](const FrameBlock& b) { return b.name == name; });
    if (it == blocks.end())
        throw std::runtime_error("no block " + name);
    return *it;
}

/// Whether q (on the patch's plane) lies in one of its triangles, by signed areas along n.
bool covers(const FrameBlock& patch, const Vec3& q, const Vec3& n)
{
    for (Index f = 0; f < patch.tris.rows(); ++f) {
        bool inside = true;
        for (int e = 0; e < 3; ++e) {
            const Vec3 a = patch.points.row(patch.tris(f, e)).transpose();
            const Vec3 b = patch.points.row(patch.tris(f, (e + 1) % 3)).transpose();
            inside = inside && (b - a).cross(q - a).dot(n) >= 0.0;
        }
        if (inside)
            return true;
    }
    return false;
}

TEST(SceneFrame, EveryPlaneIsAPatchOfTwoTrianglesUnderTheWholeBody)
{
    const fs::path file = test::write_text(test::scratch_dir("plane_patch") / "planes.toml", CASE);
    const CaseSpec spec = read_case(file);
    const LoadedScene loaded = load_scene(spec);
    const std::vector<FrameBlock> blocks = scene_frame(loaded.scene);
    const Positions& body = block_named(blocks, "block").points;

    for (std::size_t k = 0; k < 2; ++k) {
        const FrameBlock& patch = block_named(blocks, "plane" + std::to_string(k));
        ASSERT_EQ(patch.points.rows(), 4);
        ASSERT_EQ(patch.tris.rows(), 2);
        EXPECT_EQ(patch.tets.rows(), 0);
        const Vec3 p = spec.obstacles[k].point;
        const Vec3 n = spec.obstacles[k].normal.normalized();
        for (Index i = 0; i < 4; ++i)
            EXPECT_NEAR((patch.points.row(i).transpose() - p).dot(n), 0.0, 1e-12) << "plane" << k << " point " << i;
        for (Index f = 0; f < 2; ++f) {
            const Vec3 a = patch.points.row(patch.tris(f, 0)).transpose();
            const Vec3 b = patch.points.row(patch.tris(f, 1)).transpose();
            const Vec3 c = patch.points.row(patch.tris(f, 2)).transpose();
            EXPECT_NEAR((b - a).cross(c - a).normalized().dot(n), 1.0, 1e-12) << "faces the body side";
        }
        for (Index v = 0; v < body.rows(); ++v) {
            const Vec3 x = body.row(v).transpose();
            const Vec3 foot = x - (x - p).dot(n) * n;
            EXPECT_TRUE(covers(patch, foot, n)) << "plane" << k << " misses the body's node " << v;
        }
        // The plane's own point is in the scene's bounds, so under the patch too.
        EXPECT_TRUE(covers(patch, p, n));
    }
}

} // namespace
} // namespace coro
