#include <corocontact/contact/detector.hpp>

#include <corocontact/contact/broad_phase.hpp>
#include <corocontact/core/error.hpp>

#include "detail/detection_pass.hpp"
#include "detail/detection_state.hpp"
#include "detail/grouped_inside_tests.hpp"
#include "detail/inside_tests.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <memory>
#include <tuple>

namespace coro {

namespace {

using detail::DetectionPass;
using detail::VERTEX_BLOCK;

/// The positions of candidates first .. first + count − 1 of `pair`.
void block_points(const std::vector<ContactSurface>& surfaces, const PairCandidates& pair, Index first, Index count,
                  Vec3* points)
{
    const ContactSurface& body = surfaces[static_cast<std::size_t>(pair.body)];
    for (Index i = 0; i < count; ++i)
        points[i] = body.vertices.row(pair.vertices[static_cast<std::size_t>(first + i)]).transpose();
}

Index count_pairs(const std::vector<PairCandidates>& candidates) { return static_cast<Index>(candidates.size() / 2); }

/// A pass whose answers come from `inside(k, points, count, results)` for each block of
/// candidates, the blocks as TBB tasks.
template <class Inside>
void run_detection(const std::vector<ContactSurface>& surfaces, const std::vector<PairCandidates>& candidates,
                   const Inside& inside, bool contact_data, detail::DetectionState& state, DetectionStats* stats,
                   std::vector<ContactPoint>& points, const CustomNarrowPhase* custom = nullptr)
{
    DetectionPass pass(surfaces, candidates, contact_data, state, custom);
    std::vector<detail::CandidateBlock>& blocks = state.blocks;
    blocks.clear();
    for (std::size_t k = 0; k < candidates.size(); ++k) {
        const auto n = static_cast<Index>(candidates[k].vertices.size());
        for (Index b = 0; b < n; b += VERTEX_BLOCK)
            blocks.push_back({k, b, std::min(VERTEX_BLOCK, n - b)});
    }
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, blocks.size(), 1),
                      [&](const tbb::blocked_range<std::size_t>& range) {
                          Vec3 block_positions[VERTEX_BLOCK];
                          InsideTest results[VERTEX_BLOCK];
                          for (std::size_t b = range.begin(); b < range.end(); ++b) {
                              const detail::CandidateBlock& block = blocks[b];
                              block_points(surfaces, candidates[block.pair], block.first, block.count,
                                           block_positions);
                              inside(block.pair, block_positions, block.count, results);
                              pass.take(block.pair, block.first, block.count, results);
                          }
                      });
    pass.finish(count_pairs(candidates), stats, points);
}

/// The broad phase: the pairs of surfaces whose boxes (from their trees) overlap, into
/// state.pairs, sorted.
void overlapping_surfaces(const std::vector<ContactSurface>& surfaces, detail::DetectionState& state)
{
    state.boxes.clear();
    for (const ContactSurface& s : surfaces)
        state.boxes.push_back(s.tree.bounds());
    overlapping_pairs(state.boxes, state.pairs, state.sweep_order);
}

/// The mid phase of the broad phase's state.pairs: contact_candidates() into state.candidates.
const std::vector<PairCandidates>& pair_candidates(const std::vector<ContactSurface>& surfaces, DetectionMode mode,
                                                   detail::DetectionState& state)
{
    const auto box = [&](Index s) { return surfaces[static_cast<std::size_t>(s)].tree.bounds(); };
    // Both directions of each pair, ordered by (body, other): a counting sort by body, in which
    // a body's pairs with lower others (the pairs (other, body), ascending) precede its pairs
    // (body, other), ascending.
    std::vector<Index>& next = state.directed_offsets;
    next.assign(surfaces.size() + 1, 0);
    for (const auto& [a, b] : state.pairs) {
        ++next[static_cast<std::size_t>(a) + 1];
        ++next[static_cast<std::size_t>(b) + 1];
    }
    for (std::size_t s = 0; s < surfaces.size(); ++s)
        next[s + 1] += next[s];
    state.directed.resize(2 * state.pairs.size());
    state.pair_of.resize(2 * state.pairs.size());
    for (const bool lower_first : {true, false})
        for (std::size_t j = 0; j < state.pairs.size(); ++j) {
            const auto [a, b] = state.pairs[j];
            const auto at = static_cast<std::size_t>(next[static_cast<std::size_t>(lower_first ? b : a)]++);
            state.directed[at] = lower_first ? std::make_pair(b, a) : std::make_pair(a, b);
            state.pair_of[at] = j;
        }
    CORO_ASSERT(std::is_sorted(state.directed.begin(), state.directed.end()));
    std::vector<PairCandidates>& candidates = state.candidates.assign(state.directed);
    for (std::size_t k = 0; k < candidates.size(); ++k)
        std::tie(candidates[k].body, candidates[k].other) = state.directed[k];
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, candidates.size(), 1),
                      [&](const tbb::blocked_range<std::size_t>& range) {
                          std::vector<Index>& overlapping = state.overlapping_faces.local();
                          for (std::size_t k = range.begin(); k < range.end(); ++k) {
                              PairCandidates& c = candidates[k];
                              const ContactSurface& body = surfaces[static_cast<std::size_t>(c.body)];
                              const ContactSurface& other = surfaces[static_cast<std::size_t>(c.other)];
                              c.overlap = box(c.body).intersection(box(c.other));
                              body.tree.vertices_in_box(body.vertices, c.overlap, c.vertices);
                              c.faces.clear();
                              if (mode != DetectionMode::PAPER)
                                  continue;
                              other.tree.faces_overlapping(other.vertices, c.overlap, overlapping);
                              for (const Index f : overlapping) {
                                  bool any = false;
                                  for (int j = 0; j < 3 && !any; ++j)
                                      any = c.overlap.contains(other.vertices.row(other.faces(f, j)).transpose());
                                  if (any)
                                      c.faces.push_back(f);
                              }
                          }
                      });
    return candidates;
}

