#include <corocontact/fem/corotation.hpp>

#include <corocontact/core/error.hpp>

#include <Eigen/Geometry>
#include <Eigen/SVD>

#include <cmath>

namespace coro {

Mat3 deformation_gradient(const Vec3& x0, const Vec3& x1, const Vec3& x2, const Vec3& x3,
                          const Mat3& dm_inv)
{
    Mat3 ds;
    ds << x1 - x0, x2 - x0, x3 - x0;
    return ds * dm_inv;
}

Mat3 polar_rotation_svd(const Mat3& f)
{
    CORO_CHECK(f.allFinite(), NumericalError, "deformation gradient is not finite: " << f);
    const Eigen::JacobiSVD<Mat3> svd(f, Eigen::ComputeFullU | Eigen::ComputeFullV);
    Mat3 u = svd.matrixU();
    const Mat3& v = svd.matrixV();
    if ((u * v.transpose()).determinant() < 0.0)
        u.col(2) = -u.col(2); // flip along the smallest singular value
    return u * v.transpose();
}

Mat3 polar_rotation(const Mat3& f, const Mat3& guess, double tolerance)
{
    CORO_CHECK(f.allFinite(), NumericalError, "deformation gradient is not finite: " << f);
    // Polar decomposition of M = guessᵀ F, which is close to the symmetric stretch when the
    // guess is last step's rotation, by Newton's iteration X ← (X + X⁻ᵀ)/2 (Higham 1986):
    // quadratic convergence, typically 2–4 iterations. Inverted or nearly singular elements
    // go to the sign-fixed SVD.
    Mat3 x = guess.transpose() * f;
    const double scale = x.norm();
    if (!(x.determinant() > 1e-6 * scale * scale * scale))
        return polar_rotation_svd(f);
    for (int iteration = 0; iteration < 30; ++iteration) {
        const Mat3 next = 0.5 * (x + x.inverse().transpose());
        const double change = (next - x).norm();
        x = next;
        if (change < tolerance)
            return guess * x;
    }
    return polar_rotation_svd(f);
}

} // namespace coro
