#include "detection_pass.hpp"

#include "nearest_search.hpp"

#include <corocontact/core/error.hpp>

#include <algorithm>

namespace coro::detail {

namespace {

/// The contact point of `vertex` of `body` inside `other` whose nearest point on the other
/// surface is `nearest`: its distance as depth, its face's outward unit normal.
ContactPoint make_point(const std::vector<ContactSurface>& surfaces, Index body, Index vertex, Index other,
                        const NearestPoint& nearest)
{
    const ContactSurface& b = surfaces[static_cast<std::size_t>(other)];
    ContactPoint c;
    c.body = body;
    c.vertex = vertex;
    c.other = ContactTarget::surface(other);
    c.depth = nearest.distance;
    c.face = nearest.face;
    c.barycentric = nearest.barycentric;
    if (nearest.face >= 0) {
        const Vec3 x0 = b.vertices.row(b.faces(nearest.face, 0)).transpose();
        const Vec3 x1 = b.vertices.row(b.faces(nearest.face, 1)).transpose();
        const Vec3 x2 = b.vertices.row(b.faces(nearest.face, 2)).transpose();
        const Vec3 n = (x1 - x0).cross(x2 - x0);
        if (n.norm() > 0.0) {
            c.normal = n.normalized();
        } else if (nearest.distance > 0.0) { // a degenerate face: the direction to its point
            const Vec3 p = surfaces[static_cast<std::size_t>(body)].vertices.row(vertex).transpose();
            c.normal = (nearest.point - p) / nearest.distance;
        }
    }
    return c;
}

} // namespace

DetectionPass::DetectionPass(const std::vector<ContactSurface>& surfaces, const std::vector<PairCandidates>& candidates,
                             bool contact_data, DetectionState& state, const CustomNarrowPhase* custom)
    : m_surfaces(surfaces), m_candidates(candidates), m_contact_data(contact_data), m_state(state), m_custom(custom)
{
    std::vector<std::size_t>& offsets = m_state.offsets;
    offsets.assign(candidates.size() + 1, 0);
    for (std::size_t k = 0; k < candidates.size(); ++k)
        offsets[k + 1] = offsets[k] + candidates[k].vertices.size();
    if (contact_data && !(custom && custom->nearest)) {
        // The trees' searches compute the face planes they need as they go: forget the last call's.
        if (m_state.planes.size() < surfaces.size())
            m_state.planes.resize(surfaces.size());
        for (const PairCandidates& c : candidates)
            if (!c.vertices.empty())
                m_state.planes[static_cast<std::size_t>(c.other)].reset(
                    surfaces[static_cast<std::size_t>(c.other)].tree);
    }
    // Points with depth and normal are made as the answers come; without, the sorted output
    // makes them from the candidates.
    m_state.slots.resize(contact_data ? offsets.back() : 0);
    m_state.inside.assign(offsets.back(), 0);
    m_state.stats.clear();
}

ContactPoint DetectionPass::contact_point(std::size_t k, std::size_t i, double distance_bound, Index hint_face) const
{
    const PairCandidates& pair = m_candidates[k];
    const Index vertex = pair.vertices[i];
    const Vec3 p = m_surfaces[static_cast<std::size_t>(pair.body)].vertices.row(vertex).transpose();
    if (m_custom && m_custom->nearest) // the caller's search (e.g. Embree's point queries)
        return make_point(m_surfaces, pair.body, vertex, pair.other, m_custom->nearest(pair.other, p, distance_bound));
    const ContactSurface& other = m_surfaces[static_cast<std::size_t>(pair.other)];
    const NearestSearch search(other.tree, other.vertices, &m_state.planes[static_cast<std::size_t>(pair.other)]);
    return make_point(m_surfaces, pair.body, vertex, pair.other, search.find(p, distance_bound, hint_face, &other.faces));
}

void DetectionPass::count(Index candidates, Index inside, Index on_surface, Index fallbacks, Index by_neighbour)
{
    DetectionStats& counts = m_state.stats.local();
    counts.candidate_vertices += candidates;
    counts.inside += inside;
    counts.on_surface += on_surface;
    counts.winding_fallbacks += fallbacks;
    counts.by_neighbour += by_neighbour;
}

void DetectionPass::take(std::size_t k, Index first, Index count, const InsideTest* results)
{
    unsigned char* inside = m_state.inside.data() + m_state.offsets[k] + static_cast<std::size_t>(first);
    // Counted in locals: the flags are bytes, which may alias anything in memory.
    Index on_surface = 0, fallbacks = 0, inside_count = 0;
    for (Index i = 0; i < count; ++i) {
        const InsideTest& result = results[i];
        on_surface += result.on_surface ? 1 : 0;
        fallbacks += result.decided_by == DecidedBy::WINDING_NUMBER ? 1 : 0;
        inside[i] = result.inside ? 1 : 0;
        inside_count += result.inside ? 1 : 0;
    }
    this->count(count, inside_count, on_surface, fallbacks, 0);
    if (!m_contact_data)
        return;
    // Each search starts from the nearest face of the block's previous inside vertex (vertices
    // come in spatial order), else from the face its inside test crossed. Per block, so that the
    // work does not depend on the scheduling (the answers do not depend on the starts at all).
    ContactPoint* slots = m_state.slots.data() + m_state.offsets[k] + static_cast<std::size_t>(first);
    Index hint_face = -1;
    for (Index i = 0; i < count; ++i) {
        if (!results[i].inside)
            continue;
        slots[i] = contact_point(k, static_cast<std::size_t>(first + i), results[i].surface_distance_bound,
                                 hint_face >= 0 ? hint_face : results[i].crossing_face);
        hint_face = slots[i].face;
    }
}

void DetectionPass::take(std::size_t k, Index first, Index count, const GroupedAnswers& answers)
{
    unsigned char* inside = m_state.inside.data() + m_state.offsets[k] + static_cast<std::size_t>(first);
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
            fallbacks += result.decided_by == DecidedBy::WINDING_NUMBER ? 1 : 0;
        }
    }
    this->count(count, inside_count, on_surface, fallbacks, count - tests);
    if (!m_contact_data)
        return;
    CORO_ASSERT(answers.path.size() == answers.group.size()); // distance bounds wanted
    ContactPoint* slots = m_state.slots.data() + m_state.offsets[k] + static_cast<std::size_t>(first);
    Index hint_face = -1; // as in take() above
    for (Index i = 0; i < count; ++i) {
        if (!inside[i])
            continue;
        const auto c = static_cast<std::size_t>(first + i);
        const Index g = group[i];
        const double bound = tested[g] == first + i ? answer[g].surface_distance_bound
                                                    : shared_distance_bound(answers, c);
        slots[i] = contact_point(k, c, bound, hint_face >= 0 ? hint_face : answer[g].crossing_face);
        hint_face = slots[i].face;
    }
}

