// TetGen .node/.ele: files written by tetgen itself (tests/data/tetgen/README.md), both
// numberings, and malformed pairs with line-precise messages.

#include <corocontact/io/mesh_readers.hpp>

#include <corocontact/core/error.hpp>

#include "mesh_fixtures.hpp"
#include "near.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <string>

namespace coro {
namespace {

namespace fs = std::filesystem;
using ::testing::AllOf;
using ::testing::HasSubstr;
using ::testing::StartsWith;
using ::testing::ThrowsMessage;

fs::path tetgen_dir() { return fs::path(CORO_TEST_DATA_DIR) / "tetgen"; }

const fs::path& scratch()
{
    static const fs::path dir = test::scratch_dir("tetgen_reader");
    return dir;
}

/// Writes `stem.node` and `stem.ele` and returns the path of the .ele.
fs::path write_pair(const std::string& stem, const std::string& node, const std::string& ele)
{
    test::write_text(scratch() / (stem + ".node"), node);
    return test::write_text(scratch() / (stem + ".ele"), ele);
}

auto error_at(const fs::path& path, int line, const std::string& what)
{
    return ThrowsMessage<InputError>(
        AllOf(StartsWith(path.string() + ":" + std::to_string(line) + ": "), HasSubstr(what)));
}

const std::string UNIT_NODES = "# unit tet\n4 3 0 0\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n";

TEST(ReadTetgen, CubeFromTetgenHasUnitVolumeWithEitherNumbering)
{
    for (const std::string stem : {"cube.1", "cube_zero.1"}) {
        SCOPED_TRACE(stem);
        for (const std::string extension : {".ele", ".node"}) {
            TetMesh mesh = read_tet_mesh(tetgen_dir() / (stem + extension));
            EXPECT_EQ(mesh.num_vertices(), 66);
            EXPECT_EQ(mesh.num_tets(), 128);
            validate_and_orient(mesh, stem);
            EXPECT_NEAR_REL(total_volume(mesh), 1.0, 0.0, 1e-12);
        }
    }
}

TEST(ReadTetgen, ZeroAndOneBasedFilesGiveTheSameMesh)
{
    const TetMesh one = read_tetgen(tetgen_dir() / "cube.1.ele");
    const TetMesh zero = read_tetgen(tetgen_dir() / "cube_zero.1.ele");
    EXPECT_TRUE(test::is_near(one.rest_positions, zero.rest_positions, 0.0, 0.0));
    EXPECT_EQ(one.tets, zero.tets);
}

TEST(ReadTetgen, SkipsAttributesMarkersAndComments)
{
    const fs::path ele = write_pair(
        "attributes", "4 3 2 1 # two attributes, markers\n0 0 0 0 7 8 1\n1 1 0 0 7 8 1\n"
                      "2 0 1 0 7 8 0\n3 0 0 1 7 8 1\n",
        "1 4 1\n0 0 1 2 3 -2.5 # region\n");
    const TetMesh mesh = read_tetgen(ele);
    ASSERT_EQ(mesh.num_tets(), 1);
    EXPECT_EQ(mesh.tets.row(0), (Eigen::RowVector4i() << 0, 1, 2, 3).finished());
    EXPECT_EQ(mesh.rest_positions.row(3), Eigen::RowVector3d(0, 0, 1));
}

TEST(ReadTetgen, RejectsMissingNodeFileNamingBoth)
{
    const fs::path ele = test::write_text(scratch() / "lonely.ele", "1 4 0\n1 1 2 3 4\n");
    EXPECT_THAT([&] { read_tet_mesh(ele); },
                ThrowsMessage<InputError>(AllOf(StartsWith((scratch() / "lonely.node").string()),
                                                HasSubstr("TetGen file does not exist"),
                                                HasSubstr("lonely.ele"))));
}

TEST(ReadTetgen, RejectsTenNodeTets)
{
    const fs::path ele = write_pair("quadratic", UNIT_NODES, "1 10 0\n1 1 2 3 4 1 2 3 4 1 2\n");
    EXPECT_THAT([&] { read_tetgen(ele); },
                error_at(ele, 1, "10-node (quadratic) tetrahedra are not supported"));
}

TEST(ReadTetgen, RejectsNodeIndexOutOfRange)
{
    const fs::path ele = write_pair("range", UNIT_NODES, "1 4 0\n1 1 2 3 5\n");
    EXPECT_THAT([&] { read_tetgen(ele); },
                error_at(ele, 2, "tetrahedron 1 refers to node 5, expected an index in [1, 4]"));
    const fs::path zero = write_pair("range0", UNIT_NODES, "1 4 0\n1 0 1 2 3\n");
    EXPECT_THAT([&] { read_tetgen(zero); }, error_at(zero, 2, "refers to node 0"));
}

TEST(ReadTetgen, RejectsRepeatedNodeInATet)
{
    const fs::path ele = write_pair("repeat", UNIT_NODES, "1 4 0\n1 1 2 3 2\n");
    EXPECT_THAT([&] { read_tetgen(ele); },
                error_at(ele, 2, "tetrahedron 1 repeats node 2 (expected 4 distinct nodes)"));
}

TEST(ReadTetgen, RejectsMoreTetsDeclaredThanGiven)
{
    const fs::path ele = write_pair("short_ele", UNIT_NODES, "1000000000 4 0\n1 1 2 3 4\n");
    EXPECT_THAT([&] { read_tetgen(ele); },
                error_at(ele, 2, "expected tetrahedron 2 of 1000000000 declared at line 1"));
}

TEST(ReadTetgen, RejectsMoreNodesDeclaredThanGiven)
{
    const fs::path ele = write_pair("short_node", "# header\n9 3 0 0\n1 0 0 0\n", "1 4 0\n1 1 2 3 4\n");
    const fs::path node = scratch() / "short_node.node";
    EXPECT_THAT([&] { read_tetgen(ele); },
                error_at(node, 3, "expected point 2 of 9 declared at line 2"));
}

TEST(ReadTetgen, RejectsNonConsecutiveOrBadFirstIndex)
{
    const fs::path gap = write_pair("gap", "2 3 0 0\n1 0 0 0\n3 1 0 0\n", "1 4 0\n1 1 2 1 2\n");
    EXPECT_THAT([&] { read_tetgen(gap); },
                error_at(scratch() / "gap.node", 3, "expected point index 2"));
    const fs::path first = write_pair("first", "1 3 0 0\n5 0 0 0\n", "1 4 0\n1 1 2 1 2\n");
    EXPECT_THAT([&] { read_tetgen(first); },
                error_at(scratch() / "first.node", 2, "first point's index to be 0 or 1"));
}

TEST(ReadTetgen, RejectsNonFiniteCoordinateAndTwoDimensions)
{
    const fs::path nan = write_pair("nan", "1 3 0 0\n1 nan 0 0\n", "1 4 0\n1 1 1 1 1\n");
    EXPECT_THAT([&] { read_tetgen(nan); },
                error_at(scratch() / "nan.node", 2, "expected the x coordinate (a finite number)"));
    const fs::path flat = write_pair("flat", "1 2 0 0\n1 0 0\n", "1 4 0\n1 1 1 1 1\n");
    EXPECT_THAT([&] { read_tetgen(flat); },
                error_at(scratch() / "flat.node", 1, "expected dimension 3, found 2"));
}

TEST(ReadTetgen, RejectsTrailingDataAndExtraValues)
{
    const fs::path trailing = write_pair("trailing", UNIT_NODES, "1 4 0\n1 1 2 3 4\n2 1 2 3 4\n");
    EXPECT_THAT([&] { read_tetgen(trailing); },
                error_at(trailing, 3, "expected end of file after the 1 tetrahedra"));
    const fs::path extra = write_pair("extra", UNIT_NODES, "1 4 0\n1 1 2 3 4 9\n");
    EXPECT_THAT([&] { read_tetgen(extra); }, error_at(extra, 2, "expected end of line after"));
}

} // namespace
} // namespace coro
