#pragma once
/// @file aabb.hpp
/// @brief Axis-aligned bounding boxes (paper Eq. 2) and their overlap test (Eq. 3).

#include <corocontact/core/types.hpp>

#include <limits>

namespace coro {

/// An axis-aligned box; default-constructed it is empty (min = +∞, max = −∞).
struct Aabb {
    Vec3 min = Vec3::Constant(std::numeric_limits<double>::infinity());
    Vec3 max = Vec3::Constant(-std::numeric_limits<double>::infinity());

    bool empty() const { return (min.array() > max.array()).any(); }
    void extend(const Vec3& p)
    {
        min = min.cwiseMin(p);
        max = max.cwiseMax(p);
    }
    void extend(const Aabb& b)
    {
        min = min.cwiseMin(b.min);
        max = max.cwiseMax(b.max);
    }
    /// Eq. 3: the three interval conditions (closed intervals: touching boxes overlap).
    bool overlaps(const Aabb& b) const
    {
        return (min.array() <= b.max.array()).all() && (b.min.array() <= max.array()).all();
    }
    bool contains(const Vec3& p) const
    {
        return (min.array() <= p.array()).all() && (p.array() <= max.array()).all();
    }
    /// The intersection box I = A ∩ B (empty if they do not overlap).
    Aabb intersection(const Aabb& b) const { return {min.cwiseMax(b.min), max.cwiseMin(b.max)}; }
    /// Grows the box by `margin` on every side.
    Aabb inflated(double margin) const { return {min.array() - margin, max.array() + margin}; }
};

/// Eq. 2: the box of all rows of `vertices` (#V×3).
Aabb bounding_box(CRef<Positions> vertices);

} // namespace coro
