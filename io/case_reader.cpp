// Case file reader: TOML (toml++) -> CaseSpec. Schema and defaults: docs/case_file.md.
//
// Every error is an InputError whose message starts with `file:line:column:` of the offending
// node (for a missing key: of the enclosing table), then names the full key (`body[1].young`),
// then says what was expected and what was found.
#include <corocontact/io/case_reader.hpp>

#include <corocontact/core/error.hpp>
#include <corocontact/core/tet_mesh.hpp>
#include <corocontact/io/block_names.hpp>

#include <toml++/toml.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iterator>
#include <limits>
#include <new>
#include <map>
#include <optional>
#include <sstream>
#include <string_view>
#include <utility>
#include <vector>

namespace coro {
namespace {

namespace fs = std::filesystem;

// ---------------------------------------------------------------------------------------------
// Schema: the keys each table accepts, in documentation order.

struct TableSchema {
    std::string_view header;                // how the table is written: "[simulation]"
    std::vector<std::string_view> keys;
};

const TableSchema ROOT_SCHEMA{"the top level", {"simulation", "solver", "contact", "body", "obstacle"}};
const TableSchema SIMULATION_SCHEMA{
    "[simulation]",
    {"name", "analysis", "dt", "steps", "load_steps", "gravity", "output_every", "output_dir"}};
const TableSchema SOLVER_SCHEMA{"[solver]",
                                {"max_iterations", "tolerance", "preconditioner", "matrix_precision",
                                 "static_tolerance", "static_max_iterations", "parts_per_thread"}};
const TableSchema CONTACT_SCHEMA{
    "[contact]", {"enabled", "mode", "stiffness", "damping", "friction", "cross_check"}};
const TableSchema BODY_SCHEMA{
    "[[body]]",
    {"name", "mesh", "shape", "surface", "min", "max", "cells", "center", "radius", "resolution",
     "translate", "rotate_axis", "rotate_degrees", "scale", "velocity", "young", "poisson",
     "density", "rayleigh_mass", "rayleigh_stiffness", "fixed", "load"}};
const TableSchema FIXED_SCHEMA{"[[body.fixed]]", {"min", "max"}};
const TableSchema LOAD_SCHEMA{"[[body.load]]", {"min", "max", "force"}};
const TableSchema OBSTACLE_SCHEMA{"[[obstacle]]", {"type", "point", "normal", "mesh"}};

const std::vector<const TableSchema*>& all_schemas()
{
    static const std::vector<const TableSchema*> schemas{
        &SIMULATION_SCHEMA, &SOLVER_SCHEMA, &CONTACT_SCHEMA, &BODY_SCHEMA,
        &FIXED_SCHEMA,      &LOAD_SCHEMA,   &OBSTACLE_SCHEMA};
    return schemas;
}

// Keys that only one geometry of a body accepts.
const std::vector<std::string_view> BOX_KEYS{"min", "max", "cells"};
const std::vector<std::string_view> SPHERE_KEYS{"center", "radius", "resolution"};

// ---------------------------------------------------------------------------------------------
// Text helpers.

/// Shortest `%g` text that reads back as the same double.
std::string format_number(double value)
{
    if (std::isnan(value))
        return "nan";
    if (std::isinf(value))
        return value > 0 ? "inf" : "-inf";
    char buffer[40];
    int precision = 1;
    for (; precision < 17; ++precision) {
        std::snprintf(buffer, sizeof buffer, "%.*g", precision, value);
        if (std::strtod(buffer, nullptr) == value)
            break;
    }
    // No exponent for moderate magnitudes: 10, not 1e+01.
    if (std::abs(value) >= 1.0 && std::abs(value) < 1e6)
        precision = std::max(precision, static_cast<int>(std::floor(std::log10(std::abs(value)))) + 1);
    std::snprintf(buffer, sizeof buffer, "%.*g", precision, value);
    return buffer;
}

std::string format_vec(const Vec3& v)
{
    return "[" + format_number(v[0]) + ", " + format_number(v[1]) + ", " + format_number(v[2]) + "]";
}

/// "the integer 5", "the string \"abc\"", "an array of 2 elements", ... for "found ...".
std::string describe(const toml::node& node)
{
    std::ostringstream out;
    switch (node.type()) {
    case toml::node_type::string: {
        std::string text = node.as_string()->get();
        if (text.size() > 60)
            text = text.substr(0, 57) + "...";
        out << "the string \"" << text << "\"";
        break;
    }
    case toml::node_type::integer:
        out << "the integer " << node.as_integer()->get();
        break;
    case toml::node_type::floating_point: {
        std::string text = format_number(node.as_floating_point()->get());
        if (text.find_first_of(".eni") == std::string::npos)
            text += ".0";
        out << "the floating-point number " << text;
        break;
    }
    case toml::node_type::boolean:
        out << "the boolean " << (node.as_boolean()->get() ? "true" : "false");
        break;
    case toml::node_type::array: {
        const auto n = node.as_array()->size();
        out << "an array of " << n << (n == 1 ? " element" : " elements");
        break;
    }
    case toml::node_type::table:
        out << "a table";
        break;
    case toml::node_type::date:
        out << "a date";
        break;
    case toml::node_type::time:
        out << "a time";
        break;
    case toml::node_type::date_time:
        out << "a date-time";
        break;
    default:
        out << "nothing";
        break;
    }
    return out.str();
}

/// Optimal string alignment distance (Levenshtein plus adjacent transpositions), ignoring case
/// and treating '-' and ' ' like '_'.
std::size_t edit_distance(std::string_view a, std::string_view b)
{
    const auto fold = [](char c) {
        if (c == '-' || c == ' ')
            return '_';
        return static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    };
    const std::size_t n = a.size(), m = b.size();
    std::vector<std::vector<std::size_t>> d(n + 1, std::vector<std::size_t>(m + 1));
    for (std::size_t i = 0; i <= n; ++i)
        d[i][0] = i;
    for (std::size_t j = 0; j <= m; ++j)
        d[0][j] = j;
    for (std::size_t i = 1; i <= n; ++i)
        for (std::size_t j = 1; j <= m; ++j) {
            const std::size_t cost = fold(a[i - 1]) == fold(b[j - 1]) ? 0 : 1;
            d[i][j] = std::min({d[i - 1][j] + 1, d[i][j - 1] + 1, d[i - 1][j - 1] + cost});
            if (i > 1 && j > 1 && fold(a[i - 1]) == fold(b[j - 2]) && fold(a[i - 2]) == fold(b[j - 1]))
                d[i][j] = std::min(d[i][j], d[i - 2][j - 2] + 1);
        }
    return d[n][m];
}

/// "bodies" -> "body", "loads" -> "load": plural table names are a common slip.
std::string singular(std::string_view word)
{
    std::string s(word);
    if (s.size() > 4 && s.compare(s.size() - 3, 3, "ies") == 0)
        return s.substr(0, s.size() - 3) + "y";
    if (s.size() > 3 && s.back() == 's')
        s.pop_back();
    return s;
}

/// The known key closest to `key`, if it is close enough to be a likely typo.
std::optional<std::string_view> closest_key(std::string_view key, const std::vector<std::string_view>& known)
{
    std::optional<std::string_view> best;
    std::size_t best_distance = std::numeric_limits<std::size_t>::max();
    const std::string key_singular = singular(key);
    for (const std::string_view candidate : known) {
        const std::size_t distance =
            std::min(edit_distance(key, candidate), edit_distance(key_singular, candidate));
        const std::size_t allowed = candidate.size() <= 4 ? 1 : candidate.size() <= 8 ? 2 : 3;
        const bool prefix = key.size() >= 3 && candidate.substr(0, key.size()) == key;
        if ((distance <= allowed || prefix) && distance < best_distance) {
            best = candidate;
            best_distance = distance;
        }
    }
    return best;
}

std::string join_quoted(const std::vector<std::string_view>& words)
{
    std::string text;
    for (std::size_t i = 0; i < words.size(); ++i)
        text += (i == 0 ? "" : i + 1 == words.size() ? " or " : ", ") + ("\"" + std::string(words[i]) + "\"");
    return text;
}

std::string join_plain(const std::vector<std::string_view>& words)
{
    std::string text;
    for (std::size_t i = 0; i < words.size(); ++i)
        text += (i == 0 ? "" : ", ") + std::string(words[i]);
    return text;
}

/// Longest simulation or body name: with the suffixes the output adds (`_surface`,
/// `_<step>.vtm`, `.summary.json`, `.tmp`) a file name stays below the usual 255-byte limit.
constexpr std::size_t MAX_NAME_LENGTH = 128;

/// 1 to MAX_NAME_LENGTH letters, digits, '_', '.', '-'; not "." or "..": safe as a file name
/// and in a CSV field.
bool is_valid_name(const std::string& name)
{
    if (name.empty() || name.size() > MAX_NAME_LENGTH || name == "." || name == "..")
        return false;
    return std::all_of(name.begin(), name.end(), [](char c) {
        return std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '.' || c == '-';
    });
}

constexpr const char* NAME_RULE = "a name of 1 to 128 letters, digits, '_', '.' and '-'";

/// Why a name made of allowed characters is still refused: " (300 characters)" for one that is
/// too long; for "." and "..", that they name folders. Else "".
std::string name_note(const std::string& name)
{
    if (name == "." || name == "..")
        return " (\".\" and \"..\" are not allowed: they name the current and the parent folder)";
    return name.size() > MAX_NAME_LENGTH ? " (" + std::to_string(name.size()) + " characters)" : "";
}

/// Allowed interval of a number, with its text for messages.
struct Range {
    double lo = -std::numeric_limits<double>::infinity();
    double hi = std::numeric_limits<double>::infinity();
    bool lo_open = false;
    bool hi_open = false;

