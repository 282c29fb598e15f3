#include "detection_pass.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <corocontact/core/error.hpp>

#include <algorithm>
#include <cstdint>
#include <memory>

namespace coro::detail {

namespace {

/// The end of a chain of slots in sorted_points().
constexpr std::uint32_t NONE = ~std::uint32_t{0};

/// The points of the slots flagged in `inside`, sorted by (body, vertex, other). `candidates` is
/// ordered by (body, other) and slot offsets[k] + i belongs to its pair k's candidate i, a vertex
/// at most once per pair. Per body, a bit per vertex marks those inside and each marked vertex
/// heads a chain of its slots, linked from the body's last pair back so that it runs by other
/// ascending; the marks are then read in order: O(points + candidates + vertices / 64). A body
/// in one pair only (two bodies: both) needs no chains: a marked vertex has one slot. `slots`
/// holds each inside slot's point with its depth and normal; empty: the points carry body,
/// vertex and other only. The points are appended in order, each built in place: a vector
/// sized first (every point set to its defaults) and then filled by a task per body passed over
/// the output twice, which cost more than the tasks saved on two bodies.
std::vector<ContactPoint> sorted_points(const std::vector<ContactSurface>& surfaces,
                                        const std::vector<PairCandidates>& candidates,
                                        const std::vector<std::size_t>& offsets, const std::vector<ContactPoint>& slots,
                                        const std::vector<unsigned char>& inside)
{
    CORO_ASSERT(offsets.back() < NONE);
    std::size_t total = 0;
    for (const unsigned char flag : inside)
        total += flag;
    std::vector<ContactPoint> points;
    points.reserve(total);
    // A link of a chain: the next slot of the same vertex (NONE: the last) and its other body, by
    // slot − the body's first slot. Neither the links nor the heads are initialised: only those of
    // inside slots and of marked vertices are read.
    struct Link {
        std::uint32_t next;
        Index other;
    };
    std::vector<std::uint64_t> marked;
    std::unique_ptr<std::uint32_t[]> head;
    std::unique_ptr<Link[]> link;
    std::size_t head_size = 0, link_size = 0;
    for (std::size_t first = 0, last = 0; first < candidates.size(); first = last) {
        const Index body = candidates[first].body;
        while (last < candidates.size() && candidates[last].body == body)
            ++last;
        const auto vertices = static_cast<std::size_t>(surfaces[static_cast<std::size_t>(body)].vertices.rows());
        marked.assign((vertices + 63) / 64, 0);
        if (head_size < vertices)
            head.reset(new std::uint32_t[head_size = vertices]);
        const std::size_t base = offsets[first];
        if (last == first + 1) { // one pair (e.g. two bodies): no chains, a vertex has one slot
            const std::vector<Index>& vertex = candidates[first].vertices;
            const unsigned char* flag = inside.data() + base;
            const Index other = candidates[first].other;
            for (std::size_t i = 0; i < vertex.size(); ++i) {
                const auto v = static_cast<std::size_t>(vertex[i]);
                marked[v / 64] |= static_cast<std::uint64_t>(flag[i]) << (v % 64);
                head[v] = static_cast<std::uint32_t>(i); // read only where marked
            }
            for (std::size_t w = 0; w < marked.size(); ++w)
                for (std::uint64_t bits = marked[w]; bits != 0; bits &= bits - 1) {
                    const std::size_t v = 64 * w + static_cast<std::size_t>(__builtin_ctzll(bits));
                    if (!slots.empty()) {
                        points.push_back(slots[base + head[v]]);
                    } else {
                        ContactPoint& point = points.emplace_back();
                        point.body = body;
                        point.vertex = static_cast<Index>(v);
                        point.other = other;
                    }
                }
            continue;
        }
        if (link_size < offsets[last] - base)
            link.reset(new Link[link_size = offsets[last] - base]);
        for (std::size_t k = last; k-- > first;) {
            const std::vector<Index>& vertex = candidates[k].vertices;
            const unsigned char* flag = inside.data() + offsets[k];
            const Index other = candidates[k].other;
            for (std::size_t i = 0; i < vertex.size(); ++i) {
                if (!flag[i])
                    continue;
                const auto v = static_cast<std::size_t>(vertex[i]);
                std::uint64_t& word = marked[v / 64];
                const std::uint64_t bit = std::uint64_t{1} << (v % 64);
                const auto slot = static_cast<std::uint32_t>(offsets[k] + i - base);
                link[slot] = {(word & bit) != 0 ? head[v] : NONE, other};
                head[v] = slot;
                word |= bit;
            }
        }
        const auto for_each_slot = [&](const auto& emit) {
            for (std::size_t w = 0; w < marked.size(); ++w)
                for (std::uint64_t bits = marked[w]; bits != 0; bits &= bits - 1) {
                    const std::size_t v = 64 * w + static_cast<std::size_t>(__builtin_ctzll(bits));
                    for (std::uint32_t slot = head[v]; slot != NONE; slot = link[slot].next)
                        emit(static_cast<Index>(v), slot);
                }
        };
        if (!slots.empty()) {
            for_each_slot([&](Index, std::uint32_t slot) { points.push_back(slots[base + slot]); });
        } else {
            for_each_slot([&](Index v, std::uint32_t slot) {
                ContactPoint& point = points.emplace_back();
                point.body = body;
                point.vertex = v;
                point.other = link[slot].other;
            });
        }
    }
    CORO_ASSERT(points.size() == total);
    return points;
}

} // namespace

ContactPoint contact_point(const std::vector<ContactSurface>& surfaces, Index body, Index vertex, Index other,
                           double distance_bound, Index hint_face)
{
    const ContactSurface& b = surfaces[static_cast<std::size_t>(other)];
    const Vec3 p = surfaces[static_cast<std::size_t>(body)].vertices.row(vertex).transpose();
    return contact_point(surfaces, body, vertex, other, b.tree.nearest(b.vertices, p, distance_bound, hint_face));
}

ContactPoint contact_point(const std::vector<ContactSurface>& surfaces, Index body, Index vertex, Index other,
                           const AabbTree::Nearest& nearest)
{
    const ContactSurface& b = surfaces[static_cast<std::size_t>(other)];
    const Vec3 p = surfaces[static_cast<std::size_t>(body)].vertices.row(vertex).transpose();
    ContactPoint c;
    c.body = body;
    c.vertex = vertex;
    c.other = other;
    c.depth = nearest.distance;
    c.face = nearest.face;
    c.barycentric = nearest.barycentric;
    if (nearest.face >= 0) {
        const Vec3 x0 = b.vertices.row(b.faces(nearest.face, 0)).transpose();
        const Vec3 x1 = b.vertices.row(b.faces(nearest.face, 1)).transpose();
        const Vec3 x2 = b.vertices.row(b.faces(nearest.face, 2)).transpose();
        const Vec3 n = (x1 - x0).cross(x2 - x0);
        if (n.norm() > 0.0)
            c.normal = n.normalized();
        else if (nearest.distance > 0.0)
            c.normal = (nearest.point - p) / nearest.distance;
    }
    return c;
}

DetectionPass::DetectionPass(const std::vector<ContactSurface>& surfaces,
                             const std::vector<PairCandidates>& candidates, bool contact_data,
                             const NearestSearch& nearest)
    : m_surfaces(surfaces), m_candidates(candidates), m_contact_data(contact_data), m_nearest(nearest),
      m_offsets(candidates.size() + 1, 0)
{
    for (std::size_t k = 0; k < candidates.size(); ++k)
        m_offsets[k + 1] = m_offsets[k] + candidates[k].vertices.size();
    if (contact_data && !nearest) { // the depth searches skip faces by their planes: bring those up to date
        std::vector<Index> others;
        for (const PairCandidates& c : candidates)
            if (!c.vertices.empty())
                others.push_back(c.other);
        std::sort(others.begin(), others.end());
        others.erase(std::unique(others.begin(), others.end()), others.end());
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, others.size(), 1),
                          [&](const tbb::blocked_range<std::size_t>& r) {
                              for (std::size_t i = r.begin(); i < r.end(); ++i) {
                                  const ContactSurface& s = surfaces[static_cast<std::size_t>(others[i])];
                                  s.tree.update_planes(s.vertices);
                              }
                          });
    }
    // Points with depth and normal are made as the answers come; without, the sorted
    // output makes them from the candidates.
    m_slots.resize(contact_data ? m_offsets.back() : 0);
    m_inside.assign(m_offsets.back(), 0);
}

