#include <corocontact/sim/simulation.hpp>

#include <corocontact/config.hpp>
#include <corocontact/core/error.hpp>
#include <corocontact/sim/contact_step.hpp>
#include <corocontact/sim/divergence_check.hpp>
#include <corocontact/sim/integrator.hpp>
#include <corocontact/sim/scene_contact.hpp>
#include <corocontact/sim/static_solver.hpp>

#if CORO_WITH_EMBREE
#include <corocontact/embree/embree_detector.hpp>
#endif

#include <algorithm>
#include <chrono>
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
    settings.preconditioner = solver.preconditioner == Preconditioner::JACOBI
                                  ? PcgPreconditioner::JACOBI
                                  : PcgPreconditioner::BLOCK_JACOBI;
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

Simulation::Simulation(Scene& scene, const CaseSpec& spec)
    : m_scene(scene), m_spec(spec), m_divergence(scene.bodies)
{
    if (!spec.contact.enabled)
        return;
    m_scene.surfaces = make_scene_surfaces(m_scene);
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

void Simulation::detect(RunSummary& summary)
{
    if (!m_spec.contact.enabled)
        return;
    ScopedTimer timer(summary.phases.contact);
    update_contact_surfaces(m_scene.bodies, m_scene.surfaces);
    m_scene.contacts = detect_contacts(m_scene.surfaces, detection_settings(m_spec.contact), m_detection);
    if (!m_scene.planes.empty()) {
        std::vector<ContactPoint> planes = detect_plane_contacts(
            m_scene.surfaces, static_cast<Index>(m_scene.bodies.size()), m_scene.planes);
        m_scene.contacts.insert(m_scene.contacts.end(), planes.begin(), planes.end());
        std::sort(m_scene.contacts.begin(), m_scene.contacts.end(), [](const ContactPoint& a, const ContactPoint& b) {
            return std::tie(a.body, a.vertex, a.other) < std::tie(b.body, b.vertex, b.other);
        });
    }
    m_response = contact_response(m_scene.bodies, m_scene.surfaces, m_scene.contacts, m_spec.contact,
                                  m_spec.simulation.dt);
    m_scene.contact_forces = m_response.forces;
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

void Simulation::dynamic_step(RunSummary& summary)
{
    const PcgSettings settings = pcg_settings(m_spec.solver);
    if (m_spec.contact.enabled) {
        for (const PcgResult& result : implicit_euler_step_with_contact(
                 m_scene.bodies, m_response, m_spec.simulation.dt, m_spec.simulation.gravity, settings, summary.phases)) {
            ++summary.solves;
            summary.cg_iterations_mean += result.iterations;
            summary.cg_residual_mean += result.residual;
            summary.solves_not_converged += result.converged ? 0 : 1;
        }
        return;
    }
    for (Body& body : m_scene.bodies) {
        PcgResult result;
        try {
            result = implicit_euler_step(body, m_spec.simulation.dt, m_spec.simulation.gravity, settings,
                                         summary.phases);
        } catch (const NumericalError& error) {
            const std::string what = error.what();
            if (what.rfind("body '", 0) == 0)
                throw;
            CORO_THROW(NumericalError, "body '" << body.name() << "': " << what);
        }
        ++summary.solves;
        summary.cg_iterations_mean += result.iterations;
        summary.cg_residual_mean += result.residual;
        summary.solves_not_converged += result.converged ? 0 : 1;
    }
}

void Simulation::static_step(Index load_step, RunSummary& summary)
{
    const PcgSettings settings = pcg_settings(m_spec.solver);
    const double factor = static_cast<double>(load_step) / m_spec.simulation.load_steps;
    for (Body& body : m_scene.bodies) {
        StaticResult result;
        try {
            result = solve_static(body, factor, m_spec.simulation.gravity, settings, m_spec.solver.static_tolerance,
                                  m_spec.solver.static_max_iterations, summary.phases);
        } catch (const NumericalError& error) {
            const std::string what = error.what();
            if (what.rfind("body '", 0) == 0)
                throw;
            CORO_THROW(NumericalError, "body '" << body.name() << "': " << what);
        }
        ++summary.solves;
        summary.cg_iterations_mean += result.cg_iterations;
        summary.cg_residual_mean += result.residual;
        summary.static_not_converged += result.converged ? 0 : 1;
    }
}

RunSummary Simulation::run(Index steps, const FrameCallback& on_frame, const ProgressCallback& on_progress,
                           const RunControl& control)
{
    const bool is_static = m_spec.simulation.analysis == Analysis::STATIC;
    const Index total = is_static ? m_spec.simulation.load_steps : steps;
    const Index every = is_static ? 1 : m_spec.simulation.output_every;
    const auto time_of = [&](Index step) {
        return is_static ? static_cast<double>(step) / total : step * m_spec.simulation.dt;
    };
    const Index first = control.resume_step;
    CORO_CHECK(first == 0 || first < total, InputError,
               "the run to continue is at step " << first << ", but the case ends at step " << total
                                                 << " (expected a later last step; see --steps)");

    RunSummary summary = first > 0 ? control.resume_summary : RunSummary{};
    summary.first_step = first;
    summary.stop_signal = 0;
    const double wall_before = first > 0 ? summary.wall_s : 0.0;
    const auto start = std::chrono::steady_clock::now();
    const auto update_wall = [&] {
        summary.wall_s = wall_before + std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    };
    const auto write_frame = [&](Index step) {
        if (!on_frame)
            return;
        ScopedTimer timer(summary.phases.output);
        on_frame(step, time_of(step));
    };
    const auto checkpoint = [&](Index step) {
        if (control.checkpoint_every <= 0 || !control.on_checkpoint)
            return;
        update_wall();
        control.on_checkpoint(step, summary);
    };
    const auto stop_requested = [&] { return control.stop != nullptr && control.stop->load() != 0; };

    if (first > 0) {
        // The contact response of the saved state; its counters were taken when it was saved.
        RunSummary scratch;
        detect(scratch);
    } else {
        detect(summary);
        write_frame(0);
    }
    Index step = first;
    if (stop_requested())
        summary.stop_signal = control.stop->load();
    while (summary.stop_signal == 0 && step < total) {
        ++step;
        try {
            if (is_static)
                static_step(step, summary);
            else
                dynamic_step(summary);
            m_divergence.check(m_scene.bodies);
            detect(summary);
        } catch (const NumericalError& error) {
            // Solvers name what failed; add where the first NaN/Inf is, in mesh file numbering.
            const std::string where = locate_non_finite(m_scene.bodies);
            CORO_THROW(NumericalError, "step " << step << " (t = " << time_of(step) << "): " << error.what()
                                               << (where.empty() ? "" : "; first non-finite value: " + where));
        }
        summary.steps = step;
        if (stop_requested())
            summary.stop_signal = control.stop->load();
        const bool frame_due = step % every == 0 || step == total;
        if (frame_due || summary.stop_signal != 0)
            write_frame(step);
        if (step % std::max<Index>(control.checkpoint_every, 1) == 0 || step == total || summary.stop_signal != 0)
            checkpoint(step);
        if (on_progress)
            on_progress(step, total);
    }
    update_wall();
    summary.steps_per_s = summary.wall_s > 0.0 ? summary.steps / summary.wall_s : 0.0;
    if (summary.solves > 0) {
        summary.cg_iterations_mean /= summary.solves;
        summary.cg_residual_mean /= summary.solves;
    }
    if (summary.detections > 0)
        summary.contacts_mean /= summary.detections;
    return summary;
}

} // namespace coro