    bool contains(double v) const
    {
        return (lo_open ? v > lo : v >= lo) && (hi_open ? v < hi : v <= hi);
    }
    std::string text() const
    {
        const bool has_lo = std::isfinite(lo), has_hi = std::isfinite(hi);
        if (has_lo && has_hi)
            return " in " + std::string(lo_open ? "(" : "[") + format_number(lo) + ", " +
                   format_number(hi) + (hi_open ? ")" : "]");
        if (has_lo)
            return std::string(lo_open ? " > " : " >= ") + format_number(lo);
        if (has_hi)
            return std::string(hi_open ? " < " : " <= ") + format_number(hi);
        return "";
    }
};

const Range ANY{};
const Range POSITIVE{0.0, std::numeric_limits<double>::infinity(), true, false};
const Range NON_NEGATIVE{0.0, std::numeric_limits<double>::infinity(), false, false};
/// A relative tolerance: 1 or more is met before the first iteration.
const Range RELATIVE_TOLERANCE{0.0, 1.0, true, true};
/// The PCG tolerance: as RELATIVE_TOLERANCE, and 0 asks for max_iterations in every solve.
const Range PCG_TOLERANCE{0.0, 1.0, false, true};

// ---------------------------------------------------------------------------------------------
// Reading one table.

/// The case file being read: its name for messages and the folder relative paths start from.
struct Context {
    std::string file;   // as given
    fs::path base_dir;  // absolute folder of the case file

