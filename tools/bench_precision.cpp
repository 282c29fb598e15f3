// bench_precision: single-precision matrix values (solver.matrix_precision = "single") against
// double ones and against a speed-of-light kernel, on the SOFA beam (16×16×76 nodes, 101,250
// tets, cases/bench/sofa_beam_16x16x76.toml), in one run, 2 threads by default:
//   Spmv*    y = A x with the chunks' x·y: SceneMatrix::multiply with double and single values,
//            and the speed-of-light kernel's float and double paths
//   Pcg10*   10 Jacobi-PCG iterations from x = 0 (tolerance 0): PcgSolver with double and
//            single values, and the speed-of-light kernel's float and double paths
//   Step*    one whole implicit Euler step with a 10-iteration solve (SceneSystem::step:
//            element loop, assembly, PCG, advance), double and single values
// The speed-of-light kernel (KernelUpper, KernelPcg below) is the same upper-storage product
// with float or double values and the same PCG iteration, written straight into this file
// without the library's interfaces: what each precision can give at most. After the runs the
// minima over the repetitions are compared: single against double and against both of the
// kernel's paths.
// `--accuracy` instead prints how far single-precision values are from double ones (after
// assembly, in a product, and in solves to convergence measured with the double matrix).
//
// `--scale K` multiplies the beam's elements along each edge by K (~K³ times the matrix): the
// SOFA beam's double matrix (10.4 MB) fits in a 32 MB L3 cache, from where the product is bound
// by instructions rather than bytes and halving the bytes of its values gains little; at K = 2
// (80.6 MB) it streams from memory, the case single-precision values are made for.
//
//   bench_precision [--threads N] [--scale K] [--accuracy] [benchmark options]   (N: 2, K: 1)
//   e.g. bench_precision --benchmark_repetitions=10 --benchmark_enable_random_interleaving=true
#include "implicit_euler_system.hpp"

#include <corocontact/core/primitives.hpp>
#include <corocontact/partition/partition.hpp>
#include <corocontact/sim/body.hpp>
#include <corocontact/sim/scene_system.hpp>
#include <corocontact/solver/pcg.hpp>
#include <corocontact/solver/row_chunks.hpp>
#include <corocontact/solver/scene_matrix.hpp>
#include <corocontact/solver/vector_ops.hpp>

#include <benchmark/benchmark.h>

#include <tbb/global_control.h>

#if defined(__AVX2__) && defined(__FMA__)
#include <immintrin.h>
#endif

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <map>
#include <memory>
#include <string>
#include <vector>