/// Broad and mid phase into `state`.
const std::vector<PairCandidates>& find_candidates(const std::vector<ContactSurface>& surfaces, DetectionMode mode,
                                                   detail::DetectionState& state)
{
    overlapping_surfaces(surfaces, state);
    return pair_candidates(surfaces, mode, state);
}

/// Exact mode with shared answers, after the grouping is decided: the candidates of pairs not
/// grouped that lie outside the hull slabs of a closed `other` are dropped. Such a pair tests
/// each candidate on its own (a walk of a small, cold tree, ~0.3 µs), and in a pile of small
/// bodies the slabs reject ~60 % of them. Grouped pairs keep theirs: their answers are shared
/// along clear edges, and chains through the dropped vertices carry the distance bounds that
/// start the depth searches.
/// Returns how many were dropped.
Index drop_candidates_outside_hulls(const std::vector<ContactSurface>& surfaces, detail::DetectionState& state)
{
    std::vector<PairCandidates>& candidates = state.candidates.items();
    const std::vector<std::size_t>& pair_of = state.pair_of;
    const std::vector<detail::PairSlots>& slot_pairs = state.slot_pairs.items();
    const auto filtered = [&](std::size_t k) {
        const PairCandidates& c = candidates[k];
        return !slot_pairs[pair_of[k]].grouped && surfaces[static_cast<std::size_t>(c.other)].closed &&
               !c.vertices.empty();
    };
    state.hull_wanted.assign(surfaces.size(), 0);
    state.dropped.assign(candidates.size(), 0);
    for (std::size_t k = 0; k < candidates.size(); ++k)
        if (filtered(k))
            state.hull_wanted[static_cast<std::size_t>(candidates[k].other)] = 1;
    state.hulls.resize(surfaces.size());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, surfaces.size(), 16),
                      [&](const tbb::blocked_range<std::size_t>& range) {
                          for (std::size_t s = range.begin(); s < range.end(); ++s)
                              if (state.hull_wanted[s])
                                  state.hulls[s] = detail::HullSlabs::of(surfaces[s].vertices);
                      });
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, candidates.size(), 8),
                      [&](const tbb::blocked_range<std::size_t>& range) {
                          for (std::size_t k = range.begin(); k < range.end(); ++k) {
                              if (!filtered(k))
                                  continue;
                              PairCandidates& c = candidates[k];
                              const ContactSurface& body = surfaces[static_cast<std::size_t>(c.body)];
                              const detail::HullSlabs& hull = state.hulls[static_cast<std::size_t>(c.other)];
                              const std::size_t before = c.vertices.size();
                              c.vertices.erase(std::remove_if(c.vertices.begin(), c.vertices.end(),
                                                              [&](Index v) {
                                                                  return !hull.may_contain(
                                                                      body.vertices.row(v).transpose());
                                                              }),
                                               c.vertices.end());
                              state.dropped[k] = static_cast<Index>(before - c.vertices.size());
                          }
                      });
    Index dropped = 0;
    for (const Index n : state.dropped)
        dropped += n;
    return dropped;
}

