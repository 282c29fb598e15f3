#include <corocontact/io/surface_readers.hpp>

#include "detail/text_input.hpp"

#include <corocontact/core/atomic_file.hpp>
#include <corocontact/core/error.hpp>

#include <algorithm>
#include <array>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <optional>
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
using detail::read_file;
using detail::trimmed;

/// Lines with `#` comments removed (OBJ, OFF).
class LineCursor : public detail::LineCursor {
public:
    LineCursor(std::string path, std::string_view text) : detail::LineCursor(std::move(path), text, true) {}
};

/// Upper bound on what a count read from a file may pre-allocate: beyond this, containers
/// grow as items are actually read, so a corrupt header cannot request gigabytes.
constexpr std::size_t RESERVE_CAP = std::size_t{1} << 16;

/// Largest vertex count a 32-bit Index can address.
constexpr std::uint64_t MAX_VERTICES =
    static_cast<std::uint64_t>(std::numeric_limits<Index>::max());

/// Binary STL layout: an 80-byte header, a uint32 triangle count, then per triangle a normal
/// and three vertices (12 little-endian floats) and a uint16 attribute.
constexpr std::size_t STL_HEADER_BYTES = 80;
constexpr std::size_t STL_PREFIX_BYTES = 84;
constexpr std::size_t STL_RECORD_BYTES = 50;

/// Polygons up to this many corners are checked for repeated vertices pairwise.
constexpr std::size_t PAIRWISE_CHECK_MAX = 16;

bool is_space(char c) { return is_blank(c) || c == '\n'; }

char lower(char c) { return static_cast<char>(std::tolower(static_cast<unsigned char>(c))); }

/// Case-insensitive comparison with a lower-case keyword.
bool is_keyword(std::string_view token, std::string_view keyword)
{
    if (token.size() != keyword.size())
        return false;
    for (std::size_t i = 0; i < token.size(); ++i)
        if (lower(token[i]) != keyword[i])
            return false;
    return true;
}

/// Parses a whole token as a double; false if it is not a number. Accepts a leading '+'.
bool parse_double(std::string_view token, double& value)
{
    if (token.size() > 1 && token.front() == '+' && token[1] != '-')
        token.remove_prefix(1); // from_chars rejects the '+' that printf-style writers emit
    const auto [end, ec] = std::from_chars(token.data(), token.data() + token.size(), value);
    return ec == std::errc() && end == token.data() + token.size();
}

/// Parses a whole token as an integer of type T.
template <class T> std::errc parse_integer(std::string_view token, T& value)
{
    if (token.size() > 1 && token.front() == '+' && token[1] != '-')
        token.remove_prefix(1);
    const auto [end, ec] = std::from_chars(token.data(), token.data() + token.size(), value);
    if (ec != std::errc())
        return ec;
    return end == token.data() + token.size() ? std::errc() : std::errc::invalid_argument;
}

/// Whitespace-separated tokens of one line.
class Tokens : public detail::LineTokens {
public:
    using LineTokens::LineTokens;

    /// A finite double.
    double next_double(std::string_view what)
    {
        const std::string_view token = next(what);
        double value = 0.0;
        const bool ok = parse_double(token, value);
        CORO_CHECK(ok && std::isfinite(value), InputError,
                   cursor().where() << ": expected " << what << " (a finite number), found "
                                    << in_quotes(token));
        return value;
    }

    /// A non-negative integer (counts, 0-based indices).
    std::uint64_t next_count(std::string_view what)
    {
        const std::string_view token = next(what);
        std::uint64_t value = 0;
        const std::errc ec = parse_integer(token, value);
        CORO_CHECK(ec != std::errc::result_out_of_range, InputError,
                   cursor().where() << ": expected " << what << ", found " << in_quotes(token)
                                    << " (too large)");
        CORO_CHECK(ec == std::errc(), InputError,
                   cursor().where() << ": expected " << what << " (a non-negative integer), found "
                                    << in_quotes(token));
        return value;
    }
};

/// Vertices and triangles as they are read; polygons are checked and fan-triangulated.
class SurfaceBuilder {
public:
    Index num_vertices() const { return static_cast<Index>(m_vertices.size() / 3); }

    void reserve(std::uint64_t vertices, std::uint64_t faces)
    {
        m_vertices.reserve(
            3 * static_cast<std::size_t>(std::min<std::uint64_t>(vertices, RESERVE_CAP)));
        m_faces.reserve(3 * static_cast<std::size_t>(std::min<std::uint64_t>(faces, RESERVE_CAP)));
    }

    /// Appends a vertex; `where()` ("path:line", or the triangle of a binary STL) is only
    /// called for the message.
    template <class Where> void add_vertex(const std::array<double, 3>& x, const Where& where)
    {
        CORO_CHECK(m_vertices.size() / 3 < MAX_VERTICES, InputError,
                   where() << ": too many vertices for a 32-bit index (at most " << MAX_VERTICES
                           << ")");
        m_vertices.insert(m_vertices.end(), x.begin(), x.end());
    }

