// Binary Gmsh MSH (file-type 1), versions 2.2 and 4.1: Gmsh's own files against their ASCII
// twins, both byte orders, and corrupt data located by byte offset.

#include <corocontact/io/mesh_readers.hpp>

#include <corocontact/core/error.hpp>

#include "mesh_fixtures.hpp"
#include "near.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>
#include <string>

namespace coro {
namespace {

namespace fs = std::filesystem;
using ::testing::AllOf;
using ::testing::HasSubstr;
using ::testing::StartsWith;
using ::testing::ThrowsMessage;

fs::path msh_dir() { return fs::path(CORO_TEST_DATA_DIR) / "msh"; }

fs::path write_file(const std::string& name, const std::string& bytes)
{
    static const fs::path dir = test::scratch_dir("msh_binary");
    return test::write_text(dir / name, bytes);
}

std::string bytes_of(const fs::path& path)
{
    std::ifstream in(path, std::ios::binary);
    std::ostringstream ss;
    ss << in.rdbuf();
    return ss.str();
}

/// Builds a binary MSH file value by value in either byte order.
class BinaryMsh {
public:
    explicit BinaryMsh(bool big_endian) : m_big(big_endian) {}

    BinaryMsh& text(const std::string& s)
    {
        m_bytes += s;
        return *this;
    }

    template <class T>
    BinaryMsh& put(T value)
    {
        std::array<char, sizeof(T)> b{};
        std::memcpy(b.data(), &value, sizeof(T));
        if (m_big)
            std::reverse(b.begin(), b.end());
        m_bytes.append(b.data(), b.size());
        return *this;
    }

    BinaryMsh& i32(std::int32_t v) { return put(v); }
    BinaryMsh& u64(std::uint64_t v) { return put(v); }
    BinaryMsh& f64(double v) { return put(v); }