/// Mid phase and narrow phase of the broad phase's state.pairs, into points.
void detect_pairs(const std::vector<ContactSurface>& surfaces, const DetectionSettings& settings,
                  detail::DetectionState& state, std::vector<ContactPoint>& points, DetectionStats* stats)
{
    if (!settings.share_answers || settings.mode != DetectionMode::EXACT) {
        const std::vector<PairCandidates>& candidates = pair_candidates(surfaces, settings.mode, state);
        run_detection(
            surfaces, candidates,
            [&](std::size_t k, const Vec3* positions, Index count, InsideTest* results) {
                const PairCandidates& pair = candidates[k];
                detail::inside_tests(surfaces[static_cast<std::size_t>(pair.other)], positions, count, settings.mode,
                                     pair.faces, settings.tolerances, results);
            },
            settings.contact_data, state, stats, points);
        return;
    }

    // Which pairs are grouped depends on their candidates: the mid phase comes first.
    const std::vector<PairCandidates>& candidates = pair_candidates(surfaces, settings.mode, state);
    detail::overlapping_slot_pairs(surfaces, state.pairs, candidates, state.pair_of, state.grouping, state.slot_pairs);
    const Index by_hull = drop_candidates_outside_hulls(surfaces, state);
    // Each pair's answers are taken in its own task, as they come; with depth searches to do,
    // its blocks are nested tasks.
    DetectionPass pass(surfaces, candidates, settings.contact_data, state);
    detail::grouped_inside_tests(
        surfaces, candidates, state.pair_of, state.slot_pairs.items(), settings.tolerances, settings.contact_data,
        state.grouping,
        [&](std::size_t k, const detail::GroupedAnswers& answers) {
            const auto n = static_cast<Index>(answers.group.size());
            const Index blocks = (n + VERTEX_BLOCK - 1) / VERTEX_BLOCK;
            const auto take_block = [&](Index b) {
                const Index first = b * VERTEX_BLOCK;
                pass.take(k, first, std::min(VERTEX_BLOCK, n - first), answers);
            };
            if (!pass.contact_data() || blocks <= 1) {
                for (Index b = 0; b < blocks; ++b)
                    take_block(b);
                return;
            }
            tbb::parallel_for(tbb::blocked_range<Index>(0, blocks, 1), [&](const tbb::blocked_range<Index>& r) {
                for (Index b = r.begin(); b < r.end(); ++b)
                    take_block(b);
            });
        });
    pass.finish(count_pairs(candidates), stats, points, by_hull);
}

} // namespace

std::vector<PairCandidates> contact_candidates(const std::vector<ContactSurface>& surfaces, DetectionMode mode)
{
    detail::DetectionState state;
    find_candidates(surfaces, mode, state);
    return std::move(state.candidates.items());
}

DetectionScratch::DetectionScratch() : m_state(std::make_unique<detail::DetectionState>()) {}
DetectionScratch::~DetectionScratch() = default;
DetectionScratch::DetectionScratch(DetectionScratch&&) noexcept = default;
DetectionScratch& DetectionScratch::operator=(DetectionScratch&&) noexcept = default;

const std::vector<std::pair<Index, Index>>& DetectionScratch::overlapping_surfaces() const { return m_state->pairs; }

std::vector<ContactPoint> detect_contacts(const std::vector<ContactSurface>& surfaces,
                                          const DetectionSettings& settings, DetectionStats* stats)
{
    DetectionScratch scratch;
    return detect_contacts(surfaces, settings, scratch, stats);
}

std::vector<ContactPoint> detect_contacts(const std::vector<ContactSurface>& surfaces,
                                          const DetectionSettings& settings, DetectionScratch& scratch,
                                          DetectionStats* stats)
{
    std::vector<ContactPoint> points;
    detect_contacts(surfaces, settings, scratch, points, stats);
    return points;
}

void detect_contacts(const std::vector<ContactSurface>& surfaces, const DetectionSettings& settings,
                     DetectionScratch& scratch, std::vector<ContactPoint>& points, DetectionStats* stats)
{
    detail::DetectionState& state = detail::ScratchAccess::state(scratch);
    overlapping_surfaces(surfaces, state);
    detect_pairs(surfaces, settings, state, points, stats);
}

std::vector<ContactPoint> detect_contacts(const std::vector<ContactSurface>& surfaces,
                                          const std::vector<std::pair<Index, Index>>& pairs,
                                          const DetectionSettings& settings, DetectionScratch& scratch,
                                          DetectionStats* stats)
{
    CORO_ASSERT(std::is_sorted(pairs.begin(), pairs.end()));
    detail::DetectionState& state = detail::ScratchAccess::state(scratch);
    state.pairs = pairs;
    std::vector<ContactPoint> points;
    detect_pairs(surfaces, settings, state, points, stats);
    return points;
}

std::vector<ContactPoint> detect_contacts(const std::vector<ContactSurface>& surfaces,
                                          const CustomNarrowPhase& narrow, bool contact_data, DetectionStats* stats)
{
    DetectionScratch scratch;
    detail::DetectionState& state = detail::ScratchAccess::state(scratch);
    const std::vector<PairCandidates>& candidates = find_candidates(surfaces, DetectionMode::EXACT, state);
    std::vector<ContactPoint> points;
    run_detection(
        surfaces, candidates,
        [&](std::size_t k, const Vec3* positions, Index count, InsideTest* results) {
            for (Index i = 0; i < count; ++i)
                results[i] = narrow.inside(candidates[k].other, positions[i]);
        },
        contact_data, state, stats, points, &narrow);
    return points;
}

} // namespace coro
