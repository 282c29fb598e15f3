// VTK unstructured grids (.vtu XML, legacy .vtk) as tet meshes: Gmsh's export and VTK's own
// writers agree with the MSH reader; broken files give an InputError and VTK prints nothing.

#include <corocontact/io/mesh_readers.hpp>

#include <corocontact/core/error.hpp>

#include "mesh_fixtures.hpp"
#include "near.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace coro {
namespace {

namespace fs = std::filesystem;
using ::testing::AllOf;
using ::testing::HasSubstr;
using ::testing::IsEmpty;
using ::testing::StartsWith;
using ::testing::ThrowsMessage;

fs::path data_dir() { return fs::path(CORO_TEST_DATA_DIR); }

const fs::path& scratch()
{
    static const fs::path dir = test::scratch_dir("vtk_mesh_reader");
    return dir;
}

std::string bytes_of(const fs::path& path)
{
    std::ifstream in(path, std::ios::binary);
    std::ostringstream ss;
    ss << in.rdbuf();
    return ss.str();
}

auto error_about(const fs::path& path, const std::string& what)
{
    return ThrowsMessage<InputError>(AllOf(StartsWith(path.string() + ":"), HasSubstr(what)));
}

/// Reads `path` expecting an InputError containing `what`, and nothing on stderr.
void expect_quiet_error(const fs::path& path, const std::string& what)
{
    ::testing::internal::CaptureStderr();
    std::string message;
    try {
        read_tet_mesh(path);
    } catch (const InputError& error) {
        message = error.what();
    }
    const std::string printed = ::testing::internal::GetCapturedStderr();
    EXPECT_THAT(message, AllOf(StartsWith(path.string() + ":"), HasSubstr(what)));
    EXPECT_THAT(printed, IsEmpty());
}

TEST(ReadVtkMesh, EveryVtkFlavourOfTheCubeEqualsTheMshFile)
{
    const TetMesh msh = read_tet_mesh(data_dir() / "msh" / "cube_v41.msh");
    for (const std::string name :
         {"cube_gmsh.vtk", "cube_binary.vtk", "cube_ascii.vtu", "cube_appended.vtu"}) {
        SCOPED_TRACE(name);
        const TetMesh vtk = read_tet_mesh(data_dir() / "vtk" / name);
        EXPECT_TRUE(test::is_near(msh.rest_positions, vtk.rest_positions, 0.0, 0.0));
        EXPECT_EQ(msh.tets, vtk.tets);
    }
}

TEST(ReadVtkMesh, RejectsGarbageXmlQuietly)
{
    const fs::path path = test::write_text(scratch() / "garbage.vtu", "<VTKFile type=\"Unstru");
    expect_quiet_error(path, "VTK could not read the file");
}

TEST(ReadVtkMesh, RejectsTruncatedXmlQuietly)
{
    const std::string bytes = bytes_of(data_dir() / "vtk" / "cube_appended.vtu");
    const fs::path path =
        test::write_text(scratch() / "truncated.vtu", bytes.substr(0, bytes.size() * 2 / 3));
    expect_quiet_error(path, "VTK could not read the file");
}

TEST(ReadVtkMesh, RejectsTruncatedLegacyQuietly)
{
    const std::string bytes = bytes_of(data_dir() / "vtk" / "cube_gmsh.vtk");
    const fs::path path =
        test::write_text(scratch() / "truncated.vtk", bytes.substr(0, bytes.size() / 2));
    expect_quiet_error(path, "truncated.vtk:83: cell 178 of the CELLS list: expected point 3 of 3, "
                             "found the end of the data");
}

TEST(ReadVtkMesh, RejectsDeclaredCountsBeyondTheFileBeforeVtkAllocates)
{
    std::string legacy = bytes_of(data_dir() / "vtk" / "cube_gmsh.vtk");
    legacy.replace(legacy.find("POINTS 76"), 9, "POINTS 76000000000000");
    const fs::path legacy_path = test::write_text(scratch() / "huge.vtk", legacy);
    EXPECT_THAT([&] { read_tet_mesh(legacy_path); },
                error_about(legacy_path, "declares POINTS = 76000000000000, more than the file"));
    std::string xml = bytes_of(data_dir() / "vtk" / "cube_ascii.vtu");
    xml.replace(xml.find("NumberOfPoints=\"76\""), 19, "NumberOfPoints=\"7600000000000\"");
    const fs::path xml_path = test::write_text(scratch() / "huge.vtu", xml);
    EXPECT_THAT([&] { read_tet_mesh(xml_path); },
                error_about(xml_path, "declares NumberOfPoints = 7600000000000"));
}

// Found by mutation fuzzing: VTK 9.1 unpacks legacy cells without checking their counts
// (heap corruption), and takes 5.1 offsets as they come (a huge cell).
TEST(ReadVtkMesh, RejectsLegacyCellCountOverrunningTheListQuietly)
{
    std::string bytes = bytes_of(data_dir() / "vtk" / "cube_gmsh.vtk");
    bytes.replace(bytes.find("\n4 72 0 45 24\n"), 14, "\n24\n");
    const fs::path path = test::write_text(scratch() / "overrun.vtk", bytes);
    expect_quiet_error(path, "overrun.vtk:83: cell 349 declares 53 points, more than the 21 "
                             "integers left of the 1588 CELLS declares");
}

TEST(ReadVtkMesh, RejectsInconsistentOffsetsQuietly)
{
    const fs::path path = data_dir() / "bad" / "vtk_fuzz_bad_offsets.vtk";
    expect_quiet_error(path, "the cell list is inconsistent");
}

TEST(ReadVtkMesh, RejectsCellTypeCountDifferentFromCellCount)
{
    std::string bytes = bytes_of(data_dir() / "vtk" / "cube_gmsh.vtk");
    bytes.replace(bytes.find("CELL_TYPES 368"), 14, "CELL_TYPES 367");
    const fs::path path = test::write_text(scratch() / "types.vtk", bytes);
    expect_quiet_error(path, "types.vtk:453: expected CELL_TYPES to declare as many cells as CELLS "
                             "at line 83");
}

// Found by mutation fuzzing: VTK 9.1 sizes a vector from a compressed array's block count
// before reading anything, so a corrupt count stalls the reader for minutes.
TEST(ReadVtkMesh, RejectsCorruptCompressionHeaderQuickly)
{
    std::string bytes = bytes_of(data_dir() / "vtk" / "cube_appended.vtu");
    bytes.replace(bytes.find("_AQAAAACAAAA"), 12, "_////AACAAAA");
    const fs::path path = test::write_text(scratch() / "blocks.vtu", bytes);
    expect_quiet_error(path, "blocks.vtu:10: the compressed data of this DataArray declares "
                             "16777215 blocks");
}

TEST(ReadVtkMesh, RejectsGridWithoutTets)
{
    const fs::path path = test::write_text(scratch() / "triangle.vtk",
                                           "# vtk DataFile Version 2.0\ntri\nASCII\n"
                                           "DATASET UNSTRUCTURED_GRID\nPOINTS 3 double\n"
                                           "0 0 0 1 0 0 0 1 0\nCELLS 1 4\n3 0 1 2\n"
                                           "CELL_TYPES 1\n5\n");
    EXPECT_THAT([&] { read_tet_mesh(path); },
                error_about(path, "the grid has no tetrahedra (expected VTK_TETRA cells, found 1"));
}

TEST(ReadVtkMesh, RejectsOtherLegacyDatasetsAndNonVtkFiles)
{
    const fs::path poly = test::write_text(scratch() / "poly.vtk",
                                           "# vtk DataFile Version 2.0\np\nASCII\n"
                                           "DATASET POLYDATA\nPOINTS 0 float\n");
    EXPECT_THAT([&] { read_tet_mesh(poly); },
                error_about(poly, "expected 'DATASET UNSTRUCTURED_GRID', found 'DATASET POLYDATA'"));
    const fs::path text = test::write_text(scratch() / "text.vtk", "hello\n");
    EXPECT_THAT([&] { read_tet_mesh(text); },
                error_about(text, "expected '# vtk DataFile Version ...' on the first line"));
}

TEST(ReadVtkMesh, RejectsCellReferringToAMissingPointQuietly)
{
    const fs::path path = test::write_text(scratch() / "bad_index.vtk",
                                           "# vtk DataFile Version 2.0\nt\nASCII\n"
                                           "DATASET UNSTRUCTURED_GRID\nPOINTS 4 double\n"
                                           "0 0 0 1 0 0 0 1 0 0 0 1\nCELLS 1 5\n4 0 1 2 9\n"
                                           "CELL_TYPES 1\n10\n");
    ::testing::internal::CaptureStderr();
    EXPECT_THAT([&] { read_tet_mesh(path); },
                error_about(path, "cell 0 refers to point 9, expected an index in [0, 4)"));
    EXPECT_THAT(::testing::internal::GetCapturedStderr(), IsEmpty());
}

TEST(ReadVtkMesh, RejectsMissingFileAndDirectory)
{
    EXPECT_THAT([&] { read_tet_mesh(scratch() / "missing.vtu"); },
                error_about(scratch() / "missing.vtu", "does not exist"));
    fs::create_directories(scratch() / "folder.vtu");
    EXPECT_THAT([&] { read_tet_mesh(scratch() / "folder.vtu"); },
                error_about(scratch() / "folder.vtu", "is a directory"));
}

} // namespace
} // namespace coro
