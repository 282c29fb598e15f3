#include <corocontact/sim/simulation.hpp>

#include <corocontact/config.hpp>
#include <corocontact/core/collective.hpp>
#include <corocontact/core/error.hpp>
#include <corocontact/sim/divergence_check.hpp>
#include <corocontact/sim/rank_contact.hpp>
#include <corocontact/sim/run_notes.hpp>
#include <corocontact/solver/rank_exchange.hpp>
#include <corocontact/sim/scene_contact.hpp>
#include <corocontact/sim/static_solver.hpp>

#if CORO_WITH_EMBREE
#include <corocontact/embree/embree_detector.hpp>
#endif

#include <algorithm>
#include <chrono>
#include <cstring>
#include <optional>
#include <tuple>
#include <string>

namespace coro {

Index Scene::num_tets() const
{
    Index n = 0;
    for (const Body& body : bodies)
        n += body.mesh().num_tets();
    return n;
}

Index Scene::num_vertices() const
{
    Index n = 0;
    for (const Body& body : bodies)
        n += body.num_vertices();
    return n;
}

PcgSettings pcg_settings(const SolverSettings& solver)
{
    PcgSettings settings;
    settings.max_iterations = solver.max_iterations;
    settings.tolerance = solver.tolerance;
    settings.preconditioner = solver.preconditioner;
    return settings;
}

#if CORO_WITH_EMBREE
struct Simulation::EmbreeCheck {
    EmbreeScenes scenes;
    explicit EmbreeCheck(const std::vector<ContactSurface>& surfaces) : scenes(surfaces) {}
};
#else
struct Simulation::EmbreeCheck {};
#endif

struct Simulation::Ranks {
    Communicator& communicator;
    RankExchange exchange;
    std::optional<RankContact> contact; // with contact enabled
    std::uint64_t step_bytes = 0;  // received during the steps of this run
    std::uint64_t solve_bytes = 0; // of those, during the solves
    std::size_t case_bodies = 0;   // bodies of all processes
    Index steps = 0;              // steps of this run
    Index cross_rank = 0;         // contacts detected here that touch another process, summed
    Index detections = 0;         // detections of this run (a restart's totals hold the first run's)
    std::vector<Index> body_ids;  // the case index of each body of this process

