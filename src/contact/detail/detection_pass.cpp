#include "detection_pass.hpp"

#include "nearest_search.hpp"

#include <corocontact/core/error.hpp>

#include <algorithm>
#include <array>
#include <cstdint>
#include <utility>

namespace coro::detail {

namespace {

/// Below this many faces a surface's depth searches prune by boxes only: a search in so small a
/// tree opens most of its nodes anyway, and making their face planes costs more than they save
/// (the bodies of a pile, ~110–130 faces: planes and searches 3× as long as boxes alone; two
/// spheres of 1,728 faces in deep overlap: 2.5× shorter with planes).
constexpr Index FACE_PLANES_FROM = 256;

bool uses_face_planes(const ContactSurface& surface) { return surface.faces.rows() >= FACE_PLANES_FROM; }

/// A test no axis decided (counted in DetectionStats::undecided_by_axes): the exact parity of a
/// closed surface, or the winding number of an open one.
bool is_fallback(DecidedBy by) { return by == DecidedBy::EXACT_PARITY || by == DecidedBy::WINDING_NUMBER; }

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
            if (!c.vertices.empty() && uses_face_planes(surfaces[static_cast<std::size_t>(c.other)]))
                m_state.planes[static_cast<std::size_t>(c.other)].reset(
                    surfaces[static_cast<std::size_t>(c.other)].tree);
    }
    // Points with depth and normal are made as the answers come; without, the sorted output
    // makes them from the candidates.
    m_state.slots.resize(contact_data ? offsets.back() : 0);
    m_state.inside.assign(offsets.back(), 0);
    for (DetectionStats& counts : m_state.stats) // zeroed, not cleared: a thread keeps its entry
        counts = DetectionStats{};
    if (contact_data && !(custom && custom->nearest))
        keep_last_faces();
}

void DetectionPass::keep_last_faces()
{
    CORO_ASSERT(m_state.directed.size() == m_candidates.size());
    std::vector<LastFaces>& last_faces = m_state.last_faces.assign(m_state.directed);
    for (std::size_t k = 0; k < m_candidates.size(); ++k) {
        const PairCandidates& pair = m_candidates[k];
        LastFaces& faces = last_faces[k];
        if (faces.body != pair.body || faces.other != pair.other) { // a new pair: no starts yet
            faces.body = pair.body;
            faces.other = pair.other;
            faces.face.clear();
        }
        faces.face.resize(static_cast<std::size_t>(m_surfaces[static_cast<std::size_t>(pair.body)].vertices.rows()), -1);
    }
}

template <class Start>
void DetectionPass::contact_points(std::size_t k, Index first, Index count, const unsigned char* inside,
                                   const Start& start)
{
    const PairCandidates& pair = m_candidates[k];
    const Positions& vertices = m_surfaces[static_cast<std::size_t>(pair.body)].vertices;
    ContactPoint* slots = m_state.slots.data() + m_state.offsets[k] + static_cast<std::size_t>(first);
    const auto point = [&](Index i) {
        return Vec3(vertices.row(pair.vertices[static_cast<std::size_t>(first + i)]).transpose());
    };
    const auto vertex = [&](Index i) { return pair.vertices[static_cast<std::size_t>(first + i)]; };
    if (m_custom && m_custom->nearest) { // the caller's search (e.g. Embree's point queries)
        for (Index i = 0; i < count; ++i)
            if (inside[i])
                slots[i] = make_point(m_surfaces, pair.body, vertex(i), pair.other,
                                      m_custom->nearest(pair.other, point(i), start(first + i).first));
        return;
    }
    const ContactSurface& other = m_surfaces[static_cast<std::size_t>(pair.other)];
    FacePlaneCache* planes = uses_face_planes(other) ? &m_state.planes[static_cast<std::size_t>(pair.other)] : nullptr;
    const NearestSearch search(other.tree, other.vertices, planes);
    // The inside vertices in packets of neighbours (they come in spatial order), searched
    // together. Each search starts from the vertex's answer of the last detection (its nearest
    // face moves little from step to step), else from the answer of the same place in the
    // previous packet (a neighbour), else from the face its inside test crossed. The answers do
    // not depend on the starts, only the work does; within a detection the starts depend only on
    // the block, not on the scheduling.
    Index* last = m_state.last_faces.items()[k].face.data();
    constexpr int PACKET = NearestSearch::PACKET;
    Vec3 points[PACKET];
    double bounds[PACKET];
    Index hints[PACKET], previous[PACKET], at[PACKET];
    std::fill(previous, previous + PACKET, Index{-1});
    NearestPoint found[PACKET];
    int n = 0;
    const auto flush = [&] {
        search.find_packet(points, n, bounds, hints, &other.faces, found);
        for (int q = 0; q < n; ++q) {
            slots[at[q]] = make_point(m_surfaces, pair.body, vertex(at[q]), pair.other, found[q]);
            previous[q] = found[q].face;
            last[vertex(at[q])] = found[q].face;
        }
        n = 0;
    };
    for (Index i = 0; i < count; ++i) {
        if (!inside[i])
            continue;
        const auto [bound, crossing] = start(first + i);
        points[n] = point(i);
        bounds[n] = bound;
        const Index v = vertex(i);
        hints[n] = last[v] >= 0 ? last[v] : previous[n] >= 0 ? previous[n] : crossing;
        at[n++] = i;
        if (n == PACKET)
            flush();
    }
    if (n > 0)
        flush();
}

