#pragma once
/// @file tet_element.hpp
/// @brief The linear tetrahedron: rest data, shape gradients and stiffness blocks
/// (DESIGN.md, Formulation).

#include <corocontact/core/types.hpp>

namespace coro {

/// 3×4 matrix whose column i is a per-node vector of one tet (gradients g_i, forces f_i, ...).
using Mat34 = Eigen::Matrix<double, 3, 4>;

/// Rest-state data of one tet, computed once at load time.
struct TetRest {
    Mat3 dm_inv;        ///< D_m^{-1}; its rows are the shape gradients g_1, g_2, g_3 [1/m]
    double volume = 0;  ///< V = det(D_m)/6 [m³], > 0
};

/// Rest data of the tet X_0..X_3.
/// @throws NumericalError if det(D_m) ≤ 0 or is not finite (the mesh was not oriented)
TetRest make_tet_rest(const Vec3& x0, const Vec3& x1, const Vec3& x2, const Vec3& x3);

/// Shape gradients g_0..g_3 as the columns of a 3×4 matrix, g_0 = −(g_1+g_2+g_3) [1/m].
Mat34 shape_gradients(const TetRest& rest);

/// Stiffness block K_ij = V (λ g_i g_jᵀ + μ g_j g_iᵀ + μ (g_i·g_j) I) [N/m].
/// With rotated gradients R g_i, R g_j it is the rotated block R K_ij Rᵀ.
Mat3 stiffness_block(const Vec3& g_i, const Vec3& g_j, double lambda, double mu, double volume);

/// The full 12×12 element stiffness (node-major DOFs): tests and reference paths only.
Mat12 element_stiffness(const TetRest& rest, double lambda, double mu);

/// Isotropic linear stress σ = λ tr(ε) I + 2μ ε of a symmetric strain ε [Pa].
inline Mat3 linear_stress(const Mat3& strain, double lambda, double mu)
{
    return lambda * strain.trace() * Mat3::Identity() + 2.0 * mu * strain;
}

/// Von Mises equivalent stress of a symmetric stress tensor [Pa].
double von_mises(const Mat3& stress);

} // namespace coro
