// bench_solve: the scene solve of a case with several solver settings, in one run, through the
// whole time step (element loop, contact, PCG) as `corocontact run` does it.
//
//   bench_solve CASE.toml [--steps 40] [--warmup 0] [--threads 2] [--repeat 1]
//               [--variants jacobi/double,amg/double] [--tolerance T] [--max-iterations N]
//               [--per-step]
//
// A variant is PRECONDITIONER/PRECISION (jacobi, block_jacobi, amg; double, single). Each
// variant loads the case afresh, takes --warmup untimed steps, then --steps timed ones; the
// variants run one after another, --repeat times (interleaved), and the medians are compared
// with the first variant. Printed per variant: steps/s, PCG iterations per solve, solves that
// missed the tolerance, the preconditioner's set-ups and their time, the V-cycles' time and the
// rest of the solve, per step; --per-step adds a line per step (iterations, set-up, solve).
// --tolerance and --max-iterations override the case's (tolerance 0: every solve runs the cap).

#include <corocontact/core/error.hpp>
#include <corocontact/io/case_reader.hpp>
#include <corocontact/io/scene_loader.hpp>
#include <corocontact/sim/simulation.hpp>

#include <CLI/CLI.hpp>
#include <tbb/global_control.h>

#include <algorithm>
#include <cstdio>
#include <iostream>
#include <string>
#include <vector>

namespace {

struct Variant {
    std::string name;
    coro::PcgPreconditioner preconditioner = coro::PcgPreconditioner::JACOBI;
    coro::MatrixPrecision precision = coro::MatrixPrecision::DOUBLE;
};

struct Measurement {
    double steps_per_s = 0.0;
    double iterations = 0.0;       // per solve
    double residual = 0.0;         // mean relative residual
    coro::Index not_converged = 0; // solves that stopped at the cap
    coro::Index solves = 0;
    double ms_rotation = 0.0, ms_solve = 0.0, ms_contact = 0.0; // per step
    coro::PreconditionerTimes preconditioner;                   // over the timed steps
};

std::vector<Variant> parse_variants(const std::string& list)
{
    std::vector<Variant> variants;
    std::size_t start = 0;
    while (start <= list.size()) {
        const std::size_t comma = std::min(list.find(',', start), list.size());
        const std::string item = list.substr(start, comma - start);
        const std::size_t slash = item.find('/');
        const std::string kind = item.substr(0, slash), precision = slash == std::string::npos ? "double" : item.substr(slash + 1);
        Variant v;
        v.name = kind + "/" + precision;
        if (kind == "jacobi")
            v.preconditioner = coro::PcgPreconditioner::JACOBI;
        else if (kind == "block_jacobi")
            v.preconditioner = coro::PcgPreconditioner::BLOCK_JACOBI;
        else if (kind == "amg")
            v.preconditioner = coro::PcgPreconditioner::AMG;
        else
            throw std::invalid_argument("unknown preconditioner '" + kind + "' (jacobi, block_jacobi, amg)");
        if (precision == "double")
            v.precision = coro::MatrixPrecision::DOUBLE;
        else if (precision == "single")
            v.precision = coro::MatrixPrecision::SINGLE;
        else
            throw std::invalid_argument("unknown precision '" + precision + "' (double, single)");
        variants.push_back(v);
        start = comma + 1;
    }
    return variants;
}

Measurement measure(coro::CaseSpec spec, const Variant& variant, coro::Index warmup, coro::Index steps,
                    bool per_step)
{
    spec.solver.preconditioner = variant.preconditioner;
    spec.solver.matrix_precision = variant.precision;
    coro::LoadedScene loaded = coro::load_scene(spec);
    coro::Simulation simulation(loaded.scene, spec);
    simulation.start();
    for (coro::Index step = 0; step < warmup; ++step)
        simulation.step();
    const coro::RunSummary first = simulation.summary();
    coro::RunSummary previous = first;
    for (coro::Index step = 0; step < steps; ++step) {
        simulation.step();
        if (!per_step)
            continue;
        const coro::RunSummary now = simulation.summary();
        const double iterations = now.cg_iterations_mean * static_cast<double>(now.solves) -
                                  previous.cg_iterations_mean * static_cast<double>(previous.solves);
        const double setup = now.preconditioner.setup_s - previous.preconditioner.setup_s;
        std::printf("  %-18s step %5d  iterations %6.0f  set-up %7.3f s  solve without set-up %7.3f s  "
                    "step %7.3f s\n",
                    variant.name.c_str(), static_cast<int>(simulation.steps_done()), iterations, setup,
                    now.phases.solve - previous.phases.solve - setup, now.wall_s - previous.wall_s);
        previous = now;
    }
    const coro::RunSummary last = simulation.summary();
    Measurement m;
    const double n = static_cast<double>(steps);
    m.steps_per_s = n / (last.wall_s - first.wall_s);
    m.solves = last.solves - first.solves;
    m.iterations = (last.cg_iterations_mean * static_cast<double>(last.solves) -
                    first.cg_iterations_mean * static_cast<double>(first.solves)) /
                   std::max<double>(1.0, static_cast<double>(m.solves));
    m.residual = (last.cg_residual_mean * static_cast<double>(last.solves) -
                  first.cg_residual_mean * static_cast<double>(first.solves)) /
                 std::max<double>(1.0, static_cast<double>(m.solves));
    m.not_converged = last.solves_not_converged - first.solves_not_converged;
    m.ms_rotation = 1e3 * (last.phases.rotation - first.phases.rotation) / n;
    m.ms_solve = 1e3 * (last.phases.solve - first.phases.solve) / n;
    m.ms_contact = 1e3 * (last.phases.contact - first.phases.contact) / n;
    m.preconditioner.setups = last.preconditioner.setups - first.preconditioner.setups;
    m.preconditioner.setup_s = last.preconditioner.setup_s - first.preconditioner.setup_s;
    m.preconditioner.applies = last.preconditioner.applies - first.preconditioner.applies;
    m.preconditioner.apply_s = last.preconditioner.apply_s - first.preconditioner.apply_s;
    return m;
}

double median(std::vector<double> values)
{
    std::sort(values.begin(), values.end());
    return values[values.size() / 2];
}

} // namespace