    /// Appends polygon `corners` (absolute 0-based indices, already range-checked) as a fan of
    /// triangles, after checking that no vertex repeats. `file_base` is added to indices in
    /// the message (1 for OBJ), `cursor` names the line and `face` the polygon's ordinal.
    void add_polygon(const std::vector<Index>& corners, const LineCursor& cursor,
                     std::uint64_t face, Index file_base)
    {
        CORO_ASSERT(corners.size() >= 3);
        if (const auto repeated = find_repeat(corners))
            CORO_THROW(InputError, cursor.where()
                                       << ": face " << face << " repeats vertex "
                                       << corners[repeated->first] + file_base << " (corners "
                                       << repeated->first + 1 << " and " << repeated->second + 1
                                       << "), expected distinct vertices");
        for (std::size_t k = 1; k + 1 < corners.size(); ++k)
            m_faces.insert(m_faces.end(), {corners[0], corners[k], corners[k + 1]});
    }

    /// Appends a triangle without checks (STL: the caller checks).
    void add_triangle(const std::array<Index, 3>& corners)
    {
        m_faces.insert(m_faces.end(), corners.begin(), corners.end());
    }

    std::size_t num_faces() const { return m_faces.size() / 3; }

    SurfaceMesh finish() const
    {
        SurfaceMesh surface;
        surface.vertices = Eigen::Map<const Positions>(
            m_vertices.data(), static_cast<Eigen::Index>(m_vertices.size() / 3), 3);
        surface.faces = Eigen::Map<const Tris>(m_faces.data(),
                                               static_cast<Eigen::Index>(m_faces.size() / 3), 3);
        return surface;
    }

private:
    /// Positions (0-based) of a repeated corner pair, the one whose second corner comes
    /// first; none if all corners differ.
    static std::optional<std::pair<std::size_t, std::size_t>>
    find_repeat(const std::vector<Index>& corners)
    {
        if (corners.size() <= PAIRWISE_CHECK_MAX) {
            for (std::size_t j = 1; j < corners.size(); ++j)
                for (std::size_t i = 0; i < j; ++i)
                    if (corners[i] == corners[j])
                        return std::make_pair(i, j);
            return std::nullopt;
        }
        std::vector<std::pair<Index, std::size_t>> sorted; // (vertex, corner)
        sorted.reserve(corners.size());
        for (std::size_t i = 0; i < corners.size(); ++i)
            sorted.emplace_back(corners[i], i);
        std::sort(sorted.begin(), sorted.end());
        std::optional<std::pair<std::size_t, std::size_t>> best;
        for (std::size_t k = 1; k < sorted.size(); ++k)
            if (sorted[k].first == sorted[k - 1].first &&
                (!best || sorted[k].second < best->second))
                best = std::make_pair(sorted[k - 1].second, sorted[k].second);
        return best;
    }

    std::vector<double> m_vertices; // 3 per vertex
    std::vector<Index> m_faces;     // 3 per triangle
};

// ---------------------------------------------------------------------------------------------
// OBJ

/// Statements that carry no triangle geometry: read past without parsing.
/// (Texture and normal data, groups, materials, line and point elements, free-form geometry.)
constexpr std::array<std::string_view, 35> OBJ_IGNORED = {
    "vt",     "vn",     "vp",     "g",          "o",         "s",        "usemtl",
    "mtllib", "l",      "p",      "cstype",     "deg",       "bmat",     "step",
    "curv",   "curv2",  "surf",   "parm",       "trim",      "hole",     "scrv",
    "sp",     "end",    "con",    "mg",         "bevel",     "c_interp", "d_interp",
    "lod",    "maplib", "usemap", "shadow_obj", "trace_obj", "ctech",    "stech"};

bool obj_ignored(std::string_view keyword)
{
    return std::find(OBJ_IGNORED.begin(), OBJ_IGNORED.end(), keyword) != OBJ_IGNORED.end();
}

/// A face corner that refers to a vertex not yet defined when the face was read.
struct ForwardReference {
    long line;
    std::uint64_t face;
    std::int64_t index; // as written, 1-based
};

