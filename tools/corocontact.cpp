// The corocontact command: run a case, describe a mesh.
// Exit codes: 0 success, 2 bad input, 3 the simulation diverged, 4 the output could not be
// written (or its folder is in use by another run).

#include "progress.hpp"

#include <corocontact/config.hpp>
#include <corocontact/core/atomic_file.hpp>
#include <corocontact/core/error.hpp>
#include <corocontact/core/surface_mesh.hpp>
#include <corocontact/io/case_reader.hpp>
#include <corocontact/io/mesh_readers.hpp>
#include <corocontact/io/output_lock.hpp>
#include <corocontact/io/run_files.hpp>
#include <corocontact/io/scene_loader.hpp>
#include <corocontact/io/scene_output.hpp>
#include <corocontact/io/vtk_series.hpp>
#include <corocontact/sim/checkpoint.hpp>
#include <corocontact/sim/interrupt.hpp>
#include <corocontact/sim/scene_contact.hpp>
#if CORO_WITH_EMBREE
#include <corocontact/embree/embree_detector.hpp>
#endif
#include <corocontact/partition/part_layout.hpp>
#include <corocontact/partition/partition.hpp>

#include <CLI/CLI.hpp>
#include <tbb/global_control.h>
#include <tbb/info.h>

#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <charconv>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <iostream>
#include <limits>
#include <memory>

namespace {

constexpr int EXIT_BAD_INPUT = 2;
constexpr int EXIT_DIVERGED = 3;
constexpr int EXIT_OUTPUT_FAILED = 4;
constexpr int EXIT_SIGNAL_BASE = 128; // stopped by signal s: exit 128 + s (130 SIGINT, 143 SIGTERM)

double peak_rss_mb()
{
    rusage usage{};
    getrusage(RUSAGE_SELF, &usage);
    return static_cast<double>(usage.ru_maxrss) / 1024.0; // ru_maxrss is in KiB on Linux
}

struct RunOptions {
    std::string case_file;
    std::string out;
    int threads = 0;
    long steps = 0;
    bool quiet = false;
    long checkpoint_every = 0;
    std::string restart;
};

/// NAME_<step, 6 digits>.vtm, as VtkSeriesWriter names a frame.
std::string frame_file(const std::string& name, coro::Index step)
{
    const std::string digits = std::to_string(step);
    return name + "_" + std::string(digits.size() < 6 ? 6 - digits.size() : 0, '0') + digits + ".vtm";
}

/// A count from the command line as an Index: refused beyond its range instead of wrapping.
coro::Index option_index(long value, const char* option)
{
    constexpr long MAX = std::numeric_limits<coro::Index>::max();
    CORO_CHECK(value <= MAX, InputError, option << " " << value << ": expected at most " << MAX);
    return static_cast<coro::Index>(value);
}

const char* signal_name(int signal_number)
{
    return signal_number == SIGINT ? "SIGINT" : signal_number == SIGTERM ? "SIGTERM" : "a signal";
}

int run_case(const RunOptions& options)
{
    coro::CaseSpec spec = coro::read_case(options.case_file);
    if (!options.out.empty())
        spec.simulation.output_dir = options.out;
    if (options.steps > 0) {
        CORO_CHECK(spec.simulation.analysis == coro::Analysis::DYNAMIC, InputError,
                   "--steps " << options.steps << ": " << options.case_file
                              << " is a static analysis, whose steps are simulation.load_steps; --steps sets the "
                                 "time steps of a dynamic one");
        spec.simulation.steps = option_index(options.steps, "--steps");
    }
    const coro::Index checkpoint_every = option_index(options.checkpoint_every, "--checkpoint-every");
    // One run per output folder, claimed before the (possibly long) load; a run refused for bad
    // input removes its lock file again, and the folder if it made it.
    const std::filesystem::path& out_dir = spec.simulation.output_dir;
    const coro::OutputLock lock(out_dir, "corocontact run " + options.case_file);
    if (!lock.stale_owner().empty())
        std::cerr << "warning: " << lock.path().string() << ": taking over the lock of a run that ended without "
                  << "removing it (" << lock.stale_owner() << ")\n";

    // Everything is loaded and checked before anything but the lock file is written there.
    coro::LoadedScene loaded = coro::load_scene(spec);
    for (const std::string& warning : loaded.warnings)
        std::cerr << "warning: " << warning << "\n";
    if (!spec.contact.enabled && !spec.obstacles.empty())
        std::cerr << "warning: " << spec.obstacles.front().location << ": the obstacles have no effect, because "
                  << "contact.enabled is false (set enabled = true in [contact])\n";
    coro::Scene& scene = loaded.scene;

    const auto threads = static_cast<coro::Index>(
        tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism));
    if (!options.quiet)
        std::cerr << "corocontact " << CORO_VERSION << ": " << spec.simulation.name << ", "
                  << scene.bodies.size() << " bodies, " << scene.num_tets() << " tets, "
                  << scene.num_vertices() << " nodes, " << threads << " threads\n";