    std::string where(const toml::source_region& region) const
    {
        const auto line = region.begin.line == 0 ? 1 : region.begin.line;
        const auto column = region.begin.column == 0 ? 1 : region.begin.column;
        return file + ":" + std::to_string(line) + ":" + std::to_string(column);
    }
    std::string line_of(const toml::source_region& region) const
    {
        return file + ":" + std::to_string(region.begin.line == 0 ? 1 : region.begin.line);
    }
};

/// Throws an InputError at `region` about the full key `key`.
#define CORO_CASE_ERROR(ctx, region, key, msg) \
    CORO_THROW(InputError, (ctx).where(region) << ": " << (key) << ": " << msg)

/// One TOML table with its full name ("simulation", "body[1]", "body[0].fixed[2]").
class TableReader {
public:
    TableReader(const Context& ctx, const toml::table& table, std::string name)
        : m_ctx(ctx), m_table(table), m_name(std::move(name))
    {
    }

    const toml::table& table() const { return m_table; }
    const std::string& name() const { return m_name; }
    const Context& ctx() const { return m_ctx; }

    /// Full name of `key` in this table: "simulation.dt", or "dt" at the top level.
    std::string full(std::string_view key) const
    {
        return m_name.empty() ? std::string(key) : m_name + "." + std::string(key);
    }

    const toml::node* find(std::string_view key) const { return m_table.get(key); }

    /// Where the key itself (not its value) is written.
    toml::source_region key_region(std::string_view key) const
    {
        const auto it = m_table.find(key);
        return it == m_table.end() ? m_table.source() : it->first.source();
    }

    /// Throws for the first key (in file order) that `schema` does not know.
    void reject_unknown_keys(const TableSchema& schema, std::string_view extra_hint = {}) const
    {
        const toml::key* first = nullptr;
        for (auto&& [key, node] : m_table) {
            (void)node;
            const auto known = std::find(schema.keys.begin(), schema.keys.end(), key.str());
            if (known != schema.keys.end())
                continue;
            if (first == nullptr || before(key.source(), first->source()))
                first = &key;
        }
        if (first == nullptr)
            return;
        const std::string_view key = first->str();
        const toml::node& node = *m_table.get(key);
        std::ostringstream msg;
        if (&schema == &ROOT_SCHEMA)
            msg << (node.is_table() || node.is_array_of_tables() ? "unknown table" : "unknown top-level key");
        else
            msg << "unknown key in " << schema.header;
        if (const auto suggestion = closest_key(key, schema.keys)) {
            msg << "; did you mean '" << *suggestion << "'?";
        } else {
            std::vector<std::string_view> owners;
            for (const TableSchema* other : all_schemas())
                if (other != &schema &&
                    std::find(other->keys.begin(), other->keys.end(), key) != other->keys.end())
                    owners.push_back(other->header);
            if (&schema == &ROOT_SCHEMA && !owners.empty())
                msg << "; '" << key << "' is a key of " << join_plain(owners)
                    << ", so write it below that table's header";
            else if (!owners.empty())
                msg << "; '" << key << "' is a key of " << join_plain(owners);
            else
                msg << "; known keys: " << join_plain(schema.keys);
            if (!extra_hint.empty() &&
                std::find(BODY_SCHEMA.keys.begin(), BODY_SCHEMA.keys.end(), key) != BODY_SCHEMA.keys.end())
                msg << extra_hint;
        }
        CORO_CASE_ERROR(m_ctx, first->source(), full(key), msg.str());
    }

    /// A number (integer or floating-point), finite and inside `range`; `fallback` if absent.
    double number(std::string_view key, double fallback, const Range& range = ANY) const
    {
        const toml::node* node = find(key);
        return node ? as_number(*node, full(key), range) : fallback;
    }

    /// An integer inside [min, max]; `fallback` if absent.
    Index integer(std::string_view key, Index fallback, Index min,
                  Index max = std::numeric_limits<Index>::max()) const
    {
        const toml::node* node = find(key);
        return node ? as_index(*node, full(key), min, max) : fallback;
    }

    bool boolean(std::string_view key, bool fallback) const
    {
        const toml::node* node = find(key);
        if (node == nullptr)
            return fallback;
        if (!node->is_boolean())
            CORO_CASE_ERROR(m_ctx, node->source(), full(key),
                            "expected a boolean (true or false), found " << describe(*node));
        return node->as_boolean()->get();
    }

    std::optional<std::string> string(std::string_view key) const
    {
        const toml::node* node = find(key);
        if (node == nullptr)
            return std::nullopt;
        if (!node->is_string())
            CORO_CASE_ERROR(m_ctx, node->source(), full(key),
                            "expected a string, found " << describe(*node));
        return node->as_string()->get();
    }

    /// An array of 3 finite numbers; `fallback` if absent.
    Vec3 vec3(std::string_view key, const Vec3& fallback) const
    {
        const toml::node* node = find(key);
        if (node == nullptr)
            return fallback;
        const toml::array& array = array3(*node, key, "numbers");
        Vec3 v;
        for (int d = 0; d < 3; ++d)
            v[d] = as_number(*array.get(static_cast<std::size_t>(d)), element(key, d), ANY);
        return v;
    }