void DetectionPass::take(std::size_t k, Index first, Index count, const InsideTest* results)
{
    const PairCandidates& pair = m_candidates[k];
    unsigned char* inside = m_inside.data() + m_offsets[k] + static_cast<std::size_t>(first);
    // Counted in locals: the flags are bytes, which may alias anything in memory.
    Index on_surface = 0, fallbacks = 0, by_neighbour = 0, inside_count = 0;
    for (Index i = 0; i < count; ++i) {
        const InsideTest& result = results[i];
        on_surface += result.on_surface ? 1 : 0;
        fallbacks += result.deciding_axis == 3 ? 1 : 0;
        by_neighbour += result.deciding_axis == DECIDED_BY_NEIGHBOUR ? 1 : 0;
        inside[i] = result.inside ? 1 : 0;
        inside_count += result.inside ? 1 : 0;
    }
    DetectionStats& counts = m_stats.local();
    counts.candidate_vertices += count;
    counts.on_surface += on_surface;
    counts.winding_fallbacks += fallbacks;
    counts.by_neighbour += by_neighbour;
    counts.inside += inside_count;
    if (!m_contact_data)
        return;
    ContactPoint* slots = m_slots.data() + m_offsets[k] + static_cast<std::size_t>(first);
    if (m_nearest) { // the caller's search (e.g. Embree's point queries)
        const Positions& vertices = m_surfaces[static_cast<std::size_t>(pair.body)].vertices;
        for (Index i = 0; i < count; ++i) {
            if (!results[i].inside)
                continue;
            const Index v = pair.vertices[static_cast<std::size_t>(first + i)];
            slots[i] = contact_point(m_surfaces, pair.body, v, pair.other,
                                     m_nearest(pair.other, vertices.row(v).transpose(), results[i].surface_distance_bound));
        }
        return;
    }
    // The previous inside vertex's nearest face (vertices come in spatial order) seeds the
    // next nearest-point search; reset per block, so the work does not depend on the
    // scheduling (and the answers do not depend on the hints at all).
    Index hint_face = -1;
    for (Index i = 0; i < count; ++i) {
        if (!results[i].inside)
            continue;
        slots[i] = contact_point(m_surfaces, pair.body, pair.vertices[static_cast<std::size_t>(first + i)],
                                 pair.other, results[i].surface_distance_bound, hint_face);
        hint_face = slots[i].face;
    }
}