/// Reads one corner `i`, `i/t`, `i//n` or `i/t/n`; returns the 0-based vertex index, or -1
/// for a forward reference (recorded in `forward`).
Index read_obj_corner(std::string_view token, const LineCursor& cursor, std::uint64_t face,
                      Index n_defined, std::vector<ForwardReference>& forward)
{
    const std::size_t slash = token.find('/');
    const std::string_view vertex = token.substr(0, slash);
    if (slash != std::string_view::npos) {
        // Texture and normal indices are ignored, but must be integers (or empty: i//n).
        std::string_view rest = token.substr(slash + 1);
        const std::size_t second = rest.find('/');
        const std::string_view texture = rest.substr(0, second);
        const std::string_view normal =
            second == std::string_view::npos ? std::string_view() : rest.substr(second + 1);
        std::int64_t ignored = 0;
        const bool ok = (texture.empty() || parse_integer(texture, ignored) == std::errc()) &&
                        (normal.empty() || parse_integer(normal, ignored) == std::errc()) &&
                        !(texture.empty() && second == std::string_view::npos);
        CORO_CHECK(ok, InputError,
                   cursor.where() << ": expected a face corner 'v', 'v/vt', 'v//vn' or "
                                     "'v/vt/vn' with integer indices, found "
                                  << in_quotes(token));
    }
    std::int64_t index = 0;
    const std::errc ec = parse_integer(vertex, index);
    CORO_CHECK(ec == std::errc(), InputError,
               cursor.where() << ": expected a vertex index (an integer, optionally followed by "
                                 "/vt/vn) in face "
                              << face << ", found " << in_quotes(token));
    const auto expected_range = [n_defined] {
        return n_defined == 0 ? std::string("a vertex defined later (none so far)")
                              : "1.." + std::to_string(n_defined) + " or -" +
                                    std::to_string(n_defined) + "..-1";
    };
    CORO_CHECK(index != 0, InputError,
               cursor.where() << ": face " << face << " has vertex index 0, expected "
                              << expected_range()
                              << " (OBJ indices start at 1; negative ones count back from the "
                                 "last vertex)");
    if (index < 0) {
        CORO_CHECK(index >= -std::int64_t{n_defined}, InputError,
                   cursor.where() << ": face " << face << " has relative vertex index " << index
                                  << ", expected "
                                  << (n_defined == 0 ? std::string("a vertex defined before it")
                                                     : "-" + std::to_string(n_defined) + "..-1")
                                  << " (" << n_defined << " vertices defined so far)");
        return static_cast<Index>(n_defined + index);
    }
    CORO_CHECK(static_cast<std::uint64_t>(index) <= MAX_VERTICES, InputError,
               cursor.where() << ": face " << face << " has vertex index " << index
                              << ", expected at most " << MAX_VERTICES << " (32-bit indices)");
    if (index > n_defined)
        forward.push_back({cursor.line(), face, index}); // checked once every vertex is known
    return static_cast<Index>(index - 1);
}

SurfaceMesh read_obj(const std::filesystem::path& path, std::string_view text)
{
    LineCursor cursor(path.string(), text);
    SurfaceBuilder builder;
    std::vector<ForwardReference> forward;
    std::vector<Index> corners;
    std::uint64_t n_polygons = 0;
    std::string_view line;
    while (cursor.next(line)) {
        Tokens tokens(line, cursor);
        const std::string_view keyword = tokens.next("an OBJ statement");
        if (keyword == "v") {
            CORO_CHECK(line.back() != '\\', InputError,
                       cursor.where() << ": line continuation ('\\' at the end of a line) is "
                                         "not supported, expected 'v x y z' on one line");
            const std::array<double, 3> x{tokens.next_double("vertex x coordinate"),
                                          tokens.next_double("vertex y coordinate"),
                                          tokens.next_double("vertex z coordinate")};
            // Optional w, or the r g b [a] of the vertex-colour extension: read and dropped.
            const std::size_t extra = tokens.remaining();
            CORO_CHECK(extra <= 4, InputError,
                       cursor.where() << ": expected 'v x y z' with at most 4 further values "
                                         "(w or a colour), found "
                                      << 3 + extra << " values");
            for (std::size_t k = 0; k < extra; ++k)
                tokens.next_double("vertex weight or colour value");
            builder.add_vertex(x, [&] { return cursor.where(); });
        } else if (keyword == "f" || keyword == "fo") {
            CORO_CHECK(line.back() != '\\', InputError,
                       cursor.where() << ": line continuation ('\\' at the end of a line) is "
                                         "not supported, expected a face on one line");
            ++n_polygons;
            const std::size_t n = tokens.remaining();
            CORO_CHECK(n >= 3, InputError,
                       cursor.where() << ": face " << n_polygons << " has " << n
                                      << " vertices, expected at least 3");
            corners.clear();
            const Index n_defined = builder.num_vertices();
            for (std::size_t k = 0; k < n; ++k)
                corners.push_back(read_obj_corner(tokens.next("a face corner"), cursor, n_polygons,
                                                  n_defined, forward));
            builder.add_polygon(corners, cursor, n_polygons, 1);
        } else if (!obj_ignored(keyword)) {
            CORO_THROW(InputError,
                       cursor.where()
                           << ": expected an OBJ statement (v, f, vt, vn, g, o, s, usemtl, "
                              "mtllib, ...), found "
                           << in_quotes(keyword));
        }
    }
    const Index n_vertices = builder.num_vertices();
    for (const ForwardReference& ref : forward)
        CORO_CHECK(ref.index <= n_vertices, InputError,
                   path.string() << ":" << ref.line << ": face " << ref.face << " has vertex index "
                                 << ref.index << ", expected 1.." << n_vertices
                                 << " (the file defines " << n_vertices << " vertices)");
    CORO_CHECK(builder.num_faces() > 0, InputError,
               path.string() << ": expected at least one face ('f' line), found none in "
                             << cursor.line() << " lines");
    return builder.finish();
}

// ---------------------------------------------------------------------------------------------
// OFF

/// Extra values on each vertex line that an OFF header keyword announces.
struct OffVertexExtras {
    bool plain = true;   // "OFF": tolerate 0, 3 or 4 (colours written without saying COFF)
    int fixed = 0;       // ST: 2 texture coordinates, N: 3 normal components
    bool colour = false; // C: 3 or 4 colour values

    bool allows(std::size_t n) const
    {
        if (plain)
            return n == 0 || n == 3 || n == 4;
        const auto base = static_cast<std::size_t>(fixed);
        return colour ? (n == base + 3 || n == base + 4) : n == base;
    }

