#pragma once
// Private to io/: an embedded contact surface must lie on or in its body's tets. Each vertex
// moves with the tet it is bound to, by barycentric weights that extrapolate for a vertex
// outside the tets; far outside, the surface no longer follows the body.

#include <corocontact/core/surface_mesh.hpp>
#include <corocontact/core/tet_mesh.hpp>
#include <corocontact/sim/body.hpp>

#include <string>
#include <vector>

namespace coro::detail {

/// A vertex outside by more than this share of its tet's longest edge is warned about: a fine
/// surface over coarse tets lies a little outside them, where the tets' faces cut its curve
/// (up to 15 % for the coarsest ball, resolution 2, under an icosphere of the same radius).
constexpr double EMBEDDED_GAP_WARNING = 0.25;

/// The cheap check before the embedding (which searches every tet for a vertex outside them
/// all): a vertex farther outside the tets' bounding box than their longest edge is farther
/// than that from every tet.
/// @param[in] mesh     the body's tets, rest positions after its transform
/// @param[in] surface  the surface, vertices after the same transform
/// @param[in] who      "case.toml:5: body 'b': surface fine.obj", starts the message
/// @throws InputError naming the vertex and how far outside it lies
void reject_surface_far_outside(const TetMesh& mesh, const SurfaceMesh& surface, const std::string& who);

/// After the embedding: a vertex farther from the tet it is bound to than that tet's longest
/// edge is refused; one farther than EMBEDDED_GAP_WARNING of it is warned about, with the
/// distance and how many vertices lie outside.
/// @param[out] warnings  appended to
/// @throws InputError naming the vertex, its distance and the share of its tet's edge
void check_embedding(const Body& body, const std::string& who, std::vector<std::string>& warnings);

} // namespace coro::detail