int main(int argc, char** argv)
{
    CLI::App app{"bench_solve: a case's time steps with several solver settings, in one run"};
    std::string case_file, variant_list = "jacobi/double,amg/double";
    int steps = 40, warmup = 0, threads = 2, repeat = 1, max_iterations = 0;
    double tolerance = -1.0;
    bool per_step = false;
    app.add_option("case", case_file, "case file")->required();
    app.add_option("--steps", steps, "timed time steps per variant")->check(CLI::Range(1, 1000000));
    app.add_option("--warmup", warmup, "untimed steps before them")->check(CLI::Range(0, 1000000));
    app.add_option("--threads", threads, "worker threads")->check(CLI::Range(1, 1024));
    app.add_option("--repeat", repeat, "runs of every variant (interleaved); medians are compared")
        ->check(CLI::Range(1, 100));
    app.add_option("--variants", variant_list, "comma-separated PRECONDITIONER/PRECISION, the first is the reference");
    app.add_option("--tolerance", tolerance, "PCG relative residual (default: the case's)");
    app.add_option("--max-iterations", max_iterations, "PCG iteration cap (default: the case's)");
    app.add_flag("--per-step", per_step, "a line per step: iterations, set-up and solve time");
    try {
        app.parse(argc, argv);
    } catch (const CLI::ParseError& error) {
        return app.exit(error) == 0 ? 0 : 2; // --help: 0; a bad option or value: 2
    }

    try {
        const std::vector<Variant> variants = parse_variants(variant_list);
        coro::CaseSpec spec = coro::read_case(case_file);
        if (tolerance >= 0.0)
            spec.solver.tolerance = tolerance;
        if (max_iterations > 0)
            spec.solver.max_iterations = max_iterations;
        tbb::global_control control(tbb::global_control::max_allowed_parallelism, static_cast<std::size_t>(threads));
        std::printf("bench_solve: %s, %d timed steps after %d, %d threads, tolerance %g, cap %d, %d repeats\n",
                    case_file.c_str(), steps, warmup, threads, spec.solver.tolerance,
                    static_cast<int>(spec.solver.max_iterations), repeat);
        std::vector<std::vector<Measurement>> runs(variants.size());
        for (int r = 0; r < repeat; ++r)
            for (std::size_t v = 0; v < variants.size(); ++v) {
                const Measurement m = measure(spec, variants[v], warmup, steps, per_step);
                std::printf("%-18s run %d: %7.3f steps/s, %7.1f iterations per solve, %d of %d not converged\n",
                            variants[v].name.c_str(), r + 1, m.steps_per_s, m.iterations,
                            static_cast<int>(m.not_converged), static_cast<int>(m.solves));
                std::fflush(stdout);
                runs[v].push_back(m);
            }
        std::printf("\nmedians over %d runs (per step: ms; ratio: steps/s against %s)\n", repeat,
                    variants.front().name.c_str());
        std::printf("%-18s %9s %7s %10s %9s %8s %8s %8s %7s %9s %9s %9s\n", "variant", "steps/s", "ratio",
                    "iterations", "residual", "missed", "element", "contact", "setups", "setup ms", "cycle ms",
                    "rest ms");
        std::vector<double> reference;
        for (const Measurement& m : runs.front())
            reference.push_back(m.steps_per_s);
        const double reference_rate = median(reference);
        for (std::size_t v = 0; v < variants.size(); ++v) {
            const auto field = [&](auto get) {
                std::vector<double> values;
                for (const Measurement& m : runs[v])
                    values.push_back(get(m));
                return median(values);
            };
            const double rate = field([](const Measurement& m) { return m.steps_per_s; });
            const double setup = field([&](const Measurement& m) { return 1e3 * m.preconditioner.setup_s / steps; });
            const double cycles = field([&](const Measurement& m) { return 1e3 * m.preconditioner.apply_s / steps; });
            const double solve = field([](const Measurement& m) { return m.ms_solve; });
            std::printf("%-18s %9.3f %7.2f %10.1f %9.2e %8.0f %8.2f %8.2f %7.0f %9.2f %9.2f %9.2f\n",
                        variants[v].name.c_str(), rate, rate / reference_rate,
                        field([](const Measurement& m) { return m.iterations; }),
                        field([](const Measurement& m) { return m.residual; }),
                        field([](const Measurement& m) { return static_cast<double>(m.not_converged); }),
                        field([](const Measurement& m) { return m.ms_rotation; }),
                        field([](const Measurement& m) { return m.ms_contact; }),
                        field([](const Measurement& m) { return static_cast<double>(m.preconditioner.setups); }),
                        setup, cycles, solve - setup - cycles);
        }
    } catch (const std::exception& error) {
        std::cerr << "bench_solve: " << error.what() << "\n";
        return 2;
    }
    return 0;
}