    std::string describe() const
    {
        if (plain)
            return "0, 3 or 4 (a colour)";
        if (!colour)
            return std::to_string(fixed);
        return std::to_string(fixed + 3) + " or " + std::to_string(fixed + 4);
    }
};

/// Parses a header keyword [ST][C][N]OFF; false if `token` is not one.
bool parse_off_keyword(std::string_view token, OffVertexExtras& extras, const LineCursor& cursor)
{
    if (token.size() < 3 || token.substr(token.size() - 3) != "OFF")
        return false;
    std::string_view prefix = token.substr(0, token.size() - 3);
    extras = OffVertexExtras{};
    extras.plain = prefix.empty();
    if (prefix.substr(0, 2) == "ST") {
        extras.fixed += 2;
        prefix.remove_prefix(2);
    }
    if (!prefix.empty() && prefix.front() == 'C') {
        extras.colour = true;
        prefix.remove_prefix(1);
    }
    if (!prefix.empty() && prefix.front() == 'N') {
        extras.fixed += 3;
        prefix.remove_prefix(1);
    }
    CORO_CHECK(prefix.empty(), InputError,
               cursor.where() << ": unsupported OFF variant " << in_quotes(token)
                              << ", expected OFF, COFF, NOFF, CNOFF or STOFF (3-D vertices)");
    return true;
}

SurfaceMesh read_off(const std::filesystem::path& path, std::string_view text)
{
    LineCursor cursor(path.string(), text);
    std::string_view line;
    const bool has_first = cursor.next(line);
    CORO_CHECK(has_first, InputError,
               cursor.where() << ": expected the OFF header, found an empty file");

    OffVertexExtras extras;
    Tokens first(line, cursor);
    const std::string_view keyword = first.next("the OFF header");
    const bool has_keyword = parse_off_keyword(keyword, extras, cursor);
    CORO_CHECK(has_keyword || std::isdigit(static_cast<unsigned char>(keyword.front())), InputError,
               cursor.where() << ": expected the OFF header ('OFF') or the counts '#vertices "
                                 "#faces #edges', found "
                              << in_quotes(line));
    if (has_keyword && first.empty()) {
        const bool has_counts = cursor.next(line);
        CORO_CHECK(has_counts, InputError,
                   cursor.where() << ": expected the counts '#vertices #faces #edges' after the "
                                     "OFF header, found end of file");
    } else if (has_keyword) {
        line = trimmed(line.substr(keyword.size())); // counts on the header line
        CORO_CHECK(!is_keyword(line.substr(0, 6), "binary"), InputError,
                   cursor.where() << ": binary OFF is not supported, expected ASCII OFF");
    }
    Tokens counts(line, cursor);
    const long counts_line = cursor.line();
    const std::uint64_t n_vertices = counts.next_count("the number of vertices");
    const std::uint64_t n_faces = counts.next_count("the number of faces");
    if (!counts.empty())
        counts.next_count("the number of edges");
    counts.expect_end("the counts '#vertices #faces #edges'");
    CORO_CHECK(n_vertices <= MAX_VERTICES, InputError,
               cursor.where() << ": " << n_vertices << " vertices declared, expected at most "
                              << MAX_VERTICES << " (32-bit indices)");

    SurfaceBuilder builder;
    builder.reserve(n_vertices, n_faces); // capped: the counts are only trusted as lines arrive
    for (std::uint64_t i = 0; i < n_vertices; ++i) {
        const bool has_vertex = cursor.next(line);
        CORO_CHECK(has_vertex, InputError,
                   cursor.where() << ": expected vertex " << i + 1 << " of " << n_vertices
                                  << " declared at line " << counts_line
                                  << " ('x y z'), found end of file");
        Tokens tokens(line, cursor);
        const std::array<double, 3> x{tokens.next_double("vertex x coordinate"),
                                      tokens.next_double("vertex y coordinate"),
                                      tokens.next_double("vertex z coordinate")};
        const std::size_t extra = tokens.remaining();
        CORO_CHECK(extras.allows(extra), InputError,
                   cursor.where() << ": expected 'x y z' followed by " << extras.describe()
                                  << " values for vertex " << i + 1 << ", found " << extra
                                  << " more");
        for (std::size_t k = 0; k < extra; ++k)
            tokens.next_double("a vertex colour, normal or texture value");
        builder.add_vertex(x, [&] { return cursor.where(); });
    }

    std::vector<Index> corners;
    for (std::uint64_t f = 0; f < n_faces; ++f) {
        const bool has_face = cursor.next(line);
        CORO_CHECK(has_face, InputError,
                   cursor.where() << ": expected face " << f + 1 << " of " << n_faces
                                  << " declared at line " << counts_line
                                  << " ('n i0 i1 ...'), found end of file");
        Tokens tokens(line, cursor);
        const std::uint64_t n = tokens.next_count("the number of face vertices");
        CORO_CHECK(n >= 3, InputError,
                   cursor.where() << ": face " << f + 1 << " has " << n
                                  << " vertices, expected at least 3");
        const std::size_t available = tokens.remaining();
        CORO_CHECK(n <= available, InputError,
                   cursor.where() << ": face " << f + 1 << " declares " << n << " vertices, found "
                                  << available << " values");
        corners.clear();
        for (std::uint64_t k = 0; k < n; ++k) {
            const std::uint64_t index = tokens.next_count("a vertex index");
            CORO_CHECK(index < n_vertices, InputError,
                       cursor.where()
                           << ": face " << f + 1 << " has vertex index " << index << ", expected "
                           << (n_vertices == 0 ? std::string("none (the file declares "
                                                             "no vertices)")
                                               : "0.." + std::to_string(n_vertices - 1))
                           << " (" << n_vertices << " vertices)");
            corners.push_back(static_cast<Index>(index));
        }
        const std::size_t colour = tokens.remaining();
        CORO_CHECK(colour <= 4, InputError,
                   cursor.where() << ": expected at most 4 colour values after the " << n
                                  << " vertex indices of face " << f + 1 << ", found " << colour
                                  << " values");
        for (std::size_t k = 0; k < colour; ++k)
            tokens.next_double("a face colour value");
        builder.add_polygon(corners, cursor, f + 1, 0);
    }
    if (cursor.next(line))
        CORO_THROW(InputError, cursor.where() << ": expected end of file after the " << n_faces
                                              << " faces declared at line " << counts_line
                                              << ", found " << in_quotes(line));
    CORO_CHECK(builder.num_faces() > 0, InputError,
               path.string() << ":" << counts_line
                             << ": expected at least one face, found a count of 0");
    return builder.finish();
}

