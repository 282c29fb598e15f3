#include <corocontact/io/mesh_readers.hpp>

#include <corocontact/core/error.hpp>
#include <corocontact/core/primitives.hpp>

#include "mesh_fixtures.hpp"
#include "near.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace coro {
namespace {

namespace fs = std::filesystem;
using ::testing::AllOf;
using ::testing::HasSubstr;
using ::testing::StartsWith;
using ::testing::ThrowsMessage;

const std::string V22_HEADER = "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n"; // lines 1-3
const std::string V41_HEADER = "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n"; // lines 1-3

fs::path msh_dir() { return fs::path(CORO_TEST_DATA_DIR) / "msh"; }

/// Writes `text` as `name` in this suite's scratch directory.
fs::path write_msh(const std::string& name, const std::string& text)
{
    static const fs::path dir = test::scratch_dir("mesh_readers");
    return test::write_text(dir / name, text);
}

/// The message must start with `path:line:` and then say `what`.
auto input_error_at(const fs::path& path, int line, const std::string& what)
{
    return ThrowsMessage<InputError>(
        AllOf(StartsWith(path.string() + ":" + std::to_string(line) + ": "), HasSubstr(what)));
}

/// For errors about the file as a whole (no line).
auto input_error_about(const fs::path& path, const std::string& what)
{
    return ThrowsMessage<InputError>(AllOf(StartsWith(path.string() + ": "), HasSubstr(what)));
}

std::string text_of(const fs::path& path)
{
    std::ifstream in(path, std::ios::binary);
    std::ostringstream ss;
    ss << in.rdbuf();
    return ss.str();
}

// ---------------------------------------------------------------------------------------------
// Valid files

// Node tags 50, 100, 7, 5, 20, 9 map to indices 0..5 in file order.
Positions expected_sparse_positions()
{
    Positions p(6, 3);
    p << 0, 0, 0,     //
        1, 0, 0,      //
        0, 1, 0,      //
        0, 0, 1,      //
        1, 1, 1,      //
        0.5, 0.5, -1; //
    return p;
}

const std::string MSH41_MIXED = V41_HEADER + R"($PhysicalNames
1
3 1 "body"
$EndPhysicalNames
$Entities
1 0 0 1
1 0 0 0 0
1 0 0 0 1 1 1 1 1 0
$EndEntities
$Nodes
3 6 5 100
0 1 0 1
50
0 0 0
2 1 1 2
100
7
1 0 0 0.5 0.25
0 1 0 0.0 0.5
3 1 0 3
5
20
9
0 0 1
1 1 1
0.5 0.5 -1
$EndNodes
$Elements
5 8 1 20
0 1 15 1
1 50 
1 1 1 2
2 50 100 
3 100 7 
2 1 2 2
4 50 100 7 
5 100 7 5 
3 1 4 2
10 50 100 7 5 
12 100 7 20 5 
3 1 4 1
13 9 50 7 100 
$EndElements
$Periodic
0
$EndPeriodic
)";

TEST(ReadMsh, Msh41JoinsNodeBlocksInFileOrderAndKeepsOnlyTets)
{
    const TetMesh mesh = read_msh(write_msh("mixed_v41.msh", MSH41_MIXED));
    EXPECT_TRUE(test::is_near(mesh.rest_positions, expected_sparse_positions(), 0.0, 0.0));
    Tets expected(3, 4);
    expected << 0, 1, 2, 3, //
        1, 2, 4, 3,         //
        5, 0, 2, 1;
    EXPECT_EQ(mesh.tets, expected);
}

const std::string MSH22_MIXED = V22_HEADER + R"($PhysicalNames
1
3 1 "body"
$EndPhysicalNames
$Nodes
6
50 0 0 0
100 1 0 0
7 0 1 0
5 0 0 1
20 1 1 1
9 0.5 0.5 -1
$EndNodes
$Elements
6
1 15 2 0 1 50
2 1 2 0 1 50 100
3 2 2 0 1 50 100 7
4 4 2 1 1 50 100 7 5
6 4 3 1 1 0 100 7 20 5
7 4 0 9 50 7 100
$EndElements
$NodeData
1
"displacement"
0
$EndNodeData
)";