namespace {

using namespace coro;


BodySpec beam_spec()
{
        BodySpec spec;
        spec.name = "beam";
        spec.material.young = 1000.0;
        spec.material.poisson = 0.3;
        spec.material.density = 50.0 / 304.0;
        spec.rayleigh_mass = 0.1;
        spec.rayleigh_stiffness = 0.1;
        FixedRegion clamp;
        clamp.max = Vec3(0.1, 1e9, 1e9);
        spec.fixed.push_back(clamp);
        return spec;
}

/// Elements along each edge of the beam are multiplied by this (--scale); 1: SOFA's beam.
int g_scale = 1;

TetMesh beam_mesh()
{
    return make_box(Vec3(0.0, 6.0, -2.0), Vec3(19.0, 10.0, 2.0), {75 * g_scale, 15 * g_scale, 15 * g_scale});
}

constexpr double DT = 0.04;
const Vec3 GRAVITY(0.0, -9.0, 0.0);

/// The beam's system at its first implicit Euler step, with double values (`body`) and with
/// single ones assembled by the same element loop (`single`).
struct Beam {
    std::unique_ptr<Body> body;
    std::unique_ptr<Body> single;
    VecX rhs;
};

const Beam& beam()
{
    static const Beam b = [] {
        const TetMesh mesh = beam_mesh();
        const Index parts = default_num_parts(mesh.num_tets(), 4);
        Beam out;
        out.body = std::make_unique<Body>(mesh, beam_spec(), parts);
        out.single = std::make_unique<Body>(mesh, beam_spec(), parts, MatrixPrecision::SINGLE);
        out.rhs = bench::implicit_euler_system(*out.body, DT, GRAVITY);
        bench::implicit_euler_system(*out.single, DT, GRAVITY);
        return out;
    }();
    return b;
}

/// The upper-storage matrix with `Value` (float or double) values, multiplied as
/// SceneMatrix::multiply multiplies a one-body scene: the body's product chunks as tasks, each
/// chunk's rows with the mirrors of blocks inside it, then the mirrors reaching across chunks
/// gathered per row with the chunk's partial dot product.
template <typename Value>
class KernelUpper {
public:
    explicit KernelUpper(const BsrMatrix& a) : m_a(a), m_scene({&a})
    {
        m_values.assign(a.values().begin(), a.values().end()); // float: rounded once
        // Per row, the blocks (k, source row) of earlier chunks whose column is the row (the
        // BsrMatrix keeps its own list private).
        const std::vector<Index>& chunks = a.chunk_offsets();
        const Index n = a.num_block_rows();
        std::vector<Index> chunk_end(static_cast<std::size_t>(n));
        for (std::size_t c = 0; c + 1 < chunks.size(); ++c)
            for (Index r = chunks[c]; r < chunks[c + 1]; ++r)
                chunk_end[static_cast<std::size_t>(r)] = chunks[c + 1];
        m_gather_offsets.assign(static_cast<std::size_t>(n) + 1, 0);
        for (Index r = 0; r < n; ++r)
            for (Index k = a.row_offsets()[static_cast<std::size_t>(r)]; k < a.row_offsets()[static_cast<std::size_t>(r) + 1]; ++k)
                if (a.columns()[static_cast<std::size_t>(k)] >= chunk_end[static_cast<std::size_t>(r)])
                    ++m_gather_offsets[static_cast<std::size_t>(a.columns()[static_cast<std::size_t>(k)]) + 1];
        for (std::size_t i = 1; i < m_gather_offsets.size(); ++i)
            m_gather_offsets[i] += m_gather_offsets[i - 1];
        m_gather.resize(static_cast<std::size_t>(m_gather_offsets.back()));
        std::vector<Index> fill(m_gather_offsets.begin(), m_gather_offsets.end() - 1);
        for (Index r = 0; r < n; ++r)
            for (Index k = a.row_offsets()[static_cast<std::size_t>(r)]; k < a.row_offsets()[static_cast<std::size_t>(r) + 1]; ++k) {
                const Index c = a.columns()[static_cast<std::size_t>(k)];
                if (c >= chunk_end[static_cast<std::size_t>(r)])
                    m_gather[static_cast<std::size_t>(fill[static_cast<std::size_t>(c)]++)] = {k, r};
            }
        m_chunk_dots.resize(static_cast<std::size_t>(m_scene.chunks().num_chunks()));
    }

    const RowChunks& chunks() const { return m_scene.chunks(); }