    coro::Simulation simulation(scene, spec);
    const coro::Index last_step =
        spec.simulation.analysis == coro::Analysis::STATIC ? spec.simulation.load_steps : spec.simulation.steps;
    const bool checkpoints = checkpoint_every > 0;
    const std::uint64_t fingerprint =
        checkpoints || !options.restart.empty() ? coro::case_fingerprint(spec) : 0;
    coro::RunControl control;
    std::vector<coro::FrameRecord> frames; // written so far, the first run's included
    if (!options.restart.empty()) {
        std::vector<std::string> warnings;
        coro::CheckpointState state = coro::read_checkpoint(options.restart, scene, fingerprint, warnings);
        for (const std::string& warning : warnings)
            std::cerr << "warning: " << warning << "\n";
        CORO_CHECK(state.step < last_step, InputError,
                   options.restart << ": the checkpoint is at step " << state.step << ", the case ends at step "
                                   << last_step << " (nothing to continue; give a later --steps)");
        control.resume_step = state.step;
        control.resume_summary = state.summary;
        std::size_t missing = 0;
        for (const coro::FrameRecord& frame : state.frames) {
            if (std::filesystem::exists(spec.simulation.output_dir / frame_file(spec.simulation.name, frame.step)))
                frames.push_back(frame);
            else
                ++missing;
        }
        if (missing > 0)
            std::cerr << "warning: " << missing << " of the " << state.frames.size()
                      << " frames the first run wrote up to step " << state.step << " are not in "
                      << spec.simulation.output_dir.string() << "; the series lists only the others\n";
        if (!options.quiet)
            std::cerr << "continuing from step " << state.step << " (" << options.restart << ")\n";
    }

    // What an earlier run of this series left goes (a restart keeps its frames up to the
    // checkpoint), so no old summary or frame stands beside this run's series.
    const coro::RemovedFiles removed = coro::remove_earlier_run(out_dir, spec.simulation.name,
                                                                options.restart.empty() ? -1 : control.resume_step,
                                                                !options.restart.empty());
    if (removed.files > 0 && !options.quiet)
        std::cerr << "removed " << removed.files << " files (" << removed.frames << " frames) of an earlier run of "
                  << spec.simulation.name << " from " << out_dir.string() << "\n";
    coro::VtkSeriesWriter writer(out_dir, spec.simulation.name);
    for (const coro::FrameRecord& frame : frames)
        writer.adopt_frame(frame.step, frame.time);
    if (!frames.empty())
        writer.write_pvd();
    const auto checkpoint_path = coro::checkpoint_path(out_dir, spec.simulation.name);
    if (checkpoints) {
        control.checkpoint_every = checkpoint_every;
        control.on_checkpoint = [&](coro::Index step, const coro::RunSummary& so_far) {
            coro::write_checkpoint(checkpoint_path, scene, {step, so_far, frames}, fingerprint);
        };
    }
    coro::install_stop_signal_handlers();
    control.stop = &coro::stop_signal();

    coro::cli::Progress progress(!options.quiet, isatty(STDERR_FILENO) != 0);
    progress.set_first(control.resume_step);
    const coro::RunSummary summary = simulation.run(
        last_step,
        [&](coro::Index step, double time) {
            writer.write_frame(step, time, coro::scene_frame(scene));
            frames.push_back({step, time});
        },
        [&](coro::Index done, coro::Index total) { progress.update(done, total); }, control);
    progress.finish();

    coro::SummaryContext context;
    context.name = spec.simulation.name;
    context.threads = threads;
    context.bodies = static_cast<coro::Index>(scene.bodies.size());
    context.tets = scene.num_tets();
    context.peak_rss_mb = peak_rss_mb();
    const auto summary_path = coro::summary_path(out_dir, spec.simulation.name);
    coro::write_file_atomically(summary_path, coro::summary_json(summary, context));

