// Binary Gmsh MSH 2.2 and 4.1 (file-type 1): section markers and a few counts are text lines,
// node and element data are raw ints, size_t and doubles in the writer's byte order, which
// the int 1 after the format line tells.

#include "detail/msh_binary.hpp"
#include "detail/msh_builder.hpp"
#include "detail/text_input.hpp"

#include <corocontact/core/error.hpp>

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <string>
#include <string_view>
#include <system_error>

namespace coro::detail {
namespace {

enum class Version { V22, V41 };

/// The file's bytes with a read position; every read is bounds-checked by the caller through
/// `require`, so no count from the file is trusted before the bytes it needs are known to exist.
class ByteReader {
public:
    ByteReader(std::string path, std::string_view data) : m_path(std::move(path)), m_data(data) {}

    /// "path: byte N" at the current position.
    std::string where() const { return where(m_pos); }
    std::string where(std::size_t pos) const { return m_path + ": byte " + std::to_string(pos); }
    std::size_t pos() const { return m_pos; }
    std::size_t remaining() const { return m_data.size() - m_pos; }
    void set_swap(bool swap) { m_swap = swap; }

    /// Requires `count` items of `item_bytes` each to fit in what is left of the file.
    /// `what` names the items for the message ("the 76 nodes declared at byte 40").
    template <class Describe>
    void require(std::uint64_t count, std::size_t item_bytes, const Describe& what) const
    {
        CORO_CHECK(count <= remaining() / item_bytes, InputError,
                   where() << ": expected " << what() << " (" << item_bytes
                           << " bytes each), but only " << remaining()
                           << " bytes are left in the file: truncated, or a corrupt count");
    }

    /// A value of type T in the file's byte order; `require` must have covered it.
    template <class T>
    T raw()
    {
        std::array<char, sizeof(T)> bytes{};
        std::memcpy(bytes.data(), m_data.data() + m_pos, sizeof(T));
        if (m_swap)
            std::reverse(bytes.begin(), bytes.end());
        T value{};
        std::memcpy(&value, bytes.data(), sizeof(T));
        m_pos += sizeof(T);
        return value;
    }

    /// A checked value of type T; `what` names it in the message at the end of the file.
    template <class T>
    T value(const char* what)
    {
        require(1, sizeof(T), [&] { return std::string(what); });
        return raw<T>();
    }

    /// An int that must not be negative (counts and tags of MSH 2.2).
    std::uint64_t count32(const char* what)
    {
        const std::size_t at = m_pos;
        const auto v = value<std::int32_t>(what);
        CORO_CHECK(v >= 0, InputError,
                   where(at) << ": expected " << what << " (a non-negative int), found " << v);
        return static_cast<std::uint64_t>(v);
    }

    /// The next text line (leading blank lines and blanks skipped, trailing blanks trimmed);
    /// false at the end of the file.
    bool line(std::string_view& out)
    {
        while (m_pos < m_data.size() && (m_data[m_pos] == '\n' || is_blank(m_data[m_pos])))
            ++m_pos;
        if (m_pos >= m_data.size())
            return false;
        m_line_start = m_pos;
        const std::size_t end = std::min(m_data.find('\n', m_pos), m_data.size());
        out = trimmed(m_data.substr(m_pos, end - m_pos));
        m_pos = std::min(end + 1, m_data.size());
        return true;
    }

    /// Start of the line last returned by `line`.
    std::size_t line_start() const { return m_line_start; }

    /// Skips to just after the line `marker` (at the start of a line); false if there is none.
    bool skip_past_line(std::string_view marker)
    {
        std::size_t from = m_pos;
        while (true) {
            const std::size_t found = m_data.find(marker, from);
            if (found == std::string_view::npos)
                return false;
            const bool line_start = found == 0 || m_data[found - 1] == '\n';
            const std::size_t after = found + marker.size();
            const bool line_end = after >= m_data.size() || m_data[after] == '\n' ||
                                  m_data[after] == '\r';
            if (line_start && line_end) {
                m_pos = std::min(m_data.find('\n', after), m_data.size());
                return true;
            }
            from = found + 1;
        }
    }

