#include <corocontact/sim/checkpoint.hpp>

#include <corocontact/core/atomic_file.hpp>
#include <corocontact/core/error.hpp>
#include <corocontact/core/fingerprint.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <fstream>
#include <iterator>
#include <system_error>
#include <type_traits>

namespace fs = std::filesystem;

namespace coro {

namespace {

constexpr char MAGIC[8] = {'C', 'O', 'R', 'O', 'C', 'K', 'P', 'T'};
constexpr char END[4] = {'E', 'N', 'D', '!'};
constexpr std::uint32_t VERSION = 3;

std::size_t at(Index i) { return static_cast<std::size_t>(i); }

class Writer {
public:
    template <class T>
    void put(const T& value)
    {
        static_assert(std::is_trivially_copyable_v<T>);
        const auto* bytes = reinterpret_cast<const char*>(&value);
        m_bytes.insert(m_bytes.end(), bytes, bytes + sizeof(T));
    }
    void put_bytes(const char* data, std::size_t size) { m_bytes.insert(m_bytes.end(), data, data + size); }
    void put_string(const std::string& s)
    {
        put(static_cast<std::uint32_t>(s.size()));
        put_bytes(s.data(), s.size());
    }
    std::string& bytes() { return m_bytes; }

private:
    std::string m_bytes;
};

class Reader {
public:
    Reader(const std::string& bytes, std::size_t end, const fs::path& path) : m_bytes(bytes), m_end(end), m_path(path) {}
    template <class T>
    T get(const char* what)
    {
        static_assert(std::is_trivially_copyable_v<T>);
        need(sizeof(T), what);
        T value;
        std::memcpy(&value, m_bytes.data() + m_pos, sizeof(T));
        m_pos += sizeof(T);
        return value;
    }
    std::string get_string(const char* what)
    {
        const auto size = get<std::uint32_t>(what);
        need(size, what);
        std::string s = m_bytes.substr(m_pos, size);
        m_pos += size;
        return s;
    }
    /// A count of items of `item_size` bytes each that must fit in what is left.
    std::size_t get_count(std::size_t item_size, const char* what)
    {
        const auto n = get<std::uint64_t>(what);
        CORO_CHECK(item_size == 0 || n <= (m_end - m_pos) / item_size, InputError,
                   m_path.string() << ": corrupt checkpoint: " << what << " count " << n
                                   << " exceeds the file size (byte " << m_pos << ")");
        return static_cast<std::size_t>(n);
    }
    std::vector<double> get_doubles(std::size_t n, const char* what)
    {
        need(n * sizeof(double), what);
        std::vector<double> values(n);
        std::memcpy(values.data(), m_bytes.data() + m_pos, n * sizeof(double));
        m_pos += n * sizeof(double);
        return values;
    }
    std::size_t position() const { return m_pos; }
    void skip(std::size_t size, const char* what)
    {
        need(size, what);
        m_pos += size;
    }

private:
    void need(std::size_t size, const char* what) const
    {
        CORO_CHECK(size <= m_end - m_pos, InputError,
                   m_path.string() << ": corrupt checkpoint: " << what << " runs past the end (byte " << m_pos << ")");
    }
    const std::string& m_bytes;
    std::size_t m_end;
    const fs::path& m_path;
    std::size_t m_pos = 0;
};

void put_summary(Writer& w, const RunSummary& s)
{
    w.put<std::int64_t>(s.steps);
    for (const double v : {s.wall_s, s.steps_per_s, s.phases.rotation, s.phases.assembly, s.phases.solve,
                           s.phases.contact, s.phases.output, s.cg_iterations_mean, s.cg_residual_mean,
                           s.max_contact_depth, s.contacts_mean, s.static_iterations_mean,
                           s.preconditioner.setup_s, s.preconditioner.apply_s})
        w.put(v);
    for (const Index v : {s.solves, s.solves_not_converged, s.static_not_converged, s.detections,
                          s.embree_disagreements, s.first_step, s.static_iterations_max,
                          s.preconditioner.setups, s.preconditioner.applies})
        w.put<std::int64_t>(v);
}

RunSummary get_summary(Reader& r)
{
    RunSummary s;
    s.steps = static_cast<Index>(r.get<std::int64_t>("counters"));
    for (double* v : {&s.wall_s, &s.steps_per_s, &s.phases.rotation, &s.phases.assembly, &s.phases.solve,
                      &s.phases.contact, &s.phases.output, &s.cg_iterations_mean, &s.cg_residual_mean,
                      &s.max_contact_depth, &s.contacts_mean, &s.static_iterations_mean,
                      &s.preconditioner.setup_s, &s.preconditioner.apply_s})
        *v = r.get<double>("counters");
    for (Index* v : {&s.solves, &s.solves_not_converged, &s.static_not_converged, &s.detections,
                     &s.embree_disagreements, &s.first_step, &s.static_iterations_max,
                     &s.preconditioner.setups, &s.preconditioner.applies})
        *v = static_cast<Index>(r.get<std::int64_t>("counters"));
    return s;
}

std::string read_all(const fs::path& path, const char* what)
{
    std::error_code error;
    CORO_CHECK(fs::is_regular_file(path, error), InputError, path.string() << ": " << what << " not found (expected a file)");
    std::ifstream file(path, std::ios::binary);
    CORO_CHECK(file.good(), InputError, path.string() << ": cannot open the " << what);
    std::string bytes((std::istreambuf_iterator<char>(file)), std::istreambuf_iterator<char>());
    CORO_CHECK(!file.bad(), InputError, path.string() << ": cannot read the " << what);
    return bytes;
}

} // namespace

std::uint64_t case_fingerprint(const CaseSpec& spec)
{
    const std::string bytes = read_all(spec.file, "case file");
    return fnv1a(bytes.data(), bytes.size());
}

CheckpointBody checkpoint_body(const Body& body)
{
    Writer entry;
    entry.put_string(body.name());
    entry.put<std::int64_t>(body.num_vertices());
    entry.put<std::int64_t>(body.mesh().num_tets());
    entry.put<std::int64_t>(body.fem().layout().num_parts);
    // Mesh file order, so the file does not depend on the internal numbering.
    Writer state;
    const Index n = body.num_vertices(), n_tets = body.mesh().num_tets();
    std::vector<double> nodes(at(3 * n));
    for (const VecX* values : {&body.positions(), &body.velocities()}) {
        for (Index v = 0; v < n; ++v)
            for (int d = 0; d < 3; ++d)
                nodes[at(3 * body.input_node(v) + d)] = (*values)[3 * v + d];
        state.put_bytes(reinterpret_cast<const char*>(nodes.data()), nodes.size() * sizeof(double));
    }
    std::vector<double> rotations(at(9 * n_tets));
    const std::vector<Mat3>& r = body.fem().rotations();
    for (Index t = 0; t < n_tets; ++t)
        std::memcpy(rotations.data() + 9 * at(body.input_tet(t)), r[at(t)].data(), 9 * sizeof(double));
    state.put_bytes(reinterpret_cast<const char*>(rotations.data()), rotations.size() * sizeof(double));
    return {std::move(entry.bytes()), std::move(state.bytes())};
}

void write_checkpoint(const fs::path& path, const Scene& scene, const CheckpointState& state,
                      std::uint64_t fingerprint)
{
    std::vector<CheckpointBody> bodies;
    for (const Body& body : scene.bodies)
        bodies.push_back(checkpoint_body(body));
    write_checkpoint(path, bodies, state, fingerprint);
}

void write_checkpoint(const fs::path& path, const std::vector<CheckpointBody>& bodies, const CheckpointState& state,
                      std::uint64_t fingerprint)
{
    Writer w;
    w.put_bytes(MAGIC, sizeof MAGIC);
    w.put(VERSION);
    w.put(fingerprint);
    w.put<std::uint64_t>(bodies.size());
    for (const CheckpointBody& body : bodies)
        w.put_bytes(body.entry.data(), body.entry.size());
    w.put<std::int64_t>(state.step);
    put_summary(w, state.summary);
    w.put<std::uint64_t>(state.frames.size());
    for (const FrameRecord& frame : state.frames) {
        w.put<std::int64_t>(frame.step);
        w.put(frame.time);
    }
    for (const CheckpointBody& body : bodies)
        w.put_bytes(body.state.data(), body.state.size());
    w.put_bytes(END, sizeof END);
    w.put(fnv1a(w.bytes().data(), w.bytes().size()));

    write_file_atomically(path, w.bytes());
}

CheckpointState read_checkpoint(const fs::path& path, Scene& scene, std::uint64_t fingerprint,
                                std::vector<std::string>& warnings)
{
    std::vector<Index> ids(scene.bodies.size());
    for (std::size_t b = 0; b < ids.size(); ++b)
        ids[b] = static_cast<Index>(b);
    std::vector<BodyWarning> body_warnings;
    CheckpointState state = read_checkpoint(path, scene, ids, static_cast<Index>(ids.size()), fingerprint, body_warnings);
    for (BodyWarning& warning : body_warnings)
        warnings.push_back(std::move(warning.second));
    return state;
}

CheckpointState read_checkpoint(const fs::path& path, Scene& scene, const std::vector<Index>& body_ids,
                                Index case_bodies, std::uint64_t fingerprint, std::vector<BodyWarning>& warnings)
{
    const std::string bytes = read_all(path, "checkpoint");
    const std::string where = path.string();
    constexpr std::size_t TRAILER = sizeof END + sizeof(std::uint64_t);
    CORO_CHECK(bytes.size() >= sizeof MAGIC + TRAILER && std::memcmp(bytes.data(), MAGIC, sizeof MAGIC) == 0,
               InputError, where << ": not a corocontact checkpoint (no COROCKPT header)");
    const std::size_t end = bytes.size() - TRAILER;
    std::uint64_t checksum = 0;
    std::memcpy(&checksum, bytes.data() + end + sizeof END, sizeof checksum);
    CORO_CHECK(std::memcmp(bytes.data() + end, END, sizeof END) == 0 && checksum == fnv1a(bytes.data(), end + sizeof END),
               InputError, where << ": truncated or corrupt checkpoint (" << bytes.size()
                                 << " bytes; the end marker or checksum does not match)");

    Reader r(bytes, end, path);
    r.get<std::array<char, 8>>("header");
    const auto version = r.get<std::uint32_t>("version");
    CORO_CHECK(version == VERSION, InputError,
               where << ": checkpoint version " << version << ", this build reads version " << VERSION);
    CORO_CHECK(r.get<std::uint64_t>("fingerprint") == fingerprint, InputError,
               where << ": the checkpoint was written by another case file (or the case file changed since)");
    const std::size_t n_bodies = r.get_count(0, "body");
    CORO_CHECK(n_bodies == at(case_bodies), InputError,
               where << ": the checkpoint holds " << n_bodies << " bodies, the case has " << case_bodies);
    // The scene's bodies are the case's body_ids (ascending); the others' states are skipped.
    std::vector<Index> local(n_bodies, -1);
    for (std::size_t l = 0; l < body_ids.size(); ++l)
        local[at(body_ids[l])] = static_cast<Index>(l);
    std::vector<std::size_t> state_sizes(n_bodies);
    for (std::size_t k = 0; k < n_bodies; ++k) {
        const std::string name = r.get_string("body name");
        const auto n = r.get<std::int64_t>("body table"), n_tets = r.get<std::int64_t>("body table"),
                   parts = r.get<std::int64_t>("body table");
        CORO_CHECK(n >= 0 && n_tets >= 0 && n <= INT32_MAX && n_tets <= INT32_MAX, InputError,
                   where << ": corrupt checkpoint: body '" << name << "' has " << n << " nodes and " << n_tets
                         << " tets");
        state_sizes[k] = static_cast<std::size_t>(6 * n + 9 * n_tets) * sizeof(double);
        if (local[k] < 0)
            continue;
        const Body& body = scene.bodies[at(local[k])];
        CORO_CHECK(name == body.name() && n == body.num_vertices() && n_tets == body.mesh().num_tets(), InputError,
                   where << ": checkpoint body '" << name << "' (" << n << " nodes, " << n_tets
                         << " tets) does not match the case's body '" << body.name() << "' ("
                         << body.num_vertices() << " nodes, " << body.mesh().num_tets() << " tets)");
        if (parts != body.fem().layout().num_parts)
            warnings.emplace_back(static_cast<Index>(k), where + ": body '" + name + "' was split into " + std::to_string(parts) +
                               " METIS parts when saved and into " + std::to_string(body.fem().layout().num_parts) +
                               " now (another machine?): the run continues, but not bitwise as uninterrupted");
    }
    CheckpointState state;
    state.step = static_cast<Index>(r.get<std::int64_t>("step"));
    CORO_CHECK(state.step >= 1, InputError, where << ": corrupt checkpoint: step " << state.step);
    state.summary = get_summary(r);
    state.frames.resize(r.get_count(2 * sizeof(std::int64_t), "frame"));
    for (FrameRecord& frame : state.frames) {
        frame.step = static_cast<Index>(r.get<std::int64_t>("frames"));
        frame.time = r.get<double>("frames");
    }
    for (std::size_t k = 0; k < n_bodies; ++k) {
        if (local[k] < 0) {
            r.skip(state_sizes[k], "body state");
            continue;
        }
        Body& body = scene.bodies[at(local[k])];
        const Index n = body.num_vertices(), n_tets = body.mesh().num_tets();
        for (VecX* values : {&body.positions(), &body.velocities()}) {
            const std::vector<double> nodes = r.get_doubles(at(3 * n), "body state");
            // A run checkpoints only finite states: a NaN here is a damaged (or edited) file.
            const auto bad = std::find_if(nodes.begin(), nodes.end(), [](double x) { return !std::isfinite(x); });
            CORO_CHECK(bad == nodes.end(), InputError,
                       where << ": corrupt checkpoint: body '" << body.name() << "': node "
                             << (bad - nodes.begin()) / 3 << " (mesh file order) has the non-finite "
                             << (values == &body.positions() ? "position" : "velocity") << " component " << *bad);
            for (Index v = 0; v < n; ++v)
                for (int d = 0; d < 3; ++d)
                    (*values)[3 * v + d] = nodes[at(3 * body.input_node(v) + d)];
        }
        const std::vector<double> saved = r.get_doubles(at(9 * n_tets), "rotations");
        CORO_CHECK(std::all_of(saved.begin(), saved.end(), [](double x) { return std::isfinite(x); }), InputError,
                   where << ": corrupt checkpoint: body '" << body.name() << "' has a non-finite rotation");
        std::vector<Mat3> rotations(at(n_tets));
        for (Index t = 0; t < n_tets; ++t)
            std::memcpy(rotations[at(t)].data(), saved.data() + 9 * at(body.input_tet(t)), 9 * sizeof(double));
        body.fem().set_rotations(std::move(rotations));
    }
    CORO_CHECK(r.position() == end, InputError,
               where << ": corrupt checkpoint: " << end - r.position() << " bytes left over after the last body");
    return state;
}

} // namespace coro