void DetectionPass::take(std::size_t k, Index first, Index count, const GroupedAnswers& answers)
{
    const PairCandidates& pair = m_candidates[k];
    unsigned char* inside = m_inside.data() + m_offsets[k] + static_cast<std::size_t>(first);
    const Index* group = answers.group.data() + first;
    const Index* tested = answers.tested.data();
    const InsideTest* answer = answers.answer.data();
    Index on_surface = 0, fallbacks = 0, tests = 0, inside_count = 0;
    for (Index i = 0; i < count; ++i) {
        const InsideTest& result = answer[group[i]];
        inside[i] = result.inside ? 1 : 0;
        inside_count += result.inside ? 1 : 0;
        if (tested[group[i]] == first + i) { // few, where groups are shared: a branch rarely taken
            ++tests;
            on_surface += result.on_surface ? 1 : 0;
            fallbacks += result.deciding_axis == 3 ? 1 : 0;
        }
    }
    DetectionStats& counts = m_stats.local();
    counts.candidate_vertices += count;
    counts.on_surface += on_surface;
    counts.winding_fallbacks += fallbacks;
    counts.by_neighbour += count - tests;
    counts.inside += inside_count;
    if (!m_contact_data)
        return;
    CORO_ASSERT(!m_nearest && answers.path.size() == answers.group.size()); // distance bounds wanted
    ContactPoint* slots = m_slots.data() + m_offsets[k] + static_cast<std::size_t>(first);
    Index hint_face = -1; // as in take() above
    for (Index i = 0; i < count; ++i) {
        if (!inside[i])
            continue;
        const auto c = static_cast<std::size_t>(first + i);
        const Index g = group[i];
        const double bound = tested[g] == first + i ? answer[g].surface_distance_bound
                                                    : shared_distance_bound(answers, c);
        slots[i] = contact_point(m_surfaces, pair.body, pair.vertices[c], pair.other, bound, hint_face);
        hint_face = slots[i].face;
    }
}

std::vector<ContactPoint> DetectionPass::finish(Index pairs, DetectionStats* stats)
{
    if (stats) {
        DetectionStats sum;
        sum.pairs = pairs;
        for (const DetectionStats& s : m_stats) {
            sum.candidate_vertices += s.candidate_vertices;
            sum.inside += s.inside;
            sum.winding_fallbacks += s.winding_fallbacks;
            sum.on_surface += s.on_surface;
            sum.by_neighbour += s.by_neighbour;
        }
        *stats = sum;
    }
    return sorted_points(m_surfaces, m_candidates, m_offsets, m_slots, m_inside);
}

} // namespace coro::detail
