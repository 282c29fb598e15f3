// TetGen `.node` + `.ele` pairs (https://wias-berlin.de/software/tetgen/fformats.html):
//   .node: `#points 3 #attributes #markers(0|1)`, then `index x y z [attributes] [marker]`
//   .ele:  `#tets nodes-per-tet(4) #attributes`, then `index n0 n1 n2 n3 [attributes]`
// `#` starts a comment. Indices start at 0 or 1, as the first node's index says.

#include <corocontact/io/mesh_readers.hpp>

#include "detail/number_tokens.hpp"
#include "detail/text_input.hpp"

#include <corocontact/core/error.hpp>

#include <algorithm>
#include <cstdint>
#include <limits>
#include <string>
#include <string_view>
#include <vector>

namespace coro {
namespace {

namespace fs = std::filesystem;
using detail::LineCursor;
using detail::NumberTokens;

/// Reserve for `count` items, but never more than `bytes` of text can hold with at least
/// `min_line_bytes` per item: a corrupt header must not be able to request gigabytes.
std::size_t capped(std::uint64_t count, std::size_t bytes, std::size_t min_line_bytes)
{
    return static_cast<std::size_t>(std::min<std::uint64_t>(count, bytes / min_line_bytes + 1));
}

/// The next data line; a missing one is "expected <what>, found end of file".
template <class Describe>
std::string_view next_line(LineCursor& cursor, const Describe& what)
{
    std::string_view line;
    CORO_CHECK(cursor.next(line), InputError,
               cursor.where() << ": expected " << what() << ", found end of file");
    return line;
}

struct Nodes {
    std::vector<double> xyz; // 3 per node
    std::uint64_t count = 0;
    std::uint64_t base = 0; // index of the first node: 0 or 1
};

Nodes read_node_file(const fs::path& path)
{
    const std::string text = detail::read_file(path, "TetGen node file");
    LineCursor cursor(path.string(), text, true);
    NumberTokens header(next_line(cursor,
                                  [] {
                                      return std::string("the header '#points dimension "
                                                         "#attributes #boundary-markers'");
                                  }),
                        cursor);
    Nodes nodes;
    nodes.count = header.next_count("the number of points");
    const std::uint64_t dimension = header.next_count("the dimension");
    const std::uint64_t n_attributes = header.next_count("the number of attributes");
    const std::uint64_t n_markers = header.next_count("the number of boundary markers (0 or 1)");
    header.expect_end("'#points dimension #attributes #boundary-markers'");
    CORO_CHECK(nodes.count > 0, InputError,
               cursor.where() << ": expected at least one point, found a count of 0 (points "
                                 "stored in a .poly file are not supported)");
    CORO_CHECK(dimension == 3, InputError,
               cursor.where() << ": expected dimension 3, found " << dimension);
    CORO_CHECK(n_markers <= 1, InputError,
               cursor.where() << ": expected 0 or 1 boundary markers, found " << n_markers);
    CORO_CHECK(nodes.count < static_cast<std::uint64_t>(std::numeric_limits<Index>::max()),
               InputError,
               cursor.where() << ": expected fewer than 2^31 points, found " << nodes.count);
    const long header_line = cursor.line();

    nodes.xyz.reserve(3 * capped(nodes.count, text.size(), 8));
    for (std::uint64_t i = 0; i < nodes.count; ++i) {
        NumberTokens tokens(next_line(cursor,
                                      [&] {
                                          return "point " + std::to_string(i + 1) + " of " +
                                                 std::to_string(nodes.count) +
                                                 " declared at line " +
                                                 std::to_string(header_line) + " ('index x y z')";
                                      }),
                            cursor);
        const std::uint64_t index = tokens.next_count("the point index");
        if (i == 0) {
            CORO_CHECK(index <= 1, InputError,
                       cursor.where() << ": expected the first point's index to be 0 or 1 (it "
                                         "sets the numbering), found "
                                      << index);
            nodes.base = index;
        }
        CORO_CHECK(index == nodes.base + i, InputError,
                   cursor.where() << ": expected point index " << nodes.base + i
                                  << " (points numbered consecutively from " << nodes.base
                                  << "), found " << index);
        for (const char* axis : {"x", "y", "z"})
            nodes.xyz.push_back(tokens.next_double(std::string("the ") + axis + " coordinate"));
        for (std::uint64_t a = 0; a < n_attributes; ++a)
            tokens.next_double("a point attribute");
        if (n_markers == 1)
            tokens.next_int("the boundary marker");
        tokens.expect_end("'index x y z' with " + std::to_string(n_attributes) +
                          " attributes and " + std::to_string(n_markers) + " boundary markers");
    }
    std::string_view extra;
    CORO_CHECK(!cursor.next(extra), InputError,
               cursor.where() << ": expected end of file after the " << nodes.count
                              << " points declared at line " << header_line << ", found "
                              << detail::in_quotes(extra));
    return nodes;
}

Tets read_ele_file(const fs::path& path, const Nodes& nodes)
{
    const std::string text = detail::read_file(path, "TetGen element file");
    LineCursor cursor(path.string(), text, true);
    NumberTokens header(next_line(cursor,
                                  [] {
                                      return std::string(
                                          "the header '#tetrahedra nodes-per-tet #attributes'");
                                  }),
                        cursor);
    const std::uint64_t count = header.next_count("the number of tetrahedra");
    const std::uint64_t per_tet = header.next_count("the number of nodes per tetrahedron");
    const std::uint64_t n_attributes = header.next_count("the number of attributes");
    header.expect_end("'#tetrahedra nodes-per-tet #attributes'");
    CORO_CHECK(per_tet != 10, InputError,
               cursor.where() << ": 10-node (quadratic) tetrahedra are not supported, expected 4 "
                                 "nodes per tetrahedron (run tetgen without -o2)");
    CORO_CHECK(per_tet == 4, InputError,
               cursor.where() << ": expected 4 nodes per tetrahedron, found " << per_tet);
    CORO_CHECK(count > 0, InputError,
               cursor.where() << ": the mesh has no tetrahedra (expected a count of at least 1)");
    CORO_CHECK(count < static_cast<std::uint64_t>(std::numeric_limits<Index>::max()), InputError,
               cursor.where() << ": expected fewer than 2^31 tetrahedra, found " << count);
    const long header_line = cursor.line();

    std::vector<Index> tets;
    tets.reserve(4 * capped(count, text.size(), 10));
    for (std::uint64_t t = 0; t < count; ++t) {
        NumberTokens tokens(next_line(cursor,
                                      [&] {
                                          return "tetrahedron " + std::to_string(t + 1) + " of " +
                                                 std::to_string(count) + " declared at line " +
                                                 std::to_string(header_line) +
                                                 " ('index n0 n1 n2 n3')";
                                      }),
                            cursor);
        const std::uint64_t index = tokens.next_count("the tetrahedron index");
        const std::size_t first = tets.size();
        for (int k = 0; k < 4; ++k) {
            const std::uint64_t node = tokens.next_count("a node index");
            CORO_CHECK(node >= nodes.base && node - nodes.base < nodes.count, InputError,
                       cursor.where() << ": tetrahedron " << index << " refers to node " << node
                                      << ", expected an index in [" << nodes.base << ", "
                                      << nodes.base + nodes.count - 1 << "] (the points of "
                                      << fs::path(path).replace_extension(".node").string()
                                      << ")");
            const auto v = static_cast<Index>(node - nodes.base);
            for (std::size_t j = first; j < tets.size(); ++j)
                CORO_CHECK(tets[j] != v, InputError,
                           cursor.where() << ": tetrahedron " << index << " repeats node " << node
                                          << " (expected 4 distinct nodes)");
            tets.push_back(v);
        }
        for (std::uint64_t a = 0; a < n_attributes; ++a)
            tokens.next_double("a tetrahedron attribute");
        tokens.expect_end("'index n0 n1 n2 n3' with " + std::to_string(n_attributes) +
                          " attributes");
    }
    std::string_view extra;
    CORO_CHECK(!cursor.next(extra), InputError,
               cursor.where() << ": expected end of file after the " << count
                              << " tetrahedra declared at line " << header_line << ", found "
                              << detail::in_quotes(extra));
    return Eigen::Map<const Tets>(tets.data(), static_cast<Eigen::Index>(tets.size() / 4), 4);
}

} // namespace

TetMesh read_tetgen(const std::filesystem::path& path)
{
    const fs::path node_path = fs::path(path).replace_extension(".node");
    const fs::path ele_path = fs::path(path).replace_extension(".ele");
    std::error_code ec;
    for (const fs::path& part : {node_path, ele_path})
        CORO_CHECK(fs::exists(part, ec), InputError,
                   part.string() << ": TetGen file does not exist (a TetGen mesh is a .node and "
                                    "a .ele file with the same stem: "
                                 << node_path.filename().string() << " and "
                                 << ele_path.filename().string() << ")");
    const Nodes nodes = read_node_file(node_path);
    TetMesh mesh;
    mesh.tets = read_ele_file(ele_path, nodes);
    mesh.rest_positions = Eigen::Map<const Positions>(
        nodes.xyz.data(), static_cast<Eigen::Index>(nodes.count), 3);
    return mesh;
}

} // namespace coro