    const std::string& path() const { return m_path; }

private:
    std::string m_path;
    std::string_view m_data;
    std::size_t m_pos = 0;
    std::size_t m_line_start = 0;
    bool m_swap = false;
};

/// Requires the next text line to be `marker`.
void expect_line(ByteReader& in, std::string_view marker, const std::string& after)
{
    std::string_view line;
    const bool found = in.line(line);
    CORO_CHECK(found, InputError,
               in.where() << ": expected " << marker << " after " << after
                          << ", found end of file");
    CORO_CHECK(line == marker, InputError,
               in.where(in.line_start()) << ": expected " << marker << " after " << after
                                         << ", found " << in_quotes(line));
}

/// A text line holding one non-negative integer (the counts of MSH 2.2 sections).
std::uint64_t count_line(ByteReader& in, const char* what)
{
    std::string_view line;
    CORO_CHECK(in.line(line), InputError,
               in.where() << ": expected " << what << ", found end of file");
    std::uint64_t value = 0;
    const auto [end, ec] = std::from_chars(line.data(), line.data() + line.size(), value);
    CORO_CHECK(ec == std::errc() && end == line.data() + line.size(), InputError,
               in.where(in.line_start()) << ": expected " << what
                                         << " (a non-negative integer on its own line), found "
                                         << in_quotes(line));
    return value;
}

/// Reads `$MeshFormat` up to `$EndMeshFormat` and sets the byte order.
Version read_format(ByteReader& in)
{
    std::string_view line;
    CORO_CHECK(in.line(line) && line == "$MeshFormat", InputError,
               in.where(in.line_start()) << ": expected $MeshFormat on the first line");
    CORO_CHECK(in.line(line), InputError,
               in.where() << ": expected 'version file-type data-size', found end of file");
    const std::size_t format_at = in.line_start();
    Version version = Version::V22;
    if (line == "4.1 1 8")
        version = Version::V41;
    else
        CORO_CHECK(line == "2.2 1 8", InputError,
                   in.where(format_at) << ": expected '2.2 1 8' or '4.1 1 8' for a binary MSH "
                                          "file, found "
                                       << in_quotes(line));
    const std::size_t one_at = in.pos();
    const auto one = in.value<std::uint32_t>("the binary int 1 that tells the byte order");
    if (one != 1) {
        const std::uint32_t swapped = ((one & 0xffu) << 24) | ((one & 0xff00u) << 8) |
                                      ((one >> 8) & 0xff00u) | (one >> 24);
        CORO_CHECK(swapped == 1, InputError,
                   in.where(one_at) << ": expected the binary int 1 after the format line (it "
                                       "tells the byte order), found "
                                    << one);
        in.set_swap(true);
    }
    expect_line(in, "$EndMeshFormat", "the byte-order int");
    return version;
}

/// Three coordinates, which must be finite; `node` describes the node in the message.
template <class Describe>
std::array<double, 3> read_xyz(ByteReader& in, std::size_t at, const Describe& node)
{
    std::array<double, 3> x{};
    for (double& c : x) {
        c = in.raw<double>();
        CORO_CHECK(std::isfinite(c), InputError,
                   in.where(at) << ": " << node() << " has coordinate " << c
                                << ", expected a finite number");
    }
    return x;
}

/// MSH 2.2 `$Nodes`: a count line, then per node an int tag and three doubles.
void read_nodes_v22(ByteReader& in, MshBuilder& builder)
{
    const std::size_t header_at = in.pos();
    const std::uint64_t count = count_line(in, "the number of nodes");
    in.require(count, 4 + 3 * 8, [&] {
        return std::to_string(count) + " nodes as declared at byte " + std::to_string(header_at);
    });
    builder.reserve_nodes(count);
    for (std::uint64_t i = 0; i < count; ++i) {
        const std::size_t at = in.pos();
        const auto tag = in.raw<std::int32_t>();
        CORO_CHECK(tag >= 0, InputError,
                   in.where(at) << ": node " << i + 1 << " of " << count
                                << ": expected a non-negative node tag, found " << tag);
        builder.add_node_tag([&] { return in.where(at); }, static_cast<long>(at),
                             static_cast<std::uint64_t>(tag));
        builder.add_node_coordinates(
            read_xyz(in, at, [&] { return "node " + std::to_string(tag); }));
    }
    expect_line(in, "$EndNodes",
                "the " + std::to_string(count) + " nodes declared at byte " +
                    std::to_string(header_at));
}

/// MSH 2.2 `$Elements`: a count line, then groups, each an int triple (type, count, number of
/// tags) followed by its elements as ints (tag, tags..., nodes...).
void read_elements_v22(ByteReader& in, MshBuilder& builder)
{
    const std::size_t header_at = in.pos();
    const std::uint64_t count = count_line(in, "the number of elements");
    std::uint64_t n_read = 0;
    while (n_read < count) {
        const std::size_t group_at = in.pos();
        const auto type = static_cast<int>(in.count32("element type"));
        const std::uint64_t in_group = in.count32("number of elements following");
        const std::uint64_t n_tags = in.count32("number of element tags");
        const int n_nodes = msh_nodes_per_element(type);
        CORO_CHECK(n_nodes > 0, InputError,
                   in.where(group_at) << ": element group: unknown element type " << type
                                      << " (expected a Gmsh element type such as 4, the tet)");
        CORO_CHECK(in_group >= 1 && in_group <= count - n_read, InputError,
                   in.where(group_at) << ": element group of type " << type << " declares "
                                      << in_group << " elements, expected 1 to "
                                      << count - n_read << " (of the " << count
                                      << " declared at byte " << header_at << ")");
        CORO_CHECK(n_tags <= 1000, InputError,
                   in.where(group_at) << ": element group declares " << n_tags
                                      << " tags per element, expected at most 1000");
        const std::size_t ints = 1 + static_cast<std::size_t>(n_tags) +
                                 static_cast<std::size_t>(n_nodes);
        in.require(in_group, 4 * ints, [&] {
            return std::to_string(in_group) + " elements of type " + std::to_string(type) +
                   " in the group at byte " + std::to_string(group_at);
        });
        refuse_other_volume_element(type, -1, in.where(group_at));
        if (type == MSH_TET4)
            builder.reserve_elements(in_group);
        for (std::uint64_t e = 0; e < in_group; ++e) {
            const std::size_t at = in.pos();
            if (type != MSH_TET4) {
                for (std::size_t k = 0; k < ints; ++k)
                    in.raw<std::int32_t>();
                continue;
            }
            const auto tag = in.raw<std::int32_t>();
            for (std::uint64_t t = 0; t < n_tags; ++t)
                in.raw<std::int32_t>();
            std::array<std::uint64_t, 4> nodes{};
            for (auto& node : nodes) {
                const auto v = in.raw<std::int32_t>();
                CORO_CHECK(v >= 0, InputError,
                           in.where(at) << ": tet element " << tag
                                        << ": expected non-negative node tags, found " << v);
                node = static_cast<std::uint64_t>(v);
            }
            builder.add_tet([&] { return in.where(at); }, static_cast<long>(at), static_cast<std::uint64_t>(tag), nodes);
        }
        n_read += in_group;
    }
    expect_line(in, "$EndElements",
                "the " + std::to_string(count) + " elements declared at byte " +
                    std::to_string(header_at));
}

/// MSH 4.1 `$Nodes`: four size_t (blocks, nodes, min tag, max tag), then blocks of
/// (int dim, int tag, int parametric, size_t count), count size_t tags, count × (3 + params)
/// doubles.
void read_nodes_v41(ByteReader& in, MshBuilder& builder)
{
    const std::size_t header_at = in.pos();
    const auto n_blocks = in.value<std::uint64_t>("the number of node entity blocks");
    const auto n_nodes = in.value<std::uint64_t>("the number of nodes");
    in.value<std::uint64_t>("the minimum node tag");
    in.value<std::uint64_t>("the maximum node tag");
    const auto header = [&] { return " declared at byte " + std::to_string(header_at); };
    in.require(n_nodes, 8 + 3 * 8, [&] { return std::to_string(n_nodes) + " nodes" + header(); });
    in.require(n_blocks, 3 * 4 + 8,
               [&] { return std::to_string(n_blocks) + " node entity blocks" + header(); });
    builder.reserve_nodes(n_nodes);
    std::uint64_t n_read = 0;
    for (std::uint64_t b = 0; b < n_blocks; ++b) {
        const std::size_t block_at = in.pos();
        const auto dim = in.value<std::int32_t>("entity dimension");
        CORO_CHECK(dim >= 0 && dim <= 3, InputError,
                   in.where(block_at) << ": node entity block " << b + 1 << " of " << n_blocks
                                      << ": expected entity dimension 0 to 3, found " << dim);
        in.value<std::int32_t>("entity tag");
        const auto parametric = in.value<std::int32_t>("parametric flag");
        CORO_CHECK(parametric == 0 || parametric == 1, InputError,
                   in.where(block_at) << ": node entity block " << b + 1
                                      << ": expected parametric flag 0 or 1, found "
                                      << parametric);
        const auto in_block = in.value<std::uint64_t>("the number of nodes in the block");
        CORO_CHECK(in_block <= n_nodes - n_read, InputError,
                   in.where(block_at) << ": node entity block " << b + 1 << " declares "
                                      << in_block << " nodes, but only " << n_nodes - n_read
                                      << " of the " << n_nodes << header() << " are left");
        const std::size_t doubles = 3 + (parametric == 1 ? static_cast<std::size_t>(dim) : 0);
        in.require(in_block, 8 + 8 * doubles, [&] {
            return std::to_string(in_block) + " nodes in the block at byte " +
                   std::to_string(block_at);
        });
        for (std::uint64_t i = 0; i < in_block; ++i) {
            const std::size_t at = in.pos();
            builder.add_node_tag([&] { return in.where(at); }, static_cast<long>(at),
                                 in.raw<std::uint64_t>());
        }
        for (std::uint64_t i = 0; i < in_block; ++i) {
            const std::size_t at = in.pos();
            builder.add_node_coordinates(read_xyz(in, at, [&] {
                return "node " + std::to_string(i + 1) + " of the node entity block at byte " +
                       std::to_string(block_at);
            }));
            for (std::size_t p = 3; p < doubles; ++p)
                in.raw<double>();
        }
        n_read += in_block;
    }
    CORO_CHECK(n_read == n_nodes, InputError,
               in.where() << ": expected " << n_nodes << " nodes as declared at byte " << header_at
                          << ", found " << n_read << " in the blocks");
    expect_line(in, "$EndNodes", "the node entity blocks declared at byte " +
                                     std::to_string(header_at));
}

/// MSH 4.1 `$Elements`: four size_t (blocks, elements, min tag, max tag), then blocks of
/// (int dim, int tag, int type, size_t count) and count × (1 + nodes) size_t.
void read_elements_v41(ByteReader& in, MshBuilder& builder)
{
    const std::size_t header_at = in.pos();
    const auto n_blocks = in.value<std::uint64_t>("the number of element entity blocks");
    const auto n_elements = in.value<std::uint64_t>("the number of elements");
    in.value<std::uint64_t>("the minimum element tag");
    in.value<std::uint64_t>("the maximum element tag");
    const auto header = [&] { return " declared at byte " + std::to_string(header_at); };
    in.require(n_elements, 2 * 8,
               [&] { return std::to_string(n_elements) + " elements" + header(); });
    in.require(n_blocks, 3 * 4 + 8,
               [&] { return std::to_string(n_blocks) + " element entity blocks" + header(); });
    std::uint64_t n_read = 0;
    for (std::uint64_t b = 0; b < n_blocks; ++b) {
        const std::size_t block_at = in.pos();
        const auto dim = in.value<std::int32_t>("entity dimension");
        in.value<std::int32_t>("entity tag");
        const auto type = in.value<std::int32_t>("element type");
        const auto in_block = in.value<std::uint64_t>("the number of elements in the block");
        const int n_nodes = msh_nodes_per_element(type);
        CORO_CHECK(n_nodes > 0, InputError,
                   in.where(block_at) << ": element entity block " << b + 1
                                      << ": unknown element type " << type
                                      << " (expected a Gmsh element type such as 4, the tet)");
        CORO_CHECK(in_block <= n_elements - n_read, InputError,
                   in.where(block_at) << ": element entity block " << b + 1 << " declares "
                                      << in_block << " elements, but only "
                                      << n_elements - n_read << " of the " << n_elements
                                      << header() << " are left");
        const std::size_t values = 1 + static_cast<std::size_t>(n_nodes);
        in.require(in_block, 8 * values, [&] {
            return std::to_string(in_block) + " elements of type " + std::to_string(type) +
                   " in the block at byte " + std::to_string(block_at);
        });
        if (in_block > 0)
            refuse_other_volume_element(type, dim, in.where(block_at));
        if (type == MSH_TET4)
            builder.reserve_elements(in_block);
        for (std::uint64_t e = 0; e < in_block; ++e) {
            const std::size_t at = in.pos();
            if (type != MSH_TET4) {
                for (std::size_t k = 0; k < values; ++k)
                    in.raw<std::uint64_t>();
                continue;
            }
            const auto tag = in.raw<std::uint64_t>();
            std::array<std::uint64_t, 4> nodes{};
            for (auto& node : nodes)
                node = in.raw<std::uint64_t>();
            builder.add_tet([&] { return in.where(at); }, static_cast<long>(at), tag, nodes);
        }
        n_read += in_block;
    }
    CORO_CHECK(n_read == n_elements, InputError,
               in.where() << ": expected " << n_elements << " elements as declared at byte "
                          << header_at << ", found " << n_read << " in the blocks");
    expect_line(in, "$EndElements", "the element entity blocks declared at byte " +
                                        std::to_string(header_at));
}

} // namespace

TetMesh read_msh_binary(const std::string& path, std::string_view data)
{
    ByteReader in(path, data);
    const Version version = read_format(in);
    MshBuilder builder("byte", data.size());
    std::size_t nodes_at = 0;
    std::size_t elements_at = 0;
    std::string_view line;
    while (in.line(line)) {
        const std::size_t at = in.line_start();
        CORO_CHECK(line.front() == '$', InputError,
                   in.where(at) << ": expected a section such as $Nodes or $Elements, found "
                                << in_quotes(line));
        if (line == "$Nodes") {
            CORO_CHECK(nodes_at == 0, InputError,
                       in.where(at) << ": expected one $Nodes section, found a second one (the "
                                       "first is at byte "
                                    << nodes_at << ")");
            nodes_at = at;
            if (version == Version::V22)
                read_nodes_v22(in, builder);
            else
                read_nodes_v41(in, builder);
        } else if (line == "$Elements") {
            CORO_CHECK(elements_at == 0, InputError,
                       in.where(at) << ": expected one $Elements section, found a second one "
                                       "(the first is at byte "
                                    << elements_at << ")");
            CORO_CHECK(nodes_at != 0, InputError,
                       in.where(at) << ": expected $Nodes before $Elements, found $Elements "
                                       "first");
            elements_at = at;
            if (version == Version::V22)
                read_elements_v22(in, builder);
            else
                read_elements_v41(in, builder);
        } else if (line == "$MeshFormat" || (line.size() >= 4 && line.substr(0, 4) == "$End")) {
            CORO_THROW(InputError, in.where(at) << ": expected a section start such as $Nodes, "
                                                   "found "
                                                << in_quotes(line));
        } else {
            const std::string end_marker = "$End" + std::string(line.substr(1));
            CORO_CHECK(in.skip_past_line(end_marker), InputError,
                       in.where(at) << ": expected " << end_marker << " closing "
                                    << in_quotes(line) << ", found end of file");
        }
    }
    return builder.finish([&](long at) { return in.where(static_cast<std::size_t>(at)); });
}

} // namespace coro::detail
