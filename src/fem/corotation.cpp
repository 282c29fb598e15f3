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

namespace {
// X⁻ᵀ = cof(X) / det(X), or a zero matrix if X is singular.
inline Mat3 inverse_transpose(const Mat3& x, double& det)
{
    Mat3 cof;
    cof(0, 0) = x(1, 1) * x(2, 2) - x(1, 2) * x(2, 1);
    cof(0, 1) = x(1, 2) * x(2, 0) - x(1, 0) * x(2, 2);
    cof(0, 2) = x(1, 0) * x(2, 1) - x(1, 1) * x(2, 0);
    cof(1, 0) = x(0, 2) * x(2, 1) - x(0, 1) * x(2, 2);
    cof(1, 1) = x(0, 0) * x(2, 2) - x(0, 2) * x(2, 0);
    cof(1, 2) = x(0, 1) * x(2, 0) - x(0, 0) * x(2, 1);
    cof(2, 0) = x(0, 1) * x(1, 2) - x(0, 2) * x(1, 1);
    cof(2, 1) = x(0, 2) * x(1, 0) - x(0, 0) * x(1, 2);
    cof(2, 2) = x(0, 0) * x(1, 1) - x(0, 1) * x(1, 0);
    det = x(0, 0) * cof(0, 0) + x(0, 1) * cof(0, 1) + x(0, 2) * cof(0, 2);
    return cof * (1.0 / det); // one division instead of nine
}
} // namespace

Mat3 polar_rotation(const Mat3& f, const Mat3& guess, double tolerance)
{
    CORO_CHECK(f.allFinite(), NumericalError, "deformation gradient is not finite: " << f);
    // Polar decomposition of M = guessᵀ F, which is close to the symmetric stretch when the
    // guess is last step's rotation, by Newton's iteration X ← (X + X⁻ᵀ)/2 (Higham 1986).
    // It converges quadratically: the error left after an update of size c is about c²/2,
    // so the loop stops as soon as that is below the tolerance (typically after 2–3
    // iterations) instead of iterating once more to see a tiny update. Inverted or nearly
    // singular elements go to the sign-fixed SVD.
    Mat3 x = guess.transpose() * f;
    const double scale = x.norm();
    double det = 0.0;
    Mat3 inverse = inverse_transpose(x, det);
    if (!(det > 1e-6 * scale * scale * scale))
        return polar_rotation_svd(f);
    for (int iteration = 0; iteration < 30; ++iteration) {
        const Mat3 next = 0.5 * (x + inverse);
        const double change = (next - x).squaredNorm(); // relative to ‖X‖ ≈ √3
        x = next;
        if (change * change < tolerance * tolerance)
            return guess * x;
        inverse = inverse_transpose(x, det);
        if (!(det > 0.0))
            break;
    }
    return polar_rotation_svd(f);
}

} // namespace coro
