// Contact detection benchmark: two deforming spheres in deep overlap (centres one radius
// apart), ~10k tets (resolution 12) and ~100k tets (resolution 26) each. Per frame: refit of
// both trees (BM_Refit), detection with depth and normal (BM_Detect*), the inside/outside test
// alone (BM_InsideOnly*: no nearest-point queries), refit + detection (BM_FrameExact, and
// BM_FrameInsideOnlyExact without depth); the
// counter queries/s is candidate vertices tested per second of wall time (all benchmarks use
// real time, so the rates count every thread's work). Exact, paper and brute force run in the
// same invocation; bench_embree has the Embree path on comparable frames.
//
//   bench_contact [--threads N] [google benchmark flags]
//   bench_contact [--threads N] --profile exact|paper|brute [--resolution R] [--frames N] [--no-depth]
//       [--no-sharing]
//       a plain loop of N frames (refit + detection) for callgrind, see run_profile
#include <corocontact/contact/detector.hpp>
#include <corocontact/core/primitives.hpp>
#include <corocontact/core/surface_mesh.hpp>

#include <benchmark/benchmark.h>
#include <tbb/global_control.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <map>
#include <memory>
#include <string>
#include <vector>

using namespace coro;

namespace {

constexpr int FRAMES = 16;

/// One body: its rest surface positions (body node order) and its contact surface.
struct Body {
    Positions rest;
    Vec3 center;
    ContactSurface surface;
};

/// The nodes of body `b` at frame `frame`: a radial wobble travelling over the sphere.
Positions deformed(const Body& body, int frame, double phase)
{
    Positions p = body.rest;
    const double t = 0.35 * frame + phase;
    for (Eigen::Index i = 0; i < p.rows(); ++i) {
        const Vec3 d = p.row(i).transpose() - body.center;
        const double s = 1.0 + 0.06 * std::sin(3.0 * d.x() + t) * std::cos(2.0 * d.y() - 0.7 * t + d.z());
        p.row(i) = (body.center + s * d).transpose();
    }
    return p;
}

struct Scene {
    std::vector<Body> bodies;
    std::vector<std::vector<Positions>> frames; // [frame][body] node positions
    std::vector<std::vector<ContactSurface>> surfaces; // [frame] refit surfaces
    Index tets = 0;
};

const Scene& scene(Index resolution)
{
    static std::map<Index, std::unique_ptr<Scene>> cache;
    auto& slot = cache[resolution];
    if (slot)
        return *slot;
    slot = std::make_unique<Scene>();
    Scene& s = *slot;
    for (const Vec3& c : {Vec3(0, 0, 0), Vec3(1.0, 0.05, -0.03)}) {
        const TetMesh mesh = make_sphere(c, 1.0, resolution);
        s.tets += mesh.num_tets();
        s.bodies.push_back({mesh.rest_positions, c,
                            ContactSurface::from_body("ball", mesh.rest_positions, boundary_faces(mesh))});
    }
    for (int f = 0; f < FRAMES; ++f) {
        std::vector<Positions> nodes;
        std::vector<ContactSurface> surfaces;
        for (std::size_t b = 0; b < s.bodies.size(); ++b) {
            nodes.push_back(deformed(s.bodies[b], f, 1.3 * static_cast<double>(b)));
            ContactSurface surface = s.bodies[b].surface;
            surface.update(nodes.back());
            surfaces.push_back(std::move(surface));
        }
        s.frames.push_back(std::move(nodes));
        s.surfaces.push_back(std::move(surfaces));
    }
    return s;
}

void set_scene_counters(benchmark::State& state, const Scene& s)
{
    state.counters["tets"] = static_cast<double>(s.tets);
    state.counters["surface_vertices"] = static_cast<double>(s.bodies[0].surface.vertices.rows() +
                                                             s.bodies[1].surface.vertices.rows());
}

void BM_Refit(benchmark::State& state)
{
    const Scene& s = scene(static_cast<Index>(state.range(0)));
    std::vector<ContactSurface> surfaces = s.surfaces[0];
    int frame = 0;
    for (auto _ : state) {
        frame = (frame + 1) % FRAMES;
        update_surfaces(surfaces, s.frames[static_cast<std::size_t>(frame)]);
        benchmark::DoNotOptimize(surfaces[0].tree.bounds());
    }
    set_scene_counters(state, s);
}

void detect(benchmark::State& state, DetectionMode mode, bool with_refit, bool contact_data = true)
{
    const Scene& s = scene(static_cast<Index>(state.range(0)));
    DetectionSettings settings;
    settings.mode = mode;
    settings.contact_data = contact_data;
    std::vector<ContactSurface> surfaces = s.surfaces[0];
    double queries = 0.0, inside = 0.0, fallbacks = 0.0;
    DetectionScratch scratch; // kept from frame to frame, as in a time loop
    int frame = 0;
    for (auto _ : state) {
        frame = (frame + 1) % FRAMES;
        const std::vector<ContactSurface>* current = &s.surfaces[static_cast<std::size_t>(frame)];
        if (with_refit) {
            update_surfaces(surfaces, s.frames[static_cast<std::size_t>(frame)]);
            current = &surfaces;
        }
        DetectionStats stats;
        auto points = detect_contacts(*current, settings, scratch, &stats);
        benchmark::DoNotOptimize(points.data());
        queries += stats.candidate_vertices;
        inside += stats.inside;
        fallbacks += stats.undecided_by_axes;
    }
    set_scene_counters(state, s);
    const auto iterations = static_cast<double>(state.iterations());
    state.counters["queries/s"] = benchmark::Counter(queries, benchmark::Counter::kIsRate);
    state.counters["queries/frame"] = queries / iterations;
    state.counters["inside/frame"] = inside / iterations;
    state.counters["fallbacks/frame"] = fallbacks / iterations;
}

void BM_DetectExact(benchmark::State& state) { detect(state, DetectionMode::EXACT, false); }
void BM_InsideOnlyExact(benchmark::State& state) { detect(state, DetectionMode::EXACT, false, false); }
void BM_InsideOnlyPaper(benchmark::State& state) { detect(state, DetectionMode::PAPER, false, false); }
void BM_InsideOnlyBruteForce(benchmark::State& state) { detect(state, DetectionMode::BRUTE_FORCE, false, false); }
void BM_DetectPaper(benchmark::State& state) { detect(state, DetectionMode::PAPER, false); }
void BM_DetectBruteForce(benchmark::State& state) { detect(state, DetectionMode::BRUTE_FORCE, false); }
void BM_FrameExact(benchmark::State& state) { detect(state, DetectionMode::EXACT, true); }
void BM_FrameInsideOnlyExact(benchmark::State& state) { detect(state, DetectionMode::EXACT, true, false); }


// --profile: a fixed number of frames in a plain loop, for valgrind --tool=callgrind
// --toggle-collect='*profile_frames*' (instructions per frame = collected / frames; the
// inclusive costs of profile_refit and profile_detect split them). Prints wall times too.
struct ProfileTotals {
    double refit_s = 0.0, detect_s = 0.0, queries = 0.0, inside = 0.0, by_neighbour = 0.0;
};

__attribute__((noinline)) void profile_refit(std::vector<ContactSurface>& surfaces, const std::vector<Positions>& nodes)
{
    update_surfaces(surfaces, nodes);
}

__attribute__((noinline)) std::vector<ContactPoint> profile_detect(const std::vector<ContactSurface>& surfaces,
                                                                   const DetectionSettings& settings,
                                                                   DetectionScratch& scratch, DetectionStats& stats)
{
    return detect_contacts(surfaces, settings, scratch, &stats);
}

__attribute__((noinline)) ProfileTotals profile_frames(const Scene& s, const DetectionSettings& settings, int frames)
{
    using Clock = std::chrono::steady_clock;
    std::vector<ContactSurface> surfaces = s.surfaces[0];
    DetectionScratch scratch;
    ProfileTotals totals;
    for (int f = 0; f < frames; ++f) {
        const auto t0 = Clock::now();
        profile_refit(surfaces, s.frames[static_cast<std::size_t>((f + 1) % FRAMES)]);
        const auto t1 = Clock::now();
        DetectionStats stats;
        const std::vector<ContactPoint> points = profile_detect(surfaces, settings, scratch, stats);
        benchmark::DoNotOptimize(points.data());
        const auto t2 = Clock::now();
        totals.refit_s += std::chrono::duration<double>(t1 - t0).count();
        totals.detect_s += std::chrono::duration<double>(t2 - t1).count();
        totals.queries += stats.candidate_vertices;
        totals.inside += stats.inside;
        totals.by_neighbour += stats.by_neighbour;
    }
    return totals;
}

int run_profile(Index resolution, const std::string& mode, bool depth, bool share, int frames)
{
    DetectionSettings settings;
    settings.mode = mode == "paper" ? DetectionMode::PAPER
                    : mode == "brute" ? DetectionMode::BRUTE_FORCE
                                      : DetectionMode::EXACT;
    settings.contact_data = depth;
    settings.share_answers = share;
    const Scene& s = scene(resolution);
    const ProfileTotals t = profile_frames(s, settings, frames);
    std::printf("profile: %s mode, %s, resolution %d (%d tets in 2 spheres), %d frames\n", mode.c_str(),
                depth ? "with depth" : "inside only", resolution, s.tets, frames);
    std::printf("per frame: refit %.1f us, detection %.1f us, %.0f vertex queries, %.0f inside, %.0f by a "
                "neighbour (clear-edge group)\n",
                1e6 * t.refit_s / frames, 1e6 * t.detect_s / frames, t.queries / frames, t.inside / frames,
                t.by_neighbour / frames);
    return 0;
}

} // namespace

