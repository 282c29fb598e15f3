#pragma once
/// @file winding_number.hpp
/// @brief Generalized winding number of a closed (or open) triangle surface at a point
/// (Jacobson et al. 2013): the sum of the signed solid angles of the faces over 4π.

#include <corocontact/core/types.hpp>

namespace coro {

/// w(p) = Σ_f Ω_f(p) / 4π (Van Oosterom–Strackee solid angle). For a closed, outward oriented
/// surface w = 1 inside, 0 outside; for open surfaces it varies smoothly, and w > 0.5 is the
/// inside test.
double winding_number(CRef<Positions> vertices, const Tris& faces, const Vec3& point);

} // namespace coro