// ---------------------------------------------------------------------------------------------
// STL

/// Corners with identical coordinates become one vertex, numbered in order of appearance.
class VertexMerger {
public:
    explicit VertexMerger(std::size_t expected) { m_index.reserve(expected); }

    /// Index of the vertex at `x`, appending it to `builder` if new.
    template <class Where>
    Index add(const std::array<double, 3>& x, SurfaceBuilder& builder, const Where& where)
    {
        // -0.0 == +0.0 as doubles, so both must hash alike.
        const Key key{x[0] == 0.0 ? 0.0 : x[0], x[1] == 0.0 ? 0.0 : x[1], x[2] == 0.0 ? 0.0 : x[2]};
        const auto [it, inserted] = m_index.try_emplace(key, builder.num_vertices());
        if (inserted)
            builder.add_vertex(x, where);
        return it->second;
    }

private:
    struct Key {
        double x, y, z;
        bool operator==(const Key& o) const { return x == o.x && y == o.y && z == o.z; }
    };
    struct KeyHash {
        static std::uint64_t bits(double v)
        {
            std::uint64_t b = 0;
            std::memcpy(&b, &v, sizeof b);
            return b;
        }
        static std::uint64_t mix(std::uint64_t h) // splitmix64 finaliser
        {
            h ^= h >> 30U;
            h *= 0xbf58476d1ce4e5b9ULL;
            h ^= h >> 27U;
            h *= 0x94d049bb133111ebULL;
            return h ^ (h >> 31U);
        }
        std::size_t operator()(const Key& k) const
        {
            return static_cast<std::size_t>(mix(bits(k.x) ^ mix(bits(k.y) ^ mix(bits(k.z)))));
        }
    };
    std::unordered_map<Key, Index, KeyHash> m_index;
};

using Triangle = std::array<std::array<double, 3>, 3>;

/// Checks that a merged STL triangle has three distinct vertices; `where()` names it.
template <class Where>
void check_stl_triangle(const std::array<Index, 3>& corners, const Triangle& x, const Where& where)
{
    for (std::size_t j = 1; j < 3; ++j)
        for (std::size_t i = 0; i < j; ++i)
            CORO_CHECK(corners[i] != corners[j], InputError,
                       where() << " repeats the vertex (" << x[i][0] << ", " << x[i][1] << ", "
                               << x[i][2] << ") at corners " << i + 1 << " and " << j + 1
                               << ", expected three distinct vertices");
}

std::uint32_t load_u32(const char* p)
{
    std::array<unsigned char, 4> b{};
    std::memcpy(b.data(), p, 4);
    return static_cast<std::uint32_t>(b[0]) | static_cast<std::uint32_t>(b[1]) << 8U |
           static_cast<std::uint32_t>(b[2]) << 16U | static_cast<std::uint32_t>(b[3]) << 24U;
}

float load_f32(const char* p)
{
    const std::uint32_t bits = load_u32(p);
    float value = 0.0F;
    std::memcpy(&value, &bits, sizeof value);
    return value;
}

