#include <corocontact/contact/detector.hpp>

#include <corocontact/contact/broad_phase.hpp>

#include "detail/detection_pass.hpp"
#include "detail/detection_state.hpp"
#include "detail/grouped_inside_tests.hpp"
#include "detail/inside_tests.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>

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

struct Block {
    std::size_t pair;
    Index begin, end;
};

/// A pass whose answers come from `inside(k, points, count, results)` for each block of
/// candidates, the blocks as TBB tasks.
template <class Inside>
std::vector<ContactPoint> run_detection(const std::vector<ContactSurface>& surfaces,
                                        const std::vector<PairCandidates>& candidates, const Inside& inside,
                                        bool contact_data, detail::DetectionState& state, DetectionStats* stats,
                                        const CustomNarrowPhase* custom = nullptr)
{
    DetectionPass pass(surfaces, candidates, contact_data, state, custom);
    std::vector<Block> blocks;
    for (std::size_t k = 0; k < candidates.size(); ++k) {
        const auto n = static_cast<Index>(candidates[k].vertices.size());
        for (Index b = 0; b < n; b += VERTEX_BLOCK)
            blocks.push_back({k, b, std::min(n, b + VERTEX_BLOCK)});
    }
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, blocks.size(), 1),
                      [&](const tbb::blocked_range<std::size_t>& range) {
                          Vec3 points[VERTEX_BLOCK];
                          InsideTest results[VERTEX_BLOCK];
                          for (std::size_t b = range.begin(); b < range.end(); ++b) {
                              const Block& block = blocks[b];
                              const Index count = block.end - block.begin;
                              block_points(surfaces, candidates[block.pair], block.begin, count, points);
                              inside(block.pair, points, count, results);
                              pass.take(block.pair, block.begin, count, results);
                          }
                      });
    return pass.finish(count_pairs(candidates), stats);
}

/// The broad phase: the pairs of surfaces whose boxes (from their trees) overlap, sorted.
std::vector<std::pair<Index, Index>> overlapping_surfaces(const std::vector<ContactSurface>& surfaces)
{
    std::vector<Aabb> boxes;
    boxes.reserve(surfaces.size());
    for (const ContactSurface& s : surfaces)
        boxes.push_back(s.tree.bounds());
    return overlapping_pairs(boxes);
}

/// contact_candidates() of the broad phase's `pairs`.
std::vector<PairCandidates> pair_candidates(const std::vector<ContactSurface>& surfaces,
                                            const std::vector<std::pair<Index, Index>>& pairs, DetectionMode mode)
{
    const auto box = [&](Index s) { return surfaces[static_cast<std::size_t>(s)].tree.bounds(); };
    std::vector<PairCandidates> candidates(2 * pairs.size());
    for (std::size_t k = 0; k < pairs.size(); ++k) {
        const auto [a, b] = pairs[k];
        candidates[2 * k].body = a;
        candidates[2 * k].other = b;
        candidates[2 * k + 1].body = b;
        candidates[2 * k + 1].other = a;
    }
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, candidates.size(), 1),
                      [&](const tbb::blocked_range<std::size_t>& range) {
                          std::vector<Index> overlapping;
                          for (std::size_t k = range.begin(); k < range.end(); ++k) {
                              PairCandidates& c = candidates[k];
                              const ContactSurface& body = surfaces[static_cast<std::size_t>(c.body)];
                              const ContactSurface& other = surfaces[static_cast<std::size_t>(c.other)];
                              c.overlap = box(c.body).intersection(box(c.other));
                              body.tree.vertices_in_box(body.vertices, c.overlap, c.vertices);
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
    // Ordered by (body, other): the pairs are sorted by (min, max); reorder both directions.
    std::sort(candidates.begin(), candidates.end(), [](const PairCandidates& x, const PairCandidates& y) {
        return std::tie(x.body, x.other) < std::tie(y.body, y.other);
    });
    return candidates;
}

} // namespace

std::vector<PairCandidates> contact_candidates(const std::vector<ContactSurface>& surfaces, DetectionMode mode)
{
    return pair_candidates(surfaces, overlapping_surfaces(surfaces), mode);
}

DetectionScratch::DetectionScratch() : m_state(std::make_unique<detail::DetectionState>()) {}
DetectionScratch::~DetectionScratch() = default;
DetectionScratch::DetectionScratch(DetectionScratch&&) noexcept = default;
DetectionScratch& DetectionScratch::operator=(DetectionScratch&&) noexcept = default;

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
    detail::DetectionState& state = detail::ScratchAccess::state(scratch);
    if (!settings.share_answers || settings.mode != DetectionMode::EXACT) {
        const std::vector<PairCandidates> candidates = contact_candidates(surfaces, settings.mode);
        return run_detection(
            surfaces, candidates,
            [&](std::size_t k, const Vec3* points, Index count, InsideTest* results) {
                const PairCandidates& pair = candidates[k];
                detail::inside_tests(surfaces[static_cast<std::size_t>(pair.other)], points, count, settings.mode,
                                     pair.faces, settings.tolerances, results);
            },
            settings.contact_data, state, stats);
    }

    // The mid phase and the face pairs of the groups need only the broad phase: one parallel
    // phase for both.
    const auto pairs = overlapping_surfaces(surfaces);
    std::vector<PairCandidates> candidates;
    std::vector<detail::SlotPairs> slot_pairs;
    tbb::parallel_invoke([&] { candidates = pair_candidates(surfaces, pairs, settings.mode); },
                         [&] { slot_pairs = detail::overlapping_slot_pairs(surfaces, pairs); });
    // Each pair's answers are taken in its own task, as they come; with depth searches to do,
    // its blocks are nested tasks.
    DetectionPass pass(surfaces, candidates, settings.contact_data, state);
    detail::grouped_inside_tests(
        surfaces, candidates, slot_pairs, settings.tolerances, settings.contact_data, state.groups,
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
    return pass.finish(count_pairs(candidates), stats);
}

std::vector<ContactPoint> detect_contacts(const std::vector<ContactSurface>& surfaces,
                                          const CustomNarrowPhase& narrow, bool contact_data, DetectionStats* stats)
{
    DetectionScratch scratch;
    const std::vector<PairCandidates> candidates = contact_candidates(surfaces, DetectionMode::EXACT);
    return run_detection(
        surfaces, candidates,
        [&](std::size_t k, const Vec3* points, Index count, InsideTest* results) {
            for (Index i = 0; i < count; ++i)
                results[i] = narrow.inside(candidates[k].other, points[i]);
        },
        contact_data, detail::ScratchAccess::state(scratch), stats, &narrow);
}

} // namespace coro
