#pragma once
/// @file primitives.hpp
/// @brief Meshes generated from a few numbers: boxes and spheres.

#include <corocontact/core/tet_mesh.hpp>
#include <corocontact/core/types.hpp>

#include <array>

namespace coro {

/// A structured box mesh: nx×ny×nz hexahedral cells, each split into 6 tets around the
/// cell's main diagonal (Kuhn subdivision), so neighbouring cells share faces exactly.
/// Nodes are numbered x fastest, then y, then z; every tet is positively oriented.
/// @param[in] min,max  opposite corners, min < max componentwise
/// @param[in] cells    cells per axis, each ≥ 1
/// @throws InputError for an empty box or a cell count < 1
TetMesh make_box(const Vec3& min, const Vec3& max, const std::array<Index, 3>& cells);

/// A ball meshed from a cube of resolution³ cells whose shells are mapped onto spheres
/// (a smooth cube-to-sphere map), 6 tets per cell, positively oriented.
/// @param[in] center     centre of the ball
/// @param[in] radius     radius, > 0
/// @param[in] resolution cells across the diameter, ≥ 2
/// @throws InputError for radius ≤ 0 or resolution < 2
TetMesh make_sphere(const Vec3& center, double radius, Index resolution);

/// Rigid transform of a body as the case file gives it: x' = R(axis, degrees) · (scale·x) + translate.
struct BodyTransform {
    Vec3 translate = Vec3::Zero();
    Vec3 rotate_axis = Vec3::UnitZ();
    double rotate_degrees = 0.0;
    double scale = 1.0;

    /// Applies the transform to every row of `positions` (#V×3) in place.
    void apply(Eigen::Ref<Positions> positions) const;
};

} // namespace coro
