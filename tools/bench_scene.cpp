// bench_scene: what a many-body scene costs against one body of the same size, in one run.
//
//   bench_scene PILE.toml [--steps 100] [--warmup 0] [--threads 1,2] [--iterations 20] [--repeat 1]
//
// Runs the case's bodies, and one box of the same tet count (the first body's material, resting
// on the case's plane obstacles) with the same solver and contact settings, for each thread
// count, with contact on and off. The work per step is fixed: every solve runs exactly
// --iterations PCG iterations. Each run first takes --warmup steps untimed (a pile falls into
// contact), then times --steps steps. Prints milliseconds per step and per phase, the pile/box
// ratios, the contact phase's share and the 1 → N thread speed-ups. With --repeat R, pile and box
// alternate R times and each keeps its fastest run (on a shared machine the least disturbed one);
// the range of the R pile/box ratios is printed beside the ratio of the fastest runs.

#include <corocontact/core/error.hpp>
#include <corocontact/io/case_reader.hpp>
#include <corocontact/io/scene_loader.hpp>
#include <corocontact/sim/simulation.hpp>

#include <CLI/CLI.hpp>
#include <tbb/global_control.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <map>
#include <string>
#include <vector>

namespace {

struct Measurement {
    double ms_per_step = 0.0;
    coro::PhaseTimes ms_per_phase; // per step
    double contacts_per_step = 0.0;
    coro::Index bodies = 0, tets = 0;
};

// One box of about `tets` tets (6 per cell, cells of 5 cm, about twice as wide as tall) lying on
// the floor, with the first body's material and damping.
coro::CaseSpec box_like(const coro::CaseSpec& pile, coro::Index tets)
{
    coro::CaseSpec box = pile;
    box.bodies.assign(1, pile.bodies.front());
    coro::BodySpec& body = box.bodies.front();
    body.name = "box";
    body.shape = coro::BodyShape::BOX;
    body.transform = {};
    body.velocity.setZero();
    body.fixed.clear();
    body.loads.clear();
    body.surface.clear();
    const double cells = static_cast<double>(tets) / 6.0;
    const auto ny = static_cast<coro::Index>(std::max(1.0, std::round(std::cbrt(cells / 4.0))));
    const auto nx = static_cast<coro::Index>(std::max(1.0, std::round(std::sqrt(cells / static_cast<double>(ny)))));
    const auto nz = static_cast<coro::Index>(std::max(1.0, std::round(cells / static_cast<double>(nx * ny))));
    body.cells = {nx, ny, nz};
    const double h = 0.05;
    body.box_min = coro::Vec3(-0.5 * h * static_cast<double>(nx), 0.001, -0.5 * h * static_cast<double>(nz));
    body.box_max = body.box_min + h * coro::Vec3(static_cast<double>(nx), static_cast<double>(ny), static_cast<double>(nz));
    return box;
}

Measurement measure(const coro::CaseSpec& spec, coro::Index warmup, coro::Index steps, int threads)
{
    tbb::global_control control(tbb::global_control::max_allowed_parallelism, static_cast<std::size_t>(threads));
    coro::LoadedScene loaded = coro::load_scene(spec);
    coro::Simulation simulation(loaded.scene, spec);
    simulation.start();
    for (coro::Index step = 0; step < warmup; ++step)
        simulation.step();
    const coro::RunSummary before = simulation.summary();
    for (coro::Index step = 0; step < steps; ++step)
        simulation.step();
    const coro::RunSummary after = simulation.summary();
    Measurement m;
    const double per_step = 1000.0 / static_cast<double>(steps);
    m.ms_per_step = (after.wall_s - before.wall_s) * per_step;
    m.ms_per_phase.rotation = (after.phases.rotation - before.phases.rotation) * per_step;
    m.ms_per_phase.assembly = (after.phases.assembly - before.phases.assembly) * per_step;
    m.ms_per_phase.solve = (after.phases.solve - before.phases.solve) * per_step;
    m.ms_per_phase.contact = (after.phases.contact - before.phases.contact) * per_step;
    // Inside vertices per detection over the timed steps (the summary keeps their mean).
    m.contacts_per_step = (after.contacts_mean * after.detections - before.contacts_mean * before.detections) /
                          std::max<double>(1.0, static_cast<double>(after.detections - before.detections));
    m.bodies = static_cast<coro::Index>(loaded.scene.bodies.size());
    m.tets = loaded.scene.num_tets();
    return m;
}

std::vector<int> parse_threads(const std::string& list)
{
    std::vector<int> threads;
    std::size_t start = 0;
    while (start <= list.size()) {
        const std::size_t comma = std::min(list.find(',', start), list.size());
        const int n = std::stoi(list.substr(start, comma - start));
        if (n < 1)
            throw std::invalid_argument("thread counts must be at least 1");
        threads.push_back(n);
        start = comma + 1;
    }
    return threads;
}

} // namespace

