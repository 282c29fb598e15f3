#include "grouped_inside_tests.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <corocontact/core/error.hpp>

#include <algorithm>
#include <tuple>

namespace coro::detail {

namespace {

// Tested vertices per task.
constexpr Index TEST_BLOCK = 256;

struct TestBlock {
    std::size_t pair;
    std::size_t first, last; // range of that pair's tested candidates
};

} // namespace

std::vector<std::vector<InsideTest>> grouped_inside_tests(const std::vector<ContactSurface>& surfaces,
                                                          const std::vector<PairCandidates>& candidates,
                                                          const AxisRayTolerances& tolerances,
                                                          bool distance_bounds)
{
    const std::size_t pairs = candidates.size();
    std::vector<std::vector<Index>> decider(pairs);
    std::vector<std::vector<double>> path(pairs);
    std::vector<std::vector<Index>> tested(pairs); // the candidates that are their own decider
    // The face pairs of each body pair, found once for both directions: candidates holds (a, b)
    // and (b, a), the region I is the same.
    std::vector<std::vector<std::array<Index, 2>>> face_pairs(pairs);
    std::vector<std::size_t> lower(pairs); // the direction whose body < other, for each k
    std::vector<std::size_t> walks;
    for (std::size_t k = 0; k < pairs; ++k) {
        const PairCandidates& pair = candidates[k];
        if (pair.body < pair.other)
            walks.push_back(k);
        lower[k] = k;
        if (pair.body > pair.other) { // candidates are ordered by (body, other)
            const auto reverse = std::lower_bound(candidates.begin(), candidates.end(), pair,
                                                  [](const PairCandidates& x, const PairCandidates& y) {
                                                      return std::tie(x.body, x.other) < std::tie(y.other, y.body);
                                                  });
            CORO_ASSERT(reverse != candidates.end() && reverse->body == pair.other && reverse->other == pair.body);
            lower[k] = static_cast<std::size_t>(reverse - candidates.begin());
        }
    }
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, walks.size(), 1), [&](const tbb::blocked_range<std::size_t>& r) {
        for (std::size_t w = r.begin(); w < r.end(); ++w) {
            const PairCandidates& pair = candidates[walks[w]];
            const ContactSurface& body = surfaces[static_cast<std::size_t>(pair.body)];
            const ContactSurface& other = surfaces[static_cast<std::size_t>(pair.other)];
            if (other.closed || body.closed)
                body.tree.overlapping_faces(other.tree, pair.overlap, face_pairs[walks[w]]);
        }
    });
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, pairs, 1), [&](const tbb::blocked_range<std::size_t>& r) {
        for (std::size_t k = r.begin(); k < r.end(); ++k) {
            const PairCandidates& pair = candidates[k];
            const ContactSurface& body = surfaces[static_cast<std::size_t>(pair.body)];
            const ContactSurface& other = surfaces[static_cast<std::size_t>(pair.other)];
            const std::size_t n = pair.vertices.size();
            if (other.closed) {
                body.tree.clear_edge_groups(body.vertices, other.tree, other.vertices, face_pairs[lower[k]],
                                            lower[k] == k ? 0 : 1, pair.vertices, decider[k],
                                            distance_bounds ? &path[k] : nullptr);
            } else {
                decider[k].resize(n);
                for (std::size_t i = 0; i < n; ++i)
                    decider[k][i] = static_cast<Index>(i);
                if (distance_bounds)
                    path[k].assign(n, 0.0);
            }
            for (std::size_t i = 0; i < n; ++i)
                if (decider[k][i] == static_cast<Index>(i))
                    tested[k].push_back(static_cast<Index>(i));
        }
    });

    std::vector<std::vector<InsideTest>> answers(pairs);
    std::vector<TestBlock> blocks;
    for (std::size_t k = 0; k < pairs; ++k) {
        answers[k].resize(candidates[k].vertices.size());
        for (std::size_t first = 0; first < tested[k].size(); first += TEST_BLOCK)
            blocks.push_back({k, first, std::min(tested[k].size(), first + TEST_BLOCK)});
    }
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, blocks.size(), 1), [&](const tbb::blocked_range<std::size_t>& r) {
        Vec3 points[TEST_BLOCK];
        InsideTest results[TEST_BLOCK];
        for (std::size_t b = r.begin(); b < r.end(); ++b) {
            const TestBlock& block = blocks[b];
            const PairCandidates& pair = candidates[block.pair];
            const ContactSurface& body = surfaces[static_cast<std::size_t>(pair.body)];
            const Index count = static_cast<Index>(block.last - block.first);
            for (Index t = 0; t < count; ++t) {
                const Index i = tested[block.pair][block.first + static_cast<std::size_t>(t)];
                points[t] = body.vertices.row(pair.vertices[static_cast<std::size_t>(i)]).transpose();
            }
            inside_tests(surfaces[static_cast<std::size_t>(pair.other)], points, count, DetectionMode::EXACT, {},
                         tolerances, results);
            for (Index t = 0; t < count; ++t)
                answers[block.pair][static_cast<std::size_t>(tested[block.pair][block.first + static_cast<std::size_t>(t)])] =
                    results[t];
        }
    });

    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, pairs, 1), [&](const tbb::blocked_range<std::size_t>& r) {
        for (std::size_t k = r.begin(); k < r.end(); ++k)
            for (std::size_t i = 0; i < answers[k].size(); ++i) {
                const std::size_t d = static_cast<std::size_t>(decider[k][i]);
                if (d == i)
                    continue;
                const InsideTest& from = answers[k][d];
                InsideTest& to = answers[k][i];
                to = InsideTest();
                to.inside = from.inside;
                to.deciding_axis = DECIDED_BY_NEIGHBOUR;
                to.crossing_face = from.crossing_face;
                // Some point of the surface lies within the decider's bound of it; the sum is
                // rounded up by a relative 10⁻¹² (far above the rounding of the two terms).
                if (distance_bounds)
                    to.surface_distance_bound = (from.surface_distance_bound + path[k][i]) * (1.0 + 1e-12);
            }
    });
    return answers;
}

} // namespace coro::detail
