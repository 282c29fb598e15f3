// VTK unstructured grids as tet meshes: XML `.vtu` through vtkXMLUnstructuredGridReader, legacy
// `.vtk` through vtkUnstructuredGridReader. Only VTK_TETRA cells are kept. Whatever VTK
// reports (error or warning events, or text for its output window) while reading turns
// into an InputError, so nothing reaches stderr and no half-read grid is used.

#include <corocontact/io/mesh_readers.hpp>

#include "detail/text_input.hpp"

#include <corocontact/core/error.hpp>

#include <vtkCellArray.h>
#include <vtkCellTypes.h>
#include <vtkCommand.h>
#include <vtkExecutive.h>
#include <vtkIdList.h>
#include <vtkNew.h>
#include <vtkOutputWindow.h>
#include <vtkPoints.h>
#include <vtkSmartPointer.h>
#include <vtkUnstructuredGrid.h>
#include <vtkUnstructuredGridReader.h>
#include <vtkXMLReader.h>
#include <vtkXMLUnstructuredGridReader.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <limits>
#include <new>
#include <string_view>
#include <system_error>
#include <charconv>
#include <string>
#include <vector>

namespace coro {
namespace {

namespace fs = std::filesystem;

/// VTK's message without its "ERROR: In /build/.../file.cxx, line N\nClass (0x...): " prefix.
std::string vtk_message(const char* text)
{
    std::string message = text != nullptr ? text : "";
    const std::size_t cut = message.rfind("): ");
    if (cut != std::string::npos)
        message.erase(0, cut + 3);
    while (!message.empty() && std::isspace(static_cast<unsigned char>(message.back())) != 0)
        message.pop_back();
    std::replace(message.begin(), message.end(), '\n', ' ');
    return message;
}

/// Records the error and warning events of the objects it observes.
class EventRecorder : public vtkCommand {
public:
    static EventRecorder* New() { return new EventRecorder; }
    void Execute(vtkObject* /*caller*/, unsigned long /*event*/, void* data) override
    {
        messages.push_back(vtk_message(static_cast<const char*>(data)));
    }
    std::vector<std::string> messages;
};

/// Replaces VTK's output window while it lives, recording what would have been printed.
class OutputCapture : public vtkOutputWindow {
public:
    static OutputCapture* New()
    {
        auto* window = new OutputCapture;
        window->InitializeObjectBase();
        return window;
    }
    void DisplayText(const char* text) override { messages.push_back(vtk_message(text)); }
    void DisplayErrorText(const char* text) override { DisplayText(text); }
    void DisplayWarningText(const char* text) override { DisplayText(text); }
    void DisplayGenericWarningText(const char* text) override { DisplayText(text); }
    std::vector<std::string> messages;
};

/// Installs an OutputCapture for one read and puts the previous window back afterwards.
class ScopedCapture {
public:
    ScopedCapture() : m_previous(vtkOutputWindow::GetInstance())
    {
        vtkOutputWindow::SetInstance(m_capture);
    }
    ~ScopedCapture() { vtkOutputWindow::SetInstance(m_previous); }
    ScopedCapture(const ScopedCapture&) = delete;
    ScopedCapture& operator=(const ScopedCapture&) = delete;
    const std::vector<std::string>& messages() const { return m_capture->messages; }

private:
    vtkSmartPointer<vtkOutputWindow> m_previous;
    vtkNew<OutputCapture> m_capture;
};

/// Counts declared in a file must fit in it: `count` values of at least `bytes_per_value`.
void check_declared(const fs::path& path, std::uint64_t count, double bytes_per_value,
                    std::uintmax_t file_size, const std::string& what)
{
    CORO_CHECK(static_cast<double>(count) * bytes_per_value <= static_cast<double>(file_size),
               InputError,
               path.string() << ": the header declares " << what << " = " << count
                             << ", more than the file's " << file_size
                             << " bytes can hold (truncated, or a corrupt count)");
}

/// The unsigned integer at the start of `text` (after blanks); false if there is none. Values
/// beyond 64 bits read as the largest value.
bool leading_count(std::string_view text, std::uint64_t& value, std::size_t& used)
{
    std::size_t i = 0;
    while (i < text.size() && (text[i] == ' ' || text[i] == '\t'))
        ++i;
    const auto [end, ec] = std::from_chars(text.data() + i, text.data() + text.size(), value);
    if (ec == std::errc::result_out_of_range)
        value = std::numeric_limits<std::uint64_t>::max();
    else if (ec != std::errc())
        return false;
    used = static_cast<std::size_t>(end - text.data());
    return true;
}

/// Checks the counts a VTK file declares against its size before VTK allocates from them.
/// Legacy: lines `POINTS n`, `CELLS n size`, `CELL_TYPES n`, `OFFSETS`/`CONNECTIVITY`; XML:
/// `NumberOfPoints`/`NumberOfCells` (compressed XML data may shrink by up to ~1000×, so the
/// bound is looser there).
void check_counts_against_size(const fs::path& path, std::string_view text, bool legacy)
{
    const auto size = static_cast<std::uintmax_t>(text.size());
    if (legacy) {
        const bool binary = text.find("\nBINARY") != std::string_view::npos;
        const double per_value = binary ? 4.0 : 2.0;
        for (std::size_t start = 0; start < text.size();) {
            const std::size_t end = std::min(text.find('\n', start), text.size());
            std::string_view line = text.substr(start, end - start);
            start = end + 1;
            for (const std::string_view keyword :
                 {"POINTS", "CELLS", "CELL_TYPES", "OFFSETS", "CONNECTIVITY"}) {
                if (line.substr(0, keyword.size()) != keyword || line.size() == keyword.size() ||
                    (line[keyword.size()] != ' ' && line[keyword.size()] != '\t'))
                    continue;
                std::string_view rest = line.substr(keyword.size());
                std::uint64_t n = 0;
                std::size_t used = 0;
                if (!leading_count(rest, n, used))
                    break;
                check_declared(path, n, (keyword == "POINTS" ? 3.0 : 1.0) * per_value, size,
                               std::string(keyword));
                std::uint64_t total = 0;
                if (keyword == "CELLS" && leading_count(rest.substr(used), total, used))
                    check_declared(path, total, per_value, size, "the CELLS size");
                break;
            }
        }
        return;
    }
    const bool compressed = text.find("compressor=") != std::string_view::npos;
    const double per_value = compressed ? 1e-3 : 1.0;
    for (const std::string_view name : {"NumberOfPoints", "NumberOfCells"}) {
        const std::string attribute = std::string(name) + "=\"";
        for (std::size_t at = text.find(attribute); at != std::string_view::npos;
             at = text.find(attribute, at + 1)) {
            std::uint64_t n = 0;
            std::size_t used = 0;
            if (leading_count(text.substr(at + attribute.size(), 24), n, used))
                check_declared(path, n, (name == "NumberOfPoints" ? 3.0 : 4.0) * per_value, size,
                               std::string(name));
        }
    }
}

/// Runs `reader` with every VTK message recorded; any message or a reader error code is an
/// InputError naming the file.
void run_reader(const fs::path& path, vtkAlgorithm* reader)
{
    ScopedCapture capture;
    vtkNew<EventRecorder> recorder;
    for (vtkObject* object : {static_cast<vtkObject*>(reader), static_cast<vtkObject*>(reader->GetExecutive())}) {
        object->AddObserver(vtkCommand::ErrorEvent, recorder);
        object->AddObserver(vtkCommand::WarningEvent, recorder);
    }
    if (auto* xml = vtkXMLReader::SafeDownCast(reader)) {
        xml->SetReaderErrorObserver(recorder);
        xml->SetParserErrorObserver(recorder);
    }
    try {
        reader->Update();
    } catch (const std::bad_alloc&) {
        CORO_THROW(InputError, path.string() << ": VTK could not allocate the grid the file "
                                                "declares (a corrupt count?)");
    }
    std::vector<std::string> messages = recorder->messages;
    messages.insert(messages.end(), capture.messages().begin(), capture.messages().end());
    const unsigned long code = reader->GetErrorCode();
    CORO_CHECK(messages.empty() && code == 0, InputError,
               path.string() << ": VTK could not read the file: "
                             << (messages.empty() ? std::string("error code ") +
                                                        std::to_string(code)
                                                  : messages.front())
                             << (messages.size() > 1
                                     ? " (and " + std::to_string(messages.size() - 1) +
                                           " more messages)"
                                     : std::string()));
}

/// The grid's tets (VTK_TETRA cells only) and all its points.
TetMesh to_tet_mesh(const fs::path& path, vtkUnstructuredGrid* grid)
{
    CORO_CHECK(grid != nullptr, InputError,
               path.string() << ": VTK read no unstructured grid from the file");
    const vtkIdType n_points = grid->GetNumberOfPoints();
    const vtkIdType n_cells = grid->GetNumberOfCells();
    CORO_CHECK(n_points < std::numeric_limits<Index>::max() &&
                   n_cells < std::numeric_limits<Index>::max(),
               InputError, path.string() << ": too many points or cells for a 32-bit index");
    TetMesh mesh;
    mesh.rest_positions.resize(n_points, 3);
    for (vtkIdType p = 0; p < n_points; ++p) {
        double x[3];
        grid->GetPoint(p, x);
        for (int d = 0; d < 3; ++d) {
            CORO_CHECK(std::isfinite(x[d]), InputError,
                       path.string() << ": point " << p << " has coordinate " << x[d]
                                     << ", expected a finite number");
            mesh.rest_positions(p, d) = x[d];
        }
    }
    std::vector<Index> tets;
    vtkNew<vtkIdList> ids;
    for (vtkIdType c = 0; c < n_cells; ++c) {
        if (grid->GetCellType(c) != VTK_TETRA)
            continue;
        grid->GetCellPoints(c, ids);
        CORO_CHECK(ids->GetNumberOfIds() == 4, InputError,
                   path.string() << ": cell " << c << " is a VTK_TETRA with "
                                 << ids->GetNumberOfIds() << " points, expected 4");
        for (vtkIdType k = 0; k < 4; ++k) {
            const vtkIdType v = ids->GetId(k);
            CORO_CHECK(v >= 0 && v < n_points, InputError,
                       path.string() << ": cell " << c << " refers to point " << v
                                     << ", expected an index in [0, " << n_points << ")");
            tets.push_back(static_cast<Index>(v));
        }
    }
    CORO_CHECK(!tets.empty(), InputError,
               path.string() << ": the grid has no tetrahedra (expected VTK_TETRA cells, found "
                             << n_cells << " cells of other types)");
    mesh.tets = Eigen::Map<const Tets>(tets.data(), static_cast<Eigen::Index>(tets.size() / 4), 4);
    return mesh;
}

} // namespace

TetMesh read_vtk_mesh(const std::filesystem::path& path)
{
    std::string extension = path.extension().string();
    std::transform(extension.begin(), extension.end(), extension.begin(),
                   [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    const bool legacy = extension == ".vtk";
    CORO_CHECK(legacy || extension == ".vtu", InputError,
               path.string() << ": expected a .vtu or .vtk file");
    // Checks that the file exists and is not a directory, and gives the counts to check.
    const std::string text = detail::read_file(path, "VTK mesh file");
    CORO_CHECK(!text.empty(), InputError, path.string() << ": the file is empty");
    check_counts_against_size(path, text, legacy);

    if (legacy) {
        CORO_CHECK(text.rfind("# vtk DataFile", 0) == 0, InputError,
                   path.string() << ":1: expected '# vtk DataFile Version ...' on the first line "
                                    "of a legacy VTK file, found "
                                 << detail::in_quotes(text.substr(0, text.find('\n'))));
        const std::size_t dataset = text.find("DATASET");
        CORO_CHECK(dataset != std::string::npos, InputError,
                   path.string() << ": expected a DATASET line, found none");
        const std::string kind = text.substr(dataset, text.find('\n', dataset) - dataset);
        CORO_CHECK(kind.find("UNSTRUCTURED_GRID") != std::string::npos, InputError,
                   path.string() << ": expected 'DATASET UNSTRUCTURED_GRID', found "
                                 << detail::in_quotes(kind));
        vtkNew<vtkUnstructuredGridReader> reader;
        reader->SetFileName(path.c_str());
        run_reader(path, reader);
        return to_tet_mesh(path, reader->GetOutput());
    }
    vtkNew<vtkXMLUnstructuredGridReader> reader;
    reader->SetFileName(path.c_str());
    run_reader(path, reader);
    return to_tet_mesh(path, reader->GetOutput());
}

} // namespace coro
