#pragma once
// Private to io/: the load-time check that a body's values, multiplied as the solver multiplies
// them, stay inside the range where double arithmetic neither overflows nor loses them.

#include <corocontact/core/tet_mesh.hpp>
#include <corocontact/sim/case_spec.hpp>

namespace coro::detail {

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

} // namespace coro::detail
