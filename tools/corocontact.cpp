// The corocontact command: run a case, detect contacts, describe a mesh or a surface.
// Exit codes: 0 success, 2 bad input, 3 the simulation diverged, 4 the output could not be
// written (or its folder is in use by another run). Under mpirun (CORO_WITH_MPI) a run is
// distributed over the processes; they all exit with the same code, rank 0 alone prints.

#include "progress.hpp"

#include <corocontact/config.hpp>
#include <corocontact/core/atomic_file.hpp>
#include <corocontact/core/collective.hpp>
#include <corocontact/core/error.hpp>
#include <corocontact/core/fingerprint.hpp>
#include <corocontact/core/surface_mesh.hpp>
#include <corocontact/core/surface_topology.hpp>
#include <corocontact/io/case_reader.hpp>
#include <corocontact/io/mesh_readers.hpp>
#include <corocontact/io/output_file.hpp>
#include <corocontact/io/output_lock.hpp>
#include <corocontact/io/rank_output.hpp>
#include <corocontact/io/run_files.hpp>
#include <corocontact/io/scene_loader.hpp>
#include <corocontact/io/scene_output.hpp>
#include <corocontact/io/surface_readers.hpp>
#include <corocontact/io/vtk_series.hpp>
#include <corocontact/sim/checkpoint.hpp>
#include <corocontact/sim/interrupt.hpp>
#include <corocontact/sim/rank_checkpoint.hpp>
#include <corocontact/sim/run_notes.hpp>
#include <corocontact/sim/scene_contact.hpp>
#if CORO_WITH_EMBREE
#include <corocontact/embree/embree_detector.hpp>
#endif
#if CORO_WITH_MPI
#include <corocontact/mpi/mpi_session.hpp>
#endif
#include <corocontact/partition/part_layout.hpp>
#include <corocontact/partition/partition.hpp>

#include <CLI/CLI.hpp>
#include <tbb/global_control.h>
#include <tbb/task_arena.h>

#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <iostream>
#include <limits>
#include <memory>
#include <set>
#include <sstream>

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

/// A CLI11 check for a whole number in [min, max] that says so in plain words:
/// "--threads: expected a whole number from 1 to 2147483647, found 'abc'".
CLI::Validator whole_number(long long min, long long max)
{
    return CLI::Validator(
        [min, max](std::string& text) -> std::string {
            long long value = 0;
            const char* end = text.data() + text.size();
            const auto [stop, error] = std::from_chars(text.data(), end, value);
            const std::string expected =
                "expected a whole number from " + std::to_string(min) + " to " + std::to_string(max) + ", found '" +
                text + "'";
            if (text.empty() || error == std::errc::invalid_argument || stop != end)
                return expected;
            if (error == std::errc::result_out_of_range || value < min || value > max)
                return expected;
            return "";
        },
        min == 1 ? "POSITIVE" : "FROM " + std::to_string(min)); // --help: "INT:POSITIVE"
}

/// A CLI11 check for a file or directory argument: an empty one (an unset shell variable in
/// `--out "$DIR"`) would otherwise read as "not given" and write to the default place.
CLI::Validator path_given()
{
    return CLI::Validator([](std::string& text) -> std::string { return text.empty() ? "expected a path, found ''" : ""; },
                          "PATH");
}

constexpr long long INDEX_MAX = std::numeric_limits<coro::Index>::max();

/// The threads TBB runs at most: --threads (or all cores), but never more than the arena has.
int threads_used()
{
    const auto allowed = tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism);
    return static_cast<int>(
        std::min<std::size_t>(allowed, static_cast<std::size_t>(tbb::this_task_arena::max_concurrency())));
}

