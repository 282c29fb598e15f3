#include "clear_edge_groups.hpp"

#include <corocontact/core/error.hpp>

#include "segment_triangle.hpp"
#include "simd.hpp"
#include "tree_access.hpp"

#include <algorithm>
#include <cmath>
#include <type_traits>

namespace coro::detail {

namespace {

// Vertex states during the search: not a candidate, or a candidate not yet in a group; a
// grouped candidate holds its group's number (≥ 0).
constexpr Index NOT_CANDIDATE = -2;
constexpr Index UNGROUPED = -1;

// Queue places between a vertex whose edges are prefetched and the vertex being expanded.
constexpr std::size_t PREFETCH_AHEAD = 8;

/// The box of a segment [p, q], tested against the boxes of triangles (closed) without a branch
/// per bound: which of six is the first to fail is hard to predict.
class SegmentBox {
public:
    SegmentBox(const double* p, const double* q)
    {
        const simd::D4 a = simd::load_point(p), b = simd::load_point(q);
        m_lo = min(b, a); // as std::min(p, q) and std::max(p, q), NaN included
        m_hi = max(b, a);
    }

    /// Whether the box of the triangle (a, b, c) (3 doubles each) misses the segment's (the
    /// fourth lanes hold 0 on both sides: never a miss).
    bool misses(const double* a, const double* b, const double* c) const
    {
        const simd::D4 pa = simd::load_point(a), pb = simd::load_point(b), pc = simd::load_point(c);
        return ((min(min(pa, pb), pc) > m_hi) | (max(max(pa, pb), pc) < m_lo)).bits() != 0;
    }

private:
    simd::D4 m_lo, m_hi;
};

/// Resets the entries of `paired` that a call set, however it ends.
struct PairedReset {
    std::vector<Index>& paired;
    const SlotPairs& pairs;
    std::size_t mine;
    ~PairedReset()
    {
        for (const auto& pair : pairs)
            paired[static_cast<std::size_t>(pair[mine])] = -1;
    }
};

} // namespace

void check_edges_and_tree(const ContactSurface& surface)
{
    CORO_CHECK(surface.edges.start.size() == static_cast<std::size_t>(surface.vertices.rows()) + 1 &&
                   surface.edges.tree_slots.size() == surface.edges.vertex.size() &&
                   surface.tree.num_faces() == surface.faces.rows(),
               InputError,
               "surface '" << surface.name
                           << "': its edges and tree were not built with it (make contact surfaces with "
                              "ContactSurface::from_body or from_embedding)");
}

Index clear_edge_groups(const ContactSurface& surface, const ContactSurface& other, const SlotPairs& pairs,
                        PairColumn column, const std::vector<Index>& candidates, GroupScratch& scratch,
                        std::vector<Index>& group, std::vector<Index>& firsts, std::vector<double>* path)
{
    const std::size_t n = candidates.size();
    const auto face_count = static_cast<std::size_t>(surface.faces.rows());
    const auto vertex_count = static_cast<std::size_t>(surface.vertices.rows());

    // Every array sized before any entry is set, so that a failed allocation leaves the
    // invariants of the scratch intact.
    if (scratch.paired.size() < face_count)
        scratch.paired.resize(face_count, -1);
    if (scratch.state.size() < vertex_count)
        scratch.state.resize(vertex_count, NOT_CANDIDATE);
    if (scratch.start.size() < pairs.size() + 1)
        scratch.start.resize(pairs.size() + 1);
    if (scratch.next.size() < pairs.size())
        scratch.next.resize(pairs.size());
    if (scratch.partners.size() < pairs.size())
        scratch.partners.resize(pairs.size());
    if (path && scratch.length_to.size() < vertex_count)
        scratch.length_to.resize(vertex_count);
    if (scratch.queue.size() < n)
        scratch.queue.resize(n);
    group.resize(n);
    firsts.clear();
    firsts.reserve(n); // no allocation once the states below are set
    if (path)
        path->resize(n);

    // The faces of `other` paired with each paired face of this surface, all as tree slots (the
    // trees' leaf order, in which neighbouring faces lie close in memory; the edges give theirs
    // in SurfaceEdges::tree_slots): paired faces get dense ids, the partners of id j are
    // partners[start[j], start[j + 1]). Raw pointers: through the vectors, the compiler would load
    // their data pointers again after every store or call in the loops below.
    const std::size_t mine = column == PairColumn::FIRST ? 0 : 1, theirs = 1 - mine;
    const PairedReset reset{scratch.paired, pairs, mine};
    Index* const paired = scratch.paired.data();
    Index* const start = scratch.start.data();
    Index* const partners = scratch.partners.data();
    std::size_t ids = 0;
    start[0] = 0;
    for (const auto& pair : pairs) {
        Index& id = paired[static_cast<std::size_t>(pair[mine])];
        if (id < 0) {
            id = static_cast<Index>(ids++);
            start[ids] = 0;
        }
        ++start[static_cast<std::size_t>(id) + 1];
    }
    for (std::size_t j = 1; j <= ids; ++j)
        start[j] += start[j - 1];
    {
        Index* const next = scratch.next.data();
        std::copy(start, start + ids, next);
        for (const auto& pair : pairs) {
            const Index id = paired[static_cast<std::size_t>(pair[mine])];
            partners[static_cast<std::size_t>(next[static_cast<std::size_t>(id)]++)] = pair[theirs];
        }
    }

    const double* data = surface.vertices.data();
    const double* other_data = other.vertices.data();
    const Index* other_corners = TreeAccess::slot_vertices(other.tree, 0);
    // A face of `other` that meets the edge meets the box of each face holding it: test the
    // partners of the face with fewer (a face with none: the edge is clear, below). Not inlined:
    // inlined, it makes the search's loop over edges spill registers.
    const auto paired_edge_clear = [&](Index u, Index v, Index id0, Index id1) __attribute__((noinline)) {
        const auto count = [&](Index id) {
            return start[static_cast<std::size_t>(id) + 1] - start[static_cast<std::size_t>(id)];
        };
        const Index id = count(id0) <= count(id1) ? id0 : id1;
        const double* p = data + 3 * static_cast<std::ptrdiff_t>(u);
        const double* q = data + 3 * static_cast<std::ptrdiff_t>(v);
        const SegmentBox segment_box(p, q);
        // The faces whose boxes meet the edge's are tested TRIANGLE_LANES at a time.
        const double* corner[3][TRIANGLE_LANES];
        int taken = 0;
        const auto batch_clear = [&] {
            const int clear = segment_misses_triangles(p, q, corner[0], corner[1], corner[2], taken);
            return clear == (1 << taken) - 1;
        };
        for (Index k = start[static_cast<std::size_t>(id)]; k < start[static_cast<std::size_t>(id) + 1]; ++k) {
            const Index* fv = other_corners + 3 * static_cast<std::ptrdiff_t>(partners[static_cast<std::size_t>(k)]);
            const double* a = other_data + 3 * static_cast<std::ptrdiff_t>(fv[0]);
            const double* b = other_data + 3 * static_cast<std::ptrdiff_t>(fv[1]);
            const double* c = other_data + 3 * static_cast<std::ptrdiff_t>(fv[2]);
            if (segment_box.misses(a, b, c))
                continue;
            corner[0][taken] = a;
            corner[1][taken] = b;
            corner[2][taken] = c;
            if (++taken == TRIANGLE_LANES) {
                if (!batch_clear())
                    return false;
                taken = 0;
            }
        }
        return taken == 0 || batch_clear();
    };

    // Breadth-first from each candidate not yet grouped, in the order given; the search works on
    // vertex numbers, one state per vertex of this surface.
    Index* const state = scratch.state.data();
    for (const Index v : candidates)
        state[static_cast<std::size_t>(v)] = UNGROUPED;
    double* const length_to = scratch.length_to.data();
    Index* const queue = scratch.queue.data();
    const Index* const edge_start = surface.edges.start.data();
    const Index* const edge_vertex = surface.edges.vertex.data();
    const std::array<Index, 2>* const edge_faces = surface.edges.tree_slots.data();
    // The search with or without path lengths, compiled apart, so that the loop over edges
    // carries the lengths' loads and address arithmetic only when they are wanted.
    const auto search = [&](auto with_path) {
        for (std::size_t i = 0; i < n; ++i) {
            const Index first = candidates[i];
            if (state[static_cast<std::size_t>(first)] != UNGROUPED)
                continue;
            const auto number = static_cast<Index>(firsts.size());
            firsts.push_back(static_cast<Index>(i));
            state[static_cast<std::size_t>(first)] = number;
            if constexpr (with_path)
                length_to[static_cast<std::size_t>(first)] = 0.0;
            std::size_t head = 0, tail = 0;
            queue[tail++] = first;
            while (head < tail) {
                // The edges of consecutive vertices in the queue lie far apart in memory and are
                // rarely cached at the start of a frame (the other work of a step evicts them):
                // the loads of the edges of a vertex a few places ahead start now (its start
                // entry is prefetched when it is queued).
                const Index ahead = queue[std::min(head + PREFETCH_AHEAD, tail - 1)];
                const auto ahead_edges = static_cast<std::size_t>(edge_start[static_cast<std::size_t>(ahead)]);
                __builtin_prefetch(edge_vertex + ahead_edges); // may be one past the end
                __builtin_prefetch(edge_faces + ahead_edges);
                const Index u = queue[head++];
                const Index end = edge_start[static_cast<std::size_t>(u) + 1];
                for (Index k = edge_start[static_cast<std::size_t>(u)]; k < end; ++k) {
                    const Index v = edge_vertex[static_cast<std::size_t>(k)];
                    Index& s = state[static_cast<std::size_t>(v)];
                    if (s != UNGROUPED)
                        continue;
                    const std::array<Index, 2>& faces = edge_faces[static_cast<std::size_t>(k)];
                    const Index id0 = paired[static_cast<std::size_t>(faces[0])];
                    const Index id1 = paired[static_cast<std::size_t>(faces[1])];
                    if (id0 >= 0 && id1 >= 0 && !paired_edge_clear(u, v, id0, id1))
                        continue;
                    s = number;
                    queue[tail++] = v;
                    __builtin_prefetch(&edge_start[static_cast<std::size_t>(v)]);
                    if constexpr (with_path) {
                        // The sum rounded up by a relative 2⁻⁴⁰, far above the rounding of its terms.
                        const double* x = data + 3 * static_cast<std::ptrdiff_t>(u);
                        const double* y = data + 3 * static_cast<std::ptrdiff_t>(v);
                        const double length = std::sqrt((x[0] - y[0]) * (x[0] - y[0]) + (x[1] - y[1]) * (x[1] - y[1]) +
                                                        (x[2] - y[2]) * (x[2] - y[2]));
                        length_to[static_cast<std::size_t>(v)] =
                            (length_to[static_cast<std::size_t>(u)] + length) * (1.0 + 0x1p-40);
                    }
                }
            }
        }
    };
    if (path)
        search(std::true_type{});
    else
        search(std::false_type{});
    for (std::size_t i = 0; i < n; ++i)
        group[i] = state[static_cast<std::size_t>(candidates[i])];
    if (path)
        for (std::size_t i = 0; i < n; ++i)
            (*path)[i] = length_to[static_cast<std::size_t>(candidates[i])];
    return static_cast<Index>(firsts.size());
}

} // namespace coro::detail
