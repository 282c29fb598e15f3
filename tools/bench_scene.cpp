// bench_scene: what a many-body scene costs against one body of the same size, in one run.
//
//   bench_scene PILE.toml [--steps 100] [--warmup 0] [--threads 1,2] [--iterations 20] [--turn 10]
//
// Runs the case's bodies, and one box of the same tet count (the first body's material, resting
// on the case's plane obstacles) with the same solver and contact settings, for each thread
// count, with contact on and off. The work per step is fixed: every solve runs exactly
// --iterations PCG iterations. Each run first takes --warmup steps untimed (a pile falls into
// contact), then times --steps steps. Prints milliseconds per step and per phase, the pile/box
// ratios, the contact phase's share and the 1 → N thread speed-ups. Pile and box live side by side
// and take turns of --turn steps, so a slow spell of a shared machine slows both: the ratio of
// their times is printed with the median and middle half of the ratios of single turns.

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

// A running simulation (of its own copy of the case: Simulation keeps a reference to both) and
// its summary when the timed steps began.
struct Timed {
    coro::CaseSpec spec;
    coro::LoadedScene loaded;
    coro::Simulation simulation;
    coro::RunSummary before;

    explicit Timed(const coro::CaseSpec& case_spec)
        : spec(case_spec), loaded(coro::load_scene(spec)), simulation(loaded.scene, spec)
    {
        simulation.start();
    }

    void begin_timing() { before = simulation.summary(); }

    // Runs `steps` steps; returns their wall time in seconds.
    double run(coro::Index steps)
    {
        const double wall = simulation.summary().wall_s;
        for (coro::Index step = 0; step < steps; ++step)
            simulation.step();
        return simulation.summary().wall_s - wall;
    }

    // Per step of the timed steps.
    Measurement measurement() const
    {
        const coro::RunSummary after = simulation.summary();
        Measurement m;
        const double per_step = 1000.0 / static_cast<double>(after.steps - before.steps);
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
};

struct Pair {
    Measurement pile, box;
    std::vector<double> turn_ratios; // pile / box of each turn
};

// Pile and box in alternating turns of `turn` steps each; every other pair of turns starts with
// the box, so that a host growing steadily faster or slower favours neither.
Pair measure_pair(const coro::CaseSpec& pile_spec, const coro::CaseSpec& box_spec, coro::Index warmup,
                  coro::Index steps, coro::Index turn, int threads)
{
    tbb::global_control control(tbb::global_control::max_allowed_parallelism, static_cast<std::size_t>(threads));
    Timed pile(pile_spec), box(box_spec);
    pile.run(warmup);
    box.run(warmup);
    pile.begin_timing();
    box.begin_timing();
    Pair pair;
    for (coro::Index done = 0; done < steps; done += turn) {
        const coro::Index n = std::min(turn, steps - done);
        double pile_s = 0.0, box_s = 0.0;
        if (pair.turn_ratios.size() % 2 == 0) {
            pile_s = pile.run(n);
            box_s = box.run(n);
        } else {
            box_s = box.run(n);
            pile_s = pile.run(n);
        }
        pair.turn_ratios.push_back(pile_s / box_s);
    }
    pair.pile = pile.measurement();
    pair.box = box.measurement();
    return pair;
}

// The q-quantile (0 <= q <= 1) of `values`: the value of rank round(q·(n − 1)), halves rounded up.
double quantile(std::vector<double> values, double q)
{
    const auto k = static_cast<std::size_t>(std::lround(q * static_cast<double>(values.size() - 1)));
    std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(k), values.end());
    return values[k];
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
    int steps = 100, warmup = 0, iterations = 20, turn = 10;
    app.add_option("case", case_file, "pile case file (e.g. from cases/pile_large/make_pile_large.py)")->required();
    app.add_option("--steps", steps, "timed steps of each scene")->check(CLI::Range(1, 1000000));
    app.add_option("--warmup", warmup, "untimed steps before the timed ones")->check(CLI::Range(0, 1000000));
    app.add_option("--threads", thread_list, "comma-separated thread counts, the first is the reference");
    app.add_option("--iterations", iterations, "PCG iterations per solve (fixed work)")->check(CLI::Range(1, 100000));
    app.add_option("--turn", turn, "steps of a turn: pile and box alternate turn by turn")
        ->check(CLI::Range(1, 1000000));
    try {
        app.parse(argc, argv);
    } catch (const CLI::ParseError& error) {
        return app.exit(error) == 0 ? 0 : 2; // --help: 0; a bad option or value: 2
    }

    try {
        const std::vector<int> threads = parse_threads(thread_list);
        coro::CaseSpec pile = coro::read_case(case_file);
        pile.solver.max_iterations = iterations;
        pile.solver.tolerance = 1e-300; // never reached: every solve runs the cap
        std::printf("%-10s %-8s %7s %7s %6s %9s %9s %9s %9s %9s %9s\n", "scene", "contact", "threads", "bodies",
                    "tets", "ms/step", "rotation", "assembly", "solve", "contact", "inside");
        std::map<std::pair<bool, int>, Pair> results; // (contact, threads)
        for (const bool contact : {true, false}) {
            pile.contact.enabled = contact;
            coro::Index tets = 0;
            {
                coro::LoadedScene loaded = coro::load_scene(pile);
                tets = loaded.scene.num_tets();
            }
            const coro::CaseSpec box = box_like(pile, tets);
            for (const int n : threads) {
                const Pair& pair = results[{contact, n}] = measure_pair(pile, box, warmup, steps, turn, n);
                for (const auto& [name, m] :
                     {std::pair<const char*, const Measurement&>{"pile", pair.pile}, {"box", pair.box}})
                    std::printf("%-10s %-8s %7d %7d %6d %9.3f %9.3f %9.3f %9.3f %9.3f %9.1f\n", name,
                                contact ? "on" : "off", n, static_cast<int>(m.bodies), static_cast<int>(m.tets),
                                m.ms_per_step, m.ms_per_phase.rotation, m.ms_per_phase.assembly,
                                m.ms_per_phase.solve, m.ms_per_phase.contact, m.contacts_per_step);
            }
        }
        std::printf("\nratios (pile / box, same threads, in turns of %d steps: all steps; the turns' median and "
                    "middle half) and speed-ups (%d thread%s -> n):\n",
                    turn, threads.front(), threads.front() == 1 ? "" : "s");
        for (const bool contact : {true, false})
            for (const int n : threads) {
                const Pair& pair = results[{contact, n}];
                const Pair& ref = results[{contact, threads.front()}];
                const double pile_speedup = ref.pile.ms_per_step / pair.pile.ms_per_step;
                const double box_speedup = ref.box.ms_per_step / pair.box.ms_per_step;
                const std::vector<double>& turns = pair.turn_ratios;
                std::printf("  contact %-3s threads %d: pile/box %.2f (turns %.2f, %.2f-%.2f), contact share pile "
                            "%.0f%% box %.0f%%, speed-up pile %.2f box %.2f (pile/box %.2f)\n",
                            contact ? "on" : "off", n, pair.pile.ms_per_step / pair.box.ms_per_step,
                            quantile(turns, 0.5), quantile(turns, 0.25), quantile(turns, 0.75),
                            100.0 * pair.pile.ms_per_phase.contact / pair.pile.ms_per_step,
                            100.0 * pair.box.ms_per_phase.contact / pair.box.ms_per_step, pile_speedup, box_speedup,
                            pile_speedup / box_speedup);
            }
    } catch (const std::exception& error) {
        std::cerr << "bench_scene: " << error.what() << "\n";
        return 2;
    }
    return 0;
}