void DetectionPass::count(Index candidates, Index inside, Index on_surface, Index fallbacks, Index by_neighbour)
{
    DetectionStats& counts = m_state.stats.local();
    counts.candidate_vertices += candidates;
    counts.inside += inside;
    counts.on_surface += on_surface;
    counts.undecided_by_axes += fallbacks;
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
        fallbacks += is_fallback(result.decided_by) ? 1 : 0;
        inside[i] = result.inside ? 1 : 0;
        inside_count += result.inside ? 1 : 0;
    }
    this->count(count, inside_count, on_surface, fallbacks, 0);
    if (!m_contact_data)
        return;
    contact_points(k, first, count, inside, [&](Index c) {
        const InsideTest& result = results[c - first];
        return std::pair{result.surface_distance_bound, result.crossing_face};
    });
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
            fallbacks += is_fallback(result.decided_by) ? 1 : 0;
        }
    }
    this->count(count, inside_count, on_surface, fallbacks, count - tests);
    if (!m_contact_data)
        return;
    CORO_ASSERT(answers.path.size() == answers.group.size()); // distance bounds wanted
    contact_points(k, first, count, inside, [&](Index c) {
        const Index g = answers.group[static_cast<std::size_t>(c)];
        const double bound = tested[g] == c ? answer[g].surface_distance_bound
                                            : shared_distance_bound(answers, static_cast<std::size_t>(c));
        return std::pair{bound, answer[g].crossing_face};
    });
}

void DetectionPass::sorted_points(std::vector<ContactPoint>& points)
{
    // Per body (the candidates are ordered by (body, other)), a counting sort by vertex of the
    // inside slots: count the slots of each vertex, turn the counts into places, put each slot
    // at its vertex's next place (the body's pairs taken in the order of their other surfaces),
    // then write the points in that order. Through raw pointers: the flags are bytes, which may
    // alias anything.
    const std::size_t* offsets = m_state.offsets.data();
    const unsigned char* inside = m_state.inside.data();
    std::size_t total = 0;
    for (std::size_t s = 0; s < m_state.inside.size(); ++s)
        total += inside[s];
    points.clear();
    points.reserve(total);
    for (std::size_t first = 0, last = 0; first < m_candidates.size(); first = last) {
        const Index body = m_candidates[first].body;
        while (last < m_candidates.size() && m_candidates[last].body == body)
            ++last;
        const auto vertices = static_cast<std::size_t>(m_surfaces[static_cast<std::size_t>(body)].vertices.rows());
        m_state.count.assign(vertices + 1, 0);
        Index* place = m_state.count.data();
        for (std::size_t k = first; k < last; ++k) {
            const Index* vertex = m_candidates[k].vertices.data();
            const unsigned char* flag = inside + offsets[k];
            const std::size_t n = m_candidates[k].vertices.size();
            for (std::size_t i = 0; i < n; ++i)
                place[vertex[i] + 1] += flag[i];
        }
        for (std::size_t v = 0; v < vertices; ++v)
            place[v + 1] += place[v];
        m_state.order.resize(static_cast<std::size_t>(place[vertices]));
        std::array<std::uint32_t, 2>* order = m_state.order.data(); // (pair, candidate)
        for (std::size_t k = first; k < last; ++k) {
            const Index* vertex = m_candidates[k].vertices.data();
            const unsigned char* flag = inside + offsets[k];
            const std::size_t n = m_candidates[k].vertices.size();
            for (std::size_t i = 0; i < n; ++i)
                if (flag[i])
                    order[place[vertex[i]]++] = {static_cast<std::uint32_t>(k), static_cast<std::uint32_t>(i)};
        }
        for (const auto& [k, i] : m_state.order) {
            if (m_contact_data) {
                points.push_back(m_state.slots[offsets[k] + i]);
                continue;
            }
            // Without contact data the slots hold no points: made from the candidates.
            ContactPoint& point = points.emplace_back();
            point.body = body;
            point.vertex = m_candidates[k].vertices[i];
            point.other = ContactTarget::surface(m_candidates[k].other);
        }
    }
    CORO_ASSERT(points.size() == total);
}

void DetectionPass::finish(Index pairs, DetectionStats* stats, std::vector<ContactPoint>& points, Index by_hull)
{
    if (stats) {
        DetectionStats sum;
        sum.pairs = pairs;
        sum.candidate_vertices = by_hull;
        sum.by_hull = by_hull;
        for (const DetectionStats& s : m_state.stats) {
            sum.candidate_vertices += s.candidate_vertices;
            sum.inside += s.inside;
            sum.undecided_by_axes += s.undecided_by_axes;
            sum.on_surface += s.on_surface;
            sum.by_neighbour += s.by_neighbour;
        }
        *stats = sum;
    }
    sorted_points(points);
}

} // namespace coro::detail
