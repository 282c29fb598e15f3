// bench_embree: the Embree backend on two deforming spheres in deep overlap, per frame:
// Embree's update (refit, and its rebuild settings for comparison), detection, the whole
// frame, plain first-hit rays, and the axis-ray exact detector on the same frames.
//
//   bench_embree [--threads N] [benchmark options]      (N defaults to 2)
//   bench_embree [--threads N] --summary FRAMES
//       every path (exact, paper, brute force, Embree with depths by its point queries or by
//       our tree; with and without depth) on the same
//       frames in one run, interleaved frame by frame; prints refit, Embree update, detection
//       and frame times (medians), vertex queries/s and the exact/Embree ratios per frame
//
// Arguments of each benchmark: sphere resolution (12: ~10k tets, 26: ~105k tets per sphere)
// and, for Embree, the build setting (0 refit, 1 LOW rebuild, 2 MEDIUM rebuild).
#include "detail/embree_scene_set.hpp"

#include <corocontact/contact/detector.hpp>
#include <corocontact/core/primitives.hpp>
#include <corocontact/core/surface_mesh.hpp>
#include <corocontact/embree/embree_detector.hpp>

#include <benchmark/benchmark.h>

#include <tbb/blocked_range.h>
#include <tbb/global_control.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <map>
#include <memory>
#include <string>
#include <tuple>
#include <vector>

