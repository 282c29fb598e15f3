#include <corocontact/io/surface_readers.hpp>

#include <corocontact/core/error.hpp>
#include <corocontact/core/primitives.hpp>
#include <corocontact/core/surface_mesh.hpp>

#include "mesh_fixtures.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

namespace coro {
namespace {

namespace fs = std::filesystem;
using ::testing::AllOf;
using ::testing::HasSubstr;
using ::testing::StartsWith;
using ::testing::ThrowsMessage;

fs::path surface_dir() { return fs::path(CORO_TEST_DATA_DIR) / "surface"; }

fs::path scratch()
{
    static const fs::path dir = test::scratch_dir("surface_readers");
    return dir;
}

/// Writes `text` (any bytes) as `name` in this suite's scratch directory.
fs::path write_file(const std::string& name, const std::string& text)
{
    return test::write_text(scratch() / name, text);
}

std::string text_of(const fs::path& path)
{
    std::ifstream in(path, std::ios::binary);
    std::ostringstream ss;
    ss << in.rdbuf();
    return ss.str();
}

/// The message must start with `path:line:` and then say `what`.
auto input_error_at(const fs::path& path, int line, const std::string& what)
{
    return ThrowsMessage<InputError>(
        AllOf(StartsWith(path.string() + ":" + std::to_string(line) + ": "), HasSubstr(what)));
}

/// For errors about the file as a whole or a binary record (no line).
auto input_error_about(const fs::path& path, const std::string& what)
{
    return ThrowsMessage<InputError>(AllOf(StartsWith(path.string() + ": "), HasSubstr(what)));
}

/// The boundary of a tet mesh with its vertices renumbered 0..#V−1 (unused nodes dropped).
SurfaceMesh compact_boundary(const TetMesh& mesh)
{
    const Tris faces = boundary_faces(mesh);
    const std::vector<Index> used = surface_vertices(faces);
    std::vector<Index> new_index(static_cast<std::size_t>(mesh.num_vertices()), -1);
    SurfaceMesh surface;
    surface.vertices.resize(static_cast<Index>(used.size()), 3);
    for (std::size_t i = 0; i < used.size(); ++i) {
        new_index[static_cast<std::size_t>(used[i])] = static_cast<Index>(i);
        surface.vertices.row(static_cast<Index>(i)) = mesh.rest_positions.row(used[i]);
    }
    surface.faces.resize(faces.rows(), 3);
    for (Index f = 0; f < faces.rows(); ++f)
        for (int k = 0; k < 3; ++k)
            surface.faces(f, k) = new_index[static_cast<std::size_t>(faces(f, k))];
    return surface;
}

/// A closed box surface whose coordinates (thirds, sevenths) are not short decimals.
SurfaceMesh box_surface()
{
    return compact_boundary(
        make_box(Vec3(-1.0 / 3.0, 0.1, 2.0), Vec3(1.0, 2.0 / 7.0, 2.5), {3, 2, 4}));
}

SurfaceMesh sphere_surface() { return compact_boundary(make_sphere(Vec3(0.1, -0.2, 0.3), 0.7, 6)); }

/// Coordinates as a binary STL stores them.
Positions rounded_to_float(const Positions& x)
{
    Positions rounded = x;
    for (Eigen::Index i = 0; i < rounded.size(); ++i)
        rounded.data()[i] = static_cast<double>(static_cast<float>(rounded.data()[i]));
    return rounded;
}

/// Same triangles, corner by corner, with bitwise equal coordinates (vertex numbering may
/// differ: STL renumbers vertices in order of first appearance).
void expect_same_triangles(const SurfaceMesh& read, const Positions& vertices, const Tris& faces)
{
    ASSERT_EQ(read.faces.rows(), faces.rows());
    for (Index f = 0; f < faces.rows(); ++f)
        for (int k = 0; k < 3; ++k)
            for (int d = 0; d < 3; ++d)
                ASSERT_EQ(read.vertices(read.faces(f, k), d), vertices(faces(f, k), d))
                    << "face " << f << " corner " << k << " coordinate " << d;
}

void expect_closed_unit_cube(const SurfaceMesh& surface)
{
    EXPECT_EQ(surface.vertices.rows(), 8);
    EXPECT_EQ(surface.faces.rows(), 12);
    const SurfaceCheck check = check_surface(surface.faces);
    EXPECT_TRUE(check.closed_and_oriented())
        << check.open_edges << " open, " << check.nonmanifold_edges << " non-manifold, "
        << check.misoriented_edges << " misoriented edges";
    EXPECT_DOUBLE_EQ(enclosed_volume(surface.vertices, surface.faces), 1.0);
}

// ---------------------------------------------------------------------------------------------
// Binary STL built byte by byte

void put_u32(std::string& out, std::uint32_t v)
{
    for (unsigned shift = 0; shift < 32; shift += 8)
        out += static_cast<char>((v >> shift) & 0xffU);
}

void put_f32(std::string& out, float value)
{
    std::uint32_t bits = 0;
    std::memcpy(&bits, &value, sizeof bits);
    put_u32(out, bits);
}

using StlTriangle = std::array<float, 9>; // three corners x y z

/// A binary STL with the given header text, triangles and declared count.
std::string binary_stl(const std::string& header, const std::vector<StlTriangle>& triangles,
                       std::uint32_t count)
{
    std::string out = header;
    out.resize(80, '\0');
    put_u32(out, count);
    for (const StlTriangle& t : triangles) {
        for (int d = 0; d < 3; ++d)
            put_f32(out, 0.0F); // normal: ignored by the reader
        for (const float x : t)
            put_f32(out, x);
        out += std::string(2, '\0');
    }
    return out;
}

std::string binary_stl(const std::string& header, const std::vector<StlTriangle>& triangles)
{
    return binary_stl(header, triangles, static_cast<std::uint32_t>(triangles.size()));
}

const std::vector<StlTriangle> TWO_TRIANGLES = {StlTriangle{0, 0, 0, 1, 0, 0, 0, 1, 0},
                                                StlTriangle{1, 0, 0, 1, 1, 0, 0, 1, 0}};

/// One ASCII STL facet (7 lines).
std::string ascii_facet(const std::string& a, const std::string& b, const std::string& c)
{
    return "facet normal 0 0 1\n outer loop\n  vertex " + a + "\n  vertex " + b + "\n  vertex " +
           c + "\n endloop\nendfacet\n";
}

// ---------------------------------------------------------------------------------------------
// Sample files

TEST(ReadSurface, ObjCubeWithQuadsIndexFormsAndRelativeIndicesIsClosed)
{
    const SurfaceMesh cube = read_surface(surface_dir() / "cube_quads.obj");
    expect_closed_unit_cube(cube);
    // First quad "f 1 3/2 4//1 2/4/1" becomes the fan (1 3 4), (1 4 2), 0-based.
    EXPECT_EQ(cube.faces.row(0), (Eigen::RowVector3i(0, 2, 3)));
    EXPECT_EQ(cube.faces.row(1), (Eigen::RowVector3i(0, 3, 1)));
    // Last quad "f -7 -5 -1 -3" with 8 vertices: 2 4 8 6 (1-based).
    EXPECT_EQ(cube.faces.row(10), (Eigen::RowVector3i(1, 3, 7)));
    EXPECT_EQ(cube.faces.row(11), (Eigen::RowVector3i(1, 7, 5)));
}

TEST(ReadSurface, OffCubeWithCommentsAndColoursIsClosed)
{
    const SurfaceMesh cube = read_surface(surface_dir() / "cube_colours.off");
    expect_closed_unit_cube(cube);
    EXPECT_EQ(cube.faces.row(0), (Eigen::RowVector3i(0, 2, 3)));
    EXPECT_EQ(cube.faces.row(1), (Eigen::RowVector3i(0, 3, 1)));
}

TEST(ReadSurface, AsciiStlCubeMergesCornersIntoEightVertices)
{
    expect_closed_unit_cube(read_surface(surface_dir() / "cube_ascii.stl"));
}

TEST(ReadSurface, BinaryStlWhoseHeaderStartsWithSolidIsReadAsBinary)
{
    const fs::path path = surface_dir() / "cube_binary_solid.stl";
    ASSERT_EQ(text_of(path).substr(0, 5), "solid");
    const SurfaceMesh cube = read_surface(path);
    expect_closed_unit_cube(cube);
    const SurfaceMesh ascii = read_surface(surface_dir() / "cube_ascii.stl");
    EXPECT_EQ(cube.vertices, ascii.vertices);
    EXPECT_EQ(cube.faces, ascii.faces);
}

// ---------------------------------------------------------------------------------------------
// OBJ

TEST(ReadSurface, ObjPolygonsAreFanTriangulated)
{
    const fs::path path = write_file("pentagon.obj", "v 0 0 0\nv 1 0 0\nv 2 1 0\nv 1 2 0\n"
                                                     "v 0 1 0\nf 1 2 3 4 5\nf 1 2 3\n");
    const SurfaceMesh s = read_surface(path);
    Tris expected(4, 3);
    expected << 0, 1, 2, 0, 2, 3, 0, 3, 4, 0, 1, 2;
    EXPECT_EQ(s.faces, expected);
    EXPECT_EQ(s.vertices.rows(), 5);
}

TEST(ReadSurface, ObjNegativeIndicesCountBackFromTheLastVertexSoFar)
{
    const fs::path path = write_file("relative.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\n"
                                                     "f -3 -2 -1\n"
                                                     "v 0 0 1\n"
                                                     "f -4 -1 -3\n");
    const SurfaceMesh s = read_surface(path);
    Tris expected(2, 3);
    expected << 0, 1, 2, 0, 3, 1;
    EXPECT_EQ(s.faces, expected);
}

TEST(ReadSurface, ObjIgnoresTextureNormalGroupAndMaterialStatements)
{
    const fs::path path = write_file("statements.obj", "mtllib a.mtl\n"
                                                       "o thing\n"
                                                       "g group1 group2\n"
                                                       "s 1\n"
                                                       "usemtl red\n"
                                                       "v 0 0 0 # a comment after data\n"
                                                       "v 1 0 0 1.0\n"         // w
                                                       "v 0 1 0 0.5 0.2 0.1\n" // colour
                                                       "vt 0 0\nvt 1 0\nvt 0 1\n"
                                                       "vn 0 0 1\n"
                                                       "vp 0.5\n"
                                                       "l 1 2\n"
                                                       "p 3\n"
                                                       "\t f 1/1/1   2/2/1 3/3/1 \r\n"
                                                       "f 1//1 2//1 3//1\n"
                                                       "f 1/1 2/2 3/3\n"
                                                       "# end\n");
    const SurfaceMesh s = read_surface(path);
    EXPECT_EQ(s.vertices.rows(), 3);
    ASSERT_EQ(s.faces.rows(), 3);
    for (Index f = 0; f < 3; ++f)
        EXPECT_EQ(s.faces.row(f), (Eigen::RowVector3i(0, 1, 2)));
    EXPECT_EQ(s.vertices.row(2), (Eigen::RowVector3d(0.0, 1.0, 0.0)));
}

TEST(ReadSurface, ObjAcceptsFacesBeforeTheirVertices)
{
    const fs::path path = write_file("forward.obj", "f 1 2 3\nv 0 0 0\nv 1 0 0\nv 0 1 0\n");
    const SurfaceMesh s = read_surface(path);
    EXPECT_EQ(s.faces.row(0), (Eigen::RowVector3i(0, 1, 2)));
}

TEST(ReadSurface, ObjKeepsUnusedVerticesAndExactCoordinates)
{
    const fs::path path = write_file("exact.obj", "v 0.1 -2.5e-300 +3\nv 1 0 0\nv 0 1 0\n"
                                                  "v 9 9 9\nf 1 2 3\n");
    const SurfaceMesh s = read_surface(path);
    ASSERT_EQ(s.vertices.rows(), 4);
    EXPECT_EQ(s.vertices(0, 0), 0.1);
    EXPECT_EQ(s.vertices(0, 1), -2.5e-300);
    EXPECT_EQ(s.vertices(0, 2), 3.0);
}

TEST(ReadSurface, DispatchesUpperCaseExtensions)
{
    const fs::path path = write_file("upper.OBJ", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    EXPECT_EQ(read_surface(path).faces.rows(), 1);
}

// ---------------------------------------------------------------------------------------------
// OFF

TEST(ReadSurface, OffAcceptsCountsOnTheHeaderLineAndPolygons)
{
    const fs::path path = write_file("header_counts.off", "OFF 4 1 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n"
                                                          "4 0 1 2 3\n");
    const SurfaceMesh s = read_surface(path);
    Tris expected(2, 3);
    expected << 0, 1, 2, 0, 2, 3;
    EXPECT_EQ(s.faces, expected);
}

TEST(ReadSurface, OffWithoutKeywordStartsWithTheCounts)
{
    const fs::path path = write_file("no_keyword.off", "# a comment first\n3 1 3\n0 0 0\n1 0 0\n"
                                                       "0 1 0\n3 0 1 2\n");
    EXPECT_EQ(read_surface(path).faces.rows(), 1);
}

TEST(ReadSurface, OffVariantsSkipVertexColoursAndNormals)
{
    const fs::path coff = write_file("colours.off", "COFF\n3 1 0\n0 0 0 255 0 0 255\n"
                                                    "1 0 0 0 255 0 255\n0 1 0 0 0 255 255\n"
                                                    "3 0 1 2 7\n");
    EXPECT_EQ(read_surface(coff).vertices.row(1), (Eigen::RowVector3d(1.0, 0.0, 0.0)));
    const fs::path cnoff = write_file("normals.off", "CNOFF\n3 1 0\n0 0 0 0 0 1 1 0 0\n"
                                                     "1 0 0 0 0 1 0 1 0\n0 1 0 0 0 1 0 0 1\n"
                                                     "3 0 1 2\n");
    EXPECT_EQ(read_surface(cnoff).vertices.row(2), (Eigen::RowVector3d(0.0, 1.0, 0.0)));
}

// ---------------------------------------------------------------------------------------------
// STL

TEST(ReadSurface, StlMergesIdenticalCornersIncludingSignedZeros)
{
    const fs::path path =
        write_file("merge.stl", "solid s\n" + ascii_facet("0 0 0", "1 0 0", "0 1 0") +
                                    ascii_facet("1 0 0", "1 1 0", "-0 1.0 0") + "endsolid s\n");
    const SurfaceMesh s = read_surface(path);
    EXPECT_EQ(s.vertices.rows(), 4);
    Tris expected(2, 3);
    expected << 0, 1, 2, 1, 3, 2;
    EXPECT_EQ(s.faces, expected);
}

TEST(ReadSurface, AsciiStlAcceptsSeveralSolidsUpperCaseAndFreeLayout)
{
    const fs::path path = write_file(
        "layout.stl", "  SOLID first part\r\nFACET NORMAL 0 0 1 OUTER LOOP\r\n"
                      "VERTEX 0 0 0 VERTEX 1 0 0 VERTEX 0 1 0 ENDLOOP ENDFACET\r\nENDSOLID\r\n"
                      "solid second\n" +
                          ascii_facet("1 0 0", "1 1 0", "0 1 0") + "endsolid second");
    const SurfaceMesh s = read_surface(path);
    EXPECT_EQ(s.vertices.rows(), 4);
    EXPECT_EQ(s.faces.rows(), 2);
}

TEST(ReadSurface, AsciiStlIgnoresNonFiniteNormals)
{
    const fs::path path =
        write_file("nan_normal.stl", "solid s\nfacet normal nan nan nan\nouter loop\n"
                                     "vertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\nendloop\n"
                                     "endfacet\nendsolid s\n");
    EXPECT_EQ(read_surface(path).faces.rows(), 1);
}

TEST(ReadSurface, BinaryStlIsDetectedBySizeAndMerged)
{
    const fs::path path = write_file("two.stl", binary_stl("made by a CAD tool", TWO_TRIANGLES));
    const SurfaceMesh s = read_surface(path);
    EXPECT_EQ(s.vertices.rows(), 4);
    Tris expected(2, 3);
    expected << 0, 1, 2, 1, 3, 2;
    EXPECT_EQ(s.faces, expected);
}

// ---------------------------------------------------------------------------------------------
// Writers and round trips

enum class Format { OBJ, OFF, STL_ASCII, STL_BINARY };

struct FormatCase {
    Format format;
    const char* name;
};

constexpr std::array<FormatCase, 4> FORMATS = {{{Format::OBJ, "round_trip.obj"},
                                                {Format::OFF, "round_trip.off"},
                                                {Format::STL_ASCII, "round_trip_ascii.stl"},
                                                {Format::STL_BINARY, "round_trip_binary.stl"}}};

fs::path write_as(const FormatCase& c, const SurfaceMesh& surface)
{
    const fs::path path = scratch() / c.name;
    switch (c.format) {
    case Format::OBJ:
        write_obj(path, surface);
        break;
    case Format::OFF:
        write_off(path, surface);
        break;
    case Format::STL_ASCII:
        write_stl(path, surface, false);
        break;
    case Format::STL_BINARY:
        write_stl(path, surface, true);
        break;
    }
    return path;
}

TEST(WriteSurface, RoundTripsBoxAndSphereThroughEveryFormat)
{
    const std::array<std::pair<const char*, SurfaceMesh>, 2> shapes = {
        {{"box", box_surface()}, {"sphere", sphere_surface()}}};
    for (const auto& [shape, surface] : shapes) {
        ASSERT_TRUE(check_surface(surface.faces).closed_and_oriented()) << shape;
        for (const FormatCase& c : FORMATS) {
            SCOPED_TRACE(std::string(shape) + " as " + c.name);
            const SurfaceMesh read = read_surface(write_as(c, surface));
            EXPECT_EQ(read.vertices.rows(), surface.vertices.rows());
            const bool exact = c.format != Format::STL_BINARY;
            expect_same_triangles(
                read, exact ? surface.vertices : rounded_to_float(surface.vertices), surface.faces);
            if (c.format == Format::OBJ || c.format == Format::OFF) {
                EXPECT_EQ(read.vertices, surface.vertices); // same numbering, bitwise equal
                EXPECT_EQ(read.faces, surface.faces);
            }
            const SurfaceCheck check = check_surface(read.faces);
            EXPECT_TRUE(check.closed_and_oriented());
            EXPECT_NEAR(enclosed_volume(read.vertices, read.faces),
                        enclosed_volume(surface.vertices, surface.faces), exact ? 1e-14 : 1e-6);
        }
    }
}

TEST(WriteSurface, WritesShortestRoundTripNumbers)
{
    SurfaceMesh s;
    s.vertices.resize(3, 3);
    s.vertices << 0.1, 1.0 / 3.0, -0.0, 1e-310, 1.0, 2.0, 0.0, 5e300, 3.0;
    s.faces.resize(1, 3);
    s.faces << 0, 1, 2;
    const fs::path obj = scratch() / "numbers.obj";
    write_obj(obj, s);
    EXPECT_THAT(text_of(obj), HasSubstr("v 0.1 0.3333333333333333 -0\n"));
    EXPECT_THAT(text_of(obj), HasSubstr("\nf 1 2 3\n"));
    const SurfaceMesh read = read_surface(obj);
    EXPECT_EQ(read.vertices, s.vertices);
    EXPECT_TRUE(std::signbit(read.vertices(0, 2)));
    const fs::path off = scratch() / "numbers.off";
    write_off(off, s);
    EXPECT_THAT(text_of(off), StartsWith("OFF\n3 1 0\n0.1 0.3333333333333333 -0\n"));
    EXPECT_EQ(read_surface(off).vertices, s.vertices);
}

TEST(WriteSurface, BinaryStlHasStandardLayoutAndAHeaderThatIsNotSolid)
{
    const SurfaceMesh box = box_surface();
    const fs::path path = scratch() / "layout_binary.stl";
    write_stl(path, box, true);
    const std::string bytes = text_of(path);
    ASSERT_EQ(bytes.size(), 84 + 50 * static_cast<std::size_t>(box.faces.rows()));
    EXPECT_NE(bytes.substr(0, 5), "solid");
    // The first facet's normal is the unit outward normal of face 0.
    const Vec3 x0 = box.vertices.row(box.faces(0, 0)).transpose();
    const Vec3 x1 = box.vertices.row(box.faces(0, 1)).transpose();
    const Vec3 x2 = box.vertices.row(box.faces(0, 2)).transpose();
    const Vec3 n = (x1 - x0).cross(x2 - x0).normalized();
    for (int d = 0; d < 3; ++d) {
        float value = 0.0F;
        std::memcpy(&value, bytes.data() + 84 + 4 * d, sizeof value);
        EXPECT_EQ(value, static_cast<float>(n[d]));
    }
}

TEST(WriteSurface, BinaryStlWhoseHeaderIsPatchedToSolidReadsBack)
{
    const SurfaceMesh sphere = sphere_surface();
    const fs::path path = scratch() / "patched.stl";
    write_stl(path, sphere, true);
    std::string bytes = text_of(path);
    bytes.replace(0, 20, "solid sphere        ");
    write_file("patched.stl", bytes);
    const SurfaceMesh read = read_surface(path);
    expect_same_triangles(read, rounded_to_float(sphere.vertices), sphere.faces);
}

TEST(WriteSurface, AsciiStlIsReadableText)
{
    SurfaceMesh s;
    s.vertices.resize(3, 3);
    s.vertices << 0, 0, 0, 2, 0, 0, 0, 2, 0;
    s.faces.resize(1, 3);
    s.faces << 0, 1, 2;
    const fs::path path = scratch() / "layout_ascii.stl";
    write_stl(path, s, false);
    EXPECT_EQ(text_of(path), "solid corocontact\nfacet normal 0 0 1\n  outer loop\n"
                             "    vertex 0 0 0\n    vertex 2 0 0\n    vertex 0 2 0\n"
                             "  endloop\nendfacet\nendsolid corocontact\n");
}

TEST(WriteSurface, BinaryStlRejectsCoordinatesBeyondFloat)
{
    SurfaceMesh s;
    s.vertices.resize(3, 3);
    s.vertices << 0, 0, 0, 1e300, 0, 0, 0, 1, 0;
    s.faces.resize(1, 3);
    s.faces << 0, 1, 2;
    const fs::path path = scratch() / "too_large.stl";
    EXPECT_THAT([&] { write_stl(path, s, true); },
                input_error_about(path, "vertex 1 coordinate x = 1e+300 does not fit"));
}

TEST(WriteSurface, RejectsUnwritablePath)
{
    const fs::path path = scratch() / "no_such_dir" / "out.obj";
    EXPECT_THAT([&] { write_obj(path, box_surface()); },
                ThrowsMessage<OutputError>(AllOf(StartsWith(path.string() + ": cannot create out.obj.tmp"),
                                                 HasSubstr("(No such file or directory)"))));
}

// ---------------------------------------------------------------------------------------------
// Errors common to every format

TEST(ReadSurface, RejectsMissingFile)
{
    const fs::path path = scratch() / "missing.obj";
    EXPECT_THAT([&] { read_surface(path); }, input_error_about(path, "does not exist"));
}

TEST(ReadSurface, RejectsDirectory)
{
    const fs::path path = scratch() / "dir.stl";
    fs::create_directories(path);
    EXPECT_THAT([&] { read_surface(path); }, input_error_about(path, "is a directory"));
}

TEST(ReadSurface, SaysADirectoryWithoutExtensionIsADirectory)
{
    const fs::path path = scratch() / "surfaces";
    fs::create_directories(path);
    EXPECT_THAT([&] { read_surface(path); }, input_error_about(path, "is a directory, expected a surface file"));
}

TEST(ReadSurface, RejectsADeviceInsteadOfReadingItWithoutEnd)
{
    const fs::path path = scratch() / "urandom.stl";
    fs::remove(path);
    fs::create_symlink("/dev/urandom", path);
    EXPECT_THAT([&] { read_surface(path); }, input_error_about(path, "is not a regular file (a device, pipe or socket), expected a surface file"));
}

TEST(ReadSurface, RejectsUnknownExtensionListingSupportedOnes)
{
    const fs::path path = write_file("mesh.ply", "ply\n");
    EXPECT_THAT([&] { read_surface(path); },
                input_error_about(path, "unsupported surface extension '.ply', expected one of: "
                                        ".obj, .stl, .off"));
}

// ---------------------------------------------------------------------------------------------
// OBJ errors (line numbers as written)

const std::string OBJ_TRIANGLE = "v 0 0 0\nv 1 0 0\nv 0 1 0\n"; // lines 1-3

TEST(ReadSurface, RejectsObjIndexZero)
{
    const fs::path path = write_file("zero.obj", OBJ_TRIANGLE + "f 1 2 3\nf 0 1 2\n");
    EXPECT_THAT([&] { read_surface(path); },
                input_error_at(path, 5, "face 2 has vertex index 0, expected 1..3 or -3..-1"));
}

TEST(ReadSurface, RejectsObjIndexBeyondTheVertices)
{
    const fs::path path = write_file("beyond.obj", OBJ_TRIANGLE + "f 1 2 3\n\nf 1 2 4\n# end\n");
    EXPECT_THAT([&] { read_surface(path); },
                input_error_at(path, 6, "face 2 has vertex index 4, expected 1..3"));
}

TEST(ReadSurface, RejectsObjIndexBeyondThe32BitRange)
{
    const fs::path path = write_file("huge_index.obj", OBJ_TRIANGLE + "f 1 2 99999999999\n");
    EXPECT_THAT([&] { read_surface(path); },
                input_error_at(path, 4, "vertex index 99999999999, expected at most"));
}

TEST(ReadSurface, RejectsObjRelativeIndexBeforeTheFirstVertex)
{
    const fs::path path = write_file("relative_bad.obj", OBJ_TRIANGLE + "f -1 -2 -4\n");
    EXPECT_THAT([&] { read_surface(path); },
                input_error_at(path, 4, "relative vertex index -4, expected -3..-1"));
}

TEST(ReadSurface, RejectsObjIndicesBeforeAnyVertexOrAtTheInt64Limit)
{
    const fs::path first = write_file("no_vertex_yet.obj", "f -1 -2 -3\n");
    EXPECT_THAT([&] { read_surface(first); },
                input_error_at(first, 1,
                               "face 1 has relative vertex index -1, expected a vertex "
                               "defined before it (0 vertices defined so far)"));
    const fs::path limit =
        write_file("int64_min.obj", OBJ_TRIANGLE + "f -9223372036854775808 -1 -2\n");
    EXPECT_THAT([&] { read_surface(limit); },
                input_error_at(limit, 4,
                               "relative vertex index -9223372036854775808, expected "
                               "-3..-1"));
    const fs::path below =
        write_file("below_int64.obj", OBJ_TRIANGLE + "f -9223372036854775809 1 2\n");
    EXPECT_THAT([&] { read_surface(below); }, input_error_at(below, 4, "expected a vertex index"));
}

TEST(ReadSurface, RejectsObjFaceWithTwoVertices)
{
    const fs::path path = write_file("two.obj", OBJ_TRIANGLE + "f 1 2\n");
    EXPECT_THAT([&] { read_surface(path); },
                input_error_at(path, 4, "face 1 has 2 vertices, expected at least 3"));
}

TEST(ReadSurface, RejectsObjFaceRepeatingAVertex)
{
    const fs::path path = write_file("repeat.obj", OBJ_TRIANGLE + "v 1 1 0\nf 1 2 3\nf 1 2 4 -3\n");
    EXPECT_THAT([&] { read_surface(path); },
                input_error_at(path, 6, "face 2 repeats vertex 2 (corners 2 and 4)"));
}

TEST(ReadSurface, RejectsObjLongPolygonRepeatingAVertex)
{
    std::string text;
    std::string face = "f";
    for (int i = 0; i < 20; ++i) {
        text += "v " + std::to_string(i) + " 0 0\n";
        face += " " + std::to_string(i == 17 ? 5 : i + 1);
    }
    const fs::path path = write_file("long_repeat.obj", text + face + "\n");
    EXPECT_THAT([&] { read_surface(path); },
                input_error_at(path, 21, "face 1 repeats vertex 5 (corners 5 and 18)"));
}

TEST(ReadSurface, RejectsObjNonFiniteCoordinates)
{
    for (const std::string value : {"nan", "inf", "-infinity", "1e400"}) {
        const fs::path path = write_file("nonfinite.obj", "v 0 0 0\nv 1 " + value + " 0\n");
        EXPECT_THAT([&] { read_surface(path); },
                    input_error_at(path, 2,
                                   "expected vertex y coordinate (a finite number), "
                                   "found '" +
                                       value + "'"))
            << value;
    }
}

TEST(ReadSurface, RejectsObjMalformedNumbers)
{
    const fs::path path = write_file("malformed.obj", "v 0 0 0\nv 1.0.0 0 0\n");
    EXPECT_THAT([&] { read_surface(path); },
                input_error_at(path, 2,
                               "expected vertex x coordinate (a finite number), found "
                               "'1.0.0'"));
}

TEST(ReadSurface, RejectsObjMissingCoordinate)
{
    const fs::path path = write_file("short_v.obj", "v 0 0 0\n\nv 1 0\n");
    EXPECT_THAT([&] { read_surface(path); },
                input_error_at(path, 3, "expected vertex z coordinate, found end of line"));
}

TEST(ReadSurface, RejectsObjTooManyVertexValues)
{
    const fs::path path = write_file("long_v.obj", "v 0 0 0 1 2 3 4 5\n");
    EXPECT_THAT([&] { read_surface(path); },
                input_error_at(path, 1, "at most 4 further values (w or a colour), found 8"));
}

TEST(ReadSurface, RejectsObjMalformedCorners)
{
    for (const std::string corner : {"1/a/2", "1/2/3/4", "x", "1/", "2.5"}) {
        const fs::path path = write_file("corner.obj", OBJ_TRIANGLE + "f 1 2 " + corner + "\n");
        EXPECT_THAT([&] { read_surface(path); }, input_error_at(path, 4, "found '" + corner + "'"))
            << corner;
    }
}

TEST(ReadSurface, RejectsObjUnknownStatement)
{
    const fs::path path = write_file("unknown.obj", OBJ_TRIANGLE + "f 1 2 3\nvx 1 2 3\n");
    EXPECT_THAT([&] { read_surface(path); },
                input_error_at(path, 5,
                               "expected an OBJ statement (v, f, vt, vn, g, o, s, "
                               "usemtl, mtllib, ...), found 'vx'"));
}

TEST(ReadSurface, RejectsObjBinaryGarbage)
{
    const fs::path path = write_file("garbage.obj", std::string("\x7f"
                                                                "ELF\x02\x01\x01\0\0",
                                                                9));
    EXPECT_THAT([&] { read_surface(path); }, input_error_at(path, 1, "expected an OBJ statement"));
}

TEST(ReadSurface, RejectsObjLineContinuation)
{
    const fs::path path = write_file("continued.obj", OBJ_TRIANGLE + "f 1 2 \\\n 3\n");
    EXPECT_THAT([&] { read_surface(path); }, input_error_at(path, 4, "line continuation"));
}

TEST(ReadSurface, RejectsObjWithoutFaces)
{
    const fs::path path = write_file("no_faces.obj", OBJ_TRIANGLE + "vn 0 0 1\n");
    EXPECT_THAT([&] { read_surface(path); },
                input_error_about(path, "expected at least one face ('f' line), found none"));
    const fs::path empty = write_file("empty.obj", "");
    EXPECT_THAT([&] { read_surface(empty); },
                input_error_about(empty, "expected at least one face"));
}

// ---------------------------------------------------------------------------------------------
// OFF errors

const std::string OFF_HEAD = "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n"; // lines 1-5

TEST(ReadSurface, RejectsOffWithoutHeader)
{
    const fs::path path = write_file("no_header.off", "# comment\nPLY\n3 1 0\n");
    EXPECT_THAT([&] { read_surface(path); },
                input_error_at(path, 2, "expected the OFF header ('OFF') or the counts"));
    const fs::path empty = write_file("empty.off", "\n\n");
    EXPECT_THAT([&] { read_surface(empty); },
                input_error_at(empty, 2, "expected the OFF header, found an empty file"));
}

TEST(ReadSurface, RejectsOffUnsupportedVariants)
{
    const fs::path four = write_file("four.off", "4OFF\n1 0 0\n");
    EXPECT_THAT([&] { read_surface(four); },
                input_error_at(four, 1, "unsupported OFF variant '4OFF'"));
    const fs::path binary = write_file("binary.off", "OFF BINARY\n");
    EXPECT_THAT([&] { read_surface(binary); },
                input_error_at(binary, 1, "binary OFF is not supported"));
}

TEST(ReadSurface, RejectsOffMalformedCounts)
{
    const fs::path path = write_file("counts.off", "OFF\n3 x 0\n");
    EXPECT_THAT([&] { read_surface(path); },
                input_error_at(path, 2,
                               "expected the number of faces (a non-negative integer), "
                               "found 'x'"));
    const fs::path missing = write_file("counts_missing.off", "OFF\n# only a comment\n");
    EXPECT_THAT([&] { read_surface(missing); }, input_error_at(missing, 2, "expected the counts"));
    const fs::path extra = write_file("counts_extra.off", "OFF\n3 1 0 7\n");
    EXPECT_THAT([&] { read_surface(extra); },
                input_error_at(extra, 2, "expected end of line after the counts"));
}

TEST(ReadSurface, RejectsOffDeclaringMoreVerticesThanItHolds)
{
    // A count of two billion must neither allocate nor be trusted: the file ends first.
    const fs::path path = write_file("few_vertices.off", "OFF\n2000000000 1 0\n0 0 0\n1 0 0\n");
    EXPECT_THAT([&] { read_surface(path); },
                input_error_at(path, 4,
                               "expected vertex 3 of 2000000000 declared at line 2 "
                               "('x y z'), found end of file"));
}

TEST(ReadSurface, RejectsOffDeclaringMoreFacesThanItHolds)
{
    const fs::path path = write_file("few_faces.off", "OFF\n3 4000000000 0\n0 0 0\n1 0 0\n0 1 0\n"
                                                      "3 0 1 2\n");
    EXPECT_THAT([&] { read_surface(path); },
                input_error_at(path, 6, "expected face 2 of 4000000000 declared at line 2"));
}

TEST(ReadSurface, RejectsOffVertexCountBeyondThe32BitRange)
{
    const fs::path path = write_file("many_vertices.off", "OFF\n3000000000 1 0\n");
    EXPECT_THAT([&] { read_surface(path); },
                input_error_at(path, 2, "3000000000 vertices declared, expected at most"));
}

TEST(ReadSurface, RejectsOffBadVertexLines)
{
    const fs::path nan = write_file("nan.off", "OFF\n3 1 0\n0 0 0\n1 nan 0\n0 1 0\n3 0 1 2\n");
    EXPECT_THAT([&] { read_surface(nan); },
                input_error_at(nan, 4,
                               "expected vertex y coordinate (a finite number), found "
                               "'nan'"));
    const fs::path two = write_file("two_values.off", "OFF\n3 1 0\n0 0 0 1 0\n");
    EXPECT_THAT([&] { read_surface(two); },
                input_error_at(two, 3,
                               "expected 'x y z' followed by 0, 3 or 4 (a colour) values "
                               "for vertex 1, found 2 more"));
    const fs::path noff = write_file("noff.off", "NOFF\n3 1 0\n0 0 0\n");
    EXPECT_THAT([&] { read_surface(noff); },
                input_error_at(noff, 3, "followed by 3 values for vertex 1, found 0 more"));
}

TEST(ReadSurface, RejectsOffFaceWithTwoVertices)
{
    const fs::path path = write_file("face_two.off", OFF_HEAD + "2 0 1\n");
    EXPECT_THAT([&] { read_surface(path); },
                input_error_at(path, 6, "face 1 has 2 vertices, expected at least 3"));
}

TEST(ReadSurface, RejectsOffFaceDeclaringMoreVerticesThanGiven)
{
    const fs::path path = write_file("face_short.off", OFF_HEAD + "4000000000 0 1 2\n");
    EXPECT_THAT([&] { read_surface(path); },
                input_error_at(path, 6, "face 1 declares 4000000000 vertices, found 3 values"));
}

TEST(ReadSurface, RejectsOffFaceIndexOutOfRange)
{
    const fs::path path = write_file("face_range.off", OFF_HEAD + "3 0 1 3\n");
    EXPECT_THAT([&] { read_surface(path); },
                input_error_at(path, 6, "face 1 has vertex index 3, expected 0..2 (3 vertices)"));
    const fs::path negative = write_file("face_negative.off", OFF_HEAD + "3 0 1 -1\n");
    EXPECT_THAT([&] { read_surface(negative); },
                input_error_at(negative, 6,
                               "expected a vertex index (a non-negative integer), "
                               "found '-1'"));
}

TEST(ReadSurface, RejectsOffFaceWhenNoVerticesAreDeclared)
{
    const fs::path path = write_file("no_vertices.off", "OFF\n0 1 0\n3 0 1 2\n");
    EXPECT_THAT([&] { read_surface(path); },
                input_error_at(path, 3,
                               "face 1 has vertex index 0, expected none (the file "
                               "declares no vertices)"));
}

TEST(ReadSurface, RejectsOffFaceRepeatingAVertex)
{
    const fs::path path = write_file("face_repeat.off", OFF_HEAD + "3 0 2 2\n");
    EXPECT_THAT([&] { read_surface(path); },
                input_error_at(path, 6,
                               "face 1 repeats vertex 2 (corners 2 and 3), expected "
                               "distinct vertices"));
}

TEST(ReadSurface, RejectsOffTooManyColourValues)
{
    const fs::path path = write_file("face_colour.off", OFF_HEAD + "3 0 1 2 1 1 1 1 1\n");
    EXPECT_THAT([&] { read_surface(path); },
                input_error_at(path, 6,
                               "expected at most 4 colour values after the 3 vertex "
                               "indices of face 1, found 5"));
}

TEST(ReadSurface, RejectsOffTrailingData)
{
    const fs::path path = write_file("trailing.off", OFF_HEAD + "3 0 1 2\n\n3 0 1 2\n");
    EXPECT_THAT([&] { read_surface(path); },
                input_error_at(path, 8,
                               "expected end of file after the 1 faces declared at line "
                               "2, found '3 0 1 2'"));
}

TEST(ReadSurface, RejectsOffWithoutFaces)
{
    const fs::path path = write_file("no_faces.off", "OFF\n3 0 0\n0 0 0\n1 0 0\n0 1 0\n");
    EXPECT_THAT([&] { read_surface(path); },
                input_error_at(path, 2, "expected at least one face, found a count of 0"));
}

// ---------------------------------------------------------------------------------------------
// ASCII STL errors

const std::string STL_FACET = ascii_facet("0 0 0", "1 0 0", "0 1 0"); // 7 lines

TEST(ReadSurface, RejectsAsciiStlMissingEndloop)
{
    const fs::path path = write_file(
        "no_endloop.stl", "solid s\n" + STL_FACET +
                              "facet normal 0 0 1\nouter loop\nvertex 1 0 0\nvertex 1 1 0\n"
                              "vertex 0 1 0\nendfacet\nendsolid s\n");
    EXPECT_THAT([&] { read_surface(path); },
                input_error_at(path, 14,
                               "expected 'endloop' after the 3 vertices of a facet, "
                               "found 'endfacet'"));
}

TEST(ReadSurface, RejectsAsciiStlFacetWithFourVertices)
{
    const fs::path path = write_file("four.stl", "solid s\nfacet normal 0 0 1\nouter loop\n"
                                                 "vertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\n"
                                                 "vertex 1 1 0\nendloop\nendfacet\nendsolid\n");
    EXPECT_THAT([&] { read_surface(path); },
                input_error_at(path, 7,
                               "expected 'endloop' after the 3 vertices of a facet, "
                               "found 'vertex'"));
}

TEST(ReadSurface, RejectsAsciiStlFacetWithTwoVertices)
{
    const fs::path path = write_file("two.stl", "solid s\nfacet normal 0 0 1\nouter loop\n"
                                                "vertex 0 0 0\nvertex 1 0 0\nendloop\n");
    EXPECT_THAT([&] { read_surface(path); },
                input_error_at(path, 6,
                               "expected 'vertex' (vertex 3 of 3 of facet 1), found "
                               "'endloop'"));
}

TEST(ReadSurface, RejectsAsciiStlNonFiniteVertex)
{
    const fs::path path = write_file(
        "nan.stl", "solid s\n" + ascii_facet("0 0 0", "1 0 0", "0 inf 0") + "endsolid s\n");
    EXPECT_THAT([&] { read_surface(path); },
                input_error_at(path, 6,
                               "expected vertex y coordinate (a finite number), found "
                               "'inf'"));
}

TEST(ReadSurface, RejectsAsciiStlMalformedNormal)
{
    const fs::path path = write_file("normal.stl", "solid s\nfacet normal 0 0\nouter loop\n");
    EXPECT_THAT([&] { read_surface(path); },
                input_error_at(path, 3, "expected a facet normal component, found 'outer'"));
}

TEST(ReadSurface, RejectsTruncatedAsciiStl)
{
    const fs::path path = write_file("truncated.stl", "solid s\n" + STL_FACET +
                                                          "facet normal 0 0 1\nouter loop\n"
                                                          "vertex 1 0 0\nvertex 1 1\n");
    EXPECT_THAT([&] { read_surface(path); },
                input_error_at(path, 12,
                               "expected vertex z coordinate (a finite number), found "
                               "end of file"));
    const fs::path no_end = write_file("no_endsolid.stl", "solid s\n" + STL_FACET);
    EXPECT_THAT([&] { read_surface(no_end); },
                input_error_at(no_end, 8, "expected 'facet' or 'endsolid', found end of file"));
}

TEST(ReadSurface, RejectsAsciiStlUnexpectedKeyword)
{
    const fs::path path = write_file("keyword.stl", "solid s\n" + STL_FACET + "facets\n");
    EXPECT_THAT([&] { read_surface(path); },
                input_error_at(path, 9, "expected 'facet' or 'endsolid', found 'facets'"));
    const fs::path after = write_file("after_end.stl", "solid s\n" + STL_FACET +
                                                           "endsolid s\n"
                                                           "extra\n");
    EXPECT_THAT([&] { read_surface(after); },
                input_error_at(after, 10,
                               "expected 'solid' or end of file after 'endsolid', "
                               "found 'extra'"));
}

TEST(ReadSurface, RejectsAsciiStlWithoutFacets)
{
    const fs::path path = write_file("empty_solid.stl", "solid s\nendsolid s\n");
    EXPECT_THAT([&] { read_surface(path); },
                input_error_at(path, 2, "expected at least one facet"));
}

TEST(ReadSurface, RejectsAsciiStlDegenerateFacet)
{
    const fs::path path = write_file(
        "degenerate.stl",
        "solid s\n" + STL_FACET + ascii_facet("1 0 0", "1 1 0", "1.0 0 -0") + "endsolid s\n");
    EXPECT_THAT([&] { read_surface(path); },
                input_error_at(path, 9,
                               "facet 2 repeats the vertex (1, 0, 0) at corners 1 and 3, "
                               "expected three distinct vertices"));
}

// ---------------------------------------------------------------------------------------------
// Binary STL errors

TEST(ReadSurface, RejectsBinaryStlWhoseSizeDoesNotMatchItsCount)
{
    std::string bytes = binary_stl("binary", TWO_TRIANGLES);
    bytes.pop_back();
    const fs::path path = write_file("truncated_binary.stl", bytes);
    EXPECT_THAT([&] { read_surface(path); },
                input_error_about(path, "binary STL header (byte offset 80) declares 2 triangles, "
                                        "which take 84 + 50 x 2 = 184 bytes, but the file has 183 "
                                        "bytes"));
}

TEST(ReadSurface, RejectsBinaryStlWithAHugeCountWithoutAllocating)
{
    const fs::path path = write_file("huge_count.stl", binary_stl("", TWO_TRIANGLES, 0xffffffffU));
    EXPECT_THAT([&] { read_surface(path); },
                input_error_about(path, "declares 4294967295 triangles, which take 84 + 50 x "
                                        "4294967295 = 214748364834 bytes, but the file has 184"));
}

TEST(ReadSurface, RejectsTruncatedBinaryStlWhoseHeaderStartsWithSolid)
{
    std::string bytes = binary_stl("solid cube", TWO_TRIANGLES);
    bytes.resize(bytes.size() - 50);
    const fs::path path = write_file("truncated_solid.stl", bytes);
    EXPECT_THAT([&] { read_surface(path); },
                input_error_about(path, "declares 2 triangles, which take 84 + 50 x 2 = 184 "
                                        "bytes, but the file has 134 bytes"));
}

TEST(ReadSurface, RejectsShortFileThatIsNeitherStl)
{
    const fs::path path = write_file("short.stl", "not an stl");
    EXPECT_THAT([&] { read_surface(path); },
                input_error_about(path, "expected an ASCII STL (starting with 'solid') or a "
                                        "binary STL (at least 84 bytes), found 10 bytes"));
}

TEST(ReadSurface, RejectsBinaryStlNonFiniteCoordinate)
{
    std::vector<StlTriangle> triangles = TWO_TRIANGLES;
    triangles[1][7] = std::numeric_limits<float>::quiet_NaN(); // triangle 2, vertex 3, y
    const fs::path path = write_file("nan_binary.stl", binary_stl("", triangles));
    // Record 2 starts at 84 + 50 = 134; its vertex 3 at 134 + 12 + 24 = 170, y at 174.
    EXPECT_THAT([&] { read_surface(path); },
                input_error_about(path, "triangle 2 of 2 (byte offset 174): vertex 3 coordinate "
                                        "y is nan, expected a finite number"));
}

TEST(ReadSurface, RejectsBinaryStlDegenerateTriangle)
{
    std::vector<StlTriangle> triangles = TWO_TRIANGLES;
    triangles[1] = {1, 0, 0, 0, 1, 0, 1, -0.0F, 0};
    const fs::path path = write_file("degenerate_binary.stl", binary_stl("", triangles));
    EXPECT_THAT([&] { read_surface(path); },
                input_error_about(path, "triangle 2 of 2 (byte offset 134) repeats the vertex "
                                        "(1, 0, 0) at corners 1 and 3"));
}

TEST(ReadSurface, RejectsBinaryStlWithoutTriangles)
{
    const fs::path path = write_file("zero_binary.stl", binary_stl("", {}));
    EXPECT_THAT([&] { read_surface(path); },
                input_error_about(path, "declares 0 triangles, expected at least one face"));
}

} // namespace
} // namespace coro