struct RunOptions {
    std::string case_file;
    std::string out;
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

/// A stream that writes nothing: what processes other than rank 0 print to.
std::ostream& null_stream()
{
    static std::ostream null(nullptr);
    return null;
}

/// Every process's warnings about its bodies on rank 0 (empty elsewhere), in the case order of
/// their bodies, as one process gives them.
std::vector<std::string> gather_body_warnings(coro::Communicator& ranks, const std::vector<coro::BodyWarning>& mine)
{
    std::vector<char> bytes;
    for (const auto& [body, text] : mine) {
        const char* index = reinterpret_cast<const char*>(&body);
        bytes.insert(bytes.end(), index, index + sizeof body);
        bytes.insert(bytes.end(), text.begin(), text.end());
        bytes.push_back('\0');
    }
    std::vector<coro::BodyWarning> all;
    for (const std::vector<char>& theirs : ranks.gather(bytes, 0))
        for (auto at = theirs.begin(); at != theirs.end();) {
            coro::Index body;
            std::memcpy(&body, &*at, sizeof body);
            const auto end = std::find(at + sizeof body, theirs.end(), '\0');
            all.emplace_back(body, std::string(at + sizeof body, end));
            at = end + 1;
        }
    std::stable_sort(all.begin(), all.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
    std::vector<std::string> warnings;
    for (auto& [body, text] : all)
        warnings.push_back(std::move(text));
    return warnings;
}

const char* signal_name(int signal_number)
{
    return signal_number == SIGINT ? "SIGINT" : signal_number == SIGTERM ? "SIGTERM" : "a signal";
}

/// "1 body", "64 bodies".
std::string count_of(std::size_t n, const char* one, const char* many)
{
    return std::to_string(n) + " " + (n == 1 ? one : many);
}

/// Flushes stdout and checks it: stdout is buffered, so a failed write (a full disk, a closed
/// descriptor) shows only at a flush or in its error flag. Every command ends with it.
/// @throws OutputError "writing to standard output: <strerror>"
void flush_stdout()
{
    errno = 0;
    const bool flushed = std::fflush(stdout) == 0;
    const int error = errno;
    CORO_CHECK(flushed && !std::ferror(stdout), OutputError,
               "writing to standard output: " << (error != 0 ? std::strerror(error) : "an earlier write failed"));
}

/// Writes `text` to stdout now, checked (a CSV larger than stdout's buffer fails at the write).
void write_stdout(const std::string& text)
{
    if (std::fwrite(text.data(), 1, text.size(), stdout) != text.size()) {
        const int error = errno;
        CORO_THROW(OutputError, "writing to standard output: " << std::strerror(error));
    }
    flush_stdout();
}

/// Runs a case; `ranks` is null in one process, else the processes of a distributed run
/// (docs/scale_out.md): each holds its bodies, rank 0 alone prints and holds the output lock,
/// and every step, frame and checkpoint is collective, a failure anywhere throwing on every
/// process.
int run_case(const RunOptions& options, coro::Communicator* ranks)
{
    const auto setup_start = std::chrono::steady_clock::now();
    const bool root = ranks == nullptr || ranks->rank() == 0;
    coro::cli::Progress progress(!options.quiet && root, isatty(STDERR_FILENO) != 0);
    std::ostream& messages = root ? std::cerr : null_stream();
    coro::CaseSpec spec;
    coro::run_collectively(ranks, [&] {
        std::vector<std::string> notes;
        spec = coro::read_case(options.case_file, notes);
        for (const std::string& note : notes)
            messages << "note: " << note << "\n";
        if (!options.out.empty())
            spec.simulation.output_dir = options.out;
        if (options.steps > 0) {
            CORO_CHECK(spec.simulation.analysis == coro::Analysis::DYNAMIC, InputError,
                       "--steps " << options.steps << ": " << options.case_file
                                  << " is a static analysis, whose steps are simulation.load_steps; --steps sets "
                                     "the time steps of a dynamic one");
            spec.simulation.steps = static_cast<coro::Index>(options.steps); // the option's range is an Index's
        }
        // AMG's hierarchy is built from one process's whole matrix; a distributed scene has its
        // rows on several.
        CORO_CHECK(ranks == nullptr || ranks->size() == 1 ||
                       spec.solver.preconditioner != coro::PcgPreconditioner::AMG,
                   InputError,
                   options.case_file << ": solver.preconditioner = \"amg\" runs in one process only, and this run "
                                        "has "
                                     << ranks->size()
                                     << " (mpirun): use \"block_jacobi\" or \"jacobi\" for a distributed run");
    });
    // The command lines are the same (main); the case file may still differ between the nodes.
    if (ranks) {
        std::uint64_t fingerprint = 0;
        coro::run_collectively(ranks, [&] { fingerprint = coro::case_fingerprint(spec); });
        coro::require_same_on_every_process(ranks, fingerprint,
                                            options.case_file + ": the processes of this run read different case "
                                                                "files (a stale copy on one node?): every process "
                                                                "must read the same files");
    }
    const auto checkpoint_every = static_cast<coro::Index>(options.checkpoint_every);
    // One run per output folder, claimed before the (possibly long) load; a run refused for bad
    // input removes its lock file again, and the folder if it made it.
    const std::filesystem::path& out_dir = spec.simulation.output_dir;
    std::unique_ptr<coro::OutputLock> lock;
    coro::run_collectively(ranks, [&] {
        if (root)
            lock = std::make_unique<coro::OutputLock>(out_dir, "corocontact run " + options.case_file);
    });
    if (lock && !lock->stale_owner().empty())
        messages << "warning: " << lock->path().string() << ": taking over the lock of a run that ended without "
                 << "removing it (" << lock->stale_owner() << ")\n";

    // Everything is loaded and checked before anything but the lock file is written there.
    coro::LoadedScene loaded;
    coro::run_collectively(ranks, [&] {
        loaded = coro::load_scene(spec, [&](const std::string& stage) { progress.status(stage); });
    });
    coro::Scene& scene = loaded.scene;
    const auto case_bodies = static_cast<coro::Index>(scene.bodies.size());
    const coro::Index case_tets = scene.num_tets(), case_nodes = scene.num_vertices();
    coro::SceneDistribution distribution;
    if (ranks)
        distribution = coro::distribute_scene(scene, *ranks);
    if (coro::contact_applies(spec))
        progress.status("contact surfaces and their AABB trees");
    coro::Simulation simulation(scene, spec, ranks ? &distribution : nullptr);
    progress.clear();
    for (const std::string& warning : loaded.warnings)
        messages << "warning: " << warning << "\n";
    if (const auto note = coro::contact_not_applied_note(spec))
        messages << *note << "\n";
    if (!spec.contact.enabled && !spec.obstacles.empty())
        messages << "warning: " << spec.obstacles.front().location << ": the obstacles have no effect, because "
                 << "contact.enabled is false (set enabled = true in [contact])\n";

    const int threads = threads_used();
    if (!options.quiet)
        messages << "corocontact " << CORO_VERSION << ": " << spec.simulation.name << ", "
                 << count_of(static_cast<std::size_t>(case_bodies), "body", "bodies") << ", " << case_tets
                 << " tets, " << case_nodes << " nodes, "
                 << count_of(static_cast<std::size_t>(threads), "thread", "threads")
                 << (ranks ? " on each of " + std::to_string(ranks->size()) + " processes" : std::string()) << "\n";

    const coro::Index last_step =
        spec.simulation.analysis == coro::Analysis::STATIC ? spec.simulation.load_steps : spec.simulation.steps;
    const bool checkpoints = checkpoint_every > 0;
    const std::uint64_t fingerprint =
        checkpoints || !options.restart.empty() ? coro::case_fingerprint(spec) : 0;
    coro::RunControl control;
    std::vector<coro::FrameRecord> frames; // written so far, the first run's included
    if (!options.restart.empty()) {
        std::vector<std::string> warnings;
        std::vector<coro::BodyWarning> body_warnings;
        coro::CheckpointState state;
        coro::run_collectively(ranks, [&] {
            state = ranks ? coro::read_checkpoint(options.restart, scene, distribution.body_ids, case_bodies,
                                                  fingerprint, body_warnings)
                          : coro::read_checkpoint(options.restart, scene, fingerprint, warnings);
        });
        if (ranks)
            warnings = gather_body_warnings(*ranks, body_warnings);
        for (const std::string& warning : warnings)
            messages << "warning: " << warning << "\n";
        CORO_CHECK(state.step < last_step, InputError,
                   options.restart << ": the checkpoint is at step " << state.step << ", the case ends at step "
                                   << last_step << " (nothing to continue; give a later --steps)");
        control.resume_step = state.step;
        control.resume_summary = state.summary;
        std::size_t missing = 0;
        for (const coro::FrameRecord& frame : state.frames) {
            // What VtkSeriesWriter::adopt_frame accepts: checked here, before anything is removed.
            if (std::filesystem::is_regular_file(spec.simulation.output_dir /
                                                 frame_file(spec.simulation.name, frame.step)))
                frames.push_back(frame);
            else
                ++missing;
        }
        if (missing > 0)
            messages << "warning: " << missing << " of the " << state.frames.size()
                      << " frames the first run wrote up to step " << state.step << " are not in "
                      << spec.simulation.output_dir.string() << "; the series lists only the others\n";
        if (!options.quiet)
            messages << "continuing from step " << state.step << " (" << options.restart << ")\n";
    }

    // What an earlier run of this series left goes (a restart keeps its frames up to the
    // checkpoint), so no old summary or frame stands beside this run's series.
    coro::RemovedFiles removed;
    std::unique_ptr<coro::VtkSeriesWriter> writer;
    coro::run_collectively(ranks, [&] {
        if (root) // rank 0 clears the folder before any process writes in it
            removed = coro::remove_earlier_run(out_dir, spec.simulation.name,
                                               options.restart.empty() ? -1 : control.resume_step,
                                               !options.restart.empty());
    });
    if (removed.files > 0 && !options.quiet)
        messages << "removed " << removed.files << " files (" << removed.frames << " frames) of an earlier run of "
                 << spec.simulation.name << " from " << out_dir.string()
                 << (removed.checkpoint ? ", its checkpoint among them (a run without --restart starts over)" : "")
                 << "\n";
    coro::run_collectively(ranks, [&] {
        writer = std::make_unique<coro::VtkSeriesWriter>(out_dir, spec.simulation.name);
        for (const coro::FrameRecord& frame : frames)
            writer->adopt_frame(frame.step, frame.time);
        if (!frames.empty() && root)
            writer->write_pvd();
    });
    std::unique_ptr<coro::RankFrames> rank_frames;
    if (ranks)
        rank_frames = std::make_unique<coro::RankFrames>(*ranks, *writer, scene, distribution.body_ids);
    const auto checkpoint_path = coro::checkpoint_path(out_dir, spec.simulation.name);
    if (checkpoints) {
        control.checkpoint_every = checkpoint_every;
        control.on_checkpoint = [&](coro::Index step, const coro::RunSummary& so_far) {
            if (ranks)
                coro::write_checkpoint(checkpoint_path, scene, distribution, {step, so_far, frames}, fingerprint);
            else
                coro::write_checkpoint(checkpoint_path, scene, {step, so_far, frames}, fingerprint);
        };
    }
    coro::install_stop_signal_handlers();
    control.stop = &coro::stop_signal();

    progress.set_first(control.resume_step);
    const double setup_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - setup_start).count();
    progress.start_steps();
    const coro::RunSummary summary = simulation.run(
        last_step,
        [&](coro::Index step, double time) {
            if (rank_frames)
                rank_frames->write(step, time, scene);
            else
                writer->write_frame(step, time, coro::scene_frame(scene));
            frames.push_back({step, time});
        },
        [&](coro::Index done, coro::Index total) { progress.update(done, total); }, control);
    progress.finish();

    coro::SummaryContext context;
    context.name = spec.simulation.name;
    context.threads = threads;
    context.setup_s = setup_s;
    context.bodies = case_bodies;
    context.tets = case_tets;
    context.peak_rss_mb = peak_rss_mb();
    const coro::RankStats rank_stats = simulation.rank_stats();
    context.ranks = rank_stats.ranks;
    context.cross_rank_contacts_mean = rank_stats.cross_rank_contacts_mean;
    if (ranks) {
        context.per_rank = coro::gather_rank_loads(*ranks, scene, rank_stats);
        ranks->all_reduce(&context.peak_rss_mb, 1, coro::Reduction::MAX);
    }
    const auto summary_path = coro::summary_path(out_dir, spec.simulation.name);
    coro::run_collectively(ranks, [&] {
        if (root)
            coro::write_file_atomically(summary_path, coro::summary_json(summary, context));
    });
    if (!root)
        return summary.stop_signal != 0 ? EXIT_SIGNAL_BASE + summary.stop_signal : 0;

    const auto& p = summary.phases;
    const double total = std::max(p.total(), 1e-300);
    std::printf("%s: %s in %.3f s, %.2f steps/s, %s (set-up before the steps: %.3f s)\n",
                spec.simulation.name.c_str(),
                count_of(static_cast<std::size_t>(summary.steps), "step", "steps").c_str(), summary.wall_s,
                summary.steps_per_s,
                count_of(static_cast<std::size_t>(threads), "thread", "threads").c_str(), setup_s);
    if (ranks) {
        std::printf("  %d processes (MPI), bodies/tets per process:", ranks->size());
        for (const coro::RankLoad& load : context.per_rank)
            std::printf(" %d/%d", static_cast<int>(load.bodies), static_cast<int>(load.tets));
        std::printf("; received per step and process:");
        for (const coro::RankLoad& load : context.per_rank)
            std::printf(" %.0f", load.mpi_bytes_per_step);
        std::printf(" B; %.1f contact points per detection across processes\n", context.cross_rank_contacts_mean);
    }
    std::printf("  phases [s]: rotation %.3f (%.0f%%), assembly %.3f (%.0f%%), solve %.3f (%.0f%%), "
                "contact %.3f (%.0f%%), output %.3f (%.0f%%)\n",
                p.rotation, 100 * p.rotation / total, p.assembly, 100 * p.assembly / total, p.solve,
                100 * p.solve / total, p.contact, 100 * p.contact / total, p.output, 100 * p.output / total);
    std::printf("  PCG: %.1f iterations per solve, mean relative residual %.2e, %d of %d solves at the cap\n",
                summary.cg_iterations_mean, summary.cg_residual_mean, static_cast<int>(summary.solves_not_converged),
                static_cast<int>(summary.solves));
    if (summary.preconditioner.setups > 0)
        std::printf("  AMG: %d hierarchy set-ups in %.3f s, %d V-cycles in %.3f s (%.2f ms each), both within solve\n",
                    static_cast<int>(summary.preconditioner.setups), summary.preconditioner.setup_s,
                    static_cast<int>(summary.preconditioner.applies), summary.preconditioner.apply_s,
                    1e3 * summary.preconditioner.apply_s / std::max<double>(1.0, summary.preconditioner.applies));
    if (coro::contact_applies(spec)) {
        std::printf("  contact: %.1f contact points per detection (vertex inside another body or obstacle, once "
                    "per body), max depth %.4g m",
                    summary.contacts_mean, summary.max_contact_depth);
        if (spec.contact.cross_check == coro::CrossCheck::EMBREE)
            std::printf(", Embree disagreements %d", static_cast<int>(summary.embree_disagreements));
        std::printf("\n");
    }
    if (spec.simulation.analysis == coro::Analysis::STATIC)
        std::printf("  Newton: %.1f iterations per load step, at most %d\n", summary.static_iterations_mean,
                    static_cast<int>(summary.static_iterations_max));
    if (summary.static_not_converged > 0)
        std::printf("  warning: %d static load steps did not reach static_tolerance\n",
                    static_cast<int>(summary.static_not_converged));
    if (const auto warning = coro::iteration_cap_warning(summary, spec.solver))
        std::printf("  %s\n", warning->c_str());
    std::printf("  peak memory %.1f MB%s\n  series: %s\n  summary: %s\n", context.peak_rss_mb,
                ranks ? " (the largest process)" : "", writer->pvd_path().string().c_str(),
                summary_path.string().c_str());
    if (checkpoints)
        std::printf("  checkpoint: %s\n", checkpoint_path.string().c_str());
    flush_stdout();
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

    std::set<std::pair<coro::Index, coro::Index>> vertices_inside;
    for (const coro::ContactPoint& point : points)
        vertices_inside.emplace(point.body, point.vertex);
    std::FILE* report = options.csv == "-" ? stderr : stdout;
    std::fprintf(report, "%s: %s, %s, %d vertex queries, %s mode, %.3f ms\n", spec.simulation.name.c_str(),
                 count_of(surfaces.size(), "surface", "surfaces").c_str(),
                 count_of(static_cast<std::size_t>(stats.pairs), "overlapping pair", "overlapping pairs").c_str(),
                 stats.candidate_vertices, spec.contact.mode == coro::ContactMode::PAPER ? "paper" : "exact",
                 1e3 * seconds);
    std::fprintf(report,
                 "  %zu contact points at %zu vertices inside (a contact point: a surface vertex inside another body "
                 "or obstacle, once per body it is inside)\n",
                 points.size(), vertices_inside.size());
    std::fprintf(report,
                 "  %d vertices on a surface (counted outside), %d undecided by the axes, %d answered by a "
                 "neighbour (clear-edge group), %d outside the other surface's hull slabs (not tested)\n",
                 stats.on_surface, stats.undecided_by_axes, stats.by_neighbour, stats.by_hull);

#if CORO_WITH_EMBREE
    if (!options.cross_check.empty()) {
        const coro::EmbreeScenes scenes(surfaces);
        const std::vector<coro::ContactPoint> embree =
            coro::detect_contacts_embree(surfaces, scenes, coro::detection_settings(spec.contact));
        const std::vector<coro::Disagreement> disagreements = coro::cross_check(points, embree);
        const auto in_surfaces = std::count_if(points.begin(), points.end(),
                                               [](const coro::ContactPoint& c) { return c.other.is_surface(); });
        std::fprintf(report,
                     "embree cross-check: %zu disagreements (axis-ray %zu inside, Embree %zu inside; plane contacts "
                     "left out), %d depth disagreements\n",
                     disagreements.size(), static_cast<std::size_t>(in_surfaces), embree.size(),
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
        write_stdout(csv);
    else if (!options.csv.empty())
        coro::write_output_file(options.csv, csv);
    return 0;
}

/// "closed, consistently oriented, 1 piece, Euler characteristic 0, genus 1" or what is wrong,
/// then the counts of open, non-manifold and misoriented edges and pinch vertices.
std::string describe_topology(const coro::SurfaceTopology& t)
{
    const coro::SurfaceCheck& edges = t.edge_check;
    std::string text = edges.open_edges == 0 && edges.nonmanifold_edges == 0 ? "closed" : "NOT closed";
    text += edges.misoriented_edges == 0 ? ", consistently oriented" : ", NOT consistently oriented";
    text += ", " + count_of(static_cast<std::size_t>(t.components), "piece", "pieces");
    text += ", Euler characteristic " + std::to_string(t.euler_characteristic());
    if (t.closed_oriented_manifold())
        text += ", genus " + std::to_string(t.genus());
    else
        text += " (no genus: not a closed oriented 2-manifold)";
    text += "\n    open edges " + std::to_string(edges.open_edges) + ", non-manifold edges " +
            std::to_string(edges.nonmanifold_edges) + ", misoriented edges " + std::to_string(edges.misoriented_edges) +
            ", pinch vertices " + std::to_string(t.nonmanifold_vertices);
    return text;
}

void print_bounds(coro::CRef<coro::Positions> positions)
{
    const Eigen::RowVector3d lo = positions.colwise().minCoeff();
    const Eigen::RowVector3d hi = positions.colwise().maxCoeff();
    std::printf("  bounding box [%g, %g, %g] - [%g, %g, %g], size %g x %g x %g\n", lo[0], lo[1], lo[2], hi[0], hi[1],
                hi[2], hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]);
}

/// `info` of an OBJ, STL or OFF surface.
int describe_surface(const std::string& path)
{
    const coro::SurfaceMesh surface = coro::read_surface(path);
    const coro::SurfaceTopology topology = coro::surface_topology(surface.faces);
    std::printf("%s\n", path.c_str());
    std::printf("  triangle surface: vertices %d (%d used by faces), edges %d, faces %d\n",
                static_cast<int>(surface.vertices.rows()), topology.vertices, topology.edges, topology.faces);
    print_bounds(surface.vertices);
    std::printf("  surface %s\n", describe_topology(topology).c_str());
    if (topology.closed_oriented_manifold()) {
        const double volume = coro::enclosed_volume(surface.vertices, surface.faces);
        std::printf("  enclosed volume %.9g, normals point %s\n", std::abs(volume),
                    volume >= 0.0 ? "outward" : "inward (as an obstacle its faces are flipped at load)");
    }
    return 0;
}

bool is_surface_file(const std::string& path)
{
    std::string extension = std::filesystem::path(path).extension().string();
    std::transform(extension.begin(), extension.end(), extension.begin(),
                   [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    return extension == ".obj" || extension == ".stl" || extension == ".off";
}

/// `info` of a tet mesh.
int describe_mesh(const std::string& path, int parts)
{
    coro::TetMesh mesh = coro::read_tet_mesh(path);
    const coro::Index reoriented = coro::validate_and_orient(mesh, path);
    const coro::Tris faces = coro::boundary_faces(mesh);
    const coro::SurfaceTopology topology = coro::surface_topology(faces);
    double q_min = 1.0, q_sum = 0.0;
    for (coro::Index t = 0; t < mesh.num_tets(); ++t) {
        const double q = coro::mean_ratio_quality(mesh, t);
        q_min = std::min(q_min, q);
        q_sum += q;
    }
    std::printf("%s\n", path.c_str());
    std::printf("  tet mesh: nodes %d, tets %d, boundary faces %d, boundary nodes %d\n", mesh.num_vertices(),
                mesh.num_tets(), topology.faces, topology.vertices);
    std::printf("  volume %.9g\n", coro::total_volume(mesh));
    print_bounds(mesh.rest_positions);
    std::printf("  quality (mean ratio, 1 = regular): min %.4f, mean %.4f\n", q_min, q_sum / mesh.num_tets());
    const std::vector<std::array<coro::Index, 2>> coincident = coro::coincident_vertices(mesh);
    std::printf("  reoriented tets %d, nodes in no tet %zu, nodes where another node lies %zu\n", reoriented,
                coro::unreferenced_vertices(mesh).size(), coincident.size());
    std::printf("  boundary surface %s\n", describe_topology(topology).c_str());
    if (!coincident.empty())
        std::fprintf(stderr,
                     "warning: %zu nodes lie exactly where another node lies (e.g. nodes %d and %d, counted from 0 in "
                     "file order); they are not joined, so the tets on either side are separate pieces\n",
                     coincident.size(), coincident.front()[0], coincident.front()[1]);
    if (parts > mesh.num_tets()) {
        std::fprintf(stderr, "note: --parts %d: the mesh has %s, and a part holds at least one; using %d parts\n",
                     parts, count_of(static_cast<std::size_t>(mesh.num_tets()), "tet", "tets").c_str(),
                     mesh.num_tets());
        parts = mesh.num_tets();
    }
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
    // A closed pipe (`corocontact run case.toml | head -1`) makes a write fail with EPIPE, which
    // the run reports (exit 4) after finishing its frames and removing its output lock, rather
    // than killing the process with the lock left behind.
    std::signal(SIGPIPE, SIG_IGN);
    // Likewise a file-size limit (`ulimit -f`): the write fails with EFBIG and the run exits 4.
    std::signal(SIGXFSZ, SIG_IGN);
#if CORO_WITH_MPI
    // Started by mpirun: the processes of a distributed run (docs/scale_out.md); alone: no MPI.
    std::unique_ptr<coro::MpiSession> session;
    try {
        session = std::make_unique<coro::MpiSession>(argc, argv);
    } catch (const std::exception& error) {
        std::cerr << "error: " << error.what() << "\n";
        return EXIT_BAD_INPUT;
    }
    coro::Communicator* world = session->communicator();
#else
    coro::Communicator* world = nullptr;
#endif
    coro::Communicator* ranks = world != nullptr && world->size() > 1 ? world : nullptr;
    const bool root = ranks == nullptr || ranks->rank() == 0; // the one process that prints

    CLI::App app{"corocontact: co-rotational FEM bodies in contact"};
    app.set_version_flag("--version", std::string("corocontact ") + CORO_VERSION);
    app.require_subcommand(1);
    int threads = 0;
    bool verbose = false;
    const auto threads_option = [&](CLI::App* command) {
        command->add_option("--threads", threads, "worker threads (default: all cores)")
            ->check(whole_number(1, INDEX_MAX));
    };
    const auto verbose_flag = [&](CLI::App* command, const std::string& also) {
        command->add_flag("--verbose", verbose,
                          "error messages end in the source location that raised them (as with CORO_DEBUG=1)" + also);
    };
    threads_option(&app);
    verbose_flag(&app, "");

    RunOptions run;
    CLI::App* run_command = app.add_subcommand("run", "simulate a case into a VTK series");
    run_command->add_option("case", run.case_file, "case file (.toml)")->required()->check(path_given());
    run_command->add_option("--out", run.out, "output directory (overrides simulation.output_dir)")->check(path_given());
    threads_option(run_command);
    verbose_flag(run_command, "");
    run_command->add_option("--steps", run.steps, "number of time steps (overrides simulation.steps)")
        ->check(whole_number(1, INDEX_MAX));
    run_command->add_flag("--quiet", run.quiet, "no progress output");
    run_command->add_option("--checkpoint-every", run.checkpoint_every,
                            "save the whole state to OUT/NAME.checkpoint every N steps (and at the end)")
        ->check(whole_number(1, INDEX_MAX));
    run_command->add_option("--restart", run.restart,
                            "continue the run saved in a checkpoint file of this case to its last step")
        ->check(path_given());
    run_command->set_version_flag("--version", std::string("corocontact ") + CORO_VERSION);

    DetectOptions detect;
    CLI::App* detect_command =
        app.add_subcommand("detect", "contact detection on the initial configuration, optionally as CSV");
    detect_command->add_option("case", detect.case_file, "case file (.toml)")->required()->check(path_given());
    detect_command->add_option("--mode", detect.mode, "exact (default) or paper; overrides [contact] mode")
        ->check(CLI::IsMember({"exact", "paper"}));
    detect_command->add_option("--cross-check", detect.cross_check, "also detect with Embree and count disagreements")
        ->check(CLI::IsMember({"embree"}));
    detect_command->add_option("--csv", detect.csv, "write body,vertex,other,depth rows to FILE (- for stdout)")
        ->check(path_given());
    verbose_flag(detect_command, "; with --cross-check, list the vertices on which Embree disagrees");
    threads_option(detect_command);
    detect_command->set_version_flag("--version", std::string("corocontact ") + CORO_VERSION);

    std::string mesh_path;
    CLI::App* info_command = app.add_subcommand(
        "info", "counts, bounds, volume, quality and topology of a tet mesh or a triangle surface (.obj, .stl, .off)");
    info_command->add_option("mesh", mesh_path, "tet mesh or surface file")->required()->check(path_given());
    int parts = 0;
    info_command->add_option("--parts", parts, "tet mesh: also partition into K METIS parts: edge-cut and balance")
        ->check(whole_number(1, INDEX_MAX));
    verbose_flag(info_command, "");
    threads_option(info_command); // after the command too, as run and detect take it
    info_command->set_version_flag("--version", std::string("corocontact ") + CORO_VERSION);

    int parse_exit = -1;    // app.exit()'s code when the command line is not one to run
    std::ostringstream help; // --help, --version: written to stdout (by rank 0), checked
    try {
        app.parse(argc, argv);
    } catch (const CLI::ParseError& error) {
        parse_exit = app.exit(error, help, root ? std::cerr : null_stream());
    }
    // Processes started with other command lines (mpirun's MPMD form) would enter different
    // exchanges, or none, and wait for each other forever.
    if (ranks) {
        std::uint64_t fingerprint = coro::fnv1a(&parse_exit, sizeof parse_exit);
        for (int a = 1; a < argc; ++a)
            fingerprint = coro::fnv1a(argv[a], std::strlen(argv[a]) + 1, fingerprint); // with its '\0'
        try {
            coro::require_same_on_every_process(ranks, fingerprint,
                                                "the processes of this run were started with different command "
                                                "lines: run the same command on every process");
        } catch (const coro::InputError& error) {
            if (root)
                std::cerr << "error: " << error.what() << "\n";
            return EXIT_BAD_INPUT;
        }
    }
    if (parse_exit > 0)
        return EXIT_BAD_INPUT;
    if (parse_exit == 0) {
        if (!root)
            return 0;
        try {
            write_stdout(help.str());
        } catch (const coro::OutputError& output_error) {
            std::cerr << "error: " << output_error.what() << "\n";
            return EXIT_OUTPUT_FAILED;
        }
        return 0;
    }

    if (verbose)
        coro::set_source_locations_shown(true);
    detect.verbose = verbose;
    std::unique_ptr<tbb::global_control> thread_limit;
    if (threads > 0) {
        thread_limit = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism,
                                                             static_cast<std::size_t>(threads));
        if (threads_used() < threads && root)
            std::cerr << "note: --threads " << threads << ": this process may run on " << threads_used()
                      << (threads_used() == 1 ? " core" : " cores") << " only; using " << threads_used()
                      << (threads_used() == 1 ? " thread" : " threads") << "\n";
    }
    std::ostream& errors = root ? std::cerr : null_stream();
    const auto dispatch = [&]() -> int {
        try {
            int code = 0;
            if (run_command->parsed()) {
                code = run_case(run, ranks);
            } else if (detect_command->parsed()) {
                code = detect_case(detect);
            } else if (is_surface_file(mesh_path)) {
                CORO_CHECK(parts == 0, InputError,
                           "--parts: " << mesh_path << " is a triangle surface; METIS parts are for tet meshes");
                code = describe_surface(mesh_path);
            } else {
                code = describe_mesh(mesh_path, parts);
            }
            flush_stdout();
            return code;
        } catch (const coro::InputError& error) {
            errors << "error: " << error.what() << "\n";
            return EXIT_BAD_INPUT;
        } catch (const coro::OutputError& error) {
            errors << "error: " << error.what() << "\n";
            return EXIT_OUTPUT_FAILED;
        } catch (const coro::NumericalError& error) {
            errors << "error: the simulation diverged: " << error.what() << "\n";
            return EXIT_DIVERGED;
        } catch (const std::exception& error) {
            // Not one of ours (e.g. std::bad_alloc from a library reading a corrupt file): still a
            // message and the bad-input code rather than an abort.
            errors << "error: " << error.what() << "\n";
            return EXIT_BAD_INPUT;
        }
    };
    if (ranks != nullptr && !run_command->parsed()) {
        // detect and info run on rank 0; the others end with its exit code.
        std::vector<char> code(1, 0);
        if (root)
            code[0] = static_cast<char>(dispatch());
        ranks->broadcast(code, 0);
        return code[0];
    }
    return dispatch();
}