    /// y = A x with float values; returns x·y summed per chunk, then in chunk order.
    double multiply_dot(const double* x, double* y)
    {
        for_each_chunk(m_scene.chunks(), [&](Index, Index begin, Index end) {
            std::fill(y + 3 * static_cast<std::ptrdiff_t>(begin), y + 3 * static_cast<std::ptrdiff_t>(end), 0.0);
            chunk_rows(x, y, begin, end);
        });
        for_each_chunk(m_scene.chunks(), [&](Index c, Index begin, Index end) {
            for (Index r = begin; r < end; ++r)
                gather_row(x, y, r);
            double sum = 0.0;
            for (std::ptrdiff_t i = 3 * static_cast<std::ptrdiff_t>(begin); i < 3 * static_cast<std::ptrdiff_t>(end); ++i)
                sum += x[i] * y[i];
            m_chunk_dots[static_cast<std::size_t>(c)] = sum;
        });
        double sum = 0.0;
        for (const double d : m_chunk_dots)
            sum += d;
        return sum;
    }

private:
#if defined(__AVX2__) && defined(__FMA__)
    static __m256d load3(const double* p)
    {
        return _mm256_insertf128_pd(_mm256_castpd128_pd256(_mm_loadu_pd(p)), _mm_load_sd(p + 2), 1);
    }
    static void store3(double* p, __m256d v)
    {
        _mm_storeu_pd(p, _mm256_castpd256_pd128(v));
        _mm_store_sd(p + 2, _mm256_extractf128_pd(v, 1));
    }
    struct Rows {
        __m256d r0, r1, r2;
        explicit Rows(const float* a)
            : r0(_mm256_cvtps_pd(_mm_loadu_ps(a))), r1(_mm256_cvtps_pd(_mm_loadu_ps(a + 3))),
              r2(_mm256_permute4x64_pd(_mm256_cvtps_pd(_mm_loadu_ps(a + 5)), _MM_SHUFFLE(3, 3, 2, 1)))
        {
        }
        explicit Rows(const double* a) : r0(_mm256_loadu_pd(a)), r1(_mm256_loadu_pd(a + 3)), r2(load3(a + 6)) {}
    };
    static double sum3(__m256d v)
    {
        alignas(32) double lanes[4];
        _mm256_store_pd(lanes, v);
        return (lanes[0] + lanes[1]) + lanes[2];
    }
    void chunk_rows(const double* x, double* y, Index begin, Index end) const
    {
        const Index* offsets = m_a.row_offsets().data();
        const Index* columns = m_a.columns().data();
        for (Index r = begin; r != end; ++r) {
            const double* xr = x + 3 * static_cast<std::ptrdiff_t>(r);
            const __m256d xr0 = _mm256_broadcast_sd(xr), xr1 = _mm256_broadcast_sd(xr + 1),
                          xr2 = _mm256_broadcast_sd(xr + 2);
            __m256d acc0 = _mm256_setzero_pd(), acc1 = _mm256_setzero_pd(), acc2 = _mm256_setzero_pd();
            for (Index k = offsets[r]; k < offsets[r + 1]; ++k) {
                const Rows a(m_values.data() + 9 * static_cast<std::ptrdiff_t>(k));
                const Index c = columns[k];
                const __m256d xc = load3(x + 3 * static_cast<std::ptrdiff_t>(c));
                acc0 = _mm256_fmadd_pd(a.r0, xc, acc0);
                acc1 = _mm256_fmadd_pd(a.r1, xc, acc1);
                acc2 = _mm256_fmadd_pd(a.r2, xc, acc2);
                if (c != r && c < end) {
                    double* yc = y + 3 * static_cast<std::ptrdiff_t>(c);
                    store3(yc, _mm256_fmadd_pd(a.r2, xr2, _mm256_fmadd_pd(a.r1, xr1, _mm256_fmadd_pd(a.r0, xr0, load3(yc)))));
                }
            }
            double* yr = y + 3 * static_cast<std::ptrdiff_t>(r);
            yr[0] += sum3(acc0);
            yr[1] += sum3(acc1);
            yr[2] += sum3(acc2);
        }
    }
    void gather_row(const double* x, double* y, Index row) const
    {
        const Index first = m_gather_offsets[static_cast<std::size_t>(row)],
                    last = m_gather_offsets[static_cast<std::size_t>(row) + 1];
        if (first == last)
            return;
        double* yr = y + 3 * static_cast<std::ptrdiff_t>(row);
        __m256d acc = load3(yr);
        for (Index e = first; e < last; ++e) {
            const Rows a(m_values.data() + 9 * static_cast<std::ptrdiff_t>(m_gather[static_cast<std::size_t>(e)][0]));
            const double* xs = x + 3 * static_cast<std::ptrdiff_t>(m_gather[static_cast<std::size_t>(e)][1]);
            acc = _mm256_fmadd_pd(a.r2, _mm256_broadcast_sd(xs + 2),
                                  _mm256_fmadd_pd(a.r1, _mm256_broadcast_sd(xs + 1),
                                                  _mm256_fmadd_pd(a.r0, _mm256_broadcast_sd(xs), acc)));
        }
        store3(yr, acc);
    }
#else
    void chunk_rows(const double* x, double* y, Index begin, Index end) const
    {
        const Index* offsets = m_a.row_offsets().data();
        const Index* columns = m_a.columns().data();
        for (Index r = begin; r != end; ++r) {
            const double* xr = x + 3 * static_cast<std::ptrdiff_t>(r);
            double y0 = 0.0, y1 = 0.0, y2 = 0.0;
            for (Index k = offsets[r]; k < offsets[r + 1]; ++k) {
                const Value* a = m_values.data() + 9 * static_cast<std::ptrdiff_t>(k);
                const Index c = columns[k];
                const double* xc = x + 3 * static_cast<std::ptrdiff_t>(c);
                y0 += a[0] * xc[0] + a[1] * xc[1] + a[2] * xc[2];
                y1 += a[3] * xc[0] + a[4] * xc[1] + a[5] * xc[2];
                y2 += a[6] * xc[0] + a[7] * xc[1] + a[8] * xc[2];
                if (c != r && c < end) {
                    double* yc = y + 3 * static_cast<std::ptrdiff_t>(c);
                    yc[0] += a[0] * xr[0] + a[3] * xr[1] + a[6] * xr[2];
                    yc[1] += a[1] * xr[0] + a[4] * xr[1] + a[7] * xr[2];
                    yc[2] += a[2] * xr[0] + a[5] * xr[1] + a[8] * xr[2];
                }
            }
            double* yr = y + 3 * static_cast<std::ptrdiff_t>(r);
            yr[0] += y0;
            yr[1] += y1;
            yr[2] += y2;
        }
    }
    void gather_row(const double* x, double* y, Index row) const
    {
        double* yr = y + 3 * static_cast<std::ptrdiff_t>(row);
        for (Index e = m_gather_offsets[static_cast<std::size_t>(row)];
             e < m_gather_offsets[static_cast<std::size_t>(row) + 1]; ++e) {
            const Value* a = m_values.data() + 9 * static_cast<std::ptrdiff_t>(m_gather[static_cast<std::size_t>(e)][0]);
            const double* xs = x + 3 * static_cast<std::ptrdiff_t>(m_gather[static_cast<std::size_t>(e)][1]);
            yr[0] += a[0] * xs[0] + a[3] * xs[1] + a[6] * xs[2];
            yr[1] += a[1] * xs[0] + a[4] * xs[1] + a[7] * xs[2];
            yr[2] += a[2] * xs[0] + a[5] * xs[1] + a[8] * xs[2];
        }
    }
#endif

