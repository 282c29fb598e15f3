#pragma once
/// @file divergence_check.hpp
/// @brief The per-step test that a run has diverged: a non-finite node position, or an element
/// inverted (or blown up) beyond recovery.
///
/// Criterion: the volume ratio J = det F = det(D_s) / det(D_m) of every tet must stay inside
/// [min_volume_ratio, max_volume_ratio]. The co-rotational model (R from the sign-fixed polar
/// decomposition) pushes a mildly inverted tet back, so J a little below zero is survivable;
/// a tet turned inside out to half its rest volume (J ≤ −0.5 by default), or grown a
/// hundredfold (J ≥ 100), is not: the linear co-rotated stress no longer describes it and the
/// run only produces garbage from there. None of the example cases (cases/*.toml, the pile
/// included) comes near either bound.
///
/// Cost: one pass over the tets (4 gathers, one 3×3 determinant each) under TBB; about
/// 0.1 ms per 100k tets on 2 cores.

#include <corocontact/sim/body.hpp>

#include <vector>

namespace coro {

/// Bounds of the volume ratio J = det F outside which a tet counts as diverged.
struct DivergenceLimits {
    double min_volume_ratio = -0.5; ///< J ≤ this: inverted beyond recovery
    double max_volume_ratio = 100.0; ///< J ≥ this: blown up
};

/// What check found wrong first in one body: the lowest input node with a non-finite
/// position, else the lowest input tet outside the limits.
struct DivergenceFinding {
    Index node = -1;           ///< input (mesh file) index of a non-finite node, or −1
    Index element = -1;        ///< input (mesh file) index of the tet, or −1
    double volume_ratio = 0.0; ///< J of that tet (NaN if not finite)
    bool found() const { return node >= 0 || element >= 0; }
};

/// Checks one body at its current positions. Parallel; the result does not depend on the
/// thread count (the lowest input index wins).
/// @param[in] body    positions #3V [m], rest volumes from its FEM model
/// @param[in] limits  volume-ratio bounds
DivergenceFinding find_divergence(const Body& body, const DivergenceLimits& limits = {});

/// Checks every body in order and throws for the first that diverged.
/// @throws NumericalError "body 'left': element 123 (mesh file order) inverted: det F = -0.8
///         (limit -0.5)", or "body 'left': position of node 7 (mesh file order) is nan"
void check_divergence(const std::vector<Body>& bodies, const DivergenceLimits& limits = {});

} // namespace coro
