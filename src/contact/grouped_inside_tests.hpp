#pragma once
/// @file grouped_inside_tests.hpp
/// @brief Exact inside tests of the candidate vertices of every pair, one test per group of
/// vertices joined by clear edges (internal to the detector).

#include <corocontact/contact/detector.hpp>

#include <functional>
#include <vector>

namespace coro::detail {

/// Exact-mode answers for every candidate vertex, handed over pair by pair: use(k, answers) with
/// answers[i] for candidates[k].vertices[i], called once per pair from that pair's TBB task
/// (pairs run in parallel; `use` may start nested tasks). Where the other surface is closed, the
/// candidates of a pair are grouped by AabbTree::clear_edge_groups and only the first of each
/// group is tested (inside_tests()); the others take its answer with deciding_axis
/// DECIDED_BY_NEIGHBOUR, on_surface false, its crossing_face and, as surface_distance_bound,
/// its bound plus their path (+∞ without `distance_bounds`: no path lengths are summed). Else
/// every candidate is tested. The tests of a pair with many groups run in nested tasks; the
/// answers do not depend on the scheduling.
void grouped_inside_tests(const std::vector<ContactSurface>& surfaces, const std::vector<PairCandidates>& candidates,
                          const AxisRayTolerances& tolerances, bool distance_bounds,
                          const std::function<void(std::size_t pair, const std::vector<InsideTest>& answers)>& use);

} // namespace coro::detail