    const BsrMatrix& m_a;
    SceneMatrix m_scene; // the chunks and their tasks, as PcgSolver runs a one-body scene
    std::vector<Value> m_values;
    std::vector<Index> m_gather_offsets;
    std::vector<std::array<Index, 2>> m_gather;
    std::vector<double> m_chunk_dots;
};

/// PcgSolver's iteration (Jacobi) around the kernel's product: q = Ap with the chunks' pᵀq, then
/// one fused pass x += αp, r −= αq, z = D⁻¹r with the chunks' r·r and r·z, then p = z + βp;
/// every sum per chunk, then in chunk order.
template <typename Value>
struct KernelPcg {
    struct Sums {
        double rr = 0.0, rz = 0.0;
    };
    VecX r, z, p, q, inverse_diagonal;
    std::vector<Sums> chunk_sums;

    /// @return the relative residual ‖r‖/‖b‖ of the recurrence after `iterations`
    double solve(KernelUpper<Value>& a, const BsrMatrix& pattern, const VecX& b, VecX& x, Index iterations, double tolerance)
    {
        const Index n = pattern.num_dofs();
        r.resize(n);
        z.resize(n);
        p.resize(n);
        q.resize(n);
        inverse_diagonal.resize(n);
        chunk_sums.resize(static_cast<std::size_t>(a.chunks().num_chunks()));
        for (Index v = 0; v < pattern.num_block_rows(); ++v) // the stored values' diagonal
            for (int i = 0; i < 3; ++i)
                inverse_diagonal[3 * v + i] =
                    1.0 / static_cast<double>(static_cast<Value>(pattern.block(pattern.diagonal(v))(i, i)));
        a.multiply_dot(x.data(), r.data());
        Sums sums = pass(a.chunks(), b.data(), 0.0, x.data());
        double rz = sums.rz;
        const double b_norm = b.norm();
        p = z;
        Index it = 0;
        double r_norm = std::sqrt(sums.rr);
        while (it < iterations && r_norm > tolerance * b_norm) {
            const double pq = a.multiply_dot(p.data(), q.data());
            const double alpha = rz / pq;
            sums = pass(a.chunks(), nullptr, alpha, x.data());
            ++it;
            r_norm = std::sqrt(sums.rr);
            xpby(z, sums.rz / rz, p);
            rz = sums.rz;
        }
        return r_norm / b_norm;
    }