    const auto& p = summary.phases;
    const double total = std::max(p.total(), 1e-300);
    std::printf("%s: %d steps in %.3f s, %.2f steps/s, %d threads\n", spec.simulation.name.c_str(),
                static_cast<int>(summary.steps), summary.wall_s, summary.steps_per_s, static_cast<int>(threads));
    std::printf("  phases [s]: rotation %.3f (%.0f%%), assembly %.3f (%.0f%%), solve %.3f (%.0f%%), "
                "contact %.3f (%.0f%%), output %.3f (%.0f%%)\n",
                p.rotation, 100 * p.rotation / total, p.assembly, 100 * p.assembly / total, p.solve,
                100 * p.solve / total, p.contact, 100 * p.contact / total, p.output, 100 * p.output / total);
    std::printf("  PCG: %.1f iterations per solve, mean relative residual %.2e, %d of %d solves at the cap\n",
                summary.cg_iterations_mean, summary.cg_residual_mean, static_cast<int>(summary.solves_not_converged),
                static_cast<int>(summary.solves));
    if (spec.contact.enabled) {
        std::printf("  contact: %.1f vertices inside per step, max depth %.4g m", summary.contacts_mean,
                    summary.max_contact_depth);
        if (spec.contact.cross_check == coro::CrossCheck::EMBREE)
            std::printf(", Embree disagreements %d", static_cast<int>(summary.embree_disagreements));
        std::printf("\n");
    }
    if (summary.static_not_converged > 0)
        std::printf("  warning: %d static load steps did not reach static_tolerance\n",
                    static_cast<int>(summary.static_not_converged));
    std::printf("  peak memory %.1f MB\n  series: %s\n  summary: %s\n", context.peak_rss_mb,
                writer.pvd_path().string().c_str(), summary_path.string().c_str());
    if (checkpoints)
        std::printf("  checkpoint: %s\n", checkpoint_path.string().c_str());
    std::fflush(stdout);
    if (summary.stop_signal != 0) {
        std::fprintf(stderr, "%s: interrupted by %s at step %d of %d; frames, series and summary are complete up to it\n",
                     spec.simulation.name.c_str(), signal_name(summary.stop_signal), static_cast<int>(summary.steps),
                     static_cast<int>(last_step));
        return EXIT_SIGNAL_BASE + summary.stop_signal;
    }
    return 0;
}

struct DetectOptions {
    std::string case_file;
    std::string mode;
    std::string cross_check;
    std::string csv;
    bool verbose = false;
};

