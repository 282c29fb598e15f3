// Kernel benchmarks of one time step on SOFA's 16×16×76 beam (101,250 tets): element
// rotations, assembly, SpMV, one PCG iteration, and STREAM-like copy and reads measured in the
// same run (from memory, and of SpMV's own byte count), so that SpMV's effective bandwidth can
// be stated as a fraction of what the machine delivers. Run: build/bin/bench_kernels [--benchmark_filter=...]; threads via
// --threads N (default: all cores).

#include <corocontact/core/primitives.hpp>
#include <corocontact/fem/corotational_fem.hpp>
#include <corocontact/partition/part_layout.hpp>
#include <corocontact/partition/partition.hpp>
#include <corocontact/solver/pcg.hpp>
#include <corocontact/solver/vector_ops.hpp>

#include <benchmark/benchmark.h>
#include <tbb/blocked_range.h>
#include <tbb/global_control.h>
#include <tbb/info.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <cstdint>
#include <cstring>
#include <functional>
#include <memory>
#include <string>

namespace {

using namespace coro;

// The beam, partitioned and slightly bent, with its system assembled once.
struct Beam {
    TetMesh mesh;
    std::unique_ptr<CorotationalFem> fem;
    VecX x;
    BsrMatrix matrix;
    VecX forces;

    Beam()
    {
        const TetMesh input = make_box(Vec3(0, 6, -2), Vec3(19, 10, 2), {75, 15, 15});
        const Index parts = default_num_parts(input.num_tets(), 4);
        const PartLayout layout =
            make_part_layout(input.tets, input.num_vertices(), partition_tets(input.tets, input.num_vertices(), parts));
        mesh = reorder_mesh(input, layout);
        Material material;
        material.young = 1000.0;
        material.density = 50.0 / 304.0;
        fem = std::make_unique<CorotationalFem>(mesh, material, layout);
        x = fem->rest_dofs();
        for (Index v = 0; v < mesh.num_vertices(); ++v) {
            const double s = mesh.rest_positions(v, 0) / 19.0;
            x[3 * v + 1] -= 2.0 * s * s; // a bend
        }
        fem->update_rotations(x);
        matrix = fem->make_matrix();
        forces.resize(x.size());
        fem->assemble_with_forces(x, 0.0056, 1.004, {}, matrix, forces);
    }
};

Beam& beam()
{
    static Beam instance;
    return instance;
}

void BM_ElementRotations(benchmark::State& state)
{
    Beam& b = beam();
    for (auto _ : state)
        b.fem->update_rotations(b.x);
    state.SetItemsProcessed(state.iterations() * b.mesh.num_tets());
}

void BM_AssemblyWithForces(benchmark::State& state)
{
    Beam& b = beam();
    for (auto _ : state)
        b.fem->assemble_with_forces(b.x, 0.0056, 1.004, {}, b.matrix, b.forces);
    state.SetItemsProcessed(state.iterations() * b.mesh.num_tets());
    state.SetBytesProcessed(state.iterations() * static_cast<int64_t>(b.matrix.values().size() * sizeof(double)));
}

// Bytes SpMV must move at least once: values, column indices, row offsets, x and y.
int64_t spmv_bytes(const BsrMatrix& a)
{
    return static_cast<int64_t>(a.values().size() * sizeof(double) + a.columns().size() * sizeof(Index) +
                                a.row_offsets().size() * sizeof(Index) + 2 * a.num_dofs() * sizeof(double));
}

void BM_SpMV(benchmark::State& state)
{
    Beam& b = beam();
    const VecX p = VecX::LinSpaced(b.matrix.num_dofs(), -1.0, 1.0);
    VecX q(p.size());
    for (auto _ : state) {
        b.matrix.multiply(p, q);
        benchmark::DoNotOptimize(q.data());
    }
    state.SetBytesProcessed(state.iterations() * spmv_bytes(b.matrix));
}

void BM_PcgIteration(benchmark::State& state)
{
    Beam& b = beam();
    PcgSolver solver;
    PcgSettings settings;
    settings.max_iterations = 10;
    settings.tolerance = 1e-30;
    settings.preconditioner = PcgPreconditioner::JACOBI;
    VecX x(b.matrix.num_dofs());
    for (auto _ : state) {
        x.setZero();
        solver.solve(b.matrix, b.forces, x, settings);
    }
    state.SetItemsProcessed(state.iterations() * settings.max_iterations); // items = iterations
}

constexpr std::size_t STREAM_SIZE = 1 << 25; // 256 MiB per array: far beyond the caches

void BM_StreamCopy(benchmark::State& state)
{
    static std::vector<double> a(STREAM_SIZE, 1.0), c(STREAM_SIZE, 0.0);
    for (auto _ : state) {
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, STREAM_SIZE, 1 << 16), [&](const auto& r) {
            std::memcpy(c.data() + r.begin(), a.data() + r.begin(), r.size() * sizeof(double));
        });
        benchmark::DoNotOptimize(c.data());
    }
    state.SetBytesProcessed(state.iterations() * static_cast<int64_t>(2 * STREAM_SIZE * sizeof(double)));
}