namespace {

using namespace coro;

constexpr int FRAMES = 16;
constexpr double PI = 3.14159265358979323846;

/// Two unit spheres, centres 0.8 apart (deep overlap), breathing and wobbling over FRAMES
/// frames; every frame's node positions are precomputed so that no benchmark times them.
struct Scene {
    Index resolution = 0;
    Index tets_per_sphere = 0;
    std::vector<Tris> faces;                            // per body, into its nodes
    std::vector<std::vector<Positions>> frames;         // [frame][body] node positions
    std::vector<std::vector<ContactSurface>> surfaces;  // [frame]: surfaces at that frame
};

Positions deformed(const Positions& rest, const Vec3& centre, int frame, double phase)
{
    const double s = std::sin(2.0 * PI * frame / FRAMES + phase);
    Positions out(rest.rows(), 3);
    for (Eigen::Index v = 0; v < rest.rows(); ++v) {
        const Vec3 x = rest.row(v).transpose() - centre;
        const Vec3 wobble(std::sin(2.0 * x.y()), std::sin(2.0 * x.z()), std::sin(2.0 * x.x()));
        out.row(v) = (centre + (1.0 + 0.03 * s) * x + 0.04 * s * wobble).transpose();
    }
    return out;
}

const Scene& scene(Index resolution)
{
    static std::map<Index, std::unique_ptr<Scene>> cache;
    auto& entry = cache[resolution];
    if (entry)
        return *entry;
    entry = std::make_unique<Scene>();
    Scene& sc = *entry;
    sc.resolution = resolution;
    const std::vector<Vec3> centres{Vec3(0.0, 0.0, 0.0), Vec3(0.8, 0.05, -0.03)};
    std::vector<Positions> rest;
    for (const Vec3& c : centres) {
        const TetMesh mesh = make_sphere(c, 1.0, resolution);
        sc.tets_per_sphere = mesh.num_tets();
        sc.faces.push_back(boundary_faces(mesh));
        rest.push_back(mesh.rest_positions);
    }
    for (int f = 0; f < FRAMES; ++f) {
        std::vector<Positions> bodies;
        for (std::size_t b = 0; b < centres.size(); ++b)
            bodies.push_back(deformed(rest[b], centres[b], f, 1.3 * static_cast<double>(b)));
        std::vector<ContactSurface> surfaces;
        for (std::size_t b = 0; b < centres.size(); ++b)
            surfaces.push_back(ContactSurface::from_body("sphere" + std::to_string(b), bodies[b], sc.faces[b]));
        sc.frames.push_back(std::move(bodies));
        sc.surfaces.push_back(std::move(surfaces));
    }
    return sc;
}

detail::EmbreeBuild build_of(const benchmark::State& state)
{
    return static_cast<detail::EmbreeBuild>(state.range(1));
}

const char* build_name(detail::EmbreeBuild b)
{
    switch (b) {
    case detail::EmbreeBuild::REFIT: return "refit";
    case detail::EmbreeBuild::LOW_REBUILD: return "low-rebuild";
    case detail::EmbreeBuild::MEDIUM_REBUILD: return "medium-rebuild";
    }
    return "?";
}

/// Advances `frame` (cyclically) and moves the surfaces to that frame's positions.
void next_frame(const Scene& sc, int& frame, std::vector<ContactSurface>& surfaces)
{
    frame = (frame + 1) % FRAMES;
    update_surfaces(surfaces, sc.frames[static_cast<std::size_t>(frame)]);
}

void label(benchmark::State& state, const Scene& sc, const char* what)
{
    state.SetLabel(std::string(what) + ", 2 spheres x " + std::to_string(sc.tets_per_sphere) + " tets, " +
                   std::to_string(sc.surfaces[0][0].faces.rows()) + " faces each");
}

/// Embree's per-frame update alone: float upload + rtcCommitGeometry + rtcCommitScene.
void BM_EmbreeUpdate(benchmark::State& state)
{
    const Scene& sc = scene(static_cast<Index>(state.range(0)));
    detail::EmbreeSceneSet scenes(sc.surfaces[0], build_of(state));
    int frame = 0;
    for (auto _ : state) {
        frame = (frame + 1) % FRAMES;
        scenes.update(sc.surfaces[static_cast<std::size_t>(frame)]);
    }
    label(state, sc, build_name(build_of(state)));
}

/// Embree detection on one frame (scenes current), with the query counts as rates.
void BM_EmbreeDetect(benchmark::State& state)
{
    const Scene& sc = scene(static_cast<Index>(state.range(0)));
    const std::vector<ContactSurface>& surfaces = sc.surfaces[0];
    detail::EmbreeSceneSet scenes(surfaces, build_of(state));
    DetectionStats stats;
    detail::EmbreeQueryCounts counts;
    detail::detect_contacts_embree(surfaces, scenes, DetectionSettings{}, &stats, &counts); // counts, untimed
    for (auto _ : state)
        benchmark::DoNotOptimize(detail::detect_contacts_embree(surfaces, scenes, DetectionSettings{}, nullptr, nullptr));
    const auto n = static_cast<double>(state.iterations());
    state.counters["queries"] = static_cast<double>(stats.candidate_vertices);
    state.counters["rays"] = static_cast<double>(counts.rays);
    state.counters["inside"] = static_cast<double>(stats.inside);
    state.counters["vertex_queries/s"] =
        benchmark::Counter(n * static_cast<double>(stats.candidate_vertices), benchmark::Counter::kIsRate);
    state.counters["rays/s"] = benchmark::Counter(n * static_cast<double>(counts.rays), benchmark::Counter::kIsRate);
    label(state, sc, build_name(build_of(state)));
}

/// One whole Embree frame: surfaces follow the nodes (copy + AABB-tree refit, needed for the
/// mid phase and the depth), Embree update, Embree detection.
void BM_EmbreeFrame(benchmark::State& state)
{
    const Scene& sc = scene(static_cast<Index>(state.range(0)));
    std::vector<ContactSurface> surfaces = sc.surfaces[0];
    detail::EmbreeSceneSet scenes(surfaces, build_of(state));
    int frame = 0;
    for (auto _ : state) {
        next_frame(sc, frame, surfaces);
        scenes.update(surfaces);
        benchmark::DoNotOptimize(detail::detect_contacts_embree(surfaces, scenes, DetectionSettings{}, nullptr, nullptr));
    }
    label(state, sc, build_name(build_of(state)));
}

/// BM_EmbreeFrame without depth and normal (contact_data off): refit, Embree update, inside tests.
void BM_EmbreeFrameInsideOnly(benchmark::State& state)
{
    const Scene& sc = scene(static_cast<Index>(state.range(0)));
    std::vector<ContactSurface> surfaces = sc.surfaces[0];
    detail::EmbreeSceneSet scenes(surfaces, build_of(state));
    DetectionSettings settings;
    settings.contact_data = false;
    int frame = 0;
    for (auto _ : state) {
        next_frame(sc, frame, surfaces);
        scenes.update(surfaces);
        benchmark::DoNotOptimize(detail::detect_contacts_embree(surfaces, scenes, settings, nullptr, nullptr));
    }
    label(state, sc, (std::string(build_name(build_of(state))) + ", inside only").c_str());
}

/// (other body, position) of every candidate vertex of the exact mode, in pair order.
std::vector<std::pair<Index, Vec3>> candidate_queries(const std::vector<ContactSurface>& surfaces)
{
    std::vector<std::pair<Index, Vec3>> queries;
    for (const PairCandidates& pair : contact_candidates(surfaces, DetectionMode::EXACT))
        for (Index v : pair.vertices)
            queries.emplace_back(pair.other, surfaces[static_cast<std::size_t>(pair.body)].vertices.row(v).transpose());
    return queries;
}

/// Plain first-hit rays (no filter, +x) from the candidate vertices: Embree's raw ray rate.
void BM_EmbreeFirstHitRays(benchmark::State& state)
{
    const Scene& sc = scene(static_cast<Index>(state.range(0)));
    const std::vector<ContactSurface>& surfaces = sc.surfaces[0];
    detail::EmbreeSceneSet scenes(surfaces, build_of(state));
    const std::vector<std::pair<Index, Vec3>> queries = candidate_queries(surfaces);
    for (auto _ : state)
        for (const auto& [other, p] : queries)
            benchmark::DoNotOptimize(scenes.first_hit(other, p, 0));
    state.counters["rays"] = static_cast<double>(queries.size());
    state.counters["rays/s"] = benchmark::Counter(static_cast<double>(state.iterations()) *
                                                      static_cast<double>(queries.size()),
                                                  benchmark::Counter::kIsRate);
    label(state, sc, (std::string(build_name(build_of(state))) + ", 1 thread").c_str());
}

/// Embree's inside test alone (all-hit axis rays, winding-number fallback) on the candidate
/// vertices, one thread: the cost of the narrow phase without the pipeline around it.
void BM_EmbreeInsideTests(benchmark::State& state)
{
    const Scene& sc = scene(static_cast<Index>(state.range(0)));
    const std::vector<ContactSurface>& surfaces = sc.surfaces[0];
    detail::EmbreeSceneSet scenes(surfaces, build_of(state));
    const std::vector<std::pair<Index, Vec3>> queries = candidate_queries(surfaces);
    detail::EmbreeQueryCounts counts;
    for (const auto& [other, p] : queries)
        scenes.inside_test(surfaces[static_cast<std::size_t>(other)], other, p, &counts);
    for (auto _ : state)
        for (const auto& [other, p] : queries)
            benchmark::DoNotOptimize(scenes.inside_test(surfaces[static_cast<std::size_t>(other)], other, p));
    const auto n = static_cast<double>(state.iterations());
    state.counters["queries"] = static_cast<double>(queries.size());
    state.counters["rays"] = static_cast<double>(counts.rays);
    state.counters["vertex_queries/s"] =
        benchmark::Counter(n * static_cast<double>(queries.size()), benchmark::Counter::kIsRate);
    state.counters["rays/s"] = benchmark::Counter(n * static_cast<double>(counts.rays), benchmark::Counter::kIsRate);
    label(state, sc, (std::string(build_name(build_of(state))) + ", 1 thread").c_str());
}

/// The contact library's pipeline around the narrow phase (broad and mid phase, nearest-point
/// depth and normal of the inside vertices, merge and sort) with the inside answers looked up
/// from a precomputed table: what a detection pass costs besides the inside tests.
void BM_PipelineWithoutNarrowPhase(benchmark::State& state)
{
    const Scene& sc = scene(static_cast<Index>(state.range(0)));
    const std::vector<ContactSurface>& surfaces = sc.surfaces[0];
    std::map<std::tuple<Index, double, double, double>, InsideTest> answers;
    for (const PairCandidates& pair : contact_candidates(surfaces, DetectionMode::EXACT))
        for (Index v : pair.vertices) {
            const Vec3 p = surfaces[static_cast<std::size_t>(pair.body)].vertices.row(v).transpose();
            answers[{pair.other, p.x(), p.y(), p.z()}] = inside_test(
                surfaces[static_cast<std::size_t>(pair.other)], p, DetectionMode::EXACT, {}, AxisRayTolerances{});
        }
    CustomNarrowPhase lookup;
    lookup.inside = [&](Index other, const Vec3& p) { return answers.at({other, p.x(), p.y(), p.z()}); };
    for (auto _ : state)
        benchmark::DoNotOptimize(detect_contacts(surfaces, lookup, true));
    label(state, sc, "table lookup instead of inside tests");
}

/// The axis-ray detector's refit alone (surfaces follow the nodes: copy + tree refit).
void BM_AxisRayRefit(benchmark::State& state)
{
    const Scene& sc = scene(static_cast<Index>(state.range(0)));
    std::vector<ContactSurface> surfaces = sc.surfaces[0];
    int frame = 0;
    for (auto _ : state) {
        next_frame(sc, frame, surfaces);
    }
    label(state, sc, "axis-ray");
}

/// The axis-ray exact detector on one frame, and a whole frame (refit + detection).
void BM_AxisRayDetect(benchmark::State& state)
{
    const Scene& sc = scene(static_cast<Index>(state.range(0)));
    const std::vector<ContactSurface>& surfaces = sc.surfaces[0];
    DetectionStats stats;
    DetectionScratch scratch;
    detect_contacts(surfaces, DetectionSettings{}, scratch, &stats);
    for (auto _ : state)
        benchmark::DoNotOptimize(detect_contacts(surfaces, DetectionSettings{}, scratch));
    state.counters["queries"] = static_cast<double>(stats.candidate_vertices);
    state.counters["inside"] = static_cast<double>(stats.inside);
    state.counters["vertex_queries/s"] = benchmark::Counter(
        static_cast<double>(state.iterations()) * static_cast<double>(stats.candidate_vertices),
        benchmark::Counter::kIsRate);
    // Agreement with Embree on this frame (not timed).
    const EmbreeScenes scenes(surfaces);
    state.counters["disagreements"] = static_cast<double>(
        cross_check(detect_contacts(surfaces, DetectionSettings{}),
                    detect_contacts_embree(surfaces, scenes, DetectionSettings{}))
            .size());
    label(state, sc, "axis-ray exact");
}

void BM_AxisRayFrame(benchmark::State& state)
{
    const Scene& sc = scene(static_cast<Index>(state.range(0)));
    std::vector<ContactSurface> surfaces = sc.surfaces[0];
    DetectionScratch scratch;
    int frame = 0;
    for (auto _ : state) {
        next_frame(sc, frame, surfaces);
        benchmark::DoNotOptimize(detect_contacts(surfaces, DetectionSettings{}, scratch));
    }
    label(state, sc, "axis-ray exact");
}

/// BM_AxisRayFrame without depth and normal: refit and the exact inside tests.
void BM_AxisRayFrameInsideOnly(benchmark::State& state)
{
    const Scene& sc = scene(static_cast<Index>(state.range(0)));
    std::vector<ContactSurface> surfaces = sc.surfaces[0];
    DetectionSettings settings;
    settings.contact_data = false;
    DetectionScratch scratch;
    int frame = 0;
    for (auto _ : state) {
        next_frame(sc, frame, surfaces);
        benchmark::DoNotOptimize(detect_contacts(surfaces, settings, scratch));
    }
    label(state, sc, "axis-ray exact, inside only");
}


// --summary: every path on the same frames in one run, interleaved frame by frame (so that a
// loaded machine slows them alike), median wall time per frame of each part. See main().
struct PathTimes {
    std::vector<double> refit, detect; // seconds per frame
    std::vector<double> cpu;           // process CPU seconds per frame (refit, update, detect)
    double queries = 0.0, inside = 0.0, by_neighbour = 0.0;
    long differing = 0; // (vertex, other body) answers that differ from the exact path's, all frames
};

double median(std::vector<double> v)
{
    if (v.empty())
        return 0.0;
    std::sort(v.begin(), v.end());
    return v[v.size() / 2];
}

template <class F>
double seconds(F&& f)
{
    const auto t0 = std::chrono::steady_clock::now();
    f();
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

/// CPU time of this process, all threads [s]: unlike wall time, it does not grow when other
/// processes take the cores (but counts the TBB threads' waits).
double process_cpu_seconds()
{
    timespec t{};
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
    return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

void summary(Index resolution, int frames, std::size_t threads)
{
    const Scene& sc = scene(resolution);
    enum Path {
        EXACT,
        EXACT_INSIDE,
        EXACT_EACH,
        PAPER,
        PAPER_INSIDE,
        BRUTE_INSIDE,
        EMBREE,
        EMBREE_TREE_DEPTH,
        EMBREE_INSIDE,
        N_PATHS
    };
    const char* names[N_PATHS] = {"exact",  "exact, inside only",  "exact, inside, no sharing", "paper",
                                  "paper, inside only", "brute force, inside only", "embree",
                                  "embree, depth by our tree", "embree, inside only"};
    std::vector<PathTimes> t(N_PATHS);
    std::vector<std::vector<ContactSurface>> surfaces(N_PATHS, sc.surfaces[0]);
    std::vector<DetectionScratch> scratches(N_PATHS); // each path's, kept from frame to frame as in a time loop
    detail::EmbreeSceneSet scenes(sc.surfaces[0], detail::EmbreeBuild::REFIT);
    std::vector<double> embree_update;
    const int brute_frames = std::min(frames, resolution > 16 ? 4 : 16);
    std::vector<ContactPoint> exact_points; // this frame's answers of the exact path (run first)
    for (int f = 0; f < frames; ++f) {
        const auto& nodes = sc.frames[static_cast<std::size_t>((f + 1) % FRAMES)];
        for (int p = 0; p < N_PATHS; ++p) {
            if (p == BRUTE_INSIDE && f >= brute_frames)
                continue;
            std::vector<ContactSurface>& s = surfaces[static_cast<std::size_t>(p)];
            PathTimes& pt = t[static_cast<std::size_t>(p)];
            const double cpu0 = process_cpu_seconds();
            pt.refit.push_back(seconds([&] { update_surfaces(s, nodes); }));
            DetectionSettings settings;
            settings.contact_data = p == EXACT || p == PAPER || p == EMBREE || p == EMBREE_TREE_DEPTH;
            settings.share_answers = p != EXACT_EACH;
            settings.mode = p == PAPER || p == PAPER_INSIDE ? DetectionMode::PAPER
                            : p == BRUTE_INSIDE             ? DetectionMode::BRUTE_FORCE
                                                            : DetectionMode::EXACT;
            DetectionStats stats;
            std::vector<ContactPoint> points;
            if (p == EMBREE || p == EMBREE_INSIDE) {
                embree_update.push_back(seconds([&] { scenes.update(s); }));
                pt.detect.push_back(seconds([&] {
                    points = detail::detect_contacts_embree(s, scenes, settings, &stats, nullptr);
                }));
            } else if (p == EMBREE_TREE_DEPTH) { // Embree's inside tests, our tree's depth searches
                embree_update.push_back(seconds([&] { scenes.update(s); }));
                CustomNarrowPhase embree_inside;
                embree_inside.inside = [&](Index other, const Vec3& x) {
                    return scenes.inside_test(s[static_cast<std::size_t>(other)], other, x);
                };
                pt.detect.push_back(seconds([&] { points = detect_contacts(s, embree_inside, true, &stats); }));
            } else {
                DetectionScratch& scratch = scratches[static_cast<std::size_t>(p)];
                pt.detect.push_back(seconds([&] { points = detect_contacts(s, settings, scratch, &stats); }));
            }
            pt.cpu.push_back(process_cpu_seconds() - cpu0);
            if (p == EXACT)
                exact_points = points;
            else
                pt.differing += static_cast<long>(cross_check(exact_points, points).size());
            pt.queries += stats.candidate_vertices;
            pt.inside += stats.inside;
            pt.by_neighbour += stats.by_neighbour;
        }
    }
    const double update = median(embree_update);
    std::printf("\n== two deforming spheres, %d tets each, %ld faces each, deep overlap; %zu TBB threads; "
                "median wall time per frame over %d frames (brute force %d) ==\n",
                sc.tets_per_sphere, static_cast<long>(sc.surfaces[0][0].faces.rows()), threads, frames,
                brute_frames);
    std::printf("%-26s %10s %10s %10s %12s %10s %10s %10s %10s %10s\n", "path", "refit ms", "update ms", "detect ms",
                "frame ms", "queries", "Mqueries/s", "shared", "differ", "cpu ms");
    std::vector<double> frame(N_PATHS), frame_cpu(N_PATHS);
    for (int p = 0; p < N_PATHS; ++p) {
        const PathTimes& pt = t[static_cast<std::size_t>(p)];
        const bool embree = p == EMBREE || p == EMBREE_TREE_DEPTH || p == EMBREE_INSIDE;
        const double r = median(pt.refit), d = median(pt.detect), u = embree ? update : 0.0;
        frame[static_cast<std::size_t>(p)] = r + u + d;
        frame_cpu[static_cast<std::size_t>(p)] = median(pt.cpu);
        const double n = pt.queries / static_cast<double>(pt.detect.size());
        std::printf("%-26s %10.3f %10.3f %10.3f %12.3f %10.0f %10.2f %10.0f %10ld %10.3f\n", names[p], 1e3 * r,
                    1e3 * u, 1e3 * d, 1e3 * (r + u + d), n, 1e-6 * n / d,
                    pt.by_neighbour / static_cast<double>(pt.detect.size()), pt.differing,
                    1e3 * frame_cpu[static_cast<std::size_t>(p)]);
    }
    // The reference point: Embree's update plus one plain first-hit ray (+x) per
    // candidate vertex, in parallel: not an inside test (no all-hit gathering, no degenerate
    // cases), the least an Embree path could cost on these queries.
    std::vector<double> first_hit;
    std::vector<std::pair<Index, Vec3>> rays;
    {
        std::vector<ContactSurface> s = sc.surfaces[0];
        for (int f = 0; f < frames; ++f) {
            const auto& nodes = sc.frames[static_cast<std::size_t>((f + 1) % FRAMES)];
            update_surfaces(s, nodes);
            rays.clear();
            for (const PairCandidates& pair : contact_candidates(s, DetectionMode::EXACT))
                for (const Index v : pair.vertices)
                    rays.emplace_back(pair.other, s[static_cast<std::size_t>(pair.body)].vertices.row(v).transpose());
            first_hit.push_back(seconds([&] {
                scenes.update(s);
                tbb::parallel_for(tbb::blocked_range<std::size_t>(0, rays.size(), 128),
                                  [&](const tbb::blocked_range<std::size_t>& r) {
                                      for (std::size_t i = r.begin(); i < r.end(); ++i)
                                          benchmark::DoNotOptimize(scenes.first_hit(rays[i].first, rays[i].second, 0));
                                  });
            }));
        }
    }
    const double refit_emb = median(t[EMBREE].refit), refit_emb_in = median(t[EMBREE_INSIDE].refit);
    std::printf("refit = copy of the surface vertices + our AABB-tree refit (the Embree paths need it too, for "
                "the mid phase, and 'depth by our tree' for its depths); update = Embree's per-frame refit (vertex upload + rtcCommitScene); detect = broad, "
                "mid, narrow phase (+ nearest-point depth and normal unless 'inside only'), sorted output; "
                "Mqueries/s = candidate vertices / detect time; shared = vertices that took a neighbour's "
                "answer of another vertex of their group, joined by surface edges that meet no face of the other body (DetectionSettings::share_answers; 'no sharing' "
                "tests each); differ = (vertex, other body) answers of all frames that differ from the exact path's "
                "(inside for one, outside for the other); cpu ms = CPU time of the process per frame, all threads (refit + "
                "update + detect, median; with other processes on the cores it grows less than wall time)\n");
    std::printf("ratio exact with depth / exact inside only per frame: %.2f (cpu %.2f)\n", frame[EXACT] / frame[EXACT_INSIDE],
                frame_cpu[EXACT] / frame_cpu[EXACT_INSIDE]);
    std::printf("ratio exact/Embree per frame, with depth:   %.3f  (refit+detect vs refit+update+detect; Embree's "
                "depths by its point queries)\n",
                frame[EXACT] / frame[EMBREE]);
    std::printf("ratio exact/Embree per frame, with depth, Embree's depths by our tree: %.3f\n",
                frame[EXACT] / frame[EMBREE_TREE_DEPTH]);
    std::printf("ratio exact/Embree per frame, inside only:  %.3f\n", frame[EXACT_INSIDE] / frame[EMBREE_INSIDE]);
    std::printf("ratio exact/Embree, Embree not charged for our refit: with depth %.3f, inside only %.3f  "
                "(exact refit+detect vs Embree update+detect)\n",
                frame[EXACT] / (frame[EMBREE] - refit_emb), frame[EXACT_INSIDE] / (frame[EMBREE_INSIDE] - refit_emb_in));
    std::printf("Embree update + %zu plain first-hit rays (one per candidate vertex, +x, no inside decision): "
                "%.3f ms; ratio exact inside only / that: %.3f\n",
                rays.size(), 1e3 * median(first_hit), frame[EXACT_INSIDE] / median(first_hit));
}

void embree_args(benchmark::internal::Benchmark* b)
{
    for (int res : {12, 26})
        for (int build : {0, 1, 2})
            b->Args({res, build});
}

void sizes(benchmark::internal::Benchmark* b)
{
    for (int res : {12, 26})
        b->Args({res});
}

BENCHMARK(BM_EmbreeUpdate)->Apply(embree_args)->UseRealTime()->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_EmbreeDetect)->Apply(embree_args)->UseRealTime()->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_EmbreeFrame)->Apply(embree_args)->UseRealTime()->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_EmbreeFrameInsideOnly)->Apply(embree_args)->UseRealTime()->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_EmbreeFirstHitRays)->Args({12, 0})->Args({26, 0})->Args({26, 2})->UseRealTime()->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_EmbreeInsideTests)->Args({12, 0})->Args({26, 0})->Args({26, 2})->UseRealTime()->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_PipelineWithoutNarrowPhase)->Apply(sizes)->UseRealTime()->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_AxisRayRefit)->Apply(sizes)->UseRealTime()->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_AxisRayDetect)->Apply(sizes)->UseRealTime()->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_AxisRayFrame)->Apply(sizes)->UseRealTime()->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_AxisRayFrameInsideOnly)->Apply(sizes)->UseRealTime()->Unit(benchmark::kMicrosecond);

} // namespace

int main(int argc, char** argv)
{
    // --threads N (default 2) sets the TBB thread count; the rest goes to Google Benchmark.
    std::size_t threads = 2;
    int summary_frames = 0;
    std::vector<char*> args;
    for (int i = 0; i < argc; ++i) {
        if (std::strcmp(argv[i], "--threads") == 0 && i + 1 < argc) {
            threads = static_cast<std::size_t>(std::strtoul(argv[++i], nullptr, 10));
            continue;
        }
        if (std::strcmp(argv[i], "--summary") == 0 && i + 1 < argc) {
            summary_frames = std::atoi(argv[++i]);
            continue;
        }
        args.push_back(argv[i]);
    }
    const tbb::global_control control(tbb::global_control::max_allowed_parallelism, threads);
    if (summary_frames > 0) {
        for (const Index resolution : {12, 26})
            summary(resolution, summary_frames, threads);
        return 0;
    }
    int n = static_cast<int>(args.size());
    benchmark::Initialize(&n, args.data());
    if (benchmark::ReportUnrecognizedArguments(n, args.data()))
        return 1;
    benchmark::AddCustomContext("tbb_threads", std::to_string(threads));
    benchmark::RunSpecifiedBenchmarks();
    benchmark::Shutdown();
    return 0;
}