int detect_case(const DetectOptions& options)
{
    coro::CaseSpec spec = coro::read_case(options.case_file);
    if (!options.mode.empty())
        spec.contact.mode = options.mode == "paper" ? coro::ContactMode::PAPER : coro::ContactMode::EXACT;
#if !CORO_WITH_EMBREE
    CORO_CHECK(options.cross_check.empty(), InputError,
               "--cross-check embree: this build has no Embree (configure with CORO_WITH_EMBREE=ON)");
#endif
    coro::LoadedScene loaded = coro::load_scene(spec);
    for (const std::string& warning : loaded.warnings)
        std::cerr << "warning: " << warning << "\n";
    const std::vector<coro::ContactSurface> surfaces = coro::make_scene_surfaces(loaded.scene);

    coro::DetectionStats stats;
    const auto start = std::chrono::steady_clock::now();
    std::vector<coro::ContactPoint> points =
        coro::detect_contacts(surfaces, coro::detection_settings(spec.contact), &stats);
    const std::vector<coro::ContactPoint> on_planes = coro::detect_plane_contacts(
        surfaces, static_cast<coro::Index>(loaded.scene.bodies.size()), loaded.scene.planes);
    points.insert(points.end(), on_planes.begin(), on_planes.end());
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

    std::FILE* report = options.csv == "-" ? stderr : stdout;
    std::fprintf(report,
                 "%s: %zu bodies, %d overlapping pairs, %d vertex queries, %d inside, %d on a surface, "
                 "%d winding-number fallbacks, %d answered by a neighbour (clear-edge group), %s mode, %.3f ms\n",
                 spec.simulation.name.c_str(), surfaces.size(), stats.pairs, stats.candidate_vertices, stats.inside,
                 stats.on_surface, stats.winding_fallbacks, stats.by_neighbour,
                 spec.contact.mode == coro::ContactMode::PAPER ? "paper" : "exact", 1e3 * seconds);

#if CORO_WITH_EMBREE
    if (!options.cross_check.empty()) {
        const coro::EmbreeScenes scenes(surfaces);
        const std::vector<coro::ContactPoint> embree =
            coro::detect_contacts_embree(surfaces, scenes, coro::detection_settings(spec.contact));
        const std::vector<coro::Disagreement> disagreements = coro::cross_check(points, embree);
        std::fprintf(report,
                     "embree cross-check: %zu disagreements (axis-ray %zu inside, Embree %zu inside), %d depth "
                     "disagreements\n",
                     disagreements.size(), points.size(), embree.size(),
                     static_cast<int>(coro::depth_disagreements(points, embree)));
        if (options.verbose)
            for (const coro::Disagreement& d : disagreements)
                std::fprintf(report, "  %s vertex %d in %s: axis-ray says %s, Embree says %s\n",
                             surfaces[static_cast<std::size_t>(d.body)].name.c_str(),
                             surfaces[static_cast<std::size_t>(d.body)].source_id[static_cast<std::size_t>(d.vertex)],
                             surfaces[static_cast<std::size_t>(d.other)].name.c_str(),
                             d.axis_ray_inside ? "inside" : "outside", d.embree_inside ? "inside" : "outside");
    }
#endif
    const std::string csv = coro::contacts_csv(surfaces, points);
    if (options.csv == "-")
        std::fputs(csv.c_str(), stdout);
    else if (!options.csv.empty())
        coro::write_file_atomically(options.csv, csv);
    return 0;
}

int describe_mesh(const std::string& path, int parts)
{
    coro::TetMesh mesh = coro::read_tet_mesh(path);
    const coro::Index reoriented = coro::validate_and_orient(mesh, path);
    const coro::Tris faces = coro::boundary_faces(mesh);
    const coro::SurfaceCheck check = coro::check_surface(faces);
    double q_min = 1.0, q_sum = 0.0;
    for (coro::Index t = 0; t < mesh.num_tets(); ++t) {
        const double q = coro::mean_ratio_quality(mesh, t);
        q_min = std::min(q_min, q);
        q_sum += q;
    }
    const Eigen::RowVector3d lo = mesh.rest_positions.colwise().minCoeff();
    const Eigen::RowVector3d hi = mesh.rest_positions.colwise().maxCoeff();
    std::printf("%s\n", path.c_str());
    std::printf("  nodes %d, tets %d, boundary faces %d, boundary nodes %zu\n", mesh.num_vertices(),
                mesh.num_tets(), static_cast<int>(faces.rows()), coro::surface_vertices(faces).size());
    std::printf("  volume %.9g, bounding box [%g, %g, %g] - [%g, %g, %g]\n", coro::total_volume(mesh),
                lo[0], lo[1], lo[2], hi[0], hi[1], hi[2]);
    std::printf("  quality (mean ratio, 1 = regular): min %.4f, mean %.4f\n", q_min, q_sum / mesh.num_tets());
    std::printf("  reoriented tets %d, nodes in no tet %zu\n", reoriented, coro::unreferenced_vertices(mesh).size());
    std::printf("  surface %s (open edges %d, non-manifold edges %d, misoriented edges %d)\n",
                check.closed_and_oriented() ? "closed and oriented" : "NOT closed and oriented",
                check.open_edges, check.nonmanifold_edges, check.misoriented_edges);
    if (parts > 0) {
        const coro::TetPartition partition = coro::partition_tets(mesh.tets, mesh.num_vertices(), parts);
        const coro::PartLayout layout = coro::make_part_layout(mesh.tets, mesh.num_vertices(), partition);
        const std::vector<coro::Index> sizes = partition.part_sizes();
        std::printf("  METIS parts %d: edge-cut %d faces (%.2f%% of interior faces), balance %.4f (largest/mean), "
                    "tets per part %d..%d, interface nodes %d (%.1f%%)\n",
                    partition.num_parts, partition.edge_cut,
                    100.0 * partition.edge_cut / std::max<double>(1.0, (4.0 * mesh.num_tets() - faces.rows()) / 2.0),
                    partition.imbalance(), *std::min_element(sizes.begin(), sizes.end()),
                    *std::max_element(sizes.begin(), sizes.end()), layout.num_interface_nodes(),
                    100.0 * layout.num_interface_nodes() / mesh.num_vertices());
    }
    return 0;
}

} // namespace