// Sum of `n` words read in parallel chunks. Integer sums vectorize (their order does not
// matter), so the loop stays bound by the memory it reads, even from the caches.
std::uint64_t read_words(const std::uint64_t* a, std::size_t n)
{
    return tbb::parallel_reduce(
        tbb::blocked_range<std::size_t>(0, n, 1 << 14), std::uint64_t{0},
        [&](const auto& r, std::uint64_t acc) {
            std::uint64_t s = 0;
            for (std::size_t i = r.begin(); i < r.end(); ++i)
                s += a[i];
            return acc + s;
        },
        std::plus<std::uint64_t>());
}

void stream_read(benchmark::State& state, std::size_t words)
{
    const std::vector<std::uint64_t> a(words, 1);
    for (auto _ : state)
        benchmark::DoNotOptimize(read_words(a.data(), words));
    state.SetBytesProcessed(state.iterations() * static_cast<int64_t>(words * sizeof(std::uint64_t)));
}

// From memory: an array far beyond the caches.
void BM_StreamRead(benchmark::State& state) { stream_read(state, STREAM_SIZE); }

// The same number of bytes as one SpMV moves (spmv_bytes), read again and again like the
// matrix in the PCG loop: from whichever cache level holds a working set of that size, so
// SpMV's bandwidth is compared with a read of the same size from the same level.
void BM_StreamReadSpmvBytes(benchmark::State& state)
{
    stream_read(state, static_cast<std::size_t>(spmv_bytes(beam().matrix)) / sizeof(std::uint64_t));
}

BENCHMARK(BM_ElementRotations)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_AssemblyWithForces)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_SpMV)->Unit(benchmark::kMicrosecond)->UseRealTime();
BENCHMARK(BM_PcgIteration)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_StreamCopy)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_StreamRead)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_StreamReadSpmvBytes)->Unit(benchmark::kMicrosecond)->UseRealTime();

} // namespace

int main(int argc, char** argv)
{
    int threads = static_cast<int>(tbb::info::default_concurrency());
    for (int i = 1; i + 1 < argc; ++i)
        if (std::string(argv[i]) == "--threads") {
            threads = std::stoi(argv[i + 1]);
            for (int j = i; j + 2 < argc; ++j)
                argv[j] = argv[j + 2];
            argc -= 2;
            break;
        }
    tbb::global_control control(tbb::global_control::max_allowed_parallelism, static_cast<std::size_t>(threads));
    benchmark::AddCustomContext("threads", std::to_string(threads));
    benchmark::Initialize(&argc, argv);
    benchmark::RunSpecifiedBenchmarks();
    benchmark::Shutdown();
    return 0;
}