    /// An array of 3 integers, each inside [min, 2^31-1]; `fallback` if absent.
    std::array<Index, 3> index3(std::string_view key, const std::array<Index, 3>& fallback, Index min) const
    {
        const toml::node* node = find(key);
        if (node == nullptr)
            return fallback;
        const toml::array& array = array3(*node, key, "integers");
        std::array<Index, 3> v{};
        for (int d = 0; d < 3; ++d)
            v[static_cast<std::size_t>(d)] =
                as_index(*array.get(static_cast<std::size_t>(d)), element(key, d), min);
        return v;
    }

    /// One of the strings in `options`; `fallback` if absent.
    template <class E>
    E choice(std::string_view key, E fallback, const std::vector<std::pair<std::string_view, E>>& options) const
    {
        const toml::node* node = find(key);
        if (node == nullptr)
            return fallback;
        std::vector<std::string_view> names;
        for (const auto& option : options)
            names.push_back(option.first);
        if (!node->is_string())
            CORO_CASE_ERROR(m_ctx, node->source(), full(key),
                            "expected one of " << join_quoted(names) << ", found " << describe(*node));
        const std::string& value = node->as_string()->get();
        for (const auto& option : options)
            if (value == option.first)
                return option.second;
        const auto suggestion = closest_key(value, names);
        CORO_CASE_ERROR(m_ctx, node->source(), full(key),
                        "expected one of " << join_quoted(names) << ", found " << describe(*node)
                                           << (suggestion ? "; did you mean \"" + std::string(*suggestion) + "\"?"
                                                          : std::string()));
    }

    /// A non-empty path string, resolved against the case file's folder and normalised;
    /// empty if absent.
    fs::path file_path(std::string_view key) const
    {
        const std::optional<std::string> text = string(key);
        if (!text)
            return {};
        if (text->empty())
            CORO_CASE_ERROR(m_ctx, find(key)->source(), full(key),
                            "expected a file name, found the empty string");
        const fs::path path(*text);
        return (path.is_absolute() ? path : m_ctx.base_dir / path).lexically_normal();
    }

    /// The sub-table `key` ([simulation]), or nullptr if absent.
    const toml::table* sub_table(std::string_view key) const
    {
        const toml::node* node = find(key);
        if (node == nullptr)
            return nullptr;
        if (!node->is_table())
            CORO_CASE_ERROR(m_ctx, node->source(), full(key),
                            "expected a table [" << full(key) << "], found " << describe(*node));
        return node->as_table();
    }

    /// The array of tables `key` ([[body]]); empty if absent.
    std::vector<TableReader> table_array(std::string_view key) const
    {
        std::vector<TableReader> tables;
        const toml::node* node = find(key);
        if (node == nullptr)
            return tables;
        if (!node->is_array())
            CORO_CASE_ERROR(m_ctx, node->source(), full(key),
                            "expected an array of tables, written [[" << full_header(key)
                                                                       << "]], found " << describe(*node)
                                                                       << (node->is_table() ? " (written ["
                                                                              + full_header(key) + "])" : ""));
        const toml::array& array = *node->as_array();
        for (std::size_t i = 0; i < array.size(); ++i) {
            const toml::node& item = *array.get(i);
            const std::string item_name = full(key) + "[" + std::to_string(i) + "]";
            if (!item.is_table())
                CORO_CASE_ERROR(m_ctx, item.source(), item_name,
                                "expected a table, written [[" << full_header(key) << "]], found "
                                                               << describe(item));
            tables.emplace_back(m_ctx, *item.as_table(), item_name);
        }
        return tables;
    }

private:
    static bool before(const toml::source_region& a, const toml::source_region& b)
    {
        return std::make_pair(a.begin.line, a.begin.column) < std::make_pair(b.begin.line, b.begin.column);
    }

    std::string element(std::string_view key, int d) const { return full(key) + "[" + std::to_string(d) + "]"; }

    /// "body.fixed" for the key "fixed" of "body[0]": the header as the user writes it.
    std::string full_header(std::string_view key) const
    {
        std::string header;
        bool in_index = false;
        for (const char c : full(key)) {
            if (c == '[' || c == ']')
                in_index = c == '[';
            else if (!in_index)
                header += c;
        }
        return header;
    }

    const toml::array& array3(const toml::node& node, std::string_view key, const char* what) const
    {
        if (!node.is_array())
            CORO_CASE_ERROR(m_ctx, node.source(), full(key),
                            "expected an array of 3 " << what << ", found " << describe(node));
        const toml::array& array = *node.as_array();
        if (array.size() != 3)
            CORO_CASE_ERROR(m_ctx, node.source(), full(key),
                            "expected an array of 3 " << what << ", found " << describe(node));
        return array;
    }

    double as_number(const toml::node& node, const std::string& name, const Range& range) const
    {
        double value = 0.0;
        if (node.is_integer())
            value = static_cast<double>(node.as_integer()->get());
        else if (node.is_floating_point())
            value = node.as_floating_point()->get();
        else
            CORO_CASE_ERROR(m_ctx, node.source(), name,
                            "expected a number" << range.text() << ", found " << describe(node));
        if (!std::isfinite(value))
            CORO_CASE_ERROR(m_ctx, node.source(), name,
                            "expected a finite number" << range.text() << ", found " << describe(node));
        if (!range.contains(value))
            CORO_CASE_ERROR(m_ctx, node.source(), name,
                            "expected a number" << range.text() << ", found " << describe(node));
        return value;
    }