    const std::string& bytes() const { return m_bytes; }

private:
    bool m_big;
    std::string m_bytes;
};

/// MSH 2.2 binary: 5 nodes (tags 10..14), a group of 2 triangles (2 tags each), then a group of
/// 2 tets (3 tags each); `swap` writes big-endian.
std::string msh22_two_tets(bool big_endian, double x4 = 1.0)
{
    BinaryMsh m(big_endian);
    m.text("$MeshFormat\n2.2 1 8\n").i32(1).text("\n$EndMeshFormat\n$Nodes\n5\n");
    const double xyz[5][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {x4, 1, 1}};
    for (int i = 0; i < 5; ++i)
        m.i32(10 + i).f64(xyz[i][0]).f64(xyz[i][1]).f64(xyz[i][2]);
    m.text("\n$EndNodes\n$Elements\n4\n");
    m.i32(2).i32(2).i32(2);                   // triangles: type 2, 2 elements, 2 tags
    m.i32(1).i32(0).i32(1).i32(10).i32(11).i32(12);
    m.i32(2).i32(0).i32(1).i32(10).i32(12).i32(13);
    m.i32(4).i32(2).i32(3);                   // tets: type 4, 2 elements, 3 tags
    m.i32(3).i32(0).i32(1).i32(0).i32(10).i32(11).i32(12).i32(13);
    m.i32(4).i32(0).i32(1).i32(0).i32(11).i32(12).i32(13).i32(14);
    m.text("\n$EndElements\n");
    return m.bytes();
}

auto error_with(const fs::path& path, const std::string& what)
{
    return ThrowsMessage<InputError>(AllOf(StartsWith(path.string() + ": byte "), HasSubstr(what)));
}

// ---------------------------------------------------------------------------------------------
// Valid files

TEST(ReadMshBinary, GmshBinaryFilesEqualTheirAsciiTwinsBitwise)
{
    for (const std::string stem : {"cube", "sphere"})
        for (const std::string version : {"v22", "v41"}) {
            SCOPED_TRACE(stem + "_" + version);
            const TetMesh ascii = read_tet_mesh(msh_dir() / (stem + "_" + version + ".msh"));
            const TetMesh binary = read_tet_mesh(msh_dir() / (stem + "_" + version + "_bin.msh"));
            ASSERT_GT(binary.num_tets(), 100);
            EXPECT_TRUE(test::is_near(ascii.rest_positions, binary.rest_positions, 0.0, 0.0));
            EXPECT_EQ(ascii.tets, binary.tets);
        }
}

TEST(ReadMshBinary, ReadsBothByteOrdersAndSkipsOtherElementTypes)
{
    for (const bool big : {false, true}) {
        SCOPED_TRACE(big ? "big-endian" : "little-endian");
        const TetMesh mesh =
            read_msh(write_file(big ? "big.msh" : "little.msh", msh22_two_tets(big)));
        ASSERT_EQ(mesh.num_vertices(), 5);
        ASSERT_EQ(mesh.num_tets(), 2);
        EXPECT_EQ(mesh.tets.row(0), (Eigen::RowVector4i() << 0, 1, 2, 3).finished());
        EXPECT_EQ(mesh.tets.row(1), (Eigen::RowVector4i() << 1, 2, 3, 4).finished());
        EXPECT_EQ(mesh.rest_positions.row(4), Eigen::RowVector3d(1, 1, 1));
    }
}

TEST(ReadMshBinary, Msh41ParametricNodesAndSkippedBlocks)
{
    BinaryMsh m(false);
    m.text("$MeshFormat\n4.1 1 8\n").i32(1).text("\n$EndMeshFormat\n");
    m.text("$PhysicalNames\n1\n3 1 \"body\"\n$EndPhysicalNames\n$Nodes\n");
    m.u64(2).u64(4).u64(1).u64(7);
    m.i32(2).i32(1).i32(1).u64(1).u64(7).f64(0).f64(0).f64(1).f64(0.5).f64(0.5); // u v
    m.i32(3).i32(1).i32(0).u64(3).u64(1).u64(2).u64(3);
    m.f64(0).f64(0).f64(0).f64(1).f64(0).f64(0).f64(0).f64(1).f64(0);
    m.text("\n$EndNodes\n$Elements\n");
    m.u64(2).u64(2).u64(1).u64(2);
    m.i32(2).i32(1).i32(2).u64(1).u64(1).u64(1).u64(2).u64(3); // one triangle
    m.i32(3).i32(1).i32(4).u64(1).u64(2).u64(1).u64(2).u64(3).u64(7);
    m.text("\n$EndElements\n");
    const TetMesh mesh = read_msh(write_file("v41_parametric.msh", m.bytes()));
    ASSERT_EQ(mesh.num_vertices(), 4);
    ASSERT_EQ(mesh.num_tets(), 1);
    EXPECT_EQ(mesh.tets.row(0), (Eigen::RowVector4i() << 1, 2, 3, 0).finished());
    EXPECT_EQ(mesh.rest_positions.row(0), Eigen::RowVector3d(0, 0, 1));
}

// ---------------------------------------------------------------------------------------------
// Corrupt files

TEST(ReadMshBinary, RejectsTruncatedFilesOfBothVersions)
{
    for (const std::string name : {"cube_v22_bin.msh", "cube_v41_bin.msh"}) {
        SCOPED_TRACE(name);
        const std::string bytes = bytes_of(msh_dir() / name);
        for (const double fraction : {0.2, 0.5, 0.9, 0.999}) {
            const auto cut = static_cast<std::size_t>(fraction * static_cast<double>(bytes.size()));
            const fs::path path = write_file("truncated_" + name, bytes.substr(0, cut));
            EXPECT_THROW(read_msh(path), InputError) << cut;
        }
    }
}

TEST(ReadMshBinary, RejectsNodeCountBeyondTheFileWithoutAllocating)
{
    std::string bytes = msh22_two_tets(false);
    const std::string marker = "$Nodes\n5\n";
    bytes.replace(bytes.find(marker), marker.size(), "$Nodes\n4000000000\n");
    const fs::path path = write_file("huge_count.msh", bytes);
    EXPECT_THAT([&] { read_msh(path); },
                error_with(path, "expected 4000000000 nodes as declared at byte"));
    EXPECT_THAT([&] { read_msh(path); }, error_with(path, "truncated, or a corrupt count"));
}

TEST(ReadMshBinary, RejectsMsh41NodeCountBeyondTheFile)
{
    std::string bytes = bytes_of(msh_dir() / "cube_v41_bin.msh");
    const std::size_t at = bytes.find("$Nodes\n") + 7 + 8; // numNodes after numEntityBlocks
    const std::uint64_t huge = std::uint64_t{1} << 60;
    std::memcpy(bytes.data() + at, &huge, sizeof huge);
    const fs::path path = write_file("huge_v41.msh", bytes);
    EXPECT_THAT([&] { read_msh(path); },
                error_with(path, "expected 1152921504606846976 nodes declared at byte"));
}

TEST(ReadMshBinary, RejectsAByteOrderWordOtherThanOne)
{
    std::string bytes = msh22_two_tets(false);
    bytes[bytes.find("2.2 1 8\n") + 8] = 7;
    const fs::path path = write_file("bad_one.msh", bytes);
    EXPECT_THAT([&] { read_msh(path); },
                error_with(path, "expected the binary int 1 after the format line"));
}

TEST(ReadMshBinary, RejectsNonFiniteCoordinateNamingTheNode)
{
    const fs::path path = write_file("nan.msh", msh22_two_tets(false, std::nan("")));
    EXPECT_THAT([&] { read_msh(path); },
                error_with(path, "node 14 has coordinate nan, expected a finite number"));
}

TEST(ReadMshBinary, RejectsUnknownNodeTagNamingTheElement)
{
    std::string bytes = msh22_two_tets(true);
    // Last node of the last tet: tag 14 -> 99 (big-endian int at the end before the marker).
    const std::size_t end = bytes.find("\n$EndElements");
    bytes[end - 1] = 99;
    const fs::path path = write_file("unknown_tag.msh", bytes);
    EXPECT_THAT([&] { read_msh(path); },
                error_with(path, "tet element 4 references unknown node tag 99"));
}

TEST(ReadMshBinary, RejectsUnknownElementTypeAndOverlongGroup)
{
    std::string bytes = msh22_two_tets(false);
    const std::size_t group = bytes.find("$Elements\n4\n") + 12;
    std::string unknown = bytes;
    unknown[group] = 77;
    const fs::path unknown_path = write_file("unknown_type.msh", unknown);
    EXPECT_THAT([&] { read_msh(unknown_path); },
                error_with(unknown_path, "unknown element type 77"));
    std::string overlong = bytes;
    overlong[group + 4] = 9;
    const fs::path overlong_path = write_file("overlong_group.msh", overlong);
    EXPECT_THAT([&] { read_msh(overlong_path); },
                error_with(overlong_path, "declares 9 elements, expected 1 to 4"));
}

TEST(ReadMshBinary, RejectsVolumeElementsOtherThanTheLinearTet)
{
    std::string bytes = msh22_two_tets(false);
    const std::size_t group = bytes.find("$Elements\n4\n") + 12;
    bytes[group] = 11; // the triangles' group becomes one of 10-node tets
    const fs::path path = write_file("tet10_group.msh", bytes);
    EXPECT_THAT([&] { read_msh(path); },
                error_with(path, "byte " + std::to_string(group) +
                                     ": element type 11 (10-node tetrahedron) is a volume element"));
}

TEST(ReadMshBinary, RejectsMissingEndMarkerAfterTheData)
{
    std::string bytes = msh22_two_tets(false);
    bytes.replace(bytes.find("$EndNodes"), 9, "$EndNode!");
    const fs::path path = write_file("no_end_nodes.msh", bytes);
    EXPECT_THAT([&] { read_msh(path); },
                error_with(path, "expected $EndNodes after the 5 nodes declared at byte"));
}

} // namespace
} // namespace coro