TEST(ReadMsh, Msh22MapsSparseTagsAndKeepsOnlyTets)
{
    const TetMesh mesh = read_msh(write_msh("mixed_v22.msh", MSH22_MIXED));
    EXPECT_TRUE(test::is_near(mesh.rest_positions, expected_sparse_positions(), 0.0, 0.0));
    Tets expected(3, 4);
    expected << 0, 1, 2, 3, //
        1, 2, 4, 3,         //
        5, 0, 2, 1;
    EXPECT_EQ(mesh.tets, expected);
}

TEST(ReadMsh, RefusesVolumeElementsOtherThanTheLinearTet)
{
    // Skipped like the points, lines and triangles of physical groups, a 10-node tet or a
    // hexahedron would leave its volume out of the body.
    std::string v22 = MSH22_MIXED;
    const std::string tet4 = "4 4 2 1 1 50 100 7 5\n";
    v22.replace(v22.find(tet4), tet4.size(), tet4 + "5 11 2 1 1 50 100 7 5 1 2 3 4 6 8\n");
    v22.replace(v22.find("$Elements\n6\n"), 12, "$Elements\n7\n");
    const int line = static_cast<int>(std::count(v22.begin(), v22.begin() + static_cast<long>(v22.find("5 11 ")), '\n')) + 1;
    const fs::path tet10 = write_msh("tet10_v22.msh", v22);
    EXPECT_THAT([&] { read_msh(tet10); },
                input_error_at(tet10, line, "element type 11 (10-node tetrahedron) is a volume element corocontact "
                                            "cannot use; expected 4-node tetrahedra (type 4) only"));
    std::string v41 = MSH41_MIXED;
    const std::string block = "3 1 4 1\n13 9 50 7 100 \n";
    v41.replace(v41.find(block), block.size(), block + "3 1 5 1\n21 50 100 7 5 9 20 50 100 \n");
    v41.replace(v41.find("5 8 1 20"), 8, "6 9 1 21");
    const int block_line = static_cast<int>(std::count(v41.begin(), v41.begin() + static_cast<long>(v41.find("3 1 5 1")), '\n')) + 1;
    const fs::path hex = write_msh("hex_v41.msh", v41);
    EXPECT_THAT([&] { read_msh(hex); },
                input_error_at(hex, block_line, "element type 5 (8-node hexahedron) is a volume element"));
    // Types beyond the format's table: a 40-node prism in a volume's block, an unknown type.
    v41.replace(v41.find("3 1 5 1"), 7, "3 1 90 1");
    const fs::path prism = write_msh("prism40_v41.msh", v41);
    EXPECT_THAT([&] { read_msh(prism); },
                input_error_at(prism, block_line, "element type 90 (an element of a volume) is a volume element"));
    v22.replace(v22.find("5 11 "), 5, "5 999 ");
    const fs::path unknown = write_msh("unknown_v22.msh", v22);
    EXPECT_THAT([&] { read_msh(unknown); }, input_error_at(unknown, line, "unknown element type 999"));
}

TEST(ReadMsh, AcceptsCrlfLineEndingsAndBlankLines)
{
    std::string text = "\n" + MSH22_MIXED + "\n\n";
    std::string crlf;
    for (const char c : text)
        crlf += c == '\n' ? std::string("\r\n") : std::string(1, c);
    const TetMesh mesh = read_msh(write_msh("crlf.msh", crlf));
    EXPECT_EQ(mesh.num_vertices(), 6);
    EXPECT_EQ(mesh.num_tets(), 3);
}

