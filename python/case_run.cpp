#include "case_run.hpp"

#include <corocontact/core/atomic_file.hpp>
#include <corocontact/core/error.hpp>
#include <corocontact/core/tet_mesh.hpp>
#include <corocontact/io/case_reader.hpp>
#include <corocontact/io/magnitudes.hpp>
#include <corocontact/io/run_files.hpp>
#include <corocontact/io/scene_output.hpp>
#include <corocontact/sim/run_notes.hpp>

#include <sys/resource.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <charconv>
#include <chrono>
#include <cmath>
#include <sstream>

namespace coro::python {

namespace {

double peak_rss_mb()
{
    rusage usage{};
    getrusage(RUSAGE_SELF, &usage);
    return static_cast<double>(usage.ru_maxrss) / 1024.0; // ru_maxrss is in KiB on Linux
}

/// The shortest text that reads back as `value` (10.0000001, not 10).
std::string number_text(double value)
{
    char buffer[32];
    const auto end = std::to_chars(buffer, buffer + sizeof buffer, value).ptr;
    return std::string(buffer, end);
}

std::string format_row(const Eigen::RowVector3d& row)
{
    return "(" + number_text(row[0]) + ", " + number_text(row[1]) + ", " + number_text(row[2]) + ")";
}

/// The first row (input node) of `rows` holding a non-finite number, or −1.
Index first_non_finite_row(CRef<Positions> rows)
{
    for (Index v = 0; v < rows.rows(); ++v)
        if (!rows.row(v).allFinite())
            return v;
    return -1;
}

/// The case reader's check of a number (io/case_reader.cpp: POSITIVE, NON_NEGATIVE).
void check_number(double value, bool positive, const char* key)
{
    const char* range = positive ? " > 0" : " >= 0";
    CORO_CHECK(std::isfinite(value), InputError,
               key << ": expected a finite number" << range << ", found " << number_text(value));
    CORO_CHECK(positive ? value > 0.0 : value >= 0.0, InputError,
               key << ": expected a number" << range << ", found " << number_text(value));
}

} // namespace

CaseRun::CaseRun(const std::filesystem::path& case_file, std::optional<Index> threads,
                 const std::filesystem::path& output_dir)
{
    const auto setup_start = std::chrono::steady_clock::now();
    if (threads) {
        CORO_CHECK(*threads >= 1, InputError,
                   "threads = " << *threads << ": expected an integer >= 1, or None for all cores");
        m_threads = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism,
                                                          static_cast<std::size_t>(*threads));
    }
    m_spec = read_case(case_file);
    if (!output_dir.empty())
        m_spec.simulation.output_dir = output_dir;
    m_loaded = load_scene(m_spec);
    m_simulation = std::make_unique<Simulation>(m_loaded.scene, m_spec);
    // What `corocontact run` tells after loading (tools/corocontact.cpp).
    m_load_warnings = m_loaded.warnings;
    if (const auto note = contact_not_applied_note(m_spec))
        m_load_warnings.push_back(*note);
    if (!m_spec.contact.enabled && !m_spec.obstacles.empty())
        m_load_warnings.push_back(m_spec.obstacles.front().location +
                                  ": the obstacles have no effect, because contact.enabled is false (set enabled = "
                                  "true in [contact])");
    m_setup_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - setup_start).count();
    m_simulation->start(); // counted in the summary's wall_s, as in Simulation::run
}

CaseRun::~CaseRun() = default;

Index CaseRun::threads() const
{
    // As `corocontact run` reports them: never more than the task arena has.
    const auto allowed = tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism);
    return static_cast<Index>(
        std::min<std::size_t>(allowed, static_cast<std::size_t>(tbb::this_task_arena::max_concurrency())));
}

void CaseRun::check_can_step(Index n) const
{
    CORO_CHECK(m_diverged.empty(), NumericalError,
               m_diverged << " (the state is what the failed step left; load the case again to go on)");
    if (m_spec.simulation.analysis != Analysis::STATIC)
        return;
    const Index left = m_spec.simulation.load_steps - steps_done();
    CORO_CHECK(n <= left, InputError,
               "step(n = " << n << "): " << left << " of the " << m_spec.simulation.load_steps
                           << " load steps of this static analysis are left (simulation.load_steps)");
}

void CaseRun::step()
{
    check_can_step(1);
    try {
        m_simulation->step();
    } catch (const NumericalError& e) {
        m_diverged = e.what();
        throw;
    }
}

RunSummary CaseRun::summary() const
{
    RunSummary summary = m_simulation->summary();
    summary.phases.output += m_output_s;
    summary.wall_s += m_output_s;
    summary.steps_per_s = summary.wall_s > 0.0 ? summary.steps / summary.wall_s : 0.0;
    return summary;
}

