#include <corocontact/io/mesh_readers.hpp>

#include "detail/msh_binary.hpp"
#include "detail/msh_builder.hpp"
#include "detail/number_tokens.hpp"
#include "detail/text_input.hpp"

#include <corocontact/core/atomic_file.hpp>
#include <corocontact/core/error.hpp>

#include <algorithm>
#include <array>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <limits>
#include <sstream>
#include <string>
#include <string_view>
#include <system_error>
#include <unordered_map>
#include <utility>
#include <vector>

namespace coro {
namespace {

using detail::in_quotes;
using detail::is_blank;
using detail::LineCursor;
using detail::read_file;
using detail::trimmed;

using detail::MSH_TET4;
using detail::refuse_other_volume_element;
using detail::MshBuilder;

/// Returns the next line, which must hold data (not a `$Section` line, not the end of file).
/// `what` streams a description of the expected data into the message; it is only called
/// on failure.
template <class Describe>
std::string_view next_data_line(LineCursor& cursor, const Describe& what)
{
    std::string_view line;
    if (!cursor.next(line)) {
        std::ostringstream expected;
        what(expected);
        CORO_THROW(InputError, cursor.where()
                                   << ": expected " << expected.str() << ", found end of file");
    }
    if (line.front() == '$') {
        std::ostringstream expected;
        what(expected);
        CORO_THROW(InputError, cursor.where() << ": expected " << expected.str() << ", found "
                                              << in_quotes(line));
    }
    return line;
}

/// Requires the next line to be exactly `marker` (e.g. `$EndNodes`).
void expect_marker(LineCursor& cursor, std::string_view marker, std::string_view after)
{
    std::string_view line;
    const bool found = cursor.next(line);
    CORO_CHECK(found, InputError,
               cursor.where() << ": expected " << marker << " after " << after
                              << ", found end of file");
    CORO_CHECK(line == marker, InputError,
               cursor.where() << ": expected " << marker << " after " << after << ", found "
                              << in_quotes(line));
}

using Tokens = detail::NumberTokens;

enum class MshVersion { V22, V41 };

/// The location callable MshBuilder's checks take: the cursor's "path:line".
auto at(const LineCursor& cursor)
{
    return [&cursor] { return cursor.where(); };
}

std::array<double, 3> read_xyz(Tokens& tokens)
{
    return {tokens.next_double("node x coordinate"), tokens.next_double("node y coordinate"),
            tokens.next_double("node z coordinate")};
}

/// The format line after `$MeshFormat`.
struct MshFormat {
    MshVersion version = MshVersion::V22;
    bool binary = false;
};

/// Reads the line after `$MeshFormat`; for ASCII files also the `$EndMeshFormat` line (a
/// binary file has its endianness word in between, read by the binary reader).
MshFormat read_mesh_format(LineCursor& cursor)
{
    const std::string_view line =
        next_data_line(cursor, [](std::ostream& os) { os << "'version file-type data-size'"; });
    Tokens tokens(line, cursor);
    const std::string_view version = tokens.next("MSH version");
    CORO_CHECK(version == "2.2" || version == "4.1", InputError,
               cursor.where() << ": unsupported MSH version " << in_quotes(version)
                              << ", expected 2.2 or 4.1 (save from Gmsh with -format msh41 or "
                                 "msh22)");
    MshFormat result;
    result.version = version == "2.2" ? MshVersion::V22 : MshVersion::V41;
    const int file_type = tokens.next_int("file-type (0 for ASCII, 1 for binary)");
    CORO_CHECK(file_type == 0 || file_type == 1, InputError,
               cursor.where() << ": expected file-type 0 (ASCII) or 1 (binary), found "
                              << file_type);
    result.binary = file_type == 1;
    const int data_size = tokens.next_int("data-size");
    CORO_CHECK(!result.binary || data_size == 8, InputError,
               cursor.where() << ": expected data-size 8 (the size of a double and of size_t) in "
                                 "a binary file, found "
                              << data_size);
    tokens.expect_end("'version file-type data-size'");
    if (!result.binary)
        expect_marker(cursor, "$EndMeshFormat", "the format line");
    return result;
}

/// MSH 2.2 `$Nodes`: a count, then `tag x y z` lines.
void read_nodes_v22(LineCursor& cursor, MshBuilder& builder)
{
    Tokens header(next_data_line(cursor, [](std::ostream& os) { os << "the number of nodes"; }),
                  cursor);
    const long header_line = cursor.line();
    const std::uint64_t count = header.next_count("the number of nodes");
    header.expect_end("the number of nodes");
    builder.reserve_nodes(count);
    for (std::uint64_t i = 0; i < count; ++i) {
        Tokens tokens(next_data_line(cursor,
                                     [&](std::ostream& os) {
                                         os << "node " << i + 1 << " of " << count
                                            << " declared at line " << header_line
                                            << " ('tag x y z')";
                                     }),
                      cursor);
        builder.add_node_tag(at(cursor), cursor.line(), tokens.next_count("node tag"));
        builder.add_node_coordinates(read_xyz(tokens));
        tokens.expect_end("'tag x y z'");
    }
    expect_marker(cursor, "$EndNodes",
                  "the " + std::to_string(count) + " nodes declared at line " +
                      std::to_string(header_line));
}

/// MSH 4.1 `$Nodes`: entity blocks, each with its node tags followed by its coordinates.
void read_nodes_v41(LineCursor& cursor, MshBuilder& builder)
{
    Tokens header(next_data_line(cursor,
                                 [](std::ostream& os) {
                                     os << "'numEntityBlocks numNodes minNodeTag maxNodeTag'";
                                 }),
                  cursor);
    const long header_line = cursor.line();
    const std::uint64_t n_blocks = header.next_count("the number of node entity blocks");
    const std::uint64_t n_nodes = header.next_count("the number of nodes");
    header.next_count("the minimum node tag");
    header.next_count("the maximum node tag");
    header.expect_end("'numEntityBlocks numNodes minNodeTag maxNodeTag'");
    builder.reserve_nodes(n_nodes);

    std::uint64_t n_read = 0;
    for (std::uint64_t b = 0; b < n_blocks; ++b) {
        Tokens block(next_data_line(cursor,
                                    [&](std::ostream& os) {
                                        os << "node entity block " << b + 1 << " of " << n_blocks
                                           << " declared at line " << header_line
                                           << " ('entityDim entityTag parametric numNodesInBlock')";
                                    }),
                     cursor);
        const int dim = block.next_int("entity dimension");
        CORO_CHECK(dim >= 0 && dim <= 3, InputError,
                   cursor.where() << ": expected entity dimension 0 to 3, found " << dim);
        block.next_int("entity tag");
        const int parametric = block.next_int("parametric flag");
        CORO_CHECK(parametric == 0 || parametric == 1, InputError,
                   cursor.where() << ": expected parametric flag 0 or 1, found " << parametric);
        const std::uint64_t in_block = block.next_count("the number of nodes in the block");
        block.expect_end("'entityDim entityTag parametric numNodesInBlock'");
        const long block_line = cursor.line();

        for (std::uint64_t i = 0; i < in_block; ++i) {
            Tokens tokens(next_data_line(cursor,
                                         [&](std::ostream& os) {
                                             os << "node tag " << i + 1 << " of " << in_block
                                                << " in the block at line " << block_line;
                                         }),
                          cursor);
            builder.add_node_tag(at(cursor), cursor.line(), tokens.next_count("node tag"));
            tokens.expect_end("the node tag (one per line)");
        }
        const int n_parametric = parametric == 1 ? dim : 0;
        for (std::uint64_t i = 0; i < in_block; ++i) {
            Tokens tokens(next_data_line(cursor,
                                         [&](std::ostream& os) {
                                             os << "coordinates of node " << i + 1 << " of "
                                                << in_block << " in the block at line "
                                                << block_line;
                                         }),
                          cursor);
            builder.add_node_coordinates(read_xyz(tokens));
            for (int p = 0; p < n_parametric; ++p)
                tokens.next_double("parametric coordinate");
            tokens.expect_end(n_parametric > 0 ? "'x y z' and the parametric coordinates"
                                               : "'x y z'");
        }
        n_read += in_block;
    }
    CORO_CHECK(n_read == n_nodes, InputError,
               cursor.where() << ": expected " << n_nodes << " nodes as declared at line "
                              << header_line << ", found " << n_read << " in the blocks");
    expect_marker(cursor, "$EndNodes",
                  "the " + std::to_string(n_blocks) + " node entity blocks declared at line " +
                      std::to_string(header_line));
}

/// Reads four node tags of a tet, after checking that exactly four remain on the line.
std::array<std::uint64_t, 4> read_tet_nodes(Tokens& tokens, const LineCursor& cursor)
{
    const std::size_t n = tokens.remaining();
    CORO_CHECK(n == 4, InputError,
               cursor.where() << ": expected 4 node tags for a tet, found " << n);
    std::array<std::uint64_t, 4> tags{};
    for (auto& tag : tags)
        tag = tokens.next_count("node tag");
    return tags;
}

/// MSH 2.2 `$Elements`: a count, then `tag type ntags tags... nodes...` lines.
void read_elements_v22(LineCursor& cursor, MshBuilder& builder)
{
    Tokens header(next_data_line(cursor, [](std::ostream& os) { os << "the number of elements"; }),
                  cursor);
    const long header_line = cursor.line();
    const std::uint64_t count = header.next_count("the number of elements");
    header.expect_end("the number of elements");
    builder.reserve_elements(count);
    for (std::uint64_t i = 0; i < count; ++i) {
        Tokens tokens(next_data_line(cursor,
                                     [&](std::ostream& os) {
                                         os << "element " << i + 1 << " of " << count
                                            << " declared at line " << header_line
                                            << " ('tag type ntags tags... nodes...')";
                                     }),
                      cursor);
        const std::uint64_t tag = tokens.next_count("element tag");
        const int type = tokens.next_int("element type");
        if (type != MSH_TET4) {
            refuse_other_volume_element(type, -1, cursor.where());
            continue;
        }
        const std::uint64_t n_tags = tokens.next_count("the number of element tags");
        CORO_CHECK(n_tags <= tokens.remaining(), InputError,
                   cursor.where() << ": expected " << n_tags
                                  << " element tags and 4 node tags, found " << tokens.remaining()
                                  << " values");
        for (std::uint64_t t = 0; t < n_tags; ++t)
            tokens.next("element tag");
        builder.add_tet(at(cursor), cursor.line(), tag, read_tet_nodes(tokens, cursor));
    }
    expect_marker(cursor, "$EndElements",
                  "the " + std::to_string(count) + " elements declared at line " +
                      std::to_string(header_line));
}

/// MSH 4.1 `$Elements`: entity blocks of one element type each.
void read_elements_v41(LineCursor& cursor, MshBuilder& builder)
{
    Tokens header(next_data_line(cursor,
                                 [](std::ostream& os) {
                                     os << "'numEntityBlocks numElements minElementTag "
                                           "maxElementTag'";
                                 }),
                  cursor);
    const long header_line = cursor.line();
    const std::uint64_t n_blocks = header.next_count("the number of element entity blocks");
    const std::uint64_t n_elements = header.next_count("the number of elements");
    header.next_count("the minimum element tag");
    header.next_count("the maximum element tag");
    header.expect_end("'numEntityBlocks numElements minElementTag maxElementTag'");

    std::uint64_t n_read = 0;
    for (std::uint64_t b = 0; b < n_blocks; ++b) {
        Tokens block(next_data_line(cursor,
                                    [&](std::ostream& os) {
                                        os << "element entity block " << b + 1 << " of "
                                           << n_blocks << " declared at line " << header_line
                                           << " ('entityDim entityTag elementType "
                                              "numElementsInBlock')";
                                    }),
                     cursor);
        const int dim = block.next_int("entity dimension");
        block.next_int("entity tag");
        const int type = block.next_int("element type");
        const std::uint64_t in_block = block.next_count("the number of elements in the block");
        block.expect_end("'entityDim entityTag elementType numElementsInBlock'");
        const long block_line = cursor.line();
        if (in_block > 0)
            refuse_other_volume_element(type, dim, cursor.where());
        if (type == MSH_TET4)
            builder.reserve_elements(in_block);
        for (std::uint64_t i = 0; i < in_block; ++i) {
            const std::string_view line =
                next_data_line(cursor, [&](std::ostream& os) {
                    os << "element " << i + 1 << " of " << in_block << " in the block at line "
                       << block_line;
                });
            if (type != MSH_TET4)
                continue;
            Tokens tokens(line, cursor);
            const std::uint64_t tag = tokens.next_count("element tag");
            builder.add_tet(at(cursor), cursor.line(), tag, read_tet_nodes(tokens, cursor));
        }
        n_read += in_block;
    }
    CORO_CHECK(n_read == n_elements, InputError,
               cursor.where() << ": expected " << n_elements << " elements as declared at line "
                              << header_line << ", found " << n_read << " in the blocks");
    expect_marker(cursor, "$EndElements",
                  "the " + std::to_string(n_blocks) + " element entity blocks declared at line " +
                      std::to_string(header_line));
}

/// Skips a section we do not read ($Entities, $PhysicalNames, $Periodic, ...).
void skip_section(LineCursor& cursor, std::string_view name)
{
    const long opened = cursor.line();
    const std::string end_marker = "$End" + std::string(name.substr(1));
    std::string_view line;
    while (cursor.next(line))
        if (line == end_marker)
            return;
    CORO_THROW(InputError, cursor.where() << ": expected " << end_marker << " closing " << name
                                          << " opened at line " << opened
                                          << ", found end of file");
}

} // namespace

TetMesh read_msh(const std::filesystem::path& path)
{
    const std::string text = read_file(path, "mesh file");
    LineCursor cursor(path.string(), text);

    std::string_view line;
    const bool has_first = cursor.next(line);
    CORO_CHECK(has_first, InputError,
               cursor.where() << ": expected $MeshFormat, found an empty file");
    CORO_CHECK(line == "$MeshFormat", InputError,
               cursor.where() << ": expected $MeshFormat on the first line of a Gmsh MSH file, "
                                 "found "
                              << in_quotes(line));
    const MshFormat format = read_mesh_format(cursor);
    if (format.binary)
        return detail::read_msh_binary(path.string(), text);
    const MshVersion version = format.version;

    MshBuilder builder("line", text.size());
    long nodes_line = 0;
    long elements_line = 0;
    while (cursor.next(line)) {
        CORO_CHECK(line.front() == '$', InputError,
                   cursor.where() << ": expected a section such as $Nodes or $Elements, found "
                                  << in_quotes(line));
        if (line == "$Nodes") {
            CORO_CHECK(nodes_line == 0, InputError,
                       cursor.where() << ": expected one $Nodes section, found a second one "
                                         "(the first is at line "
                                      << nodes_line << ")");
            nodes_line = cursor.line();
            if (version == MshVersion::V22)
                read_nodes_v22(cursor, builder);
            else
                read_nodes_v41(cursor, builder);
        } else if (line == "$Elements") {
            CORO_CHECK(elements_line == 0, InputError,
                       cursor.where() << ": expected one $Elements section, found a second one "
                                         "(the first is at line "
                                      << elements_line << ")");
            CORO_CHECK(nodes_line != 0, InputError,
                       cursor.where()
                           << ": expected $Nodes before $Elements, found $Elements first");
            elements_line = cursor.line();
            if (version == MshVersion::V22)
                read_elements_v22(cursor, builder);
            else
                read_elements_v41(cursor, builder);
        } else if (line == "$MeshFormat") {
            CORO_THROW(InputError, cursor.where() << ": expected one $MeshFormat section, found a "
                                                     "second one");
        } else if (line.size() >= 4 && line.substr(0, 4) == "$End") {
            CORO_THROW(InputError, cursor.where()
                                       << ": expected a section start such as $Nodes, found "
                                       << in_quotes(line) << " without its opening line");
        } else {
            skip_section(cursor, line);
        }
    }
    const std::string name = path.string();
    return builder.finish([&](long at_line) { return name + ":" + std::to_string(at_line); });
}

TetMesh read_tet_mesh(const std::filesystem::path& path)
{
    std::error_code ec; // an inaccessible path is reported by read_file
    CORO_CHECK(!std::filesystem::is_directory(path, ec), InputError,
               path.string() << ": is a directory, expected a mesh file");
    std::string extension = path.extension().string();
    std::transform(extension.begin(), extension.end(), extension.begin(),
                   [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    if (extension == ".msh")
        return read_msh(path);
    if (extension == ".vtu" || extension == ".vtk")
        return read_vtk_mesh(path);
    if (extension == ".node" || extension == ".ele")
        return read_tetgen(path);
    CORO_THROW(InputError, path.string() << ": unsupported mesh extension "
                                         << (extension.empty() ? std::string("(none)")
                                                               : in_quotes(extension))
                                         << ", expected one of: .msh (Gmsh 2.2 or 4.1, ASCII or "
                                            "binary), .vtu, .vtk (VTK unstructured grid), .node "
                                            "or .ele (TetGen)");
}

void write_msh22(const std::filesystem::path& path, const TetMesh& mesh)
{
    std::string out;
    out.reserve(64 + static_cast<std::size_t>(mesh.num_vertices()) * 64 +
                static_cast<std::size_t>(mesh.num_tets()) * 48);
    std::array<char, 64> buffer{};
    const auto append_int = [&](long long value) {
        const auto result = std::to_chars(buffer.data(), buffer.data() + buffer.size(), value);
        out.append(buffer.data(), result.ptr);
    };
    const auto append_double = [&](double value) {
        // Shortest representation that reads back to the same double (round trip exact).
        const auto result = std::to_chars(buffer.data(), buffer.data() + buffer.size(), value);
        out.append(buffer.data(), result.ptr);
    };

    out += "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n";
    append_int(mesh.num_vertices());
    out += '\n';
    for (Index v = 0; v < mesh.num_vertices(); ++v) {
        append_int(v + 1LL);
        for (int d = 0; d < 3; ++d) {
            out += ' ';
            append_double(mesh.rest_positions(v, d));
        }
        out += '\n';
    }
    out += "$EndNodes\n$Elements\n";
    append_int(mesh.num_tets());
    out += '\n';
    for (Index t = 0; t < mesh.num_tets(); ++t) {
        append_int(t + 1LL);
        out += " 4 2 0 1"; // type 4, two tags: physical 0 (none), elementary entity 1
        for (int k = 0; k < 4; ++k) {
            CORO_ASSERT(mesh.tets(t, k) >= 0 && mesh.tets(t, k) < mesh.num_vertices());
            out += ' ';
            append_int(mesh.tets(t, k) + 1LL);
        }
        out += '\n';
    }
    out += "$EndElements\n";

    write_file_atomically(path, out);
}

} // namespace coro
