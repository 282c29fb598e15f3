#include <corocontact/solver/vector_ops.hpp>

#include <corocontact/core/error.hpp>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <cmath>
#include <functional>

namespace coro {

namespace {
constexpr Eigen::Index DOT_GRAIN = 4096;
constexpr Eigen::Index AXPY_GRAIN = 8192;
} // namespace

double dot(CRef<VecX> a, CRef<VecX> b)
{
    const double sum = tbb::parallel_deterministic_reduce(
        tbb::blocked_range<Eigen::Index>(0, a.size(), DOT_GRAIN), 0.0,
        [&](const tbb::blocked_range<Eigen::Index>& r, double acc) {
            return acc + a.segment(r.begin(), static_cast<Eigen::Index>(r.size()))
                             .dot(b.segment(r.begin(), static_cast<Eigen::Index>(r.size())));
        },
        std::plus<double>());
    CORO_CHECK(std::isfinite(sum), NumericalError, "dot product is " << sum);
    return sum;
}

double norm(CRef<VecX> a) { return std::sqrt(dot(a, a)); }

void axpy(double alpha, CRef<VecX> x, Eigen::Ref<VecX> y)
{
    tbb::parallel_for(tbb::blocked_range<Eigen::Index>(0, x.size(), AXPY_GRAIN),
                      [&](const tbb::blocked_range<Eigen::Index>& r) {
                          const auto n = static_cast<Eigen::Index>(r.size());
                          y.segment(r.begin(), n) += alpha * x.segment(r.begin(), n);
                      });
}

void xpby(CRef<VecX> x, double beta, Eigen::Ref<VecX> y)
{
    tbb::parallel_for(tbb::blocked_range<Eigen::Index>(0, x.size(), AXPY_GRAIN),
                      [&](const tbb::blocked_range<Eigen::Index>& r) {
                          const auto n = static_cast<Eigen::Index>(r.size());
                          y.segment(r.begin(), n) = x.segment(r.begin(), n) + beta * y.segment(r.begin(), n);
                      });
}

} // namespace coro