TEST(ReadMsh, ReturnsNoTetsForASurfaceMesh)
{
    const TetMesh mesh = read_msh(write_msh("surface.msh", V22_HEADER + R"($Nodes
3
1 0 0 0
2 1 0 0
3 0 1 0
$EndNodes
$Elements
1
1 2 2 0 1 1 2 3
$EndElements
)"));
    EXPECT_EQ(mesh.num_vertices(), 3);
    EXPECT_EQ(mesh.num_tets(), 0);
}

TEST(ReadTetMesh, DispatchesUpperCaseMshExtension)
{
    const TetMesh mesh = read_tet_mesh(write_msh("UPPER.MSH", MSH41_MIXED));
    EXPECT_EQ(mesh.num_tets(), 3);
}

// Gmsh-generated meshes (tests/data/msh/*.geo say how): both versions of a ball and a box.
struct GmshFile {
    const char* name;
    Index vertices;
    Index tets;
    double volume;  // analytic
    double rel_tol; // the polyhedral ball is inscribed: 4.4% below for these 503 tets
};

/// What a failing test prints as its parameter: the file, not the struct's bytes.
void PrintTo(const GmshFile& file, std::ostream* os) { *os << file.name; }

class ReadMshGmshFile : public ::testing::TestWithParam<GmshFile> {};

TEST_P(ReadMshGmshFile, HasAnalyticVolumeAfterOrientation)
{
    const GmshFile& file = GetParam();
    TetMesh mesh = read_tet_mesh(msh_dir() / file.name);
    EXPECT_EQ(mesh.num_vertices(), file.vertices);
    EXPECT_EQ(mesh.num_tets(), file.tets);
    validate_and_orient(mesh, file.name);
    const double volume = total_volume(mesh);
    EXPECT_GT(volume, 0.0);
    EXPECT_NEAR_REL(volume, file.volume, 0.0, file.rel_tol);
    EXPECT_LE(volume, file.volume * (1.0 + 1e-12));
}

const double BALL_VOLUME = 4.0 / 3.0 * std::acos(-1.0);

INSTANTIATE_TEST_SUITE_P(GmshBallAndBox, ReadMshGmshFile,
                         ::testing::Values(GmshFile{"sphere_v41.msh", 158, 503, BALL_VOLUME, 0.06},
                                           GmshFile{"sphere_v22.msh", 158, 503, BALL_VOLUME, 0.06},
                                           GmshFile{"cube_v41.msh", 76, 172, 1.0, 1e-12},
                                           GmshFile{"cube_v22.msh", 76, 172, 1.0, 1e-12}),
                         [](const ::testing::TestParamInfo<GmshFile>& param_info) {
                             std::string name = fs::path(param_info.param.name).stem().string();
                             name.erase(std::remove(name.begin(), name.end(), '_'), name.end());
                             return name;
                         });

TEST(ReadMsh, GmshVersionsOfOneMeshAgree)
{
    for (const std::string stem : {"sphere", "cube"}) {
        SCOPED_TRACE(stem);
        const TetMesh v22 = read_msh(msh_dir() / (stem + "_v22.msh"));
        const TetMesh v41 = read_msh(msh_dir() / (stem + "_v41.msh"));
        EXPECT_TRUE(test::is_near(v22.rest_positions, v41.rest_positions, 0.0, 0.0));
        EXPECT_EQ(v22.tets, v41.tets);
    }
}

// ---------------------------------------------------------------------------------------------
// Writer

TEST(WriteMsh22, RoundTripsPositionsAndTetsExactly)
{
    TetMesh mesh = test::irregular_box(3, 0.3, 7); // random coordinates use all 53 bits
    mesh.rest_positions.col(1) *= 1e-7;
    mesh.rest_positions.col(2).array() += 1.0 / 3.0;
    const fs::path path = write_msh("box_roundtrip.msh", "");
    write_msh22(path, mesh);
    const TetMesh read = read_tet_mesh(path);
    ASSERT_EQ(read.rest_positions.rows(), mesh.rest_positions.rows());
    EXPECT_TRUE((read.rest_positions.array() == mesh.rest_positions.array()).all());
    EXPECT_EQ(read.tets, mesh.tets);
}

TEST(WriteMsh22, RoundTripsMakeBox)
{
    const TetMesh mesh = make_box(Vec3(-0.3, 0.1, 1.0 / 3.0), Vec3(0.7, 2.0 / 3.0, 1.9), {3, 2, 4});
    const fs::path path = write_msh("make_box.msh", "");
    write_msh22(path, mesh);
    const TetMesh read = read_msh(path);
    ASSERT_EQ(read.rest_positions.rows(), mesh.rest_positions.rows());
    EXPECT_TRUE((read.rest_positions.array() == mesh.rest_positions.array()).all());
    EXPECT_EQ(read.tets, mesh.tets);
}

TEST(WriteMsh22, WritesGmsh22WithOneBasedTags)
{
    const fs::path path = write_msh("unit_tet_written.msh", "");
    write_msh22(path, test::unit_tet());
    EXPECT_EQ(text_of(path), "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n"
                             "$Nodes\n4\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n$EndNodes\n"
                             "$Elements\n1\n1 4 2 0 1 1 2 3 4\n$EndElements\n");
}

TEST(WriteMsh22, RejectsUnwritablePath)
{
    const fs::path path = write_msh("x.msh", "").parent_path() / "no_such_dir" / "out.msh";
    EXPECT_THAT([&] { write_msh22(path, test::unit_tet()); },
                ThrowsMessage<OutputError>(AllOf(StartsWith(path.string() + ": cannot create out.msh.tmp"),
                                                 HasSubstr("(No such file or directory)"))));
}

// ---------------------------------------------------------------------------------------------
// Errors: every message starts with path:line:

TEST(ReadMsh, RejectsMissingFile)
{
    const fs::path path = write_msh("exists.msh", "").parent_path() / "absent.msh";
    EXPECT_THAT([&] { read_msh(path); }, input_error_about(path, "does not exist"));
}

TEST(ReadMsh, RejectsDirectory)
{
    const fs::path path = write_msh("exists.msh", "").parent_path() / "dir.msh";
    fs::create_directories(path);
    EXPECT_THAT([&] { read_msh(path); }, input_error_about(path, "is a directory"));
}

TEST(ReadTetMesh, SaysADirectoryWithoutExtensionIsADirectory)
{
    const fs::path path = write_msh("exists.msh", "").parent_path() / "meshes";
    fs::create_directories(path);
    EXPECT_THAT([&] { read_tet_mesh(path); }, input_error_about(path, "is a directory, expected a mesh file"));
}

TEST(ReadTetMesh, RejectsADeviceInsteadOfReadingItWithoutEnd)
{
    const fs::path path = write_msh("exists.msh", "").parent_path() / "zero.msh";
    fs::remove(path);
    fs::create_symlink("/dev/zero", path);
    EXPECT_THAT([&] { read_tet_mesh(path); },
                input_error_about(path, "is not a regular file (a device, pipe or socket), expected a mesh file"));
}

TEST(ReadTetMesh, NamesAPathItCannotAccess)
{
    const fs::path path = write_msh("exists.msh", "").parent_path() / "loop.msh";
    fs::remove(path);
    fs::create_symlink("loop.msh", path); // a link to itself
    EXPECT_THAT([&] { read_tet_mesh(path); }, input_error_about(path, "cannot access the mesh file: "));
}

TEST(ReadTetMesh, RejectsUnknownExtensionListingSupportedOnes)
{
    const fs::path path = write_msh("mesh.obj", MSH22_MIXED);
    EXPECT_THAT(
        [&] { read_tet_mesh(path); },
        input_error_about(path, "unsupported mesh extension '.obj', expected one of: .msh"));
    const fs::path bare = write_msh("mesh", MSH22_MIXED);
    EXPECT_THAT([&] { read_tet_mesh(bare); },
                input_error_about(bare, "unsupported mesh extension (none)"));
}

TEST(ReadMsh, RejectsEmptyFile)
{
    const fs::path path = write_msh("empty.msh", "");
    EXPECT_THAT([&] { read_msh(path); }, input_error_at(path, 1, "expected $MeshFormat"));
}

TEST(ReadMsh, ShowsBytesThatAreNotUtf8AsQuestionMarks)
{
    // Two stray bytes, "été" in UTF-8, and a cut three-byte sequence: the terminal gets text.
    const fs::path path = write_msh("garbage.msh", "\xff\xfe\xc3\xa9t\xc3\xa9 \xe2\x82\n");
    EXPECT_THAT([&] { read_msh(path); }, input_error_at(path, 1, "found '?\x3f\xc3\xa9t\xc3\xa9 ?\x3f'"));
}

TEST(ReadMsh, RejectsMissingMeshFormat)
{
    const fs::path path = write_msh("no_format.msh", "\n\n$Nodes\n1\n1 0 0 0\n$EndNodes\n");
    EXPECT_THAT([&] { read_msh(path); },
                input_error_at(path, 3, "expected $MeshFormat on the first line of a Gmsh MSH "
                                        "file, found '$Nodes'"));
}

TEST(ReadMsh, RejectsUnsupportedVersion)
{
    const fs::path v40 = write_msh("v40.msh", "$MeshFormat\n4.0 0 8\n$EndMeshFormat\n");
    EXPECT_THAT([&] { read_msh(v40); },
                input_error_at(v40, 2, "unsupported MSH version '4.0', expected 2.2 or 4.1"));
    const fs::path v3 = write_msh("v3.msh", "\n$MeshFormat\n3 0 8\n$EndMeshFormat\n");
    EXPECT_THAT([&] { read_msh(v3); }, input_error_at(v3, 3, "unsupported MSH version '3'"));
}

TEST(ReadMsh, RejectsUnknownFileTypeAndBinaryDataSizeOtherThanEight)
{
    const fs::path type2 = write_msh("type2.msh", "$MeshFormat\n4.1 2 8\n$EndMeshFormat\n");
    EXPECT_THAT([&] { read_msh(type2); },
                input_error_at(type2, 2, "expected file-type 0 (ASCII) or 1 (binary), found 2"));
    const fs::path size4 = write_msh("size4.msh", "$MeshFormat\n2.2 1 4\n$EndMeshFormat\n");
    EXPECT_THAT([&] { read_msh(size4); },
                input_error_at(size4, 2, "expected data-size 8"));
}

TEST(ReadMsh, RejectsMissingEndMeshFormat)
{
    const fs::path path = write_msh("no_end_format.msh", "$MeshFormat\n2.2 0 8\n$Nodes\n");
    EXPECT_THAT([&] { read_msh(path); },
                input_error_at(path, 3, "expected $EndMeshFormat after the format line, found "
                                        "'$Nodes'"));
}

TEST(ReadMsh, RejectsMissingEndNodes)
{
    const fs::path path = write_msh(
        "no_end_nodes.msh", V22_HEADER + "$Nodes\n1\n1 0 0 0\n$Elements\n0\n$EndElements\n");
    EXPECT_THAT([&] { read_msh(path); },
                input_error_at(path, 7, "expected $EndNodes after the 1 nodes declared at line 5, "
                                        "found '$Elements'"));
}

TEST(ReadMsh, RejectsEndOfFileInsideNodes)
{
    const fs::path path = write_msh("eof_nodes.msh", V22_HEADER + "$Nodes\n3\n1 0 0 0\n2 1 0 0\n");
    EXPECT_THAT([&] { read_msh(path); },
                input_error_at(path, 7, "expected node 3 of 3 declared at line 5 ('tag x y z'), "
                                        "found end of file"));
}

TEST(ReadMsh, RejectsEndOfFileInsideMsh41Elements)
{
    const fs::path path = write_msh("eof_elements.msh", V41_HEADER + R"($Nodes
1 4 1 4
3 1 0 4
1
2
3
4
0 0 0
1 0 0
0 1 0
0 0 1
$EndNodes
$Elements
1 2 1 2
3 1 4 2
1 1 2 3 4)");
    EXPECT_THAT([&] { read_msh(path); },
                input_error_at(path, 19, "expected element 2 of 2 in the block at line 18, "
                                         "found end of file"));
}

TEST(ReadMsh, RejectsUnclosedUnknownSection)
{
    const fs::path path =
        write_msh("unclosed.msh", V22_HEADER + "$PhysicalNames\n1\n3 1 \"body\"\n\n");
    EXPECT_THAT([&] { read_msh(path); },
                input_error_at(path, 7, "expected $EndPhysicalNames closing $PhysicalNames "
                                        "opened at line 4, found end of file"));
}

TEST(ReadMsh, RejectsNonNumericCoordinate)
{
    const fs::path path =
        write_msh("bad_coordinate.msh", V22_HEADER + "$Nodes\n2\n1 0 0 0\n2 1 abc 0\n$EndNodes\n");
    EXPECT_THAT([&] { read_msh(path); },
                input_error_at(path, 7, "expected node y coordinate (a finite number), found "
                                        "'abc'"));
}

TEST(ReadMsh, RejectsNonFiniteCoordinate)
{
    const fs::path path =
        write_msh("nan_coordinate.msh", V22_HEADER + "$Nodes\n1\n1 0 0 nan\n$EndNodes\n");
    EXPECT_THAT([&] { read_msh(path); },
                input_error_at(path, 6, "expected node z coordinate (a finite number), found "
                                        "'nan'"));
}

TEST(ReadMsh, RejectsNonNumericMsh41NodeTag)
{
    const fs::path path =
        write_msh("bad_tag.msh", V41_HEADER + "$Nodes\n1 2 1 2\n3 1 0 2\n1\nx2\n");
    EXPECT_THAT([&] { read_msh(path); },
                input_error_at(path, 8, "expected node tag (a non-negative integer), found 'x2'"));
}

TEST(ReadMsh, RejectsNegativeNodeTag)
{
    const fs::path path = write_msh("negative_tag.msh", V22_HEADER + "$Nodes\n1\n-1 0 0 0\n");
    EXPECT_THAT([&] { read_msh(path); },
                input_error_at(path, 6, "expected node tag (a non-negative integer), found '-1'"));
}

TEST(ReadMsh, RejectsExtraValuesOnNodeLine)
{
    const fs::path path =
        write_msh("extra_values.msh", V22_HEADER + "$Nodes\n1\n1 0 0 0 7\n$EndNodes\n");
    EXPECT_THAT([&] { read_msh(path); },
                input_error_at(path, 6, "expected end of line after 'tag x y z', found '7'"));
}

TEST(ReadMsh, RejectsTetWithThreeNodes)
{
    const fs::path path = write_msh("tet3.msh", V22_HEADER + R"($Nodes
4
1 0 0 0
2 1 0 0
3 0 1 0
4 0 0 1
$EndNodes
$Elements
2
1 4 2 0 1 1 2 3 4
2 4 2 0 1 1 2 3
$EndElements
)");
    EXPECT_THAT([&] { read_msh(path); },
                input_error_at(path, 14, "expected 4 node tags for a tet, found 3"));
}

TEST(ReadMsh, RejectsMsh41TetWithFiveNodes)
{
    const fs::path path = write_msh("tet5.msh", V41_HEADER + R"($Nodes
1 4 1 4
3 1 0 4
1
2
3
4
0 0 0
1 0 0
0 1 0
0 0 1
$EndNodes
$Elements
1 1 1 1
3 1 4 1
1 1 2 3 4 4
$EndElements
)");
    EXPECT_THAT([&] { read_msh(path); },
                input_error_at(path, 19, "expected 4 node tags for a tet, found 5"));
}

TEST(ReadMsh, RejectsUnknownNodeTag)
{
    const fs::path v22 = write_msh("unknown_tag_v22.msh", V22_HEADER + R"($Nodes
4
1 0 0 0
2 1 0 0
3 0 1 0
4 0 0 1
$EndNodes
$Elements
1
8 4 2 0 1 1 2 99 4
$EndElements
)");
    EXPECT_THAT([&] { read_msh(v22); },
                input_error_at(v22, 13, "tet element 8 references unknown node tag 99"));

    const fs::path v41 = write_msh("unknown_tag_v41.msh", V41_HEADER + R"($Nodes
1 4 1 4
3 1 0 4
1
2
3
4
0 0 0
1 0 0
0 1 0
0 0 1
$EndNodes
$Elements
1 1 1 1
3 1 4 1
5 1 2 3 0
$EndElements
)");
    EXPECT_THAT([&] { read_msh(v41); },
                input_error_at(v41, 19, "tet element 5 references unknown node tag 0"));
}

TEST(ReadMsh, RejectsTetRepeatingANodeTag)
{
    const fs::path path = write_msh("repeated_tag.msh", V22_HEADER + R"($Nodes
4
1 0 0 0
2 1 0 0
3 0 1 0
4 0 0 1
$EndNodes
$Elements
1
8 4 2 0 1 1 2 4 2
$EndElements
)");
    EXPECT_THAT([&] { read_msh(path); },
                input_error_at(path, 13, "tet element 8 repeats node tag 2 (expected 4 distinct "
                                         "nodes)"));
}

TEST(ReadMsh, RejectsDuplicateNodeTag)
{
    const fs::path v22 =
        write_msh("duplicate_v22.msh", V22_HEADER + "$Nodes\n3\n1 0 0 0\n2 1 0 0\n1 0 1 0\n");
    EXPECT_THAT([&] { read_msh(v22); },
                input_error_at(v22, 8, "duplicate node tag 1 (first defined at line 6)"));

    // Across two entity blocks.
    const fs::path v41 = write_msh("duplicate_v41.msh", V41_HEADER + R"($Nodes
2 2 5 5
0 1 0 1
5
0 0 0
0 2 0 1
5
1 0 0
$EndNodes
)");
    EXPECT_THAT([&] { read_msh(v41); },
                input_error_at(v41, 10, "duplicate node tag 5 (first defined at line 7)"));
}

TEST(ReadMsh, RejectsHeaderDeclaringMoreNodesThanTheFileHolds)
{
    // Counts near 2^64 must not be allocated up front: the file ends long before.
    const fs::path v22 =
        write_msh("huge_count_v22.msh", V22_HEADER + "$Nodes\n1000000000000\n1 0 0 0\n$EndNodes\n");
    EXPECT_THAT([&] { read_msh(v22); },
                input_error_at(v22, 7, "expected node 2 of 1000000000000 declared at line 5 "
                                       "('tag x y z'), found '$EndNodes'"));

    const fs::path v41 = write_msh("huge_count_v41.msh",
                                   V41_HEADER + "$Nodes\n18446744073709551615 18446744073709551615 "
                                                "1 1\n0 1 0 18446744073709551615\n1\n$EndNodes\n");
    EXPECT_THAT([&] { read_msh(v41); },
                input_error_at(v41, 8, "expected node tag 2 of 18446744073709551615 in the block "
                                       "at line 6, found '$EndNodes'"));

    const fs::path elements =
        write_msh("huge_elements.msh", V22_HEADER + "$Nodes\n0\n$EndNodes\n$Elements\n"
                                                    "4294967296\n$EndElements\n");
    EXPECT_THAT([&] { read_msh(elements); },
                input_error_at(elements, 9, "expected element 1 of 4294967296 declared at line 8"));
}

TEST(ReadMsh, RejectsHugeCountsWithAnInputErrorNotAnAllocationFailure)
{
    // Reserving 2^62 nodes or elements would throw std::length_error or std::bad_alloc.
    const fs::path nodes = write_msh("huge_nodes.msh",
                                     V22_HEADER + "$Nodes\n4611686018427387904\n1 0 0 0\n");
    EXPECT_THAT([&] { read_msh(nodes); },
                input_error_at(nodes, 6, "expected node 2 of 4611686018427387904"));
    const fs::path elements =
        write_msh("huge_elements.msh", V41_HEADER + "$Nodes\n0 0 0 0\n$EndNodes\n$Elements\n"
                                                    "1 4611686018427387904 1 1\n"
                                                    "3 1 4 4611686018427387904\n");
    EXPECT_THAT([&] { read_msh(elements); },
                input_error_at(elements, 9, "expected element 1 of 4611686018427387904"));
}

TEST(ReadMsh, RejectsCountBeyondSixtyFourBits)
{
    const fs::path path =
        write_msh("overflow.msh", V22_HEADER + "$Nodes\n99999999999999999999999\n$EndNodes\n");
    EXPECT_THAT([&] { read_msh(path); },
                input_error_at(path, 5, "expected the number of nodes, found "
                                        "'99999999999999999999999' (too large)"));
}

TEST(ReadMsh, RejectsMsh41BlocksDisagreeingWithHeaderCount)
{
    const fs::path path = write_msh("count_mismatch.msh", V41_HEADER + R"($Nodes
1 4 1 4
3 1 0 4
1
2
3
4
0 0 0
1 0 0
0 1 0
0 0 1
$EndNodes
$Elements
1 3 1 1
3 1 4 1
1 1 2 3 4
$EndElements
)");
    EXPECT_THAT([&] { read_msh(path); },
                input_error_at(path, 19, "expected 3 elements as declared at line 17, found 1"));
}

TEST(ReadMsh, RejectsElementsBeforeNodes)
{
    const fs::path path =
        write_msh("elements_first.msh", V22_HEADER + "$Elements\n0\n$EndElements\n");
    EXPECT_THAT([&] { read_msh(path); },
                input_error_at(path, 4, "expected $Nodes before $Elements"));
}

TEST(ReadMsh, RejectsTextOutsideSections)
{
    const fs::path path = write_msh("stray.msh", V22_HEADER + "$Nodes\n0\n$EndNodes\nhello\n");
    EXPECT_THAT([&] { read_msh(path); },
                input_error_at(path, 7, "expected a section such as $Nodes or $Elements, found "
                                        "'hello'"));
}

} // namespace
} // namespace coro
