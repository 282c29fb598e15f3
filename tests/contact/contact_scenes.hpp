#pragma once
/// @file contact_scenes.hpp
/// @brief Surfaces and independent references for the contact tests.

#include <corocontact/contact/contact_surface.hpp>
#include <corocontact/core/surface_mesh.hpp>
#include <corocontact/core/tet_mesh.hpp>

#include <random>
#include <string>
#include <vector>

namespace coro::test {

/// The boundary of a tet mesh (at its rest positions) as a contact surface.
ContactSurface surface_of(const TetMesh& mesh, const std::string& name);

/// A contact surface from a triangle surface (all vertices used).
ContactSurface surface_of(const SurfaceMesh& mesh, const std::string& name);

/// A closed, outward torus around the z axis through `center`: tube radius r around the circle of
/// radius R, nu × nv quads split into triangles.
SurfaceMesh make_torus(const Vec3& center, double R, double r, int nu, int nv);

/// A bar along x deformed analytically: twist by `twist` radians per unit length about the x axis
/// through (·, 0, 0), then bend in the x–y plane around a circle of radius `bend_radius`.
Positions twist_and_bend(CRef<Positions> positions, double twist, double bend_radius);

/// Ray parity along a random direction (redrawn until no crossing is near an edge, a vertex or
/// the start): the exact point-in-polyhedron answer for a closed surface, independent of the
/// axis-ray code. Möller–Trumbore crossings.
bool ray_parity_inside(CRef<Positions> vertices, const Tris& faces, const Vec3& point, std::mt19937& rng);

/// Random triangles in [0, 1]³ of mixed sizes (a "soup", not a closed surface).
SurfaceMesh random_triangles(int count, std::mt19937& rng);

/// The vertices of `a` in the order detection sends them (AabbTree::vertices_in_box over the
/// overlap of a's and b's boxes).
std::vector<Vec3> candidate_points(const ContactSurface& a, const ContactSurface& b);

/// The surface of a tet-mesh sphere whose radius wobbles by a relative `wobble` (smooth, so the
/// surface stays closed and star-shaped for small wobbles).
ContactSurface deformed_ball(const Vec3& center, double radius, Index resolution, double wobble, const std::string& name);

/// Uniform random point in a box.
Vec3 random_point(const Vec3& min, const Vec3& max, std::mt19937& rng);

} // namespace coro::test