std::string CaseRun::summary_json() const
{
    SummaryContext context;
    context.name = m_spec.simulation.name;
    context.threads = threads();
    context.bodies = static_cast<Index>(scene().bodies.size());
    context.tets = scene().num_tets();
    context.peak_rss_mb = peak_rss_mb();
    context.setup_s = m_setup_s;
    return coro::summary_json(summary(), context);
}

VtkSeriesWriter& CaseRun::writer()
{
    if (m_writer)
        return *m_writer;
    const std::filesystem::path& dir = m_spec.simulation.output_dir;
    const std::string& name = m_spec.simulation.name;
    // Kept only once the writer stands: a write that fails here lets the folder go again, so a
    // retry (after the user fixed the cause) does not find its own lock.
    auto lock = std::make_unique<OutputLock>(dir, "python3: corocontact.Simulation('" + m_spec.file.string() + "')");
    std::vector<std::string> notes;
    if (!lock->stale_owner().empty())
        notes.push_back(lock->path().string() + ": taking over the lock of a run that ended without " +
                        "removing it (" + lock->stale_owner() + ")");
    const RemovedFiles removed = remove_earlier_run(dir, name, -1, false);
    if (removed.files > 0)
        notes.push_back("removed " + std::to_string(removed.files) + " files (" + std::to_string(removed.frames) +
                        " frames) of an earlier run of " + name + " from " + dir.string());
    m_writer = std::make_unique<VtkSeriesWriter>(dir, name);
    m_lock = std::move(lock);
    m_output_notes.insert(m_output_notes.end(), notes.begin(), notes.end());
    return *m_writer;
}

std::filesystem::path CaseRun::write_summary()
{
    writer();
    const auto path = summary_path(m_spec.simulation.output_dir, m_spec.simulation.name);
    write_file_atomically(path, summary_json());
    return path;
}

std::filesystem::path CaseRun::write_frame()
{
    CORO_CHECK(m_diverged.empty(), NumericalError, m_diverged << " (a frame of this state would be meaningless)");
    const Index step = steps_done();
    CORO_CHECK(step != m_last_frame, InputError,
               "write_frame(): the frame of step " << step << " is already written (step first)");
    const auto start = std::chrono::steady_clock::now();
    writer().write_frame(step, time(), scene_frame(scene()));
    m_last_frame = step;
    m_output_s += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return m_writer->pvd_path();
}

std::filesystem::path CaseRun::series_path() const
{
    return m_spec.simulation.output_dir / (m_spec.simulation.name + ".pvd");
}

Body& CaseRun::body(Index b)
{
    return m_loaded.scene.bodies[static_cast<std::size_t>(b)];
}

void CaseRun::check_scales(const CaseSpec& spec, const char* what) const
{
    for (std::size_t b = 0; b < spec.bodies.size(); ++b)
        check_scales(spec, static_cast<Index>(b), spec.bodies[b], what);
}

void CaseRun::check_scales(const CaseSpec& spec, Index b, const BodySpec& body_spec, const std::string& what) const
{
    // The value comes from Python, not from the case file's line: the message starts with its name.
    BodySpec from_python = body_spec;
    from_python.location = what;
    check_magnitudes(spec, from_python, scene().bodies[static_cast<std::size_t>(b)].mesh());
}

namespace {

/// The row of `rows` with the largest norm (zero for none).
Vec3 largest_row(CRef<Positions> rows)
{
    Vec3 largest = Vec3::Zero();
    for (Index v = 0; v < rows.rows(); ++v)
        if (rows.row(v).stableNorm() > largest.stableNorm())
            largest = rows.row(v).transpose();
    return largest;
}

} // namespace

void CaseRun::set_velocities(Index b, CRef<Positions> velocities)
{
    Body& target = body(b);
    const Index bad = first_non_finite_row(velocities);
    CORO_CHECK(bad < 0, InputError,
               "body '" << target.name() << "': velocities[" << bad << "] = " << format_row(velocities.row(bad))
                        << ": expected finite numbers");
    for (Index v = 0; v < target.num_vertices(); ++v) {
        const Index node = target.input_node(v);
        CORO_CHECK(!target.fixed()[static_cast<std::size_t>(v)] || velocities.row(node).isZero(0.0), InputError,
                   "body '" << target.name() << "': velocities[" << node << "] = " << format_row(velocities.row(node))
                            << ": node " << node << " is fixed, expected velocity 0 there");
    }
    BodySpec scaled = m_spec.bodies[static_cast<std::size_t>(b)]; // the fastest node as its velocity
    scaled.velocity = largest_row(velocities);
    check_scales(m_spec, b, scaled, "velocities");
    target.velocities() = target.from_input_order(velocities);
    m_simulation->update_contact_response();
}