    Ranks(const SceneDistribution& distribution, const Scene& scene, SceneMatrix& matrix, bool with_contact)
        : communicator(*distribution.communicator),
          exchange(communicator, chunk_bodies(distribution, matrix), matrix.num_block_rows()),
          case_bodies(distribution.ownership.owner.size()), body_ids(distribution.body_ids)
    {
        // Until a detection joins them, every case body is a component of its own.
        matrix.set_components(distribution.body_ids, exchange.num_components());
        if (with_contact)
            contact.emplace(communicator, distribution.ownership, distribution.body_ids, scene);
    }
    static std::vector<Index> chunk_bodies(const SceneDistribution& distribution, const SceneMatrix& matrix)
    {
        std::vector<Index> bodies;
        for (Index c = 0; c < matrix.chunks().num_chunks(); ++c)
            bodies.push_back(distribution.body_ids[static_cast<std::size_t>(matrix.chunk_body(c))]);
        return bodies;
    }
};

namespace {
// Seconds since `start`.
double seconds_since(std::chrono::steady_clock::time_point start)
{
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

// What a preconditioner did between two readings of its counters, added to `total`.
void add_difference(const PreconditionerTimes& before, const PreconditionerTimes& after, PreconditionerTimes& total)
{
    total.setups += after.setups - before.setups;
    total.setup_s += after.setup_s - before.setup_s;
    total.applies += after.applies - before.applies;
    total.apply_s += after.apply_s - before.apply_s;
}

void add_solve(const PcgResult& result, RunSummary& summary)
{
    ++summary.solves;
    summary.cg_iterations_mean += result.iterations;
    summary.cg_residual_mean += result.residual;
    summary.solves_not_converged += result.converged ? 0 : 1;
}
} // namespace

Simulation::Simulation(Scene& scene, const CaseSpec& spec, const SceneDistribution* distribution)
    : m_scene(scene), m_spec(spec), m_system(scene.bodies), m_divergence(scene.bodies)
{
    const bool distributed = distribution != nullptr && distribution->communicator != nullptr;
    CORO_CHECK(!distributed || !contact_applies(spec) || spec.contact.cross_check != CrossCheck::EMBREE, InputError,
               spec.file.string() << ": contact.cross_check = \"embree\" runs in one process only (expected "
                                     "\"none\" under mpirun with several processes)");
    if (contact_applies(spec))
        m_scene.surfaces = make_scene_surfaces(m_scene);
    if (distributed)
        m_ranks = std::make_unique<Ranks>(*distribution, m_scene, m_system.matrix(), contact_applies(spec));
    if (!contact_applies(spec))
        return;
    if (spec.contact.cross_check == CrossCheck::EMBREE) {
#if CORO_WITH_EMBREE
        m_embree = std::make_unique<EmbreeCheck>(m_scene.surfaces);
#else
        CORO_THROW(InputError, spec.file.string() << ": contact.cross_check = \"embree\", but this build has no "
                                                     "Embree (configure with CORO_WITH_EMBREE=ON)");
#endif
    }
}

Simulation::~Simulation() = default;

void Simulation::collectively(FunctionRef<void()> work)
{
    if (!m_ranks) {
        work();
        return;
    }
    // A failure in a body: of all processes', the one in the first body in case order, as one
    // process meets it first.
    Index body = -1;
    std::string message;
    run_collectively(&m_ranks->communicator, [&] {
        try {
            work();
        } catch (const NumericalError& error) {
            if (error.body() < 0)
                throw;
            body = error.body();
            message = error.what();
        }
    });
    message = first_over_processes(body, std::move(message));
    if (!message.empty())
        throw NumericalError(message);
}

void Simulation::detect(RunSummary& summary)
{
    if (!contact_applies(m_spec))
        return;
    ScopedTimer timer(summary.phases.contact);
    if (m_ranks) {
        const RankContact::Counts counts = m_ranks->contact->detect(
            m_scene, m_spec.contact, m_spec.simulation.dt, m_response, m_system.matrix(), m_ranks->exchange);
        ++summary.detections;
        summary.contacts_mean += static_cast<double>(counts.contacts);
        summary.max_contact_depth = std::max(summary.max_contact_depth, counts.max_depth);
        m_ranks->cross_rank += counts.cross_rank;
        ++m_ranks->detections;
        return;
    }
    update_contact_surfaces(m_scene.bodies, m_scene.surfaces);
    // Into buffers kept from step to step: a step allocates nothing once they have grown.
    const auto num_bodies = static_cast<Index>(m_scene.bodies.size());
    detect_contacts(m_scene.surfaces, detection_settings(m_spec.contact), m_detection, m_surface_contacts);
    if (m_scene.planes.empty()) {
        m_scene.contacts.swap(m_surface_contacts);
    } else {
        detect_plane_contacts(m_scene.surfaces, num_bodies, m_scene.planes, m_plane_contacts, m_plane_scratch);
        m_scene.contacts.resize(m_surface_contacts.size() + m_plane_contacts.size());
        std::merge(m_surface_contacts.begin(), m_surface_contacts.end(), m_plane_contacts.begin(),
                   m_plane_contacts.end(), m_scene.contacts.begin(), contact_order);
    }
    contact_components(m_detection.overlapping_surfaces(), num_bodies, m_components);
    m_system.matrix().set_components(m_components);
    m_response.compute(m_scene.bodies, m_scene.surfaces, m_scene.contacts, m_spec.contact, m_spec.simulation.dt,
                       m_system.matrix(), m_scene.contact_forces);
    ++summary.detections;
    summary.contacts_mean += static_cast<double>(m_scene.contacts.size());
    for (const ContactPoint& point : m_scene.contacts)
        summary.max_contact_depth = std::max(summary.max_contact_depth, point.depth);
#if CORO_WITH_EMBREE
    if (m_embree) {
        m_embree->scenes.update(m_scene.surfaces);
        // The summary counts inside/outside disagreements only: no depth queries for it.
        DetectionSettings settings = detection_settings(m_spec.contact);
        settings.contact_data = false;
        const std::vector<ContactPoint> embree =
            detect_contacts_embree(m_scene.surfaces, m_embree->scenes, settings);
        summary.embree_disagreements += static_cast<Index>(cross_check(m_scene.contacts, embree).size());
    }
#endif
}

void Simulation::update_contact_response()
{
    if (!contact_applies(m_spec))
        return;
    m_response.compute(m_scene.bodies, m_scene.surfaces, m_scene.contacts, m_spec.contact, m_spec.simulation.dt,
                       m_system.matrix(), m_scene.contact_forces);
}

void Simulation::dynamic_step()
{
    const double dt = m_spec.simulation.dt;
    PhaseTimes& phases = m_totals.phases;
    collectively([&] {
        {
            ScopedTimer timer(phases.rotation);
            m_system.element_loop(dt);
        }
        ScopedTimer timer(phases.assembly);
        m_system.assemble(dt, m_spec.simulation.gravity, m_scene.contact_forces); // empty without contact
    });
    ScopedTimer timer(phases.solve);
    const PreconditionerTimes before = m_system.preconditioner_times();
    const std::uint64_t bytes = m_ranks ? m_ranks->communicator.bytes_received() : 0;
    add_solve(m_system.solve(pcg_settings(m_spec.solver), m_ranks ? &m_ranks->exchange : nullptr), m_totals);
    if (m_ranks)
        m_ranks->solve_bytes += m_ranks->communicator.bytes_received() - bytes;
    add_difference(before, m_system.preconditioner_times(), m_totals.preconditioner);
    collectively([&] { m_system.advance(dt); });
}

void Simulation::static_step(Index load_step)
{
    const PcgSettings settings = pcg_settings(m_spec.solver);
    const double factor = static_cast<double>(load_step) / m_spec.simulation.load_steps;
    for (Body& body : m_scene.bodies) {
        StaticResult result;
        const PreconditionerTimes before = body.pcg().preconditioner_times();
        try {
            result = solve_static(body, factor, m_spec.simulation.gravity, settings, m_spec.solver.static_tolerance,
                                  m_spec.solver.static_max_iterations, m_totals.phases);
        } catch (const NumericalError& error) {
            const std::string what = error.what();
            if (what.rfind("body '", 0) == 0)
                throw;
            CORO_THROW(NumericalError, "body '" << body.name() << "': " << what);
        }
        add_difference(before, body.pcg().preconditioner_times(), m_totals.preconditioner);
        m_totals.solves += result.solves;
        m_totals.cg_iterations_mean += result.cg_iterations;
        m_totals.cg_residual_mean += result.cg_residual_sum;
        m_totals.solves_not_converged += result.solves_not_converged;
        m_totals.static_not_converged += result.converged ? 0 : 1;
        m_totals.static_iterations_mean += result.iterations;
        m_totals.static_iterations_max = std::max(m_totals.static_iterations_max, result.iterations);
    }
}

double Simulation::time_of(Index step) const
{
    return m_spec.simulation.analysis == Analysis::STATIC
               ? static_cast<double>(step) / static_cast<double>(m_spec.simulation.load_steps)
               : static_cast<double>(step) * m_spec.simulation.dt;
}

void Simulation::start(Index resume_step, const RunSummary& resume)
{
    const auto start = std::chrono::steady_clock::now();
    m_step = resume_step;
    if (resume_step > 0) {
        // The contact response of the saved state; its counters were taken when it was saved.
        m_totals = resume;
        if (m_ranks && m_ranks->communicator.rank() != 0) {
            // Counters summed over the processes (totals()) continue from rank 0's.
            m_totals.contacts_mean = 0.0;
            if (m_spec.simulation.analysis == Analysis::STATIC) {
                m_totals.cg_iterations_mean = m_totals.cg_residual_mean = m_totals.static_iterations_mean = 0.0;
                m_totals.solves = m_totals.solves_not_converged = m_totals.static_not_converged = 0;
            }
        }
        RunSummary scratch;
        detect(scratch);
    } else {
        m_totals = RunSummary{};
        detect(m_totals);
    }
    m_totals.first_step = resume_step;
    m_totals.stop_signal = 0;
    m_totals.wall_s += seconds_since(start);
}

std::string Simulation::first_over_processes(Index body, std::string text) const
{
    if (!m_ranks)
        return text;
    const Index case_body = body < 0 ? -1 : m_ranks->body_ids[static_cast<std::size_t>(body)];
    std::vector<char> mine(sizeof case_body + text.size());
    std::memcpy(mine.data(), &case_body, sizeof case_body);
    std::copy(text.begin(), text.end(), mine.begin() + sizeof case_body);
    Index best = -1;
    for (const std::vector<char>& theirs : m_ranks->communicator.all_gather(mine)) {
        Index theirs_body;
        std::memcpy(&theirs_body, theirs.data(), sizeof theirs_body);
        if (theirs_body >= 0 && (best < 0 || theirs_body < best)) {
            best = theirs_body;
            text.assign(theirs.begin() + sizeof theirs_body, theirs.end());
        }
    }
    return text;
}

std::string Simulation::first_non_finite() const
{
    for (std::size_t b = 0; b < m_scene.bodies.size(); ++b)
        if (std::string where = locate_non_finite(m_scene.bodies[b]); !where.empty())
            return first_over_processes(static_cast<Index>(b), std::move(where));
    return first_over_processes(-1, {});
}

void Simulation::step()
{
    const auto start = std::chrono::steady_clock::now();
    const std::uint64_t bytes = m_ranks ? m_ranks->communicator.bytes_received() : 0;
    const Index step = m_step + 1;
    try {
        if (m_spec.simulation.analysis == Analysis::STATIC)
            collectively([&] { static_step(step); });
        else
            dynamic_step();
        collectively([&] { m_divergence.check(m_scene.bodies); });
        detect(m_totals);
    } catch (const NumericalError& error) {
        // Solvers name what failed; add where the first NaN/Inf is, in mesh file numbering.
        const std::string where = first_non_finite();
        CORO_THROW(NumericalError, "step " << step << " (t = " << time_of(step) << "): " << error.what()
                                           << (where.empty() ? "" : "; first non-finite value: " + where));
    }
    m_step = step;
    m_totals.steps = step;
    m_totals.wall_s += seconds_since(start);
    if (m_ranks) {
        m_ranks->step_bytes += m_ranks->communicator.bytes_received() - bytes;
        ++m_ranks->steps;
    }
}

namespace {
// Σ over the processes of one value each, added in rank order.
double sum_over_ranks(Communicator& communicator, double value)
{
    std::vector<double> all(static_cast<std::size_t>(communicator.size()));
    std::vector<int> counts(all.size(), 1), offsets(all.size());
    for (std::size_t r = 0; r < offsets.size(); ++r)
        offsets[r] = static_cast<int>(r);
    communicator.all_gather(&value, 1, all.data(), counts.data(), offsets.data());
    double sum = 0.0;
    for (const double v : all)
        sum += v;
    return sum;
}
} // namespace

RunSummary Simulation::totals() const
{
    RunSummary totals = m_totals;
    if (!m_ranks)
        return totals;
    // Contacts are counted where they are detected; static load steps solve each process's
    // bodies; everything else is the same on every process (a dynamic step's one solve).
    Communicator& communicator = m_ranks->communicator;
    totals.contacts_mean = sum_over_ranks(communicator, totals.contacts_mean);
    communicator.all_reduce(&totals.max_contact_depth, 1, Reduction::MAX);
    if (m_spec.simulation.analysis == Analysis::STATIC) {
        totals.cg_iterations_mean = sum_over_ranks(communicator, totals.cg_iterations_mean);
        totals.cg_residual_mean = sum_over_ranks(communicator, totals.cg_residual_mean);
        totals.static_iterations_mean = sum_over_ranks(communicator, totals.static_iterations_mean);
        std::int64_t counts[] = {totals.solves, totals.solves_not_converged, totals.static_not_converged};
        communicator.all_reduce(counts, 3, Reduction::SUM);
        totals.solves = static_cast<Index>(counts[0]);
        totals.solves_not_converged = static_cast<Index>(counts[1]);
        totals.static_not_converged = static_cast<Index>(counts[2]);
        std::int64_t most = totals.static_iterations_max;
        communicator.all_reduce(&most, 1, Reduction::MAX);
        totals.static_iterations_max = static_cast<Index>(most);
    }
    return totals;
}

RankStats Simulation::rank_stats() const
{
    RankStats stats;
    if (!m_ranks)
        return stats;
    stats.ranks = m_ranks->communicator.size();
    const double steps = static_cast<double>(std::max<Index>(m_ranks->steps, 1));
    stats.mpi_bytes_per_step = static_cast<double>(m_ranks->step_bytes) / steps;
    stats.solve_bytes_per_step = static_cast<double>(m_ranks->solve_bytes) / steps;
    std::int64_t cross_rank = m_ranks->cross_rank;
    m_ranks->communicator.all_reduce(&cross_rank, 1, Reduction::SUM);
    stats.cross_rank_contacts_mean =
        m_ranks->detections > 0 ? static_cast<double>(cross_rank) / static_cast<double>(m_ranks->detections) : 0.0;
    return stats;
}

RunSummary Simulation::summary() const
{
    RunSummary summary = totals();
    summary.steps_per_s = summary.wall_s > 0.0 ? summary.steps / summary.wall_s : 0.0;
    if (summary.solves > 0) {
        summary.cg_iterations_mean /= summary.solves;
        summary.cg_residual_mean /= summary.solves;
    }
    if (summary.detections > 0)
        summary.contacts_mean /= summary.detections;
    const std::size_t bodies = m_ranks ? m_ranks->case_bodies : m_scene.bodies.size();
    if (m_spec.simulation.analysis == Analysis::STATIC && summary.steps > 0)
        summary.static_iterations_mean /= static_cast<double>(summary.steps) * static_cast<double>(bodies);
    return summary;
}

RunSummary Simulation::run(Index steps, const FrameCallback& on_frame, const ProgressCallback& on_progress,
                           const RunControl& control)
{
    const bool is_static = m_spec.simulation.analysis == Analysis::STATIC;
    const Index total = is_static ? m_spec.simulation.load_steps : steps;
    const Index every = is_static ? 1 : m_spec.simulation.output_every;
    const Index first = control.resume_step;
    CORO_CHECK(first == 0 || first < total, InputError,
               "the run to continue is at step " << first << ", but the case ends at step " << total
                                                 << " (expected a later last step; see --steps)");
    const auto timed = [&](double& phase, const auto& work) {
        const auto start = std::chrono::steady_clock::now();
        work();
        const double seconds = seconds_since(start);
        phase += seconds;
        m_totals.wall_s += seconds;
    };
    const auto write_frame = [&](Index step) {
        if (on_frame)
            timed(m_totals.phases.output, [&] { on_frame(step, time_of(step)); });
    };
    const auto checkpoint = [&](Index step) {
        if (control.checkpoint_every <= 0 || !control.on_checkpoint)
            return;
        double unused = 0.0;
        timed(unused, [&] { control.on_checkpoint(step, totals()); });
    };
    // Distributed: a signal may reach the processes in different steps; all stop at the first.
    const auto stop_signal = [&] {
        std::int64_t signal = control.stop != nullptr ? control.stop->load() : 0;
        if (m_ranks)
            m_ranks->communicator.all_reduce(&signal, 1, Reduction::MAX);
        return static_cast<int>(signal);
    };

    start(first, control.resume_summary);
    if (first == 0)
        write_frame(0);
    m_totals.stop_signal = stop_signal();
    while (m_totals.stop_signal == 0 && m_step < total) {
        step();
        m_totals.stop_signal = stop_signal();
        const bool frame_due = m_step % every == 0 || m_step == total;
        if (frame_due || m_totals.stop_signal != 0)
            write_frame(m_step);
        if (m_step % std::max<Index>(control.checkpoint_every, 1) == 0 || m_step == total || m_totals.stop_signal != 0)
            checkpoint(m_step);
        if (on_progress)
            on_progress(m_step, total);
    }
    return summary();
}

} // namespace coro
