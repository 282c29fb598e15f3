#pragma once
/// @file divergence_check.hpp
/// @brief The per-step test that a run has diverged: a non-finite node position, or an element
/// inverted (or blown up) beyond recovery.
///
/// Criterion: the volume ratio J = det F = det(D_s) / det(D_m) of every tet must stay inside
/// (min_volume_ratio, max_volume_ratio) = (−3, 30) by default. The co-rotational model (R from
/// the sign-fixed polar decomposition) pushes an inverted tet back, and contact does produce
/// inverted tets that recover: the 64-body pile reaches J = −1.01, the first step of the overlap
/// case (bodies that start deep inside each other) J = −1.52 and 5.5. A tet turned inside out to
/// three times its rest volume, or grown thirtyfold, is past that: its nodes have crossed far
/// through the opposite face, the linear co-rotated stress no longer describes it, and the run
/// only produces garbage from there (tests/cli/data/soft_block_hit_hard.toml: J = −5.4 in step
/// 2, −60 by step 20 if let run). The bounds keep a factor of two from what the example cases
/// (cases/*.toml) reach.
///
/// Cost: one pass over the tets (4 gathers and one 3×3 determinant each; the rest volume is
/// read only for tets with det D_s ≤ 0 or close to the upper bound) under TBB: 3.4 ns of CPU
/// time per tet, 0.34 ms for the 101k-tet SOFA beam (under 2% of its step on 2 cores).

#include <corocontact/sim/body.hpp>

#include <string>
#include <vector>

namespace coro {

/// Bounds of the volume ratio J = det F outside which a tet counts as diverged.
struct DivergenceLimits {
    double min_volume_ratio = -3.0; ///< J ≤ this: inverted beyond recovery
    double max_volume_ratio = 30.0; ///< J ≥ this: blown up
};

/// What check found wrong first in one body: the lowest input node with a non-finite
/// position, else the lowest input tet outside the limits.
struct DivergenceFinding {
    Index node = -1;           ///< input (mesh file) index of a non-finite node, or −1
    Index element = -1;        ///< input (mesh file) index of the tet, or −1
    double volume_ratio = 0.0; ///< J of that tet (NaN if not finite)
    bool found() const { return node >= 0 || element >= 0; }
};

/// The check of a scene's bodies, with what it precomputes once (each body's smallest rest
/// volume: tets with 0 < det D_s < max_volume_ratio · 6 V_min pass without reading their own
/// volume, which keeps the per-step pass light).
class DivergenceCheck {
public:
    /// @param[in] bodies  the bodies to check later, in the same order (only their rest volumes are read)
    explicit DivergenceCheck(const std::vector<Body>& bodies, const DivergenceLimits& limits = {});

    /// Checks body `b` at its current positions. Parallel; the result does not depend on the
    /// thread count (the lowest input index wins).
    DivergenceFinding find(const std::vector<Body>& bodies, std::size_t b) const;

    /// Checks every body (in parallel) and throws for the first, in body order, that diverged.
    /// @throws NumericalError about that body (NumericalError::body()): "body 'left': element 123 (mesh file order) inverted beyond
    ///         recovery: det F = -3.8 (limit -3)", "... blown up: det F = 41 (limit 30)", or
    ///         "body 'left': position of node 7 (mesh file order) is nan"
    void check(const std::vector<Body>& bodies);

private:
    DivergenceLimits m_limits;
    std::vector<double> m_min_volumes;
    std::vector<DivergenceFinding> m_findings; // check()'s per body, kept between calls
};

/// Where the body's first non-finite position or velocity is, for a message after a solver
/// reported a NaN or Inf: "body 'left': velocity of node 12 (mesh file order) is nan", or "" if
/// all are finite. Serial; only meant for the error path.
std::string locate_non_finite(const Body& body);

/// DivergenceCheck(…).find() for one body, without keeping the precomputed data.
DivergenceFinding find_divergence(const Body& body, const DivergenceLimits& limits = {});

/// DivergenceCheck(bodies, limits).check(bodies).
/// @throws NumericalError as DivergenceCheck::check
void check_divergence(const std::vector<Body>& bodies, const DivergenceLimits& limits = {});

} // namespace coro
