#include "orientation.hpp"

#include <gmpxx.h>

namespace coro::detail {

// A double converts to mpq_class exactly (it is a dyadic rational), so these are the exact
// values of the expressions, whatever the magnitudes.

int exact_plane_side(const double* A, const double* B, const double* C, const double* P)
{
    mpq_class e1[3], e2[3], d[3];
    for (int j = 0; j < 3; ++j) {
        const mpq_class a(A[j]);
        e1[j] = mpq_class(B[j]) - a;
        e2[j] = mpq_class(C[j]) - a;
        d[j] = a - mpq_class(P[j]);
    }
    const mpq_class value = (e1[1] * e2[2] - e1[2] * e2[1]) * d[0] + (e1[2] * e2[0] - e1[0] * e2[2]) * d[1] +
                            (e1[0] * e2[1] - e1[1] * e2[0]) * d[2];
    return sgn(value);
}

int exact_orient2d(double pu, double pv, double bu, double bv, double cu, double cv)
{
    const mpq_class u(pu), v(pv);
    const mpq_class value = (mpq_class(bu) - u) * (mpq_class(cv) - v) - (mpq_class(bv) - v) * (mpq_class(cu) - u);
    return sgn(value);
}

} // namespace coro::detail