/// Binary STL whose size has been checked: exactly 84 + 50·count bytes.
SurfaceMesh read_binary_stl(const std::filesystem::path& path, std::string_view bytes)
{
    const std::uint32_t count = load_u32(bytes.data() + STL_HEADER_BYTES);
    CORO_ASSERT(STL_PREFIX_BYTES + STL_RECORD_BYTES * std::uint64_t{count} == bytes.size());
    CORO_CHECK(count > 0, InputError,
               path.string() << ": binary STL header (byte offset 80) declares 0 triangles, "
                                "expected at least one face");
    const auto triangle = [&](std::uint32_t t, std::size_t offset) {
        return path.string() + ": triangle " + std::to_string(t + 1) + " of " +
               std::to_string(count) + " (byte offset " + std::to_string(offset) + ")";
    };
    SurfaceBuilder builder;
    builder.reserve(count / 2 + 3, count);
    VertexMerger merger(count / 2 + 3); // a closed surface has about count/2 vertices
    for (std::uint32_t t = 0; t < count; ++t) {
        const std::size_t record = STL_PREFIX_BYTES + STL_RECORD_BYTES * t;
        Triangle x{};
        std::array<Index, 3> corners{};
        for (std::size_t k = 0; k < 3; ++k) {
            const std::size_t offset = record + 12 + 12 * k; // the normal comes first
            for (std::size_t d = 0; d < 3; ++d) {
                const float value = load_f32(bytes.data() + offset + 4 * d);
                CORO_CHECK(std::isfinite(value), InputError,
                           triangle(t, offset + 4 * d)
                               << ": vertex " << k + 1 << " coordinate "
                               << "xyz"[d] << " is " << value << ", expected a finite number");
                x[k][d] = static_cast<double>(value);
            }
            corners[k] = merger.add(x[k], builder, [&] { return triangle(t, offset); });
        }
        check_stl_triangle(corners, x, [&] { return triangle(t, record); });
        builder.add_triangle(corners);
    }
    return builder.finish();
}

/// Whitespace-separated tokens of an ASCII STL, across lines, with line numbers.
class StlScanner {
public:
    StlScanner(std::string path, std::string_view text) : m_path(std::move(path)), m_text(text) {}

    /// The next token, or an empty view at the end of the text.
    std::string_view next()
    {
        long newlines = 0;
        while (m_pos < m_text.size() && is_space(m_text[m_pos])) {
            newlines += m_text[m_pos] == '\n' ? 1 : 0;
            ++m_pos;
        }
        if (m_pos == m_text.size() && newlines > 0 && m_text.back() == '\n')
            --newlines; // at the end, name the last line rather than the empty one after it
        m_line += newlines;
        const std::size_t start = m_pos;
        while (m_pos < m_text.size() && !is_space(m_text[m_pos]))
            ++m_pos;
        return m_text.substr(start, m_pos - start);
    }

    /// Requires the next token to be `keyword` (case-insensitive); `context()` is streamed
    /// into the message.
    template <class Context> void expect(std::string_view keyword, const Context& context)
    {
        const std::string_view token = next();
        CORO_CHECK(is_keyword(token, keyword), InputError,
                   where() << ": expected '" << keyword << "' " << context() << ", found "
                           << found(token));
    }

    /// The next token as a double; `finite` requires a finite value.
    double number(std::string_view what, bool finite)
    {
        const std::string_view token = next();
        double value = 0.0;
        const bool ok = parse_double(token, value) && (!finite || std::isfinite(value));
        CORO_CHECK(ok, InputError,
                   where() << ": expected " << what << (finite ? " (a finite number)" : "")
                           << ", found " << found(token));
        return value;
    }

    /// Skips the rest of the current line (a solid's name).
    void skip_line()
    {
        while (m_pos < m_text.size() && m_text[m_pos] != '\n')
            ++m_pos;
    }

    long line() const { return m_line; }

    std::string where() const { return m_path + ":" + std::to_string(m_line); }

    static std::string found(std::string_view token)
    {
        return token.empty() ? std::string("end of file") : in_quotes(token);
    }

private:
    std::string m_path;
    std::string_view m_text;
    std::size_t m_pos = 0;
    long m_line = 1;
};

SurfaceMesh read_ascii_stl(const std::filesystem::path& path, std::string_view text)
{
    StlScanner scanner(path.string(), text);
    SurfaceBuilder builder;
    VertexMerger merger(std::min<std::size_t>(text.size() / 500, RESERVE_CAP));
    const auto where = [&] { return scanner.where(); };
    scanner.expect("solid", [] { return "at the start of an ASCII STL file"; });
    scanner.skip_line(); // the solid's name
    std::uint64_t n_facets = 0;
    for (;;) {
        std::string_view token = scanner.next();
        if (is_keyword(token, "endsolid")) {
            scanner.skip_line();
            token = scanner.next();
            if (token.empty())
                break;
            CORO_CHECK(is_keyword(token, "solid"), InputError,
                       scanner.where() << ": expected 'solid' or end of file after 'endsolid', "
                                          "found "
                                       << in_quotes(token));
            scanner.skip_line();
            continue;
        }
        CORO_CHECK(is_keyword(token, "facet"), InputError,
                   scanner.where()
                       << ": expected 'facet' or 'endsolid', found " << StlScanner::found(token));
        ++n_facets;
        const long facet_line = scanner.line();
        scanner.expect("normal", [] { return "after 'facet'"; });
        for (int d = 0; d < 3; ++d)
            scanner.number("a facet normal component", false); // ignored, may be nan
        scanner.expect("outer", [] { return "after the facet normal"; });
        scanner.expect("loop", [] { return "after 'outer'"; });
        Triangle x{};
        std::array<Index, 3> corners{};
        for (std::size_t k = 0; k < 3; ++k) {
            scanner.expect("vertex", [&] {
                return "(vertex " + std::to_string(k + 1) + " of 3 of facet " +
                       std::to_string(n_facets) + ")";
            });
            x[k] = {scanner.number("vertex x coordinate", true),
                    scanner.number("vertex y coordinate", true),
                    scanner.number("vertex z coordinate", true)};
            corners[k] = merger.add(x[k], builder, where);
        }
        scanner.expect("endloop", [] { return "after the 3 vertices of a facet"; });
        scanner.expect("endfacet", [] { return "after 'endloop'"; });
        check_stl_triangle(corners, x, [&] {
            return path.string() + ":" + std::to_string(facet_line) + ": facet " +
                   std::to_string(n_facets);
        });
        builder.add_triangle(corners);
    }
    CORO_CHECK(n_facets > 0, InputError,
               scanner.where() << ": expected at least one facet in the ASCII STL, found none");
    return builder.finish();
}