    Index as_index(const toml::node& node, const std::string& name, Index min,
                   Index max = std::numeric_limits<Index>::max()) const
    {
        if (!node.is_integer())
            CORO_CASE_ERROR(m_ctx, node.source(), name,
                            "expected an integer >= " << min << ", found " << describe(node)
                                                      << (node.is_floating_point()
                                                              ? " (write it without a decimal point)"
                                                              : ""));
        const std::int64_t value = node.as_integer()->get();
        if (value < min)
            CORO_CASE_ERROR(m_ctx, node.source(), name,
                            "expected an integer >= " << min << ", found " << describe(node));
        if (value > max)
            CORO_CASE_ERROR(m_ctx, node.source(), name,
                            "expected an integer >= " << min << " and <= " << max << ", found "
                                                      << describe(node));
        return static_cast<Index>(value);
    }

    const Context& m_ctx;
    const toml::table& m_table;
    std::string m_name;
};

// ---------------------------------------------------------------------------------------------
// The tables of a case.

void read_simulation(const TableReader& root, const fs::path& file, CaseSpec& spec)
{
    const toml::table* table = root.sub_table("simulation");
    const toml::table empty;
    const TableReader t(root.ctx(), table ? *table : empty, "simulation");
    t.reject_unknown_keys(SIMULATION_SCHEMA);
    SimulationSettings& s = spec.simulation;

    if (const auto name = t.string("name")) {
        if (!is_valid_name(*name))
            CORO_CASE_ERROR(t.ctx(), t.find("name")->source(), "simulation.name",
                            "expected " << NAME_RULE << " (it becomes a file name), found "
                                        << describe(*t.find("name")) << name_note(*name));
        s.name = *name;
    } else {
        s.name = file.stem().string();
        if (!is_valid_name(s.name))
            CORO_CASE_ERROR(t.ctx(), table ? table->source() : root.table().source(), "simulation.name",
                            "not given, and the case file's stem \""
                                << s.name << "\" is not " << NAME_RULE
                                << "; set simulation.name in [simulation]");
    }
    s.analysis = t.choice<Analysis>("analysis", s.analysis,
                                    {{"dynamic", Analysis::DYNAMIC}, {"static", Analysis::STATIC}});
    s.dt = t.number("dt", s.dt, POSITIVE);
    s.steps = t.integer("steps", s.steps, 1);
    s.load_steps = t.integer("load_steps", s.load_steps, 1);
    s.gravity = t.vec3("gravity", s.gravity);
    s.output_every = t.integer("output_every", s.output_every, 1);
    if (const auto dir = t.string("output_dir")) {
        if (dir->empty())
            CORO_CASE_ERROR(t.ctx(), t.find("output_dir")->source(), "simulation.output_dir",
                            "expected a folder name, found the empty string");
        fs::path path = fs::path(*dir).lexically_normal();
        if (!path.has_filename() && path.has_parent_path() && path != path.root_path())
            path = path.parent_path(); // "out/a/" -> "out/a"
        s.output_dir = path;
    } else {
        s.output_dir = fs::path("out") / s.name;
    }
}

/// A note for the keys of [simulation] that the analysis does not use: a static analysis has
/// no time steps (its steps are load_steps, and it writes every one), a dynamic one no load steps.
std::optional<std::string> unused_simulation_keys(const TableReader& root, const SimulationSettings& s)
{
    const toml::table* table = root.sub_table("simulation");
    if (table == nullptr)
        return std::nullopt;
    const TableReader t(root.ctx(), *table, "simulation");
    const bool dynamic = s.analysis == Analysis::DYNAMIC;
    const std::vector<std::string_view> keys =
        dynamic ? std::vector<std::string_view>{"load_steps"} : std::vector<std::string_view>{"dt", "steps", "output_every"};
    std::vector<std::string_view> given;
    for (const std::string_view key : keys)
        if (t.find(key))
            given.push_back(key);
    if (given.empty())
        return std::nullopt;
    std::ostringstream note;
    note << t.ctx().where(t.key_region(given.front())) << ": ";
    for (std::size_t k = 0; k < given.size(); ++k)
        note << (k == 0 ? "" : k + 1 == given.size() ? " and " : ", ") << t.full(given[k]);
    note << (given.size() == 1 ? " is" : " are") << " not used by a" << (dynamic ? " dynamic" : " static")
         << " analysis, which "
         << (dynamic ? "runs simulation.steps time steps" : "has no time steps: it runs simulation.load_steps = " +
                                                                std::to_string(s.load_steps) +
                                                                " load steps and writes every one");
    return note.str();
}

void read_solver(const TableReader& root, SolverSettings& s)
{
    const toml::table* table = root.sub_table("solver");
    if (table == nullptr)
        return;
    const TableReader t(root.ctx(), *table, "solver");
    t.reject_unknown_keys(SOLVER_SCHEMA);
    s.max_iterations = t.integer("max_iterations", s.max_iterations, 1);
    s.tolerance = t.number("tolerance", s.tolerance, PCG_TOLERANCE);
    s.preconditioner = t.choice<PcgPreconditioner>("preconditioner", s.preconditioner,
                                                   {{"jacobi", PcgPreconditioner::JACOBI},
                                                    {"block_jacobi", PcgPreconditioner::BLOCK_JACOBI},
                                                    {"amg", PcgPreconditioner::AMG}});
    s.matrix_precision = t.choice<MatrixPrecision>(
        "matrix_precision", s.matrix_precision,
        {{"double", MatrixPrecision::DOUBLE}, {"single", MatrixPrecision::SINGLE}});
    s.static_tolerance = t.number("static_tolerance", s.static_tolerance, RELATIVE_TOLERANCE);
    s.static_max_iterations = t.integer("static_max_iterations", s.static_max_iterations, 1);
    // Times the core count, it must still fit an Index.
    s.parts_per_thread = t.integer("parts_per_thread", s.parts_per_thread, 1, 100000);
}

void read_contact(const TableReader& root, ContactSettings& s)
{
    const toml::table* table = root.sub_table("contact");
    if (table == nullptr)
        return;
    const TableReader t(root.ctx(), *table, "contact");
    t.reject_unknown_keys(CONTACT_SCHEMA);
    s.enabled = t.boolean("enabled", s.enabled);
    s.mode = t.choice<ContactMode>("mode", s.mode,
                                   {{"exact", ContactMode::EXACT}, {"paper", ContactMode::PAPER}});
    s.stiffness = t.number("stiffness", s.stiffness, POSITIVE);
    s.damping = t.number("damping", s.damping, NON_NEGATIVE);
    s.friction = t.number("friction", s.friction, Range{0.0, MAX_FRICTION, false, false});
    s.cross_check = t.choice<CrossCheck>("cross_check", s.cross_check,
                                         {{"none", CrossCheck::NONE}, {"embree", CrossCheck::EMBREE}});
}

/// min/max of a box: `strict` demands max > min in every component, else max >= min.
void check_box(const TableReader& t, const Vec3& min, const Vec3& max, bool strict)
{
    for (int d = 0; d < 3; ++d) {
        const bool ok = strict ? max[d] > min[d] : max[d] >= min[d];
        if (ok)
            continue;
        const char* blame = t.find("max") ? "max" : "min";
        CORO_CASE_ERROR(t.ctx(), t.find(blame)->source(), t.full(blame),
                        "expected max" << (strict ? " > " : " >= ") << "min in every component, found max["
                                       << d << "] = " << format_number(max[d]) << " and min[" << d
                                       << "] = " << format_number(min[d]));
    }
}

/// A position given in the case (a corner, a centre, a translation, a plane's point) must be
/// as small as validate_and_orient demands of mesh nodes: beyond, volumes overflow double.
void check_coordinates(const TableReader& t, std::string_view key, const Vec3& v)
{
    if (!t.find(key) || v.cwiseAbs().maxCoeff() <= MAX_COORDINATE)
        return;
    CORO_CASE_ERROR(t.ctx(), t.find(key)->source(), t.full(key),
                    "expected coordinates of magnitude at most " << format_number(MAX_COORDINATE) << ", found "
                                                                  << format_vec(v));
}

/// A generated mesh's tet and node counts (exact in double up to 2^53) must fit the 32-bit
/// Index that numbers them; the memory they need is checked when the scene is loaded.
void check_generated_size(const TableReader& t, std::string_view key, const std::string& value, double tets,
                          double nodes)
{
    constexpr double MAX = std::numeric_limits<Index>::max();
    if (tets <= MAX && nodes <= MAX)
        return;
    CORO_CASE_ERROR(t.ctx(), t.find(key)->source(), t.full(key),
                    value << " makes " << format_number(tets) << " tets and " << format_number(nodes)
                          << " nodes, expected at most " << format_number(MAX)
                          << " of each (they are numbered by 32-bit integers)");
}

constexpr std::string_view NESTED_HINT =
    " (keys below a [[body.fixed]] or [[body.load]] header belong to that table: move it above "
    "the first [[body.fixed]] or [[body.load]] of this body)";

FixedRegion read_fixed(const TableReader& t)
{
    t.reject_unknown_keys(FIXED_SCHEMA, NESTED_HINT);
    FixedRegion region;
    region.min = t.vec3("min", region.min);
    region.max = t.vec3("max", region.max);
    check_box(t, region.min, region.max, false);
    return region;
}

BoxLoad read_load(const TableReader& t)
{
    t.reject_unknown_keys(LOAD_SCHEMA, NESTED_HINT);
    BoxLoad load;
    load.min = t.vec3("min", load.min);
    load.max = t.vec3("max", load.max);
    check_box(t, load.min, load.max, false);
    load.force = t.vec3("force", load.force);
    return load;
}

/// Throws if `t` holds one of `keys`, which belong to another geometry than `geometry`.
void reject_keys_of(const TableReader& t, const std::vector<std::string_view>& keys,
                    std::string_view owner, std::string_view geometry)
{
    for (const std::string_view key : keys)
        if (t.find(key))
            CORO_CASE_ERROR(t.ctx(), t.key_region(key), t.full(key),
                            "'" << key << "' is a key of " << owner << ", but this body " << geometry);
}

BodySpec read_body(const TableReader& t, Index k)
{
    t.reject_unknown_keys(BODY_SCHEMA);
    BodySpec body;
    body.location = t.ctx().line_of(t.table().source());

    if (const auto name = t.string("name")) {
        if (!is_valid_name(*name))
            CORO_CASE_ERROR(t.ctx(), t.find("name")->source(), t.full("name"),
                            "expected " << NAME_RULE << ", found " << describe(*t.find("name"))
                                        << name_note(*name));
        body.name = *name;
    } else {
        body.name = "body" + std::to_string(k);
    }

    // Geometry: exactly one of `mesh` and `shape`.
    const toml::node* mesh = t.find("mesh");
    const toml::node* shape = t.find("shape");
    if (mesh && shape)
        CORO_CASE_ERROR(t.ctx(), t.key_region("shape"), t.full("shape"),
                        "expected either 'mesh' or 'shape', found both ('mesh' at "
                            << t.ctx().where(t.key_region("mesh")) << ")");
    if (!mesh && !shape)
        CORO_CASE_ERROR(t.ctx(), t.table().source(), t.name(),
                        "expected a geometry, mesh = \"file\" or shape = \"box\" or shape = \"sphere\", "
                        "found neither 'mesh' nor 'shape'");
    if (mesh) {
        body.shape = BodyShape::MESH;
        body.mesh = t.file_path("mesh");
        reject_keys_of(t, BOX_KEYS, "shape = \"box\"", "reads a mesh");
        reject_keys_of(t, SPHERE_KEYS, "shape = \"sphere\"", "reads a mesh");
    } else {
        body.shape = t.choice<BodyShape>("shape", BodyShape::BOX,
                                         {{"box", BodyShape::BOX}, {"sphere", BodyShape::SPHERE}});
    }
    if (body.shape == BodyShape::BOX) {
        reject_keys_of(t, SPHERE_KEYS, "shape = \"sphere\"", "has shape = \"box\"");
        body.box_min = t.vec3("min", body.box_min);
        body.box_max = t.vec3("max", body.box_max);
        check_coordinates(t, "min", body.box_min);
        check_coordinates(t, "max", body.box_max);
        check_box(t, body.box_min, body.box_max, true);
        body.cells = t.index3("cells", body.cells, 1);
        const auto& c = body.cells;
        check_generated_size(t, "cells", "[" + std::to_string(c[0]) + ", " + std::to_string(c[1]) + ", " +
                                             std::to_string(c[2]) + "]",
                             6.0 * c[0] * c[1] * c[2], (c[0] + 1.0) * (c[1] + 1.0) * (c[2] + 1.0));
    } else if (body.shape == BodyShape::SPHERE) {
        reject_keys_of(t, BOX_KEYS, "shape = \"box\"", "has shape = \"sphere\"");
        body.center = t.vec3("center", body.center);
        check_coordinates(t, "center", body.center);
        body.radius = t.number("radius", body.radius, Range{0.0, MAX_COORDINATE, true, false});
        body.resolution = t.integer("resolution", body.resolution, 2);
        const double r = body.resolution;
        check_generated_size(t, "resolution", std::to_string(body.resolution), 6.0 * r * r * r,
                             (r + 1.0) * (r + 1.0) * (r + 1.0));
    }
    body.surface = t.file_path("surface");

    BodyTransform& x = body.transform;
    x.translate = t.vec3("translate", x.translate);
    check_coordinates(t, "translate", x.translate);
    x.rotate_axis = t.vec3("rotate_axis", x.rotate_axis);
    // Ten turns either way: beyond, the angle is likely a unit mistake, and far beyond (1e17)
    // its remainder by 360 is rounding noise.
    x.rotate_degrees = t.number("rotate_degrees", x.rotate_degrees, Range{-3600.0, 3600.0, false, false});
    x.scale = t.number("scale", x.scale, POSITIVE);
    if (x.rotate_degrees != 0.0 && !(x.rotate_axis.stableNorm() > 0.0))
        CORO_CASE_ERROR(t.ctx(), t.find("rotate_axis")->source(), t.full("rotate_axis"),
                        "expected a nonzero axis because rotate_degrees = "
                            << format_number(x.rotate_degrees) << ", found " << format_vec(x.rotate_axis));

    body.velocity = t.vec3("velocity", body.velocity);
    Material& m = body.material;
    m.young = t.number("young", m.young, POSITIVE);
    m.poisson = t.number("poisson", m.poisson, Range{-1.0, 0.5, true, true});
    m.density = t.number("density", m.density, POSITIVE);
    body.rayleigh_mass = t.number("rayleigh_mass", body.rayleigh_mass, NON_NEGATIVE);
    body.rayleigh_stiffness = t.number("rayleigh_stiffness", body.rayleigh_stiffness, NON_NEGATIVE);

    for (const TableReader& fixed : t.table_array("fixed"))
        body.fixed.push_back(read_fixed(fixed));
    for (const TableReader& load : t.table_array("load"))
        body.loads.push_back(read_load(load));
    return body;
}

ObstacleSpec read_obstacle(const TableReader& t)
{
    t.reject_unknown_keys(OBSTACLE_SCHEMA);
    ObstacleSpec obstacle;
    obstacle.location = t.ctx().line_of(t.table().source());
    obstacle.type = t.choice<ObstacleType>("type", obstacle.type,
                                           {{"plane", ObstacleType::PLANE}, {"mesh", ObstacleType::MESH}});
    if (obstacle.type == ObstacleType::PLANE) {
        if (t.find("mesh"))
            CORO_CASE_ERROR(t.ctx(), t.key_region("mesh"), t.full("mesh"),
                            "'mesh' is a key of type = \"mesh\", but this obstacle is a plane");
        obstacle.point = t.vec3("point", obstacle.point);
        check_coordinates(t, "point", obstacle.point);
        const Vec3 normal = t.vec3("normal", obstacle.normal);
        if (!(normal.stableNorm() > 0.0))
            CORO_CASE_ERROR(t.ctx(), t.find("normal")->source(), t.full("normal"),
                            "expected a nonzero vector, found " << format_vec(normal));
        obstacle.normal = normal.stableNormalized();
    } else {
        for (const std::string_view key : {"point", "normal"})
            if (t.find(key))
                CORO_CASE_ERROR(t.ctx(), t.key_region(key), t.full(key),
                                "'" << key << "' is a key of type = \"plane\", but this obstacle is a mesh");
        if (!t.find("mesh"))
            CORO_CASE_ERROR(t.ctx(), t.table().source(), t.full("mesh"),
                            "expected the obstacle's surface file, mesh = \"file\", for type = "
                            "\"mesh\", found no 'mesh'");
        obstacle.mesh = t.file_path("mesh");
    }
    return obstacle;
}

/// A body named like another output block of a frame (an embedded surface's, an obstacle's)
/// would make two blocks of one name: the frame could not be written.
void reject_block_name_clashes(const Context& ctx, const std::vector<TableReader>& bodies, const CaseSpec& spec)
{
    std::map<std::string, std::string> taken; // block name -> what writes it
    for (std::size_t k = 0; k < spec.bodies.size(); ++k)
        if (!spec.bodies[k].surface.empty())
            taken[surface_block_name(spec.bodies[k].name)] =
                "the embedded surface of body '" + spec.bodies[k].name + "' (" +
                ctx.where(bodies[k].key_region("surface")) + ")";
    Index meshes = 0, planes = 0;
    for (const ObstacleSpec& obstacle : spec.obstacles) {
        const bool mesh = obstacle.type == ObstacleType::MESH;
        Index& k = mesh ? meshes : planes;
        taken[mesh ? obstacle_block_name(k) : plane_block_name(k)] = (mesh ? "mesh obstacle " : "plane obstacle ") +
                                                                     std::to_string(k) + " ([[obstacle]] at " +
                                                                     obstacle.location + ")";
        ++k;
    }
    for (std::size_t k = 0; k < spec.bodies.size(); ++k) {
        const auto it = taken.find(spec.bodies[k].name);
        if (it == taken.end())
            continue;
        const TableReader& t = bodies[k];
        const toml::node* name = t.find("name");
        CORO_CASE_ERROR(ctx, name ? name->source() : t.table().source(), t.full("name"),
                        "expected a name that no other block of the output has, found \""
                            << it->first << "\"" << (name ? "" : " (the default name)")
                            << ", the block name of " << it->second << "; rename the body");
    }
}

} // namespace

CaseSpec parse_case(const std::string& text, const fs::path& file)
{
    std::vector<std::string> notes;
    return parse_case(text, file, notes);
}

CaseSpec parse_case(const std::string& text, const fs::path& file, std::vector<std::string>& notes)
{
    Context ctx;
    ctx.file = file.string();
    ctx.base_dir = (file.empty() ? fs::current_path() : fs::absolute(file).parent_path()).lexically_normal();

    toml::table document;
    try {
        document = toml::parse(std::string_view(text), std::string_view(ctx.file));
    } catch (const toml::parse_error& e) {
        CORO_THROW(InputError, ctx.where(e.source()) << ": invalid TOML: " << e.description());
    }

    CaseSpec spec;
    spec.file = file;
    const TableReader root(ctx, document, "");
    root.reject_unknown_keys(ROOT_SCHEMA);
    read_simulation(root, file, spec);
    if (auto note = unused_simulation_keys(root, spec.simulation))
        notes.push_back(std::move(*note));
    read_solver(root, spec.solver);
    read_contact(root, spec.contact);

    const std::vector<TableReader> bodies = root.table_array("body");
    if (bodies.empty())
        CORO_CASE_ERROR(ctx, root.find("body") ? root.find("body")->source() : document.source(), "body",
                        "expected at least one [[body]] table, found none");
    std::map<std::string, std::string> seen; // body name -> where it is set
    for (std::size_t k = 0; k < bodies.size(); ++k) {
        const TableReader& t = bodies[k];
        spec.bodies.push_back(read_body(t, static_cast<Index>(k)));
        const std::string& name = spec.bodies.back().name;
        const toml::node* name_node = t.find("name");
        const toml::source_region region = name_node ? name_node->source() : t.table().source();
        const auto [it, inserted] = seen.emplace(name, ctx.where(region));
        if (!inserted)
            CORO_CASE_ERROR(ctx, region, t.full("name"),
                            "expected a unique body name, found \""
                                << name << "\" again" << (name_node ? "" : " (the default name)")
                                << "; first used at " << it->second);
    }
    for (const TableReader& t : root.table_array("obstacle"))
        spec.obstacles.push_back(read_obstacle(t));
    reject_block_name_clashes(ctx, bodies, spec);
    return spec;
}

CaseSpec read_case(const fs::path& file)
{
    std::vector<std::string> notes;
    return read_case(file, notes);
}

CaseSpec read_case(const fs::path& file, std::vector<std::string>& notes)
{
    std::error_code ec;
    const fs::file_status status = fs::status(file, ec);
    CORO_CHECK(!ec || ec == std::errc::no_such_file_or_directory, InputError,
               file.string() << ": cannot access the case file: " << ec.message());
    CORO_CHECK(fs::exists(status), InputError,
               file.string() << ": cannot read the case file: no such file");
    CORO_CHECK(!fs::is_directory(status), InputError,
               file.string() << ": cannot read the case file: it is a directory, expected a .toml file");
    // A device (/dev/zero) or a pipe would be read without end or bound.
    CORO_CHECK(fs::is_regular_file(status), InputError,
               file.string() << ": cannot read the case file: it is not a regular file, expected a .toml file");
    std::ifstream in(file, std::ios::binary);
    CORO_CHECK(in.is_open(), InputError,
               file.string() << ": cannot open the case file: " << std::strerror(errno));
    std::string text;
    try {
        text.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
    } catch (const std::bad_alloc&) {
        std::string().swap(text);
        CORO_THROW(InputError, file.string() << ": the case file does not fit in memory");
    }
    CORO_CHECK(!in.bad(), InputError, file.string() << ": cannot read the case file: read error");
    return parse_case(text, file, notes);
}

#undef CORO_CASE_ERROR

} // namespace coro
