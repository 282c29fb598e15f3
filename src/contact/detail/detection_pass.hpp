#pragma once
/// @file detection_pass.hpp
/// @brief The part of a detection pass after the inside tests: the depth and normal of the
/// inside vertices, the counts, and the sorted output.

#include <corocontact/contact/detector.hpp>

#include "detection_state.hpp"
#include "grouped_inside_tests.hpp"

#include <vector>

namespace coro::detail {

/// Candidate vertices per task: large pairs are split, small ones stay whole.
constexpr Index VERTEX_BLOCK = 256;

/// The answers of the inside tests, taken block by block (blocks of at most VERTEX_BLOCK
/// candidates of one pair, in any order and from any thread), become contact points, with
/// their depth and normal when asked for; finish() returns them sorted by contact_order().
class DetectionPass {
public:
    /// With `contact_data`, the depths come from `nearest`, or when it is empty from the
    /// trees' searches with the face planes of `state`. `surfaces`, `candidates` and `state`
    /// must outlive the pass.
    DetectionPass(const std::vector<ContactSurface>& surfaces, const std::vector<PairCandidates>& candidates,
                  bool contact_data, DetectionState& state, const CustomNarrowPhase* custom = nullptr);

    /// Candidates first .. first + count − 1 of pair k, answered by results[0 .. count − 1].
    void take(std::size_t k, Index first, Index count, const InsideTest* results);

    /// Candidates first .. first + count − 1 of pair k, answered by their groups' tests.
    void take(std::size_t k, Index first, Index count, const GroupedAnswers& answers);

    bool contact_data() const { return m_contact_data; }

    /// The inside points, sorted, into `points` (its old content replaced); the counts of every
    /// block taken, with `pairs`, into `stats`.
    void finish(Index pairs, DetectionStats* stats, std::vector<ContactPoint>& points, Index by_hull = 0);

private:
    /// The contact points of the inside candidates among first .. first + count − 1 of pair k,
    /// into their slots. `start(i)` gives candidate i's distance bound and a face near it (its
    /// inside test's crossing) to start its nearest-point search from.
    template <class Start>
    void contact_points(std::size_t k, Index first, Index count, const unsigned char* inside, const Start& start);
    /// Counts of a block into the thread's stats.
    void count(Index candidates, Index inside, Index on_surface, Index fallbacks, Index by_neighbour);
    /// The points of the inside slots, sorted (a counting sort by vertex per body).
    void sorted_points(std::vector<ContactPoint>& points);
    /// The starts of the depth searches: the last detection's for the pairs it had, none for new ones.
    void keep_last_faces();

    const std::vector<ContactSurface>& m_surfaces;
    const std::vector<PairCandidates>& m_candidates;
    bool m_contact_data;
    DetectionState& m_state;
    const CustomNarrowPhase* m_custom; // null, or with an empty nearest: the trees' searches
};

} // namespace coro::detail