int main(int argc, char** argv)
{
    CLI::App app{"bench_scene: a many-body case against one box of the same tet count, in one run"};
    std::string case_file, thread_list = "1,2";
    int steps = 100, warmup = 0, iterations = 20, repeat = 1;
    app.add_option("case", case_file, "pile case file (e.g. from cases/pile_large/make_pile_large.py)")->required();
    app.add_option("--steps", steps, "time steps per measurement")->check(CLI::Range(1, 1000000));
    app.add_option("--warmup", warmup, "untimed steps before the timed ones")->check(CLI::Range(0, 1000000));
    app.add_option("--threads", thread_list, "comma-separated thread counts, the first is the reference");
    app.add_option("--iterations", iterations, "PCG iterations per solve (fixed work)")->check(CLI::Range(1, 100000));
    app.add_option("--repeat", repeat, "runs of pile and box, alternating; each keeps its fastest")
        ->check(CLI::Range(1, 100));
    CLI11_PARSE(app, argc, argv);

    try {
        const std::vector<int> threads = parse_threads(thread_list);
        coro::CaseSpec pile = coro::read_case(case_file);
        pile.solver.max_iterations = iterations;
        pile.solver.tolerance = 1e-300; // never reached: every solve runs the cap
        std::printf("%-10s %-8s %7s %7s %6s %9s %9s %9s %9s %9s %9s\n", "scene", "contact", "threads", "bodies",
                    "tets", "ms/step", "rotation", "assembly", "solve", "contact", "inside");
        std::map<std::pair<bool, int>, std::pair<Measurement, Measurement>> results; // (contact, threads)
        std::map<std::pair<bool, int>, std::pair<double, double>> ratio_range;          // of the repeats
        for (const bool contact : {true, false}) {
            pile.contact.enabled = contact;
            coro::Index tets = 0;
            {
                coro::LoadedScene loaded = coro::load_scene(pile);
                tets = loaded.scene.num_tets();
            }
            const coro::CaseSpec box = box_like(pile, tets);
            for (const int n : threads) {
                Measurement a, b;
                double lowest = INFINITY, highest = 0.0;
                for (int r = 0; r < repeat; ++r) {
                    const Measurement pile_run = measure(pile, warmup, steps, n), box_run = measure(box, warmup, steps, n);
                    if (r == 0 || pile_run.ms_per_step < a.ms_per_step)
                        a = pile_run;
                    if (r == 0 || box_run.ms_per_step < b.ms_per_step)
                        b = box_run;
                    const double ratio = pile_run.ms_per_step / box_run.ms_per_step;
                    lowest = std::min(lowest, ratio);
                    highest = std::max(highest, ratio);
                }
                results[{contact, n}] = {a, b};
                ratio_range[{contact, n}] = {lowest, highest};
                for (const auto& [name, m] : {std::pair<const char*, const Measurement&>{"pile", a}, {"box", b}})
                    std::printf("%-10s %-8s %7d %7d %6d %9.3f %9.3f %9.3f %9.3f %9.3f %9.1f\n", name,
                                contact ? "on" : "off", n, static_cast<int>(m.bodies), static_cast<int>(m.tets),
                                m.ms_per_step, m.ms_per_phase.rotation, m.ms_per_phase.assembly,
                                m.ms_per_phase.solve, m.ms_per_phase.contact, m.contacts_per_step);
            }
        }
        std::printf("\nratios (pile / box, same threads%s) and speed-ups (%d thread%s -> n):\n",
                    repeat > 1 ? ", fastest of each" : "", threads.front(), threads.front() == 1 ? "" : "s");
        for (const bool contact : {true, false})
            for (const int n : threads) {
                const auto& [pile_m, box_m] = results[{contact, n}];
                const auto& [pile_ref, box_ref] = results[{contact, threads.front()}];
                const double pile_speedup = pile_ref.ms_per_step / pile_m.ms_per_step;
                const double box_speedup = box_ref.ms_per_step / box_m.ms_per_step;
                const auto [lowest, highest] = ratio_range[{contact, n}];
                char range[64] = "";
                if (repeat > 1)
                    std::snprintf(range, sizeof range, " (runs %.2f-%.2f)", lowest, highest);
                std::printf("  contact %-3s threads %d: pile/box %.2f%s, contact share pile %.0f%% box %.0f%%, "
                            "speed-up pile %.2f box %.2f (pile/box %.2f)\n",
                            contact ? "on" : "off", n, pile_m.ms_per_step / box_m.ms_per_step, range,
                            100.0 * pile_m.ms_per_phase.contact / pile_m.ms_per_step,
                            100.0 * box_m.ms_per_phase.contact / box_m.ms_per_step, pile_speedup, box_speedup,
                            pile_speedup / box_speedup);
            }
    } catch (const std::exception& error) {
        std::cerr << "bench_scene: " << error.what() << "\n";
        return 2;
    }
    return 0;
}