/// True if the text starts (after blanks) with "solid" and holds no control characters
/// other than whitespace: an ASCII STL. Binary STL data almost always has NUL bytes.
bool looks_like_ascii_stl(std::string_view bytes)
{
    std::size_t start = 0;
    while (start < bytes.size() && is_space(bytes[start]))
        ++start;
    if (!is_keyword(bytes.substr(start, 5), "solid"))
        return false;
    return std::none_of(bytes.begin(), bytes.end(), [](char c) {
        const auto u = static_cast<unsigned char>(c);
        return (u < 0x20 && !is_space(c)) || u == 0x7f;
    });
}

SurfaceMesh read_stl(const std::filesystem::path& path, const std::string& bytes)
{
    // An exact size match is decisive, even for a header that starts with "solid": for an
    // ASCII file, bytes 80..83 are text, a count ≥ 0x09090909, so it would need > 7 GB.
    if (bytes.size() >= STL_PREFIX_BYTES) {
        const std::uint64_t count = load_u32(bytes.data() + STL_HEADER_BYTES);
        if (STL_PREFIX_BYTES + STL_RECORD_BYTES * count == bytes.size())
            return read_binary_stl(path, bytes);
    }
    if (looks_like_ascii_stl(bytes))
        return read_ascii_stl(path, bytes);
    CORO_CHECK(bytes.size() >= STL_PREFIX_BYTES, InputError,
               path.string() << ": expected an ASCII STL (starting with 'solid') or a binary STL "
                                "(at least 84 bytes), found "
                             << bytes.size() << " bytes");
    const std::uint64_t count = load_u32(bytes.data() + STL_HEADER_BYTES);
    CORO_THROW(InputError, path.string() << ": binary STL header (byte offset 80) declares "
                                         << count << " triangles, which take 84 + 50 x " << count
                                         << " = " << STL_PREFIX_BYTES + STL_RECORD_BYTES * count
                                         << " bytes, but the file has " << bytes.size()
                                         << " bytes (truncated, or not an STL file)");
}
// ---------------------------------------------------------------------------------------------
// Writers

class TextOut {
public:
    void number(double value)
    {
        // Shortest representation that reads back to the same double (round trip exact).
        const auto result =
            std::to_chars(m_buffer.data(), m_buffer.data() + m_buffer.size(), value);
        m_out.append(m_buffer.data(), result.ptr);
    }
    void number(long long value)
    {
        const auto result =
            std::to_chars(m_buffer.data(), m_buffer.data() + m_buffer.size(), value);
        m_out.append(m_buffer.data(), result.ptr);
    }
    TextOut& operator<<(std::string_view text)
    {
        m_out += text;
        return *this;
    }
    TextOut& operator<<(char c)
    {
        m_out += c;
        return *this;
    }
    void reserve(std::size_t n) { m_out.reserve(n); }
    const std::string& str() const { return m_out; }

private:
    std::string m_out;
    std::array<char, 64> m_buffer{};
};

void assert_valid(const SurfaceMesh& surface)
{
#ifndef NDEBUG
    for (Eigen::Index i = 0; i < surface.faces.size(); ++i)
        CORO_ASSERT(surface.faces.data()[i] >= 0 &&
                    surface.faces.data()[i] < surface.vertices.rows());
#else
    (void)surface;
#endif
}

Vec3 unit_normal(const SurfaceMesh& surface, Index f)
{
    const Vec3 x0 = surface.vertices.row(surface.faces(f, 0)).transpose();
    const Vec3 x1 = surface.vertices.row(surface.faces(f, 1)).transpose();
    const Vec3 x2 = surface.vertices.row(surface.faces(f, 2)).transpose();
    const Vec3 n = (x1 - x0).cross(x2 - x0);
    const double length = n.norm();
    return length > 0.0 && std::isfinite(length) ? Vec3(n / length) : Vec3::Zero();
}

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