void CaseRun::check_fixed(Index b, const std::vector<char>& fixed) const
{
    const Body& target = scene().bodies[static_cast<std::size_t>(b)];
    // A node in no tet has no mass: released, it would make the system singular.
    for (const Index v : unreferenced_vertices(target.mesh())) {
        const Index node = target.input_node(v);
        CORO_CHECK(fixed[static_cast<std::size_t>(node)], InputError,
                   "body '" << target.name() << "': fixed[" << node << "] = False: node " << node
                            << " belongs to no tet, expected it to stay fixed");
    }
}

void CaseRun::set_fixed(Index b, const std::vector<char>& fixed)
{
    check_fixed(b, fixed);
    Body& target = body(b);
    std::vector<char> internal(fixed.size());
    for (Index v = 0; v < target.num_vertices(); ++v)
        internal[static_cast<std::size_t>(v)] = fixed[static_cast<std::size_t>(target.input_node(v))];
    target.set_fixed(internal);
    m_simulation->update_contact_response();
}

void CaseRun::check_loads(Index b, CRef<Positions> loads) const
{
    const Body& target = scene().bodies[static_cast<std::size_t>(b)];
    const Index bad = first_non_finite_row(loads);
    CORO_CHECK(bad < 0, InputError,
               "body '" << target.name() << "': loads[" << bad << "] = " << format_row(loads.row(bad))
                        << ": expected finite numbers");
    // The largest node force as the force per node, and that on every node as the total.
    BodySpec scaled = m_spec.bodies[static_cast<std::size_t>(b)];
    scaled.loads.assign(1, BoxLoad{});
    scaled.loads[0].force = largest_row(loads) * static_cast<double>(target.num_vertices());
    check_scales(m_spec, b, scaled, "loads");
}

void CaseRun::set_loads(Index b, CRef<Positions> loads)
{
    check_loads(b, loads);
    Body& target = body(b);
    target.load_forces() = target.from_input_order(loads);
}

std::optional<std::string> CaseRun::loads_on_fixed_nodes(Index b, const Positions* loads,
                                                         const std::vector<char>* fixed) const
{
    const Body& target = scene().bodies[static_cast<std::size_t>(b)];
    const VecX forces = loads ? target.from_input_order(*loads) : target.load_forces();
    Vec3 lost = Vec3::Zero(), total = Vec3::Zero();
    for (Index v = 0; v < target.num_vertices(); ++v) {
        total += forces.segment<3>(3 * v);
        const bool held = fixed ? (*fixed)[static_cast<std::size_t>(target.input_node(v))] != 0
                                : target.fixed()[static_cast<std::size_t>(v)] != 0;
        if (held)
            lost += forces.segment<3>(3 * v);
    }
    if (!(lost.stableNorm() > 1e-12 * total.stableNorm()))
        return std::nullopt;
    std::ostringstream message;
    message << "body '" << target.name() << "': " << lost.stableNorm() << " of the " << total.stableNorm()
            << " N of its loads fall on fixed nodes and have no effect";
    return message.str();
}

void CaseRun::set_gravity(const Vec3& gravity)
{
    CORO_CHECK(gravity.allFinite(), InputError,
               "gravity = " << format_row(gravity.transpose()) << ": expected finite numbers");
    CaseSpec changed = m_spec;
    changed.simulation.gravity = gravity;
    check_scales(changed, "gravity");
    m_spec.simulation.gravity = gravity;
}

void CaseRun::check_contact_applies(const char* key) const
{
    CORO_CHECK(m_spec.contact.enabled, InputError,
               key << ": the case has no contact (expected [contact] enabled = true in " << m_spec.file.string()
                   << ")");
    CORO_CHECK(contact_applies(m_spec), InputError,
               key << ": contact is not applied in static analysis (expected analysis = \"dynamic\" in "
                   << m_spec.file.string() << ")");
}

void CaseRun::set_contact_stiffness(double stiffness)
{
    check_contact_applies("contact.stiffness");
    check_number(stiffness, true, "contact.stiffness");
    CaseSpec changed = m_spec;
    changed.contact.stiffness = stiffness;
    check_scales(changed, "contact.stiffness");
    m_spec.contact.stiffness = stiffness;
    m_simulation->update_contact_response();
}

void CaseRun::set_contact_damping(double damping)
{
    check_contact_applies("contact.damping");
    check_number(damping, false, "contact.damping");
    CaseSpec changed = m_spec;
    changed.contact.damping = damping;
    check_scales(changed, "contact.damping");
    m_spec.contact.damping = damping;
    m_simulation->update_contact_response();
}

void CaseRun::set_contact_friction(double friction)
{
    check_contact_applies("contact.friction");
    CORO_CHECK(friction >= 0.0 && friction <= MAX_FRICTION, InputError, // false for NaN too
               "contact.friction: expected a number in [0, " << MAX_FRICTION << "], found " << number_text(friction));
    CaseSpec changed = m_spec;
    changed.contact.friction = friction;
    check_scales(changed, "contact.friction");
    m_spec.contact.friction = friction;
    m_simulation->update_contact_response();
}

} // namespace coro::python
