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
    Eigen::Quaterniond q(guess);
    q.normalize();
    for (int iteration = 0; iteration < 30; ++iteration) {
        const Mat3 r = q.toRotationMatrix();
        const Vec3 torque = r.col(0).cross(f.col(0)) + r.col(1).cross(f.col(1)) + r.col(2).cross(f.col(2));
        const double alignment = r.col(0).dot(f.col(0)) + r.col(1).dot(f.col(1)) + r.col(2).dot(f.col(2));
        if (!(alignment > 0.0))
            break; // far from the maximum of tr(RᵀF): let the SVD decide
        const Vec3 omega = torque / alignment;
        const double angle = omega.norm();
        if (angle < tolerance)
            return r;
        q = Eigen::Quaterniond(Eigen::AngleAxisd(angle, omega / angle)) * q;
        q.normalize();
    }
    return polar_rotation_svd(f);
}

} // namespace coro
