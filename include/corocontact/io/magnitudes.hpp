#pragma once
/// @file magnitudes.hpp
/// @brief The check that a body's values, multiplied as the solver multiplies them, stay inside
/// the range where double arithmetic neither overflows nor loses them: at load time
/// (io/scene_loader) and whenever a script changes a value between steps (python/).

#include <corocontact/core/tet_mesh.hpp>
#include <corocontact/sim/case_spec.hpp>

namespace coro {

/// Every scale the solver forms from the case's values and the body's mesh must lie in
/// [1e-140, 1e140]: matrix entries (element stiffness (λ + 2μ)·h, node mass ρV/4, their dt² and
/// dt multiples and their ratio), right-hand-side terms (internal, gravity, inertia, load,
/// damping, contact forces). PCG squares such values in its dot products and sums millions of
/// them, so beyond that window they overflow to inf or vanish (1e-300² is 0 in double). The
/// products are formed in log space, so the check itself cannot overflow. Also the node
/// coordinates may not exceed the shortest edge by more than 1e10: beyond, positions keep
/// fewer than six significant digits of an edge and strains are rounding noise.
/// @param[in] mesh  the body's mesh after its transform, validated (validate_and_orient)
/// @throws InputError naming the body's case line, the scale, its value and the keys it comes
///         from
void check_magnitudes(const CaseSpec& spec, const BodySpec& body, const TetMesh& mesh);

/// The part of check_magnitudes that contact detection alone needs, for surfaces given without
/// a case: coordinates of magnitude at most 1e70 and edges of non-zero length at least 1e-70 (its
/// nearest-point test and normals multiply four lengths).
/// @param[in] vertices  #V×3 [m]; faces: #F×3 vertex indices, in range
/// @throws InputError naming `source`, the vertex or face and the value
void check_contact_lengths(CRef<Positions> vertices, const Tris& faces, const std::string& source);

} // namespace coro