    Sums pass(const RowChunks& chunks, const double* b, double alpha, double* x)
    {
        for_each_chunk(chunks, [&](Index c, Index row_begin, Index row_end) {
            const std::ptrdiff_t begin = 3 * static_cast<std::ptrdiff_t>(row_begin);
            const std::ptrdiff_t end = 3 * static_cast<std::ptrdiff_t>(row_end);
            if (b) {
                for (std::ptrdiff_t i = begin; i < end; ++i)
                    r[i] = b[i] - r[i];
            } else {
                for (std::ptrdiff_t i = begin; i < end; ++i) {
                    x[i] += alpha * p[i];
                    r[i] -= alpha * q[i];
                }
            }
            for (std::ptrdiff_t i = begin; i < end; ++i)
                z[i] = inverse_diagonal[i] * r[i];
            Sums sums;
            for (std::ptrdiff_t i = begin; i < end; ++i) {
                sums.rr += r[i] * r[i];
                sums.rz += r[i] * z[i];
            }
            chunk_sums[static_cast<std::size_t>(c)] = sums;
        });
        Sums total;
        for (const Sums& sums : chunk_sums) {
            total.rr += sums.rr;
            total.rz += sums.rz;
        }
        return total;
    }
};

void spmv(benchmark::State& state, const BsrMatrix& a)
{
    const SceneMatrix scene({&a});
    const VecX x = beam().rhs;
    VecX y(x.size());
    std::vector<double> chunk_dots(static_cast<std::size_t>(scene.chunks().num_chunks()));
    for (auto _ : state) {
        scene.multiply(x.data(), y.data(), chunk_dots.data());
        double sum = 0.0;
        for (const double d : chunk_dots)
            sum += d;
        benchmark::DoNotOptimize(sum);
    }
    state.counters["blocks"] = a.num_blocks();
}

void SpmvDouble(benchmark::State& state) { spmv(state, beam().body->system_matrix()); }
void SpmvSingle(benchmark::State& state) { spmv(state, beam().single->system_matrix()); }

template <typename Value>
void spmv_kernel(benchmark::State& state)
{
    KernelUpper<Value> f(beam().body->system_matrix());
    const VecX x = beam().rhs;
    VecX y(x.size());
    for (auto _ : state)
        benchmark::DoNotOptimize(f.multiply_dot(x.data(), y.data()));
}

void SpmvKernelFloat(benchmark::State& state) { spmv_kernel<float>(state); }
void SpmvKernelDouble(benchmark::State& state) { spmv_kernel<double>(state); }

void pcg10(benchmark::State& state, const BsrMatrix& a)
{
    const SceneMatrix scene({&a});
    PcgSolver pcg;
    PcgSettings settings;
    settings.max_iterations = 10;
    settings.tolerance = 0.0;
    settings.preconditioner = PcgPreconditioner::JACOBI;
    VecX x(a.num_dofs());
    double residual = 0.0;
    for (auto _ : state) {
        x.setZero();
        residual = pcg.solve(scene, beam().rhs, x, settings).residual;
    }
    state.counters["residual"] = residual;
}

void Pcg10Double(benchmark::State& state) { pcg10(state, beam().body->system_matrix()); }
void Pcg10Single(benchmark::State& state) { pcg10(state, beam().single->system_matrix()); }

template <typename Value>
void pcg10_kernel(benchmark::State& state)
{
    const BsrMatrix& a = beam().body->system_matrix();
    KernelUpper<Value> f(a);
    KernelPcg<Value> pcg;
    VecX x(a.num_dofs());
    double residual = 0.0;
    for (auto _ : state) {
        x.setZero();
        residual = pcg.solve(f, a, beam().rhs, x, 10, 0.0);
    }
    state.counters["residual"] = residual;
}

void Pcg10KernelFloat(benchmark::State& state) { pcg10_kernel<float>(state); }
void Pcg10KernelDouble(benchmark::State& state) { pcg10_kernel<double>(state); }

/// Whole implicit Euler steps of the beam (no contact), 10 Jacobi-PCG iterations each.
void step(benchmark::State& state, MatrixPrecision precision)
{
    const TetMesh mesh = beam_mesh();
    std::vector<Body> bodies;
    bodies.emplace_back(mesh, beam_spec(), default_num_parts(mesh.num_tets(), 4), precision);
    SceneSystem system(bodies);
    PcgSettings settings;
    settings.max_iterations = 10;
    settings.tolerance = 0.0;
    settings.preconditioner = PcgPreconditioner::JACOBI;
    for (auto _ : state)
        system.step(DT, GRAVITY, {}, settings);
}

void StepDouble(benchmark::State& state) { step(state, MatrixPrecision::DOUBLE); }
void StepSingle(benchmark::State& state) { step(state, MatrixPrecision::SINGLE); }

/// Milliseconds of real time, and with repetitions the minimum too: on a machine shared with
/// other work, the least disturbed repetition is the best estimate of each kernel's own speed.
void configure(benchmark::internal::Benchmark* b)
{
    b->Unit(benchmark::kMillisecond)->UseRealTime()->ComputeStatistics("min", [](const std::vector<double>& v) {
        return *std::min_element(v.begin(), v.end());
    });
}

BENCHMARK(SpmvDouble)->Apply(configure);
BENCHMARK(SpmvSingle)->Apply(configure);
BENCHMARK(SpmvKernelFloat)->Apply(configure);
BENCHMARK(SpmvKernelDouble)->Apply(configure);
BENCHMARK(Pcg10Double)->Apply(configure);
BENCHMARK(Pcg10Single)->Apply(configure);
BENCHMARK(Pcg10KernelFloat)->Apply(configure);
BENCHMARK(Pcg10KernelDouble)->Apply(configure);
BENCHMARK(StepDouble)->Apply(configure);
BENCHMARK(StepSingle)->Apply(configure);

/// The console output, and each benchmark's real time (its minimum when repeated).
class RecordingReporter : public benchmark::ConsoleReporter {
public:
    void ReportRuns(const std::vector<Run>& runs) override
    {
        for (const Run& run : runs)
            if (run.run_type == Run::RT_Aggregate ? run.aggregate_name == "min" : !m_times.count(name(run)))
                m_times[name(run)] = run.GetAdjustedRealTime();
        ConsoleReporter::ReportRuns(runs);
    }
    /// Real time of a benchmark, or 0 if it did not run.
    double time(const std::string& benchmark) const
    {
        const auto it = m_times.find(benchmark);
        return it == m_times.end() ? 0.0 : it->second;
    }

private:
    static std::string name(const Run& run) { return run.run_name.function_name; }
    std::map<std::string, double> m_times;
};

void print_comparison(const RecordingReporter& r)
{
    std::printf("\nsingle-precision values (ratios of real times; > 1: single is faster):\n");
    for (const std::string what : {"Spmv", "Pcg10", "Step"}) {
        const double single = r.time(what + "Single"), dbl = r.time(what + "Double");
        if (single <= 0.0)
            continue;
        std::printf("  %-6s single %8.3f ms: %.2f × the double path (%.3f ms)", what.c_str(), single, dbl / single, dbl);
        for (const std::string kind : {"Float", "Double"}) {
            const double kernel = r.time(what + "Kernel" + kind);
            if (kernel > 0.0)
                std::printf(", %.2f × the speed-of-light kernel's %s path (%.3f ms)", kernel / single,
                            kind == "Float" ? "float" : "double", kernel);
        }
        std::printf("\n");
    }
}

/// ‖a − b‖/‖b‖ over all values of two matrices of the same pattern.
double relative_difference(const BsrMatrix& a, const BsrMatrix& b)
{
    double difference = 0.0, size = 0.0;
    for (Index k = 0; k < a.num_blocks(); ++k) {
        difference += (a.block(k) - b.block(k)).squaredNorm();
        size += b.block(k).squaredNorm();
    }
    return std::sqrt(difference / size);
}

void accuracy()
{
    const BsrMatrix& a = beam().body->system_matrix();
    const BsrMatrix& single = beam().single->system_matrix();
    const BsrMatrix rounded = a.with_precision(MatrixPrecision::SINGLE);
    const VecX& b = beam().rhs;
    std::printf("assembled in single precision against the double matrix: %.3e; the double matrix rounded "
                "to float: %.3e; the two float matrices: %.3e (relative, all values)\n",
                relative_difference(single, a), relative_difference(rounded, a), relative_difference(single, rounded));
    VecX ax(b.size()), af(b.size());
    a.multiply(b, ax);
    single.multiply(b, af);
    std::printf("product with the single matrix against the double one: ‖A_s b − A b‖/‖A b‖ = %.3e\n",
                (af - ax).norm() / ax.norm());
    for (const Index iterations : {10, 100, 400, 1000, 3000}) {
        PcgSettings settings;
        settings.max_iterations = iterations;
        settings.tolerance = 1e-14;
        settings.preconditioner = PcgPreconditioner::JACOBI;
        VecX xd = VecX::Zero(b.size()), xs = VecX::Zero(b.size());
        PcgSolver().solve(a, b, xd, settings);
        const double own = PcgSolver().solve(single, b, xs, settings).residual;
        a.multiply(xd, ax);
        const double true_double = (b - ax).norm() / b.norm();
        a.multiply(xs, ax);
        const double true_single = (b - ax).norm() / b.norm();
        std::printf("%5d iterations: ‖b − A x‖/‖b‖ with the double A: double values %.3e, single values %.3e "
                    "(against their own matrix %.3e); ‖x_single − x_double‖/‖x_double‖ %.3e\n",
                    static_cast<int>(iterations), true_double, true_single, own, (xs - xd).norm() / xd.norm());
    }
}

} // namespace

