#pragma once
/// @file vector_ops.hpp
/// @brief Parallel vector kernels whose results do not depend on the thread count.

#include <corocontact/core/types.hpp>

namespace coro {

/// a·b with a fixed reduction tree (tbb::parallel_deterministic_reduce, fixed grain).
/// @throws NumericalError if the result is not finite
double dot(CRef<VecX> a, CRef<VecX> b);

/// ‖a‖₂ (deterministic, as dot()).
double norm(CRef<VecX> a);

/// y += alpha·x, parallel.
void axpy(double alpha, CRef<VecX> x, Eigen::Ref<VecX> y);

/// y = x + beta·y, parallel (the PCG direction update).
void xpby(CRef<VecX> x, double beta, Eigen::Ref<VecX> y);

} // namespace coro