void write_binary_stl(const std::filesystem::path& path, const SurfaceMesh& surface)
{
    const auto n_faces = static_cast<std::uint64_t>(surface.faces.rows());
    CORO_CHECK(n_faces <= std::numeric_limits<std::uint32_t>::max(), InputError,
               path.string() << ": " << n_faces << " faces do not fit in a binary STL count");
    std::string out;
    out.reserve(STL_PREFIX_BYTES + STL_RECORD_BYTES * n_faces);
    std::string header = "binary STL written by corocontact";
    header.resize(STL_HEADER_BYTES, ' ');
    out += header;
    put_u32(out, static_cast<std::uint32_t>(n_faces));
    constexpr double FLOAT_MAX = std::numeric_limits<float>::max();
    for (Index v = 0; v < surface.vertices.rows(); ++v)
        for (int d = 0; d < 3; ++d)
            CORO_CHECK(std::abs(surface.vertices(v, d)) <= FLOAT_MAX, InputError,
                       path.string() << ": vertex " << v << " coordinate "
                                     << "xyz"[d] << " = " << surface.vertices(v, d)
                                     << " does not fit in the float of binary STL");
    for (Index f = 0; f < surface.faces.rows(); ++f) {
        const Vec3 n = unit_normal(surface, f);
        for (int d = 0; d < 3; ++d)
            put_f32(out, static_cast<float>(n[d]));
        for (int k = 0; k < 3; ++k)
            for (int d = 0; d < 3; ++d)
                put_f32(out, static_cast<float>(surface.vertices(surface.faces(f, k), d)));
        out += '\0';
        out += '\0'; // attribute byte count
    }
    write_file_atomically(path, out);
}

void write_ascii_stl(const std::filesystem::path& path, const SurfaceMesh& surface)
{
    TextOut out;
    out.reserve(64 + static_cast<std::size_t>(surface.faces.rows()) * 320);
    out << "solid corocontact\n";
    for (Index f = 0; f < surface.faces.rows(); ++f) {
        const Vec3 n = unit_normal(surface, f);
        out << "facet normal";
        for (int d = 0; d < 3; ++d) {
            out << ' ';
            out.number(n[d]);
        }
        out << "\n  outer loop\n";
        for (int k = 0; k < 3; ++k) {
            out << "    vertex";
            for (int d = 0; d < 3; ++d) {
                out << ' ';
                out.number(surface.vertices(surface.faces(f, k), d));
            }
            out << '\n';
        }
        out << "  endloop\nendfacet\n";
    }
    out << "endsolid corocontact\n";
    write_file_atomically(path, out.str());
}

void append_vertices(TextOut& out, const SurfaceMesh& surface, std::string_view prefix)
{
    for (Index v = 0; v < surface.vertices.rows(); ++v) {
        out << prefix;
        for (int d = 0; d < 3; ++d) {
            if (d > 0)
                out << ' ';
            out.number(surface.vertices(v, d));
        }
        out << '\n';
    }
}

} // namespace

SurfaceMesh read_surface(const std::filesystem::path& path)
{
    std::error_code ec; // an inaccessible path is reported by read_file
    CORO_CHECK(!std::filesystem::is_directory(path, ec), InputError,
               path.string() << ": is a directory, expected a surface file");
    std::string extension = path.extension().string();
    std::transform(extension.begin(), extension.end(), extension.begin(), lower);
    CORO_CHECK(extension == ".obj" || extension == ".stl" || extension == ".off", InputError,
               path.string() << ": unsupported surface extension "
                             << (extension.empty() ? std::string("(none)") : in_quotes(extension))
                             << ", expected one of: .obj, .stl, .off");
    const std::string bytes = read_file(path, "surface file");
    if (extension == ".obj")
        return read_obj(path, bytes);
    if (extension == ".off")
        return read_off(path, bytes);
    return read_stl(path, bytes);
}

void write_obj(const std::filesystem::path& path, const SurfaceMesh& surface)
{
    assert_valid(surface);
    TextOut out;
    out.reserve(64 + static_cast<std::size_t>(surface.vertices.rows()) * 64 +
                static_cast<std::size_t>(surface.faces.rows()) * 32);
    out << "# written by corocontact\n";
    append_vertices(out, surface, "v ");
    for (Index f = 0; f < surface.faces.rows(); ++f) {
        out << 'f';
        for (int k = 0; k < 3; ++k) {
            out << ' ';
            out.number(surface.faces(f, k) + 1LL);
        }
        out << '\n';
    }
    write_file_atomically(path, out.str());
}

void write_off(const std::filesystem::path& path, const SurfaceMesh& surface)
{
    assert_valid(surface);
    TextOut out;
    out.reserve(64 + static_cast<std::size_t>(surface.vertices.rows()) * 64 +
                static_cast<std::size_t>(surface.faces.rows()) * 32);
    out << "OFF\n";
    out.number(static_cast<long long>(surface.vertices.rows()));
    out << ' ';
    out.number(static_cast<long long>(surface.faces.rows()));
    out << " 0\n";
    append_vertices(out, surface, "");
    for (Index f = 0; f < surface.faces.rows(); ++f) {
        out << '3';
        for (int k = 0; k < 3; ++k) {
            out << ' ';
            out.number(static_cast<long long>(surface.faces(f, k)));
        }
        out << '\n';
    }
    write_file_atomically(path, out.str());
}

void write_stl(const std::filesystem::path& path, const SurfaceMesh& surface, bool binary)
{
    assert_valid(surface);
    if (binary)
        write_binary_stl(path, surface);
    else
        write_ascii_stl(path, surface);
}

} // namespace coro
