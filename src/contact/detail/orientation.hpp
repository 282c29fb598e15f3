#pragma once
/// @file orientation.hpp
/// @brief Rounding bounds of orientation signs and a face normal with the permanent that bounds
/// its rounding: what the exact narrow-phase tests (axis_ray.cpp, segment_triangle.hpp) share;
/// and the exact signs (GMP rationals) for the rare case that a sign lies within its bound.

#include <cmath>
#include <limits>

namespace coro::detail {

constexpr double EPS = std::numeric_limits<double>::epsilon();
// Rounding bounds, relative to the sum of the absolute products (Shewchuk's static filters
// ccwerrboundA ≈ 3ε/2 and o3derrboundA ≈ 7ε/2, ε = 2^-53, taken with a safety factor).
constexpr double ORIENT2D_BOUND = 3.0 * EPS;
constexpr double ORIENT3D_BOUND = 8.0 * EPS;
/// Absolute allowance for underflow. The bounds above hold while no product underflows (falls
/// below 2⁻¹⁰²², from tiny coordinates or differences). One that does errs by up to 2⁻¹⁰⁷⁵ more,
/// absolutely, and additions lose nothing to underflow: a sign sums a few such errors, multiplied
/// at most once more by a difference d, in all below 2⁻¹⁰⁷³·(1 + Σ_j |d_j|). So each bound adds
/// UNDERFLOW_BOUND, times 1 + Σ_j |d_j| where its products are multiplied again: a margin of
/// 2¹³; only values below ~2⁻¹⁰⁰⁰ feel it (the exact signs decide them).
constexpr double UNDERFLOW_BOUND = 0x1p-1060;

/// n = (B − A) × (C − A) from rounded differences, and per component the sum of the absolute
/// values of its two products: n·d (d a rounded difference) has the exact sign of the
/// orientation when |n·d| > ORIENT3D_BOUND·Σ_j permanent_j·|d_j| + UNDERFLOW_BOUND·(1 + Σ_j |d_j|).
struct FaceNormal {
    double n[3];
    double permanent[3];
};

inline FaceNormal face_normal(const double* A, const double* B, const double* C)
{
    const double d1[3] = {B[0] - A[0], B[1] - A[1], B[2] - A[2]};
    const double d2[3] = {C[0] - A[0], C[1] - A[1], C[2] - A[2]};
    const double p0 = d1[1] * d2[2], p1 = d1[2] * d2[1];
    const double p2 = d1[2] * d2[0], p3 = d1[0] * d2[2];
    const double p4 = d1[0] * d2[1], p5 = d1[1] * d2[0];
    return {{p0 - p1, p2 - p3, p4 - p5},
            {std::abs(p0) + std::abs(p1), std::abs(p2) + std::abs(p3), std::abs(p4) + std::abs(p5)}};
}

/// The exact sign (−1, 0, +1) of ((B − A) × (C − A))·(A − P), the orientation of point P
/// against the plane of triangle (A, B, C), each a point of 3 doubles; positive when P lies on the
/// side that (B − A) × (C − A) points away from. Computed in rational arithmetic: for the signs
/// that the rounding bounds above leave open.
int exact_plane_side(const double* A, const double* B, const double* C, const double* P);

/// The exact sign of (bu − pu)(cv − pv) − (bv − pv)(cu − pu): the orientation of the 2D points
/// p, b, c (doubles), in rational arithmetic.
int exact_orient2d(double pu, double pv, double bu, double bv, double cu, double cv);

} // namespace coro::detail