int main(int argc, char** argv)
{
    int threads = 2;
    bool check_accuracy = false;
    std::vector<char*> rest{argv[0]};
    // A whole number in [lo, hi], else the usage error: exit 2.
    const auto whole_number = [&](int i, int lo, int hi) {
        char* end = nullptr;
        const long value = i < argc ? std::strtol(argv[i], &end, 10) : 0;
        if (i >= argc || end == argv[i] || *end != '\0' || value < lo || value > hi) {
            std::fprintf(stderr, "bench_precision: %s expects a whole number from %d to %d, got '%s'\n", argv[i - 1],
                         lo, hi, i < argc ? argv[i] : "");
            std::exit(2);
        }
        return static_cast<int>(value);
    };
    for (int i = 1; i < argc; ++i) {
        if (std::strcmp(argv[i], "--threads") == 0) {
            threads = whole_number(i + 1, 1, 1024);
            ++i;
        } else if (std::strcmp(argv[i], "--scale") == 0) {
            g_scale = whole_number(i + 1, 1, 4);
            ++i;
        } else if (std::strcmp(argv[i], "--accuracy") == 0) {
            check_accuracy = true;
        } else {
            rest.push_back(argv[i]);
        }
    }
    // Google Benchmark takes its own options from the rest; whatever is left is a usage error,
    // found before the beam is built.
    int count = static_cast<int>(rest.size());
    benchmark::Initialize(&count, rest.data());
    if (benchmark::ReportUnrecognizedArguments(count, rest.data()))
        return 2;
    tbb::global_control control(tbb::global_control::max_allowed_parallelism, static_cast<std::size_t>(threads));
    const BsrMatrix& matrix = beam().body->system_matrix();
    std::printf("bench_precision: beam of %dx%dx%d nodes (%s), %d blocks (upper, %.1f MB of double values), "
                "%d threads\n",
                15 * g_scale + 1, 15 * g_scale + 1, 75 * g_scale + 1,
                g_scale == 1 ? "SOFA's" : ("SOFA's with " + std::to_string(g_scale) + "× the elements along each edge").c_str(),
                static_cast<int>(matrix.num_blocks()), static_cast<double>(matrix.num_blocks()) * 9.0 * sizeof(double) / 1e6,
                threads);
    if (check_accuracy) {
        accuracy();
        return 0;
    }
    RecordingReporter reporter;
    benchmark::RunSpecifiedBenchmarks(&reporter);
    benchmark::Shutdown();
    print_comparison(reporter);
    return 0;
}
