#include <corocontact/io/vtk_series.hpp>

#include <corocontact/core/error.hpp>
#include <corocontact/core/primitives.hpp>

#include "mesh_fixtures.hpp"
#include "near.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <vtkCellData.h>
#include <vtkCellType.h>
#include <vtkCompositeDataSet.h>
#include <vtkDataArray.h>
#include <vtkIdList.h>
#include <vtkInformation.h>
#include <vtkMultiBlockDataSet.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkSmartPointer.h>
#include <vtkUnstructuredGrid.h>
#include <vtkXMLDataElement.h>
#include <vtkXMLMultiBlockDataReader.h>
#include <vtkXMLUtilities.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

namespace fs = std::filesystem;
using ::testing::AllOf;
using ::testing::HasSubstr;
using ::testing::ThrowsMessage;

namespace coro {
namespace {

// ---------------------------------------------------------------------------------------------
// The scene: a tet box and a triangle "floor", with data that changes per frame and has no
// short decimal form (so a lossy round trip would show).

constexpr const char* SOLID = "solid body";
constexpr const char* FLOOR = "floor/plane <1> & \"co\""; // not a safe file name

DataArray make_array(const std::string& name, Eigen::Index rows, Eigen::Index cols, int frame)
{
    DataArray a{name, Eigen::MatrixXd(rows, cols)};
    for (Eigen::Index i = 0; i < rows; ++i)
        for (Eigen::Index j = 0; j < cols; ++j)
            a.values(i, j) = std::sqrt(static_cast<double>(1 + i + 7 * j)) / 3.0 +
                             static_cast<double>(frame) / 7.0 - static_cast<double>(j);
    return a;
}

std::vector<FrameBlock> make_scene(int frame)
{
    const TetMesh box = make_box(Vec3(0.0, 0.0, 0.0), Vec3(1.0, 0.5, 0.25), {3, 2, 2});
    FrameBlock solid;
    solid.name = SOLID;
    solid.points = box.rest_positions;
    solid.points.col(2).array() += 0.1 * std::sin(1.0 + frame);
    solid.tets = box.tets;
    const Eigen::Index nv = solid.points.rows(), nt = solid.tets.rows();
    solid.point_data = {make_array("displacement", nv, 3, frame),
                        make_array("contact_inside", nv, 1, frame)};
    solid.cell_data = {make_array("von_mises", nt, 1, frame),
                       make_array("partition", nt, 1, frame)};

    FrameBlock floor;
    floor.name = FLOOR;
    floor.points.resize(4, 3);
    floor.points << -1.0, -1.0, -0.1, 2.0, -1.0, -0.1, 2.0, 1.5, -0.1, -1.0, 1.5, -0.1 / 3.0;
    floor.points *= 1.0 + frame / 3.0;
    floor.tris.resize(2, 3);
    floor.tris << 0, 1, 2, 0, 2, 3;
    floor.point_data = {make_array("contact_force", 4, 3, frame)};
    floor.cell_data = {make_array("pressure", 2, 1, frame)};
    return {solid, floor};
}

double frame_time(int frame) { return 0.1 * frame + 1.0 / 3.0; }

// ---------------------------------------------------------------------------------------------
// Reading back with VTK

struct PvdEntry {
    double time;
    std::string file;
};

/// The DataSet entries of a .pvd, parsed with VTK's XML parser.
std::vector<PvdEntry> read_pvd(const fs::path& pvd)
{
    std::vector<PvdEntry> entries;
    vtkXMLDataElement* root = vtkXMLUtilities::ReadElementFromFile(pvd.string().c_str());
    EXPECT_NE(root, nullptr) << pvd << " is not well-formed XML";
    if (root == nullptr)
        return entries;
    EXPECT_STREQ(root->GetName(), "VTKFile");
    EXPECT_STREQ(root->GetAttribute("type"), "Collection");
    vtkXMLDataElement* collection = root->FindNestedElementWithName("Collection");
    EXPECT_NE(collection, nullptr);
    for (int i = 0; collection != nullptr && i < collection->GetNumberOfNestedElements(); ++i) {
        vtkXMLDataElement* ds = collection->GetNestedElement(i);
        EXPECT_STREQ(ds->GetName(), "DataSet");
        const char* t = ds->GetAttribute("timestep");
        const char* f = ds->GetAttribute("file");
        EXPECT_NE(t, nullptr);
        EXPECT_NE(f, nullptr);
        if (t != nullptr && f != nullptr)
            entries.push_back({std::strtod(t, nullptr), f});
    }
    root->Delete();
    return entries;
}

vtkSmartPointer<vtkMultiBlockDataSet> read_vtm(const fs::path& vtm)
{
    vtkNew<vtkXMLMultiBlockDataReader> reader;
    reader->SetFileName(vtm.string().c_str());
    reader->Update();
    EXPECT_EQ(reader->GetErrorCode(), 0UL) << vtm;
    return vtkMultiBlockDataSet::SafeDownCast(reader->GetOutputDataObject(0));
}

Eigen::MatrixXd to_eigen(vtkDataArray* a)
{
    Eigen::MatrixXd m(a->GetNumberOfTuples(), a->GetNumberOfComponents());
    for (Eigen::Index i = 0; i < m.rows(); ++i)
        for (Eigen::Index j = 0; j < m.cols(); ++j)
            m(i, j) = a->GetComponent(i, static_cast<int>(j));
    return m;
}

/// Compares one block read back from disk with what was written: exact (bitwise) equality
/// of coordinates and data, same connectivity and cell types.
void expect_block_equal(vtkUnstructuredGrid* grid, const FrameBlock& b)
{
    ASSERT_NE(grid, nullptr) << b.name;
    ASSERT_EQ(grid->GetNumberOfPoints(), b.points.rows()) << b.name;
    ASSERT_EQ(grid->GetPoints()->GetDataType(), VTK_DOUBLE) << b.name;
    EXPECT_NEAR_REL(to_eigen(grid->GetPoints()->GetData()), Eigen::MatrixXd(b.points), 0.0, 0.0);

    const bool tets = b.tets.rows() > 0;
    const Eigen::Index num_cells = tets ? b.tets.rows() : b.tris.rows();
    const int per_cell = tets ? 4 : 3;
    ASSERT_EQ(grid->GetNumberOfCells(), num_cells) << b.name;
    vtkNew<vtkIdList> ids;
    for (vtkIdType c = 0; c < grid->GetNumberOfCells(); ++c) {
        ASSERT_EQ(grid->GetCellType(c), tets ? VTK_TETRA : VTK_TRIANGLE) << b.name << " cell " << c;
        grid->GetCellPoints(c, ids);
        ASSERT_EQ(ids->GetNumberOfIds(), per_cell);
        for (int k = 0; k < per_cell; ++k)
            ASSERT_EQ(ids->GetId(k), tets ? b.tets(c, k) : b.tris(c, k))
                << b.name << " cell " << c << " corner " << k;
    }

    const auto expect_arrays = [&](vtkDataSetAttributes* attributes,
                                   const std::vector<DataArray>& arrays, const char* kind) {
        EXPECT_EQ(attributes->GetNumberOfArrays(), static_cast<int>(arrays.size()))
            << b.name << " " << kind;
        for (const DataArray& a : arrays) {
            vtkDataArray* read = attributes->GetArray(a.name.c_str());
            ASSERT_NE(read, nullptr) << b.name << " " << kind << " " << a.name;
            EXPECT_EQ(read->GetDataType(), VTK_DOUBLE) << a.name;
            EXPECT_NEAR_REL(to_eigen(read), a.values, 0.0, 0.0) << b.name << " " << a.name;
        }
    };
    expect_arrays(grid->GetPointData(), b.point_data, "point_data");
    expect_arrays(grid->GetCellData(), b.cell_data, "cell_data");
}

std::vector<fs::path> temporary_files(const fs::path& dir)
{
    std::vector<fs::path> found;
    for (const fs::directory_entry& e : fs::recursive_directory_iterator(dir))
        if (e.path().extension() == ".tmp")
            found.push_back(e.path());
    return found;
}

// ---------------------------------------------------------------------------------------------

TEST(VtkSeriesWriter, RoundTripsThreeFramesThroughVtkReaders)
{
    const fs::path dir = test::scratch_dir("vtk_round_trip") / "out";
    VtkSeriesWriter writer(dir, "run");
    const std::vector<int> steps = {0, 5, 1234567};
    for (int k = 0; k < 3; ++k)
        writer.write_frame(steps[static_cast<std::size_t>(k)], frame_time(k), make_scene(k));
    EXPECT_EQ(writer.num_frames(), 3U);
    EXPECT_EQ(writer.pvd_path(), dir / "run.pvd");

    const std::vector<PvdEntry> entries = read_pvd(writer.pvd_path());
    ASSERT_EQ(entries.size(), 3U);
    EXPECT_EQ(entries[0].file, "run_000000.vtm");
    EXPECT_EQ(entries[1].file, "run_000005.vtm");
    EXPECT_EQ(entries[2].file, "run_1234567.vtm");
    for (std::size_t k = 0; k < entries.size(); ++k) {
        SCOPED_TRACE(entries[k].file);
        EXPECT_EQ(entries[k].time, frame_time(static_cast<int>(k))); // full precision
        const vtkSmartPointer<vtkMultiBlockDataSet> mb = read_vtm(dir / entries[k].file);
        ASSERT_NE(mb, nullptr);
        const std::vector<FrameBlock> scene = make_scene(static_cast<int>(k));
        ASSERT_EQ(mb->GetNumberOfBlocks(), scene.size());
        for (unsigned i = 0; i < mb->GetNumberOfBlocks(); ++i) {
            ASSERT_TRUE(mb->HasMetaData(i));
            const char* name = mb->GetMetaData(i)->Get(vtkCompositeDataSet::NAME());
            ASSERT_NE(name, nullptr);
            EXPECT_EQ(std::string(name), scene[i].name);
            expect_block_equal(vtkUnstructuredGrid::SafeDownCast(mb->GetBlock(i)), scene[i]);
        }
    }
    EXPECT_TRUE(fs::is_regular_file(dir / "run_000005" / "solid_body.vtu"));
    EXPECT_TRUE(temporary_files(dir).empty());
}

TEST(VtkSeriesWriter, PvdListsExactlyTheFramesWrittenSoFar)
{
    const fs::path dir = test::scratch_dir("vtk_pvd_count");
    VtkSeriesWriter writer(dir, "series");
    EXPECT_FALSE(fs::exists(writer.pvd_path()));
    for (int k = 1; k <= 3; ++k) {
        writer.write_frame(10 * k, frame_time(k), make_scene(k));
        const std::vector<PvdEntry> entries = read_pvd(writer.pvd_path());
        ASSERT_EQ(entries.size(), static_cast<std::size_t>(k));
        EXPECT_EQ(writer.num_frames(), static_cast<std::size_t>(k));
        for (const PvdEntry& e : entries)
            EXPECT_TRUE(fs::is_regular_file(dir / e.file)) << e.file;
        EXPECT_EQ(entries.back().time, frame_time(k));
        EXPECT_TRUE(temporary_files(dir).empty());
    }
}

TEST(VtkSeriesWriter, AContinuedSeriesListsTheEarlierRunsFramesFirst)
{
    const fs::path dir = test::scratch_dir("vtk_adopt");
    {
        VtkSeriesWriter first(dir, "series");
        first.write_frame(0, 0.0, make_scene(0));
        first.write_frame(5, 0.5, make_scene(1));
    }
    VtkSeriesWriter second(dir, "series");
    second.adopt_frame(0, 0.0);
    second.adopt_frame(5, 0.5);
    EXPECT_THROW(second.adopt_frame(7, 0.7), InputError); // never written
    second.write_frame(10, 1.0, make_scene(2));
    const std::vector<PvdEntry> entries = read_pvd(second.pvd_path());
    ASSERT_EQ(entries.size(), 3U);
    EXPECT_EQ(entries[0].file, "series_000000.vtm");
    EXPECT_EQ(entries[1].file, "series_000005.vtm");
    EXPECT_EQ(entries[1].time, 0.5);
    EXPECT_EQ(entries[2].file, "series_000010.vtm");
}

TEST(VtkSeriesWriter, RewritingAStepReplacesItsEntry)
{
    const fs::path dir = test::scratch_dir("vtk_rewrite");
    VtkSeriesWriter writer(dir, "series");
    writer.write_frame(1, 0.5, make_scene(0));
    writer.write_frame(2, 1.0, make_scene(1));
    writer.write_frame(1, 0.25, make_scene(2));
    const std::vector<PvdEntry> entries = read_pvd(writer.pvd_path());
    ASSERT_EQ(entries.size(), 2U);
    EXPECT_EQ(entries[0].file, "series_000001.vtm");
    EXPECT_EQ(entries[0].time, 0.25);
    EXPECT_EQ(writer.num_frames(), 2U);
}

TEST(VtkSeriesWriter, KeepsBlockNamesButWritesSafeUniqueFileNames)
{
    const fs::path dir = test::scratch_dir("vtk_names");
    VtkSeriesWriter writer(dir, "n");
    std::vector<FrameBlock> blocks = make_scene(0);
    blocks.push_back(blocks[0]);
    blocks[0].name = "a b";
    blocks[1].name = "../A_b";
    blocks[2].name = "a_b";
    writer.write_frame(0, 0.0, blocks);

    std::vector<std::string> files;
    for (const fs::directory_entry& e : fs::directory_iterator(dir / "n_000000"))
        files.push_back(e.path().filename().string());
    std::sort(files.begin(), files.end());
    EXPECT_EQ(files, (std::vector<std::string>{"_._A_b.vtu", "a_b.vtu", "a_b_2.vtu"}));
    std::vector<std::string> top;
    for (const fs::directory_entry& e : fs::directory_iterator(dir))
        top.push_back(e.path().filename().string());
    std::sort(top.begin(), top.end());
    EXPECT_EQ(top, (std::vector<std::string>{"n.pvd", "n_000000", "n_000000.vtm"}))
        << "nothing may be written outside the frame directory";

    const vtkSmartPointer<vtkMultiBlockDataSet> mb = read_vtm(dir / "n_000000.vtm");
    ASSERT_NE(mb, nullptr);
    ASSERT_EQ(mb->GetNumberOfBlocks(), 3U);
    for (unsigned i = 0; i < 3; ++i) {
        EXPECT_STREQ(mb->GetMetaData(i)->Get(vtkCompositeDataSet::NAME()), blocks[i].name.c_str());
        expect_block_equal(vtkUnstructuredGrid::SafeDownCast(mb->GetBlock(i)), blocks[i]);
    }
}

TEST(VtkSeriesWriter, ThrowsOutputErrorWhenTheDirectoryIsARegularFile)
{
    const fs::path file = test::write_text(test::scratch_dir("vtk_dir_is_file") / "out", "x");
    EXPECT_THAT([&] { VtkSeriesWriter(file, "run"); },
                ThrowsMessage<OutputError>(HasSubstr(file.string())));
    EXPECT_THAT([&] { VtkSeriesWriter(file / "sub", "run"); },
                ThrowsMessage<OutputError>(AllOf(HasSubstr((file / "sub").string()), HasSubstr("(Not a directory)"))));
}

TEST(VtkSeriesWriter, ThrowsOutputErrorNamingTheFileVtkCannotWrite)
{
    const fs::path dir = test::scratch_dir("vtk_write_fails");
    VtkSeriesWriter writer(dir, "run");
    writer.write_frame(0, 0.0, make_scene(0));
    // A directory where the writer's temporary file must go makes VTK's Write() fail.
    const fs::path target = dir / "run_000001" / "solid_body.vtu";
    fs::create_directories(fs::path(target).concat(".tmp"));
    EXPECT_THAT([&] { writer.write_frame(1, 0.1, make_scene(1)); },
                ThrowsMessage<OutputError>(HasSubstr(target.string())));
    EXPECT_FALSE(fs::exists(target));
    EXPECT_FALSE(fs::exists(dir / "run_000001.vtm"));
    EXPECT_EQ(writer.num_frames(), 1U);
    EXPECT_EQ(read_pvd(writer.pvd_path()).size(), 1U);

    // A frame directory that cannot be created.
    test::write_text(dir / "run_000002", "not a directory");
    EXPECT_THAT([&] { writer.write_frame(2, 0.2, make_scene(2)); },
                ThrowsMessage<OutputError>(HasSubstr((dir / "run_000002").string())));
    EXPECT_EQ(read_pvd(writer.pvd_path()).size(), 1U);

    // A .pvd that cannot be rewritten: the writer does not count a frame the .pvd does not
    // list, and removes the files of that frame again.
    fs::create_directories(dir / "run.pvd.tmp");
    EXPECT_THAT([&] { writer.write_frame(3, 0.3, make_scene(3)); },
                ThrowsMessage<OutputError>(AllOf(HasSubstr((dir / "run.pvd").string()), HasSubstr("(Is a directory)"))));
    EXPECT_EQ(writer.num_frames(), 1U);
    EXPECT_EQ(read_pvd(writer.pvd_path()).size(), 1U);
    EXPECT_FALSE(fs::exists(dir / "run_000003.vtm"));
    EXPECT_FALSE(fs::exists(dir / "run_000003"));
    fs::remove(dir / "run.pvd.tmp");
    writer.write_frame(4, 0.4, make_scene(4));
    EXPECT_EQ(writer.num_frames(), 2U);
    ASSERT_EQ(read_pvd(writer.pvd_path()).size(), 2U);
    EXPECT_EQ(read_pvd(writer.pvd_path())[1].file, "run_000004.vtm");
}

TEST(VtkSeriesWriter, ANewFrameThatFailsHalfwayLeavesNoneOfItsFiles)
{
    const fs::path dir = test::scratch_dir("vtk_half_frame");
    VtkSeriesWriter writer(dir, "run");
    writer.write_frame(0, 0.0, make_scene(0));
    // The second block's file cannot be written (the first one's can): a file where the
    // frame's folder wants the second block's temporary.
    const std::vector<FrameBlock> blocks = make_scene(1);
    ASSERT_EQ(blocks.size(), 2U);
    fs::create_directories(dir / "run_000001");
    fs::create_directories(dir / "run_000001" / "floor_plane__1_____co_.vtu.tmp");
    EXPECT_THROW(writer.write_frame(1, 0.1, blocks), OutputError);
    EXPECT_FALSE(fs::exists(dir / "run_000001" / "solid_body.vtu")) << "the finished first block stays";
    EXPECT_FALSE(fs::exists(dir / "run_000001.vtm"));
    EXPECT_TRUE(fs::exists(dir / "run_000001")) << "a folder the writer did not make is not removed";
    EXPECT_EQ(read_pvd(writer.pvd_path()).size(), 1U);

    // The same in a folder the writer makes itself: the folder goes too.
    fs::remove_all(dir / "run_000001");
    fs::create_directories(dir / "run_000002.vtm.tmp"); // the .vtm cannot be written
    EXPECT_THROW(writer.write_frame(2, 0.2, blocks), OutputError);
    EXPECT_FALSE(fs::exists(dir / "run_000002"));
    EXPECT_EQ(read_pvd(writer.pvd_path()).size(), 1U);
}

TEST(VtkSeriesWriter, ReplacesFilesByRenameNeverInPlace)
{
    // Every target starts as a hard link to a sentinel: writing in place would change the
    // sentinel, a rename only replaces the directory entry.
    const fs::path dir = test::scratch_dir("vtk_rename");
    const fs::path sentinel = test::write_text(dir / "sentinel", "old");
    const std::vector<fs::path> targets = {dir / "run.pvd", dir / "run_000007.vtm",
                                           dir / "run_000007" / "solid_body.vtu"};
    fs::create_directories(dir / "run_000007");
    for (const fs::path& t : targets)
        fs::create_hard_link(sentinel, t);
    ASSERT_EQ(fs::hard_link_count(sentinel), 4U);

    VtkSeriesWriter writer(dir, "run");
    writer.write_frame(7, 1.5, make_scene(0));
    std::ifstream in(sentinel);
    const std::string content((std::istreambuf_iterator<char>(in)),
                              std::istreambuf_iterator<char>());
    EXPECT_EQ(content, "old");
    EXPECT_EQ(fs::hard_link_count(sentinel), 1U);
    for (const fs::path& t : targets)
        EXPECT_GT(fs::file_size(t), 3U) << t;
    EXPECT_TRUE(temporary_files(dir).empty());
}

TEST(VtkSeriesWriter, RejectsBadOutputName)
{
    const fs::path dir = test::scratch_dir("vtk_bad_name");
    EXPECT_THAT([&] { VtkSeriesWriter(dir, ""); }, ThrowsMessage<InputError>(HasSubstr("name")));
    EXPECT_THAT([&] { VtkSeriesWriter(dir, "a/b"); }, ThrowsMessage<InputError>(HasSubstr("a/b")));
}

TEST(VtkSeriesWriter, RejectsMalformedFrames)
{
    const fs::path dir = test::scratch_dir("vtk_malformed");
    VtkSeriesWriter writer(dir, "run");
    const auto expect_rejected = [&](std::vector<FrameBlock> blocks, const std::string& what) {
        EXPECT_THAT([&] { writer.write_frame(0, 0.0, blocks); },
                    ThrowsMessage<std::invalid_argument>(HasSubstr(what)));
    };
    {
        std::vector<FrameBlock> b = make_scene(0);
        b[0].point_data[0].values.conservativeResize(b[0].points.rows() - 1, 3);
        expect_rejected(b, "displacement");
    }
    {
        std::vector<FrameBlock> b = make_scene(0);
        b[1].cell_data[0].values.resize(3, 1);
        expect_rejected(b, "pressure");
    }
    {
        std::vector<FrameBlock> b = make_scene(0);
        b[1].name = b[0].name;
        expect_rejected(b, "twice");
    }
    {
        std::vector<FrameBlock> b = make_scene(0);
        b[1].name.clear();
        expect_rejected(b, "empty name");
    }
    {
        std::vector<FrameBlock> b = make_scene(0);
        b[1].tris(1, 2) = 4;
        expect_rejected(b, "outside the 4 points");
    }
    {
        std::vector<FrameBlock> b = make_scene(0);
        b[0].tris = b[1].tris;
        expect_rejected(b, "both tets and tris");
    }
    EXPECT_EQ(writer.num_frames(), 0U);
    EXPECT_FALSE(fs::exists(writer.pvd_path()));
}

} // namespace
} // namespace coro
