#pragma once
/// @file detection_pass.hpp
/// @brief The part of a detection pass after the inside tests: contact points, counts and the
/// sorted output (internal to the detector).

#include <corocontact/contact/detector.hpp>

#include "grouped_inside_tests.hpp"

#include <tbb/enumerable_thread_specific.h>

#include <vector>

namespace coro::detail {

/// Candidate vertices per task: large pairs are split, small ones stay whole.
constexpr Index VERTEX_BLOCK = 256;

/// make_contact_point() with the hints of AabbTree::nearest (same answer, faster).
ContactPoint contact_point(const std::vector<ContactSurface>& surfaces, Index body, Index vertex, Index other,
                           double distance_bound, Index hint_face);

/// The contact point of vertex `vertex` of `body` inside `other` whose nearest point on the
/// other surface is `nearest`: its distance as depth, its face's outward unit normal.
ContactPoint contact_point(const std::vector<ContactSurface>& surfaces, Index body, Index vertex, Index other,
                           const AabbTree::Nearest& nearest);

/// The answers of the inside tests, taken block by block (blocks of at most VERTEX_BLOCK
/// candidates of one pair, in any order and from any thread), become contact points with their
/// depth and normal when asked for, and finish() returns them sorted by (body, vertex, other).
class DetectionPass {
public:
    /// With `contact_data`, the depths come from `nearest`, or when it is empty from the trees,
    /// whose face planes it then brings up to date (TBB tasks). `surfaces` and `candidates`
    /// must outlive the pass.
    DetectionPass(const std::vector<ContactSurface>& surfaces, const std::vector<PairCandidates>& candidates,
                  bool contact_data, const NearestSearch& nearest = {});

    /// Candidates first .. first + count − 1 of pair k, answered by results[0 .. count − 1].
    void take(std::size_t k, Index first, Index count, const InsideTest* results);

    /// Candidates first .. first + count − 1 of pair k, answered by their groups' tests.
    void take(std::size_t k, Index first, Index count, const GroupedAnswers& answers);

    bool contact_data() const { return m_contact_data; }

    /// The inside points, sorted; the counts of every block taken, with `pairs`, into `stats`.
    std::vector<ContactPoint> finish(Index pairs, DetectionStats* stats);

private:
    const std::vector<ContactSurface>& m_surfaces;
    const std::vector<PairCandidates>& m_candidates;
    bool m_contact_data;
    NearestSearch m_nearest; // empty: the trees
    std::vector<std::size_t> m_offsets; // pair k's candidate i has slot offsets[k] + i
    std::vector<ContactPoint> m_slots;
    std::vector<unsigned char> m_inside;
    tbb::enumerable_thread_specific<DetectionStats> m_stats;
};

} // namespace coro::detail
