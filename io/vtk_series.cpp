#include <corocontact/io/vtk_series.hpp>

#include <corocontact/core/atomic_file.hpp>
#include <corocontact/core/error.hpp>

#include <vtkCellArray.h>
#include <vtkCellData.h>
#include <vtkCellType.h>
#include <vtkCommand.h>
#include <vtkDoubleArray.h>
#include <vtkErrorCode.h>
#include <vtkExecutive.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkSmartPointer.h>
#include <vtkTypeInt32Array.h>
#include <vtkUnsignedCharArray.h>
#include <vtkUnstructuredGrid.h>
#include <vtkXMLUnstructuredGridWriter.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstring>
#include <fstream>
#include <set>
#include <sstream>
#include <stdexcept>
#include <system_error>
#include <utility>

namespace fs = std::filesystem;

namespace coro {
namespace {

// ---------------------------------------------------------------------------------------------
// Small text helpers

/// Escapes a string for use inside a double-quoted XML attribute.
std::string xml_escape(const std::string& s)
{
    std::string out;
    out.reserve(s.size());
    for (const char c : s) {
        switch (c) {
        case '&': out += "&amp;"; break;
        case '<': out += "&lt;"; break;
        case '>': out += "&gt;"; break;
        case '"': out += "&quot;"; break;
        case '\'': out += "&apos;"; break;
        case '\n': out += "&#10;"; break;
        case '\r': out += "&#13;"; break;
        case '\t': out += "&#9;"; break;
        default: out += c;
        }
    }
    return out;
}

/// Shortest decimal text that reads back to exactly `x` (locale independent).
std::string format_double(double x)
{
    char buf[64];
    const std::to_chars_result r = std::to_chars(buf, buf + sizeof(buf), x);
    return std::string(buf, r.ptr);
}

/// `name_000042`: the step zero-padded to 6 digits (more digits when needed).
std::string frame_stem(const std::string& name, Index step)
{
    const std::string digits = std::to_string(step); // locale independent
    return name + "_" + std::string(digits.size() < 6 ? 6 - digits.size() : 0, '0') + digits;
}

/// A file-name-safe version of a block name: [A-Za-z0-9._-] kept, everything else '_',
/// no leading '.' (no hidden files, no "." or "..").
std::string sanitize_file_stem(const std::string& name)
{
    std::string out = name;
    for (char& c : out) {
        const bool safe = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') ||
                          (c >= '0' && c <= '9') || c == '.' || c == '_' || c == '-';
        if (!safe)
            c = '_';
    }
    if (!out.empty() && out.front() == '.')
        out.front() = '_';
    return out;
}

std::string to_lower(std::string s)
{
    for (char& c : s)
        if (c >= 'A' && c <= 'Z')
            c = static_cast<char>(c - 'A' + 'a');
    return s;
}

/// File stems for the blocks of one frame: sanitized, unique even on case-insensitive file
/// systems ("_2", "_3", ... appended on a clash).
std::vector<std::string> block_file_stems(const std::vector<std::string>& names)
{
    std::vector<std::string> stems;
    std::set<std::string> taken; // lower case
    for (const std::string& name : names) {
        const std::string base = sanitize_file_stem(name);
        std::string stem = base;
        for (int k = 2; taken.count(to_lower(stem)) != 0; ++k)
            stem = base + "_" + std::to_string(k);
        taken.insert(to_lower(stem));
        stems.push_back(stem);
    }
    return stems;
}

// ---------------------------------------------------------------------------------------------
// Validation of a frame (shape mismatches are programming errors: std::invalid_argument)

[[noreturn]] void invalid(const std::string& message)
{
    throw std::invalid_argument("VtkSeriesWriter: " + message);
}

void validate_arrays(const std::vector<DataArray>& arrays, Eigen::Index rows,
                     const std::string& block, const char* kind, const char* row_kind)
{
    std::set<std::string> names;
    for (const DataArray& a : arrays) {
        if (a.name.empty())
            invalid("block '" + block + "': a " + kind + " array has an empty name");
        if (!names.insert(a.name).second)
            invalid("block '" + block + "': " + kind + " array '" + a.name + "' appears twice");
        if (a.values.rows() != rows || a.values.cols() < 1)
            invalid("block '" + block + "': " + kind + " array '" + a.name + "' is " +
                    std::to_string(a.values.rows()) + "x" + std::to_string(a.values.cols()) +
                    ", expected " + std::to_string(rows) + " rows (one per " + row_kind +
                    ") and at least 1 column");
    }
}

template <class Cells>
void validate_cells(const Cells& cells, Eigen::Index num_points, const std::string& block,
                    const char* cell_kind)
{
    if (cells.size() == 0)
        return;
    const Index lo = cells.minCoeff(), hi = cells.maxCoeff();
    if (lo < 0 || hi >= num_points)
        invalid("block '" + block + "': " + cell_kind + " index range [" + std::to_string(lo) +
                ", " + std::to_string(hi) + "] outside the " + std::to_string(num_points) +
                " points");
}

void validate_frame(Index step, double time, const std::vector<FrameBlock>& blocks)
{
    if (step < 0)
        invalid("step " + std::to_string(step) + " is negative");
    if (!std::isfinite(time))
        invalid("time of step " + std::to_string(step) + " is not finite");
    std::set<std::string> names;
    for (const FrameBlock& b : blocks) {
        if (b.name.empty())
            invalid("a block of step " + std::to_string(step) + " has an empty name");
        if (!names.insert(b.name).second)
            invalid("block name '" + b.name + "' appears twice in step " + std::to_string(step));
        if (b.tets.rows() > 0 && b.tris.rows() > 0)
            invalid("block '" + b.name + "' has both tets and tris; set exactly one");
        validate_cells(b.tets, b.points.rows(), b.name, "tet");
        validate_cells(b.tris, b.points.rows(), b.name, "triangle");
        const Eigen::Index num_cells = b.tets.rows() > 0 ? b.tets.rows() : b.tris.rows();
        validate_arrays(b.point_data, b.points.rows(), b.name, "point_data", "point");
        validate_arrays(b.cell_data, num_cells, b.name, "cell_data", "cell");
    }
}

// ---------------------------------------------------------------------------------------------
// VTK

/// Receives VTK's error messages instead of its output window (a library never prints) and
/// keeps the gist of each: "Error opening output file ...", without the source location and
/// object address VTK prepends.
class ErrorCollector : public vtkCommand {
public:
    static ErrorCollector* New() { return new ErrorCollector; }
    void Execute(vtkObject* /*caller*/, unsigned long /*event*/, void* call_data) override
    {
        if (call_data == nullptr)
            return;
        std::string text = static_cast<const char*>(call_data);
        if (text.rfind("ERROR: In ", 0) == 0 && text.find('\n') != std::string::npos)
            text.erase(0, text.find('\n') + 1);   // "ERROR: In file, line N\n"
        const std::size_t colon = text.find("): ");
        if (colon != std::string::npos && colon < text.find('\n'))
            text.erase(0, colon + 3);               // "vtkXMLWriter (0x...): "
        text.erase(text.find_last_not_of(" \n") + 1);
        if (!m_messages.empty())
            m_messages += "; ";
        m_messages += text;
    }
    const std::string& messages() const { return m_messages; }

private:
    std::string m_messages;
};

/// Text for the code a VTK writer leaves in GetErrorCode(): an errno value from the failing
/// system call, or a vtkErrorCode (vtkErrorCode::GetStringFromErrorCode lives in
/// VTK::CommonMisc, which we do not link for one string).
std::string describe_vtk_error(unsigned long code)
{
    if (code > 0 && code < vtkErrorCode::FirstVTKErrorCode)
        return std::generic_category().message(static_cast<int>(code));
    switch (code) {
    case vtkErrorCode::NoError: return "no error code set";
    case vtkErrorCode::FileNotFoundError: return "file not found";
    case vtkErrorCode::CannotOpenFileError: return "cannot open file";
    case vtkErrorCode::UnrecognizedFileTypeError: return "unrecognized file type";
    case vtkErrorCode::PrematureEndOfFileError: return "premature end of file";
    case vtkErrorCode::FileFormatError: return "file format error";
    case vtkErrorCode::NoFileNameError: return "no file name";
    case vtkErrorCode::OutOfDiskSpaceError: return "out of disk space";
    default: return "VTK error code " + std::to_string(code);
    }
}

/// A #rows×k double array, tuples interleaved as VTK wants (Eigen's MatrixXd is column-major).
vtkSmartPointer<vtkDoubleArray> to_vtk(const DataArray& a)
{
    auto arr = vtkSmartPointer<vtkDoubleArray>::New();
    arr->SetName(a.name.c_str());
    const Eigen::Index rows = a.values.rows(), cols = a.values.cols();
    arr->SetNumberOfComponents(static_cast<int>(cols));
    arr->SetNumberOfTuples(rows);
    using RowMajor = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
    Eigen::Map<RowMajor>(arr->GetPointer(0), rows, cols) = a.values;
    return arr;
}

template <class Cells>
vtkSmartPointer<vtkCellArray> to_vtk_cells(const Cells& cells)
{
    constexpr int per_cell = Cells::ColsAtCompileTime;
    const Eigen::Index n = cells.rows();
    vtkNew<vtkTypeInt32Array> offsets, connectivity;
    offsets->SetNumberOfValues(n + 1);
    for (Eigen::Index i = 0; i <= n; ++i)
        offsets->SetValue(i, static_cast<vtkTypeInt32>(per_cell * i));
    connectivity->SetNumberOfValues(n * per_cell);
    static_assert(sizeof(Index) == sizeof(vtkTypeInt32), "Index must be 32 bit");
    if (n > 0)
        std::memcpy(connectivity->GetPointer(0), cells.data(),
                    static_cast<std::size_t>(n * per_cell) * sizeof(Index));
    auto out = vtkSmartPointer<vtkCellArray>::New();
    out->SetData(offsets, connectivity);
    return out;
}

vtkSmartPointer<vtkUnstructuredGrid> to_vtk_grid(const FrameBlock& b)
{
    auto grid = vtkSmartPointer<vtkUnstructuredGrid>::New();

    vtkNew<vtkDoubleArray> coords;
    coords->SetNumberOfComponents(3);
    coords->SetNumberOfTuples(b.points.rows());
    if (b.points.rows() > 0)
        std::memcpy(coords->GetPointer(0), b.points.data(),
                    static_cast<std::size_t>(b.points.size()) * sizeof(double));
    vtkNew<vtkPoints> points;
    points->SetData(coords);
    grid->SetPoints(points);

    const bool tets = b.tets.rows() > 0;
    const vtkSmartPointer<vtkCellArray> cells = tets ? to_vtk_cells(b.tets) : to_vtk_cells(b.tris);
    vtkNew<vtkUnsignedCharArray> types;
    types->SetNumberOfValues(cells->GetNumberOfCells());
    types->FillValue(static_cast<unsigned char>(tets ? VTK_TETRA : VTK_TRIANGLE));
    grid->SetCells(types, cells);

    for (const DataArray& a : b.point_data)
        grid->GetPointData()->AddArray(to_vtk(a));
    for (const DataArray& a : b.cell_data)
        grid->GetCellData()->AddArray(to_vtk(a));
    return grid;
}

/// Writes one block with VTK's XML writer (raw binary appended data) to `target`'s temporary
/// name, then renames it into place.
void write_vtu(const FrameBlock& block, const fs::path& target)
{
    const vtkSmartPointer<vtkUnstructuredGrid> grid = to_vtk_grid(block);
    const fs::path tmp = temporary_path(target);

    vtkNew<vtkXMLUnstructuredGridWriter> writer;
    vtkNew<ErrorCollector> errors, pipeline_errors; // the latter only repeats "failure"
    writer->AddObserver(vtkCommand::ErrorEvent, errors);
    writer->GetExecutive()->AddObserver(vtkCommand::ErrorEvent, pipeline_errors);
    writer->SetInputData(grid);
    writer->SetFileName(tmp.string().c_str());
    writer->SetDataModeToAppended();
    writer->EncodeAppendedDataOff();
    writer->SetHeaderTypeToUInt64();
    writer->SetIdTypeToInt32();
    writer->SetCompressorTypeToNone();
    const int ok = writer->Write();
    const unsigned long code = writer->GetErrorCode();
    if (ok != 1 || code != vtkErrorCode::NoError) {
        remove_temporary(tmp);
        std::ostringstream why;
        why << describe_vtk_error(code);
        if (!errors->messages().empty())
            why << ": " << errors->messages();
        CORO_THROW(OutputError, target.string() << ": VTK cannot write block '" << block.name
                                                << "' (" << why.str() << ")");
    }
    commit_file(tmp, target);
}

} // namespace

// ---------------------------------------------------------------------------------------------

VtkSeriesWriter::VtkSeriesWriter(fs::path dir, std::string name)
    : m_dir(std::move(dir)), m_name(std::move(name))
{
    CORO_CHECK(!m_name.empty() && m_name != "." && m_name != ".." &&
                   m_name.find_first_of("/\\") == std::string::npos,
               InputError,
               "output name '" << m_name << "' is not a plain file name (empty, '.', '..' or "
                               << "containing a path separator)");
    std::error_code ec;
    fs::create_directories(m_dir, ec);
    CORO_CHECK(!ec && fs::is_directory(m_dir), OutputError,
               m_dir.string() << ": cannot create the output folder ("
                              << (ec ? ec.message() : std::string("a file of that name is in the way")) << ")");
}

fs::path VtkSeriesWriter::pvd_path() const { return m_dir / (m_name + ".pvd"); }

void VtkSeriesWriter::write_frame(Index step, double time, const std::vector<FrameBlock>& blocks)
{
    validate_frame(step, time, blocks);
    std::vector<std::string> names;
    for (const FrameBlock& block : blocks)
        names.push_back(block.name);
    list_written_frame(step, time, names, [&](std::vector<fs::path>& written) {
        write_block_files(frame_stem(m_name, step), names, blocks, written);
    });
}

std::vector<fs::path> VtkSeriesWriter::write_blocks(Index step, const std::vector<std::string>& names,
                                                    const std::vector<FrameBlock>& blocks) const
{
    validate_frame(step, 0.0, blocks);
    std::vector<fs::path> written;
    try {
        write_block_files(frame_stem(m_name, step), names, blocks, written);
    } catch (...) {
        std::error_code ec;
        for (const fs::path& file : written)
            fs::remove(file, ec);
        throw;
    }
    return written;
}

void VtkSeriesWriter::list_frame(Index step, double time, const std::vector<std::string>& names)
{
    if (!std::isfinite(time))
        invalid("time of step " + std::to_string(step) + " is not finite");
    list_written_frame(step, time, names, [](std::vector<fs::path>&) {});
}

void VtkSeriesWriter::list_written_frame(Index step, double time, const std::vector<std::string>& names,
                                         FunctionRef<void(std::vector<fs::path>& written)> write_blocks)
{
    const std::string stem = frame_stem(m_name, step);
    const std::string vtm_file = stem + ".vtm";
    const auto same = std::find_if(m_frames.begin(), m_frames.end(),
                                   [&](const FrameEntry& f) { return f.vtm == vtm_file; });
    if (same != m_frames.end()) {
        // Rewriting a listed step replaces its files one by one, each complete; on failure the
        // object is left as it was.
        std::vector<fs::path> written;
        write_blocks(written);
        write_vtm(stem, names, written);
        const FrameEntry old = *same;
        same->time = time;
        try {
            write_pvd();
        } catch (...) {
            *same = old;
            throw;
        }
        return;
    }
    // A new frame: if any of its files cannot be written, none of them stays.
    const fs::path block_dir = m_dir / stem;
    std::error_code ec;
    const bool new_dir = !fs::exists(block_dir, ec);
    std::vector<fs::path> written;
    try {
        write_blocks(written);
        write_vtm(stem, names, written);
        m_frames.push_back({time, vtm_file});
        try {
            write_pvd();
        } catch (...) {
            m_frames.pop_back();
            throw;
        }
    } catch (...) {
        for (const fs::path& file : written)
            fs::remove(file, ec);
        if (new_dir)
            fs::remove(block_dir, ec); // only if empty
        throw;
    }
}

void VtkSeriesWriter::write_block_files(const std::string& stem, const std::vector<std::string>& names,
                                        const std::vector<FrameBlock>& blocks, std::vector<fs::path>& written) const
{
    const fs::path block_dir = m_dir / stem;
    std::error_code ec;
    fs::create_directories(block_dir, ec);
    CORO_CHECK(!ec && fs::is_directory(block_dir), OutputError,
               block_dir.string() << ": cannot create the frame folder ("
                                  << (ec ? ec.message() : std::string("a file of that name is in the way"))
                                  << ")");
    const std::vector<std::string> file_stems = block_file_stems(names);
    for (const FrameBlock& block : blocks) {
        const auto name = std::find(names.begin(), names.end(), block.name);
        if (name == names.end())
            invalid("block '" + block.name + "' of " + stem + " is not among the frame's names");
        const fs::path file = block_dir / (file_stems[static_cast<std::size_t>(name - names.begin())] + ".vtu");
        write_vtu(block, file);
        written.push_back(file);
    }
}

void VtkSeriesWriter::write_vtm(const std::string& stem, const std::vector<std::string>& names,
                                std::vector<fs::path>& written) const
{
    // After the blocks, and before the caller writes the .pvd: whatever is listed is complete.
    const std::vector<std::string> file_stems = block_file_stems(names);
    std::ostringstream vtm;
    vtm << "<?xml version=\"1.0\"?>\n"
        << "<VTKFile type=\"vtkMultiBlockDataSet\" version=\"1.0\" byte_order=\"LittleEndian\" "
           "header_type=\"UInt64\">\n"
        << "  <vtkMultiBlockDataSet>\n";
    for (std::size_t i = 0; i < names.size(); ++i)
        vtm << "    <DataSet index=\"" << std::to_string(i) << "\" name=\"" << xml_escape(names[i])
            << "\" file=\"" << xml_escape(stem + "/" + file_stems[i] + ".vtu") << "\"/>\n";
    vtm << "  </vtkMultiBlockDataSet>\n"
        << "</VTKFile>\n";
    write_file_atomically(m_dir / (stem + ".vtm"), vtm.str(), Sync::NONE);
    written.push_back(m_dir / (stem + ".vtm"));
}

void VtkSeriesWriter::adopt_frame(Index step, double time)
{
    const std::string vtm_file = frame_stem(m_name, step) + ".vtm";
    CORO_CHECK(fs::is_regular_file(m_dir / vtm_file), InputError,
               (m_dir / vtm_file).string() << ": frame " << step << " of the earlier run is missing");
    m_frames.push_back({time, vtm_file});
}

void VtkSeriesWriter::write_pvd() const
{
    std::ostringstream pvd;
    pvd << "<?xml version=\"1.0\"?>\n"
        << "<VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">\n"
        << "  <Collection>\n";
    for (const FrameEntry& f : m_frames)
        pvd << "    <DataSet timestep=\"" << format_double(f.time)
            << "\" group=\"\" part=\"0\" file=\"" << xml_escape(f.vtm) << "\"/>\n";
    pvd << "  </Collection>\n"
        << "</VTKFile>\n";
    // The listing reaches the disk before it replaces the previous one: after a crash the .pvd
    // is one of the two, never empty or cut (the frames' own files are new names, not synced).
    write_file_atomically(pvd_path(), pvd.str(), Sync::FILE);
}

} // namespace coro
