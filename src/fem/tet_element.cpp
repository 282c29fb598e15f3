#include <corocontact/fem/tet_element.hpp>

#include <corocontact/core/error.hpp>

#include <cmath>

namespace coro {

TetRest make_tet_rest(const Vec3& x0, const Vec3& x1, const Vec3& x2, const Vec3& x3)
{
    Mat3 dm;
    dm << x1 - x0, x2 - x0, x3 - x0;
    const double det = dm.determinant();
    CORO_CHECK(std::isfinite(det) && det > 0.0, NumericalError,
               "tet rest shape has det(D_m) = " << det << ", expected > 0");
    return {dm.inverse(), det / 6.0};
}

Mat34 shape_gradients(const TetRest& rest)
{
    Mat34 g;
    g.rightCols<3>() = rest.dm_inv.transpose();
    g.col(0) = -g.rightCols<3>().rowwise().sum();
    return g;
}

Mat3 stiffness_block(const Vec3& g_i, const Vec3& g_j, double lambda, double mu, double volume)
{
    return volume * (lambda * g_i * g_j.transpose() + mu * g_j * g_i.transpose() +
                     mu * g_i.dot(g_j) * Mat3::Identity());
}

Mat12 element_stiffness(const TetRest& rest, double lambda, double mu)
{
    const Mat34 g = shape_gradients(rest);
    Mat12 k;
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j)
            k.block<3, 3>(3 * i, 3 * j) = stiffness_block(g.col(i), g.col(j), lambda, mu, rest.volume);
    return k;
}

double von_mises(const Mat3& s)
{
    const double a = s(0, 0) - s(1, 1), b = s(1, 1) - s(2, 2), c = s(2, 2) - s(0, 0);
    const double shear = s(0, 1) * s(0, 1) + s(1, 2) * s(1, 2) + s(2, 0) * s(2, 0);
    return std::sqrt(0.5 * (a * a + b * b + c * c) + 3.0 * shear);
}

} // namespace coro
