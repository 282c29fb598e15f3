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
#include <vtkUnsignedCharArray.h>
#include <vtkLogger.h>
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
#include <cstring>
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

/// VTK's message without its "ERROR: In /build/.../file.cxx, line N\nClass (0x...): " or
/// "Generic Warning: In /build/.../file.cxx, line N\n" prefix.
std::string vtk_message(const char* text)
{
    std::string message = text != nullptr ? text : "";
    const std::size_t cut = message.rfind("): ");
    if (cut != std::string::npos)
        message.erase(0, cut + 3);
    else if (message.rfind("Generic Warning: In ", 0) == 0 && message.find('\n') != std::string::npos)
        message.erase(0, message.find('\n') + 1);
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

/// Installs an OutputCapture for one read and silences vtkLogger's stderr sink (VTK 9 logs
/// every error and warning there as well); both are put back afterwards.
class ScopedCapture {
public:
    ScopedCapture()
        : m_previous(vtkOutputWindow::GetInstance()),
          m_verbosity(vtkLogger::GetCurrentVerbosityCutoff())
    {
        vtkOutputWindow::SetInstance(m_capture);
        vtkLogger::SetStderrVerbosity(vtkLogger::VERBOSITY_OFF);
    }
    ~ScopedCapture()
    {
        vtkLogger::SetStderrVerbosity(m_verbosity);
        vtkOutputWindow::SetInstance(m_previous);
    }
    ScopedCapture(const ScopedCapture&) = delete;
    ScopedCapture& operator=(const ScopedCapture&) = delete;
    const std::vector<std::string>& messages() const { return m_capture->messages; }

private:
    vtkSmartPointer<vtkOutputWindow> m_previous;
    vtkLogger::Verbosity m_verbosity;
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

/// Position just after the line that starts with `keyword` (and a blank), and that line's
/// number; npos if there is none.
std::size_t after_keyword_line(std::string_view text, std::string_view keyword, long& line,
                               std::string_view& rest_of_line)
{
    long number = 1;
    for (std::size_t start = 0; start < text.size();) {
        const std::size_t end = std::min(text.find('\n', start), text.size());
        const std::string_view current = text.substr(start, end - start);
        if (current.substr(0, keyword.size()) == keyword && current.size() > keyword.size() &&
            (current[keyword.size()] == ' ' || current[keyword.size()] == '\t')) {
            line = number;
            rest_of_line = current.substr(keyword.size());
            return std::min(end + 1, text.size());
        }
        start = end + 1;
        ++number;
    }
    return std::string_view::npos;
}

/// Legacy files before version 5 list cells as `npts id...` runs that VTK 9.1 unpacks without
/// checking them against the declared size (a corrupt count overruns its buffer). So the
/// `CELLS n size` block is walked here first: n runs filling exactly `size` integers, and
/// `CELL_TYPES` must declare the same n.
void check_legacy_cells(const fs::path& path, std::string_view text)
{
    const std::string_view first_line = text.substr(0, text.find('\n'));
    const std::size_t version_at = first_line.find("Version ");
    int major = 0;
    const bool has_version =
        version_at != std::string_view::npos &&
        std::from_chars(first_line.data() + version_at + 8,
                        first_line.data() + first_line.size(), major)
                .ec == std::errc();
    CORO_CHECK(has_version && major >= 1, InputError,
               path.string() << ":1: expected '# vtk DataFile Version <major>.<minor>', found "
                             << detail::in_quotes(first_line));
    const bool new_layout = major >= 5; // OFFSETS/CONNECTIVITY instead of npts-prefixed runs
    long line = 0;
    std::string_view header;
    const std::size_t data = after_keyword_line(text, "CELLS", line, header);
    if (data == std::string_view::npos)
        return; // VTK reports a grid without cells; the tet check below names it
    std::uint64_t n = 0, size = 0;
    std::size_t used = 0;
    CORO_CHECK(leading_count(header, n, used) && leading_count(header.substr(used), size, used),
               InputError,
               path.string() << ":" << line << ": expected 'CELLS count size', found "
                             << detail::in_quotes(header));
    long types_line = 0;
    std::string_view types_header;
    if (after_keyword_line(text, "CELL_TYPES", types_line, types_header) !=
        std::string_view::npos) {
        std::uint64_t n_types = 0;
        CORO_CHECK(leading_count(types_header, n_types, used) &&
                       n_types == (new_layout ? (n > 0 ? n - 1 : 0) : n),
                   InputError,
                   path.string() << ":" << types_line << ": expected CELL_TYPES to declare as many "
                                 << "cells as CELLS at line " << line << ", found "
                                 << detail::in_quotes(types_header));
    }
    if (new_layout)
        return; // OFFSETS/CONNECTIVITY arrays: checked on the grid (vtkCellArray::IsValid)

    const bool binary = text.find("\nBINARY") != std::string_view::npos;
    std::size_t pos = data;
    const auto next_value = [&](std::int64_t& value) {
        if (binary) {
            if (text.size() - pos < 4)
                return false;
            const auto* b = reinterpret_cast<const unsigned char*>(text.data() + pos);
            const std::uint32_t u = (std::uint32_t{b[0]} << 24) | (std::uint32_t{b[1]} << 16) |
                                    (std::uint32_t{b[2]} << 8) | std::uint32_t{b[3]};
            value = static_cast<std::int32_t>(u);
            pos += 4;
            return true;
        }
        while (pos < text.size() && std::isspace(static_cast<unsigned char>(text[pos])) != 0)
            ++pos;
        const auto [end, ec] = std::from_chars(text.data() + pos, text.data() + text.size(), value);
        if (ec != std::errc())
            return false;
        pos = static_cast<std::size_t>(end - text.data());
        return true;
    };
    std::uint64_t consumed = 0;
    for (std::uint64_t c = 0; c < n; ++c) {
        std::int64_t count = 0;
        CORO_CHECK(consumed < size && next_value(count), InputError,
                   path.string() << ":" << line << ": CELLS declares " << n << " cells in " << size
                                 << " integers, but the list ends at cell " << c);
        CORO_CHECK(count >= 0 && static_cast<std::uint64_t>(count) < size - consumed, InputError,
                   path.string() << ":" << line << ": cell " << c << " declares " << count
                                 << " points, more than the " << size - consumed - 1
                                 << " integers left of the " << size << " CELLS declares");
        consumed += 1 + static_cast<std::uint64_t>(count);
        for (std::int64_t k = 0; k < count; ++k) {
            std::int64_t id = 0;
            CORO_CHECK(next_value(id), InputError,
                       path.string() << ":" << line << ": cell " << c << " of the CELLS list: "
                                     << "expected point " << k + 1 << " of " << count
                                     << ", found the end of the data or a non-integer");
        }
    }
    CORO_CHECK(consumed == size, InputError,
               path.string() << ":" << line << ": CELLS declares " << size << " integers, but its "
                             << n << " cells use " << consumed);
}

/// The value of `name="..."` in the XML tag around `at` (searched forward from `at`, within the
/// tag); empty if absent.
std::string_view xml_attribute(std::string_view text, std::size_t at, std::string_view name)
{
    const std::size_t tag_end = std::min(text.find('>', at), text.size());
    const std::string key = " " + std::string(name) + "=\"";
    const std::size_t found = text.substr(0, tag_end).find(key, at);
    if (found == std::string_view::npos)
        return {};
    const std::size_t begin = found + key.size();
    const std::size_t end = std::min(text.find('"', begin), tag_end);
    return text.substr(begin, end - begin);
}

/// The first `n` bytes of base64 text (blanks skipped); fewer if the text ends or is not base64.
std::string decode_base64_prefix(std::string_view text, std::size_t n)
{
    const auto value = [](char c) -> int {
        if (c >= 'A' && c <= 'Z')
            return c - 'A';
        if (c >= 'a' && c <= 'z')
            return c - 'a' + 26;
        if (c >= '0' && c <= '9')
            return c - '0' + 52;
        return c == '+' ? 62 : c == '/' ? 63 : -1;
    };
    std::string out;
    unsigned bits = 0;
    int n_bits = 0;
    for (const char c : text) {
        if (out.size() >= n)
            break;
        if (std::isspace(static_cast<unsigned char>(c)) != 0)
            continue;
        const int v = value(c);
        if (v < 0)
            break;
        bits = (bits << 6) | static_cast<unsigned>(v);
        n_bits += 6;
        if (n_bits >= 8) {
            n_bits -= 8;
            out += static_cast<char>((bits >> n_bits) & 0xffu);
        }
    }
    return out;
}

/// Compressed XML arrays start with a header whose first word is the number of blocks; VTK 9.1
/// sizes a vector from it before reading anything else, so a corrupt word stalls or exhausts
/// memory. Each block needs at least one header word in the file: more blocks than the file
/// has bytes for is rejected here, for appended and inline binary arrays.
void check_compression_headers(const fs::path& path, std::string_view text)
{
    const std::size_t root = text.find("<VTKFile");
    if (root == std::string_view::npos || xml_attribute(text, root, "compressor").empty())
        return;
    const std::size_t word = xml_attribute(text, root, "header_type") == "UInt64" ? 8 : 4;
    const bool big_endian = xml_attribute(text, root, "byte_order") == "BigEndian";
    const std::size_t appended_tag = text.find("<AppendedData");
    const bool appended_raw =
        appended_tag != std::string_view::npos && xml_attribute(text, appended_tag, "encoding") == "raw";
    const std::size_t appended_data =
        appended_tag == std::string_view::npos ? std::string_view::npos : text.find('_', appended_tag);
    const std::size_t xml_end = std::min(appended_tag, text.size());

    for (std::size_t at = text.find("<DataArray"); at < xml_end; at = text.find("<DataArray", at + 1)) {
        const std::string_view format = xml_attribute(text, at, "format");
        std::string header;
        if (format == "appended") {
            std::uint64_t offset = 0;
            std::size_t used = 0;
            if (appended_data == std::string_view::npos ||
                !leading_count(xml_attribute(text, at, "offset"), offset, used))
                continue; // VTK reports it
            if (offset >= text.size() - appended_data - 1)
                continue;
            const std::string_view data = text.substr(appended_data + 1 + offset);
            header = appended_raw ? std::string(data.substr(0, word))
                                  : decode_base64_prefix(data, word);
        } else if (format == "binary") {
            const std::size_t body = text.find('>', at);
            if (body == std::string_view::npos || text[body - 1] == '/')
                continue;
            header = decode_base64_prefix(text.substr(body + 1), word);
        } else {
            continue;
        }
        if (header.size() < word)
            continue; // VTK reports a short header
        if (big_endian)
            std::reverse(header.begin(), header.end());
        std::uint64_t blocks = 0;
        if (word == 4) {
            std::uint32_t w = 0;
            std::memcpy(&w, header.data(), 4);
            blocks = w;
        } else {
            std::memcpy(&blocks, header.data(), 8);
        }
        CORO_CHECK(blocks <= text.size() / word, InputError,
                   path.string() << ":" << 1 + std::count(text.begin(), text.begin() + static_cast<std::ptrdiff_t>(at), '\n')
                                 << ": the compressed data of this DataArray declares " << blocks
                                 << " blocks, more than the file's " << text.size()
                                 << " bytes can hold (corrupt data)");
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
    vtkCellArray* cells = grid->GetCells();
    vtkUnsignedCharArray* types = grid->GetCellTypesArray();
    CORO_CHECK(n_cells == 0 || (cells != nullptr && types != nullptr && cells->IsValid() &&
                                cells->GetNumberOfCells() == n_cells &&
                                types->GetNumberOfValues() == n_cells),
               InputError,
               path.string() << ": the cell list is inconsistent (offsets out of order or beyond "
                                "the connectivity, or a cell type count that differs from the "
                                "cell count)");
    for (vtkIdType c = 0; c < n_cells; ++c) {
        if (types->GetValue(c) != VTK_TETRA)
            continue;
        vtkIdType size = 0;
        const vtkIdType* points = nullptr;
        cells->GetCellAtId(c, size, points);
        CORO_CHECK(size == 4, InputError,
                   path.string() << ": cell " << c << " is a VTK_TETRA with " << size
                                 << " points, expected 4");
        for (vtkIdType k = 0; k < 4; ++k) {
            const vtkIdType v = points[k];
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
        check_legacy_cells(path, text);
        vtkNew<vtkUnstructuredGridReader> reader;
        reader->SetFileName(path.c_str());
        run_reader(path, reader);
        return to_tet_mesh(path, reader->GetOutput());
    }
    check_compression_headers(path, text);
    vtkNew<vtkXMLUnstructuredGridReader> reader;
    reader->SetFileName(path.c_str());
    run_reader(path, reader);
    return to_tet_mesh(path, reader->GetOutput());
}

} // namespace coro