std::vector<ContactPoint> DetectionPass::sorted_points()
{
    // Per body (the candidates are ordered by (body, other)), a counting sort by vertex: count
    // the inside slots of each vertex, turn the counts into places, and put each point at its
    // vertex's next place, the body's pairs taken in the order of their other surfaces.
    const std::vector<std::size_t>& offsets = m_state.offsets;
    const std::vector<unsigned char>& inside = m_state.inside;
    std::size_t total = 0;
    for (const unsigned char flag : inside)
        total += flag;
    std::vector<ContactPoint> points(total);
    std::vector<Index>& place = m_state.count;
    std::size_t base = 0;
    for (std::size_t first = 0, last = 0; first < m_candidates.size(); first = last) {
        const Index body = m_candidates[first].body;
        while (last < m_candidates.size() && m_candidates[last].body == body)
            ++last;
        const auto vertices = static_cast<std::size_t>(m_surfaces[static_cast<std::size_t>(body)].vertices.rows());
        place.assign(vertices + 1, 0);
        for (std::size_t k = first; k < last; ++k)
            for (std::size_t i = 0; i < m_candidates[k].vertices.size(); ++i)
                place[static_cast<std::size_t>(m_candidates[k].vertices[i]) + 1] += inside[offsets[k] + i];
        for (std::size_t v = 0; v < vertices; ++v)
            place[v + 1] += place[v];
        const auto in_body = static_cast<std::size_t>(place[vertices]);
        for (std::size_t k = first; k < last; ++k) {
            const PairCandidates& pair = m_candidates[k];
            for (std::size_t i = 0; i < pair.vertices.size(); ++i) {
                if (!inside[offsets[k] + i])
                    continue;
                const Index v = pair.vertices[i];
                ContactPoint& point = points[base + static_cast<std::size_t>(place[static_cast<std::size_t>(v)]++)];
                if (m_contact_data) {
                    point = m_state.slots[offsets[k] + i];
                } else {
                    point.body = body;
                    point.vertex = v;
                    point.other = ContactTarget::surface(pair.other);
                }
            }
        }
        base += in_body;
    }
    CORO_ASSERT(base == total);
    return points;
}

std::vector<ContactPoint> DetectionPass::finish(Index pairs, DetectionStats* stats)
{
    if (stats) {
        DetectionStats sum;
        sum.pairs = pairs;
        for (const DetectionStats& s : m_state.stats) {
            sum.candidate_vertices += s.candidate_vertices;
            sum.inside += s.inside;
            sum.winding_fallbacks += s.winding_fallbacks;
            sum.on_surface += s.on_surface;
            sum.by_neighbour += s.by_neighbour;
        }
        *stats = sum;
    }
    return sorted_points();
}

} // namespace coro::detail
