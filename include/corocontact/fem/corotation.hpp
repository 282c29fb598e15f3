#pragma once
/// @file corotation.hpp
/// @brief The element rotation R_e of the co-rotational formulation (paper Eq. 1).
///
/// R_e is the rotation of the polar decomposition F_e = R_e S_e, taken as the proper rotation
/// (det R = +1) that maximises tr(Rᵀ F): for det F > 0 the polar rotation itself, for an
/// inverted element the polar factor of the sign-fixed SVD.

#include <corocontact/core/types.hpp>

namespace coro {

/// Deformation gradient F = D_s D_m^{-1} of a tet from its current nodes and rest D_m^{-1}.
Mat3 deformation_gradient(const Vec3& x0, const Vec3& x1, const Vec3& x2, const Vec3& x3,
                          const Mat3& dm_inv);

/// Reference rotation from the SVD F = U Σ Vᵀ: R = U diag(1, 1, det(U Vᵀ)) Vᵀ.
/// Slow (a 3×3 JacobiSVD); used by tests and as a fallback.
/// @throws NumericalError if F has a non-finite entry
Mat3 polar_rotation_svd(const Mat3& f);

/// The same rotation found iteratively from a nearby rotation: R = guess · polar(guessᵀ F),
/// the inner polar factor by Newton's iteration X ← (X + X⁻ᵀ)/2, which converges
/// quadratically (two or three iterations when `guess` is last step's rotation). Stops when
/// the error left, about the square of the last update's Frobenius norm, is below `tolerance`;
/// falls back to the SVD for inverted or nearly singular guessᵀF, or after 30 iterations.
/// @throws NumericalError if F has a non-finite entry
Mat3 polar_rotation(const Mat3& f, const Mat3& guess, double tolerance = 1e-15);

} // namespace coro