int main(int argc, char** argv)
{
    CLI::App app{"corocontact: co-rotational FEM bodies in contact"};
    app.set_version_flag("--version", std::string("corocontact ") + CORO_VERSION);
    app.require_subcommand(1);
    int threads = 0;
    app.add_option("--threads", threads, "worker threads (default: all cores)")->check(CLI::PositiveNumber);

    RunOptions run;
    CLI::App* run_command = app.add_subcommand("run", "simulate a case into a VTK series");
    run_command->add_option("case", run.case_file, "case file (.toml)")->required();
    run_command->add_option("--out", run.out, "output directory (overrides simulation.output_dir)");
    run_command->add_option("--threads", threads, "worker threads (default: all cores)")->check(CLI::PositiveNumber);
    run_command->add_option("--steps", run.steps, "number of time steps (overrides simulation.steps)")
        ->check(CLI::PositiveNumber);
    run_command->add_flag("--quiet", run.quiet, "no progress output");
    run_command->add_option("--checkpoint-every", run.checkpoint_every,
                            "save the whole state to OUT/NAME.checkpoint every N steps (and at the end)")
        ->check(CLI::PositiveNumber);
    run_command->add_option("--restart", run.restart,
                            "continue the run saved in a checkpoint file of this case to its last step");
    run_command->set_version_flag("--version", std::string("corocontact ") + CORO_VERSION);

    DetectOptions detect;
    CLI::App* detect_command =
        app.add_subcommand("detect", "contact detection on the initial configuration, optionally as CSV");
    detect_command->add_option("case", detect.case_file, "case file (.toml)")->required();
    detect_command->add_option("--mode", detect.mode, "exact (default) or paper; overrides [contact] mode")
        ->check(CLI::IsMember({"exact", "paper"}));
    detect_command->add_option("--cross-check", detect.cross_check, "also detect with Embree and count disagreements")
        ->check(CLI::IsMember({"embree"}));
    detect_command->add_option("--csv", detect.csv, "write body,vertex,other,depth rows to FILE (- for stdout)");
    detect_command->add_flag("--verbose", detect.verbose, "list the vertices on which Embree disagrees");
    detect_command->add_option("--threads", threads, "worker threads (default: all cores)")->check(CLI::PositiveNumber);
    detect_command->set_version_flag("--version", std::string("corocontact ") + CORO_VERSION);

    std::string mesh_path;
    CLI::App* info_command = app.add_subcommand("info", "counts, volume, quality and surface check of a mesh");
    info_command->add_option("mesh", mesh_path, "tet mesh file")->required();
    int parts = 0;
    info_command->add_option("--parts", parts, "also partition into K METIS parts: edge-cut and balance")
        ->check(CLI::PositiveNumber);
    info_command->set_version_flag("--version", std::string("corocontact ") + CORO_VERSION);

    try {
        app.parse(argc, argv);
    } catch (const CLI::ParseError& error) {
        const int code = app.exit(error);
        return code == 0 ? 0 : EXIT_BAD_INPUT;
    }

    std::unique_ptr<tbb::global_control> thread_limit;
    if (threads > 0)
        thread_limit = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism,
                                                             static_cast<std::size_t>(threads));
    try {
        if (run_command->parsed())
            return run_case(run);
        if (detect_command->parsed())
            return detect_case(detect);
        return describe_mesh(mesh_path, parts);
    } catch (const coro::InputError& error) {
        std::cerr << "error: " << error.what() << "\n";
        return EXIT_BAD_INPUT;
    } catch (const coro::OutputError& error) {
        std::cerr << "error: " << error.what() << "\n";
        return EXIT_OUTPUT_FAILED;
    } catch (const coro::NumericalError& error) {
        std::cerr << "error: the simulation diverged: " << error.what() << "\n";
        return EXIT_DIVERGED;
    } catch (const std::exception& error) {
        // Not one of ours (e.g. std::bad_alloc from a library reading a corrupt file): still a
        // message and the bad-input code rather than an abort.
        std::cerr << "error: " << error.what() << "\n";
        return EXIT_BAD_INPUT;
    }
}