BENCHMARK(BM_Refit)->Arg(12)->Arg(26)->UseRealTime()->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_DetectExact)->Arg(12)->Arg(26)->UseRealTime()->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_FrameExact)->Arg(12)->Arg(26)->UseRealTime()->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_FrameInsideOnlyExact)->Arg(12)->Arg(26)->UseRealTime()->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_InsideOnlyExact)->Arg(12)->Arg(26)->UseRealTime()->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_InsideOnlyPaper)->Arg(12)->Arg(26)->UseRealTime()->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_InsideOnlyBruteForce)->Arg(12)->Arg(26)->UseRealTime()->Unit(benchmark::kMillisecond);
BENCHMARK(BM_DetectPaper)->Arg(12)->Arg(26)->UseRealTime()->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_DetectBruteForce)->Arg(12)->Arg(26)->UseRealTime()->Unit(benchmark::kMillisecond);

int main(int argc, char** argv)
{
    // --threads N (as in the corocontact command) is ours; the rest goes to Google Benchmark.
    std::unique_ptr<tbb::global_control> threads;
    std::vector<char*> args;
    bool profile = false, depth = true, share = true;
    Index resolution = 26;
    int frames = FRAMES;
    std::string mode = "exact";
    for (int i = 0; i < argc; ++i) {
        if (std::strcmp(argv[i], "--threads") == 0 && i + 1 < argc) {
            threads = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism,
                                                            static_cast<std::size_t>(std::stoul(argv[++i])));
            continue;
        }
        if (std::strcmp(argv[i], "--profile") == 0 && i + 1 < argc) {
            profile = true;
            mode = argv[++i];
            continue;
        }
        if (std::strcmp(argv[i], "--resolution") == 0 && i + 1 < argc) {
            resolution = static_cast<Index>(std::stoi(argv[++i]));
            continue;
        }
        if (std::strcmp(argv[i], "--frames") == 0 && i + 1 < argc) {
            frames = std::stoi(argv[++i]);
            continue;
        }
        if (std::strcmp(argv[i], "--no-depth") == 0) {
            depth = false;
            continue;
        }
        if (std::strcmp(argv[i], "--no-sharing") == 0) {
            share = false;
            continue;
        }
        args.push_back(argv[i]);
    }
    if (profile)
        return run_profile(resolution, mode, depth, share, frames);
    int count = static_cast<int>(args.size());
    benchmark::Initialize(&count, args.data());
    if (benchmark::ReportUnrecognizedArguments(count, args.data()))
        return 1;
    benchmark::AddCustomContext("scene", "two deforming spheres (radius 1, centres 1 apart), Arg 12: ~10k tets "
                                         "each, Arg 26: ~105k tets each; wall time per frame (real time)");
    benchmark::AddCustomContext("measured", "BM_Refit: surface vertex copy + AABB-tree refit of both bodies; "
                                            "BM_Detect*: detection with depth and normal of every inside vertex (on "
                                            "surfaces refit once per frame outside the loop, so the face-plane "
                                            "cache of the depth search is filled once, not timed); "
                                            "BM_InsideOnly*: detection without depth; BM_Frame*: refit + detection; "
                                            "queries/s: candidate vertices tested per second of wall time");
    benchmark::AddCustomContext("embree", "bench_embree --summary prints every path, Embree included, on the "
                                          "same frames, with the exact/Embree ratios per frame");
    benchmark::RunSpecifiedBenchmarks();
    benchmark::Shutdown();
    return 0;
}
