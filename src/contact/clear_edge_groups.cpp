#include <corocontact/contact/aabb_tree.hpp>

#include "segment_triangle.hpp"

#if defined(__AVX2__)
#include <immintrin.h>
#endif

#include <algorithm>
#include <cmath>
#include <type_traits>
#include <vector>

namespace coro {

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
#if defined(__AVX2__)
        const __m256d a = _mm256_maskload_pd(p, xyz()), b = _mm256_maskload_pd(q, xyz());
        m_lo = _mm256_min_pd(b, a); // as std::min(p, q) and std::max(p, q), NaN included
        m_hi = _mm256_max_pd(b, a);
#else
        for (int j = 0; j < 3; ++j) {
            m_lo[j] = std::min(p[j], q[j]);
            m_hi[j] = std::max(p[j], q[j]);
        }
#endif
    }

    /// Whether the box of the triangle (a, b, c) (3 doubles each) misses the segment's.
    bool misses(const double* a, const double* b, const double* c) const
    {
#if defined(__AVX2__)
        // The fourth lanes hold 0 on both sides: never a miss.
        const __m256d pa = _mm256_maskload_pd(a, xyz()), pb = _mm256_maskload_pd(b, xyz());
        const __m256d pc = _mm256_maskload_pd(c, xyz());
        const __m256d min = _mm256_min_pd(_mm256_min_pd(pa, pb), pc);
        const __m256d max = _mm256_max_pd(_mm256_max_pd(pa, pb), pc);
        const __m256d miss = _mm256_or_pd(_mm256_cmp_pd(min, m_hi, _CMP_GT_OQ), _mm256_cmp_pd(max, m_lo, _CMP_LT_OQ));
        return _mm256_movemask_pd(miss) != 0;
#else
        bool miss = false; // min/max in the AVX2 operand order
        for (int j = 0; j < 3; ++j)
            miss = miss | (std::min(c[j], std::min(b[j], a[j])) > m_hi[j]) |
                   (std::max(c[j], std::max(b[j], a[j])) < m_lo[j]);
        return miss;
#endif
    }

private:
#if defined(__AVX2__)
    static __m256i xyz() { return _mm256_setr_epi64x(-1, -1, -1, 0); } // 3 doubles: no load past them
    __m256d m_lo, m_hi;
#else
    double m_lo[3], m_hi[3];
#endif
};

// Per-thread arrays kept from call to call, as large as the largest surface the thread has
// grouped (the grouping starts no tasks, so a thread runs one call at a time), instead of
// allocating and filling two arrays the size of the whole surface in every call while only a
// band of it is paired. Between calls, paired_id holds −1 everywhere: a call resets the entries
// of its pairs. And state holds no UNGROUPED: a call sets its candidates to UNGROUPED (after
// every allocation) and the search puts each in a group; any other value stops the search as
// NOT_CANDIDATE does, so stale groups need no reset.
struct Scratch {
    std::vector<Index> paired_id; // by slot of this surface
    std::vector<Index> state;     // by vertex
    std::vector<Index> start, partners, next, queue;
    std::vector<double> length_to; // by vertex, valid where grouped
};

thread_local Scratch scratch;

// Resets the entries of paired_id that a call set, however it ends.
struct PairedIdReset {
    const std::vector<std::array<Index, 2>>& slot_pairs;
    std::size_t mine;
    ~PairedIdReset()
    {
        for (const auto& pair : slot_pairs)
            scratch.paired_id[static_cast<std::size_t>(pair[mine])] = -1;
    }
};

} // namespace

Index AabbTree::clear_edge_groups(CRef<Positions> vertices, const AabbTree& other, CRef<Positions> other_vertices,
                                  const std::vector<std::array<Index, 2>>& slot_pairs, int column,
                                  const std::vector<Index>& candidates, std::vector<Index>& group,
                                  std::vector<Index>& firsts, std::vector<double>* path) const
{
    const std::size_t n = candidates.size();

    // The faces of `other` paired with each paired face of this surface (slots of both trees):
    // paired slots get dense ids, the partners of id j are partners[start[j], start[j + 1]).
    const auto mine = static_cast<std::size_t>(column), theirs = 1 - mine;
    if (scratch.paired_id.size() < m_order.size())
        scratch.paired_id.resize(m_order.size(), -1);
    const std::size_t vertex_count = m_edge_start.empty() ? 0 : m_edge_start.size() - 1;
    if (scratch.state.size() < vertex_count)
        scratch.state.resize(vertex_count, NOT_CANDIDATE);
    // Every array sized before any entry is set, so that a failed allocation leaves the
    // invariants below intact.
    if (scratch.start.size() < slot_pairs.size() + 1)
        scratch.start.resize(slot_pairs.size() + 1);
    if (scratch.next.size() < slot_pairs.size())
        scratch.next.resize(slot_pairs.size());
    if (scratch.partners.size() < slot_pairs.size())
        scratch.partners.resize(slot_pairs.size());
    if (path && scratch.length_to.size() < vertex_count) // when a path is wanted
        scratch.length_to.resize(vertex_count);
    if (scratch.queue.size() < n)
        scratch.queue.resize(n);
    group.resize(n);
    firsts.clear();
    firsts.reserve(n); // no allocation once the states below are set
    if (path)
        path->resize(n);
    const PairedIdReset reset{slot_pairs, mine};
    // Raw pointers into the thread's arrays: through the vectors, every store or call in the
    // loops below made the compiler load their data pointers again.
    Index* const paired_id = scratch.paired_id.data();

    Index* const start = scratch.start.data();
    Index* const partners = scratch.partners.data();
    std::size_t ids = 0;
    start[0] = 0;
    for (const auto& pair : slot_pairs) {
        Index& id = paired_id[static_cast<std::size_t>(pair[mine])];
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
        for (const auto& pair : slot_pairs) {
            const Index id = paired_id[static_cast<std::size_t>(pair[mine])];
            partners[static_cast<std::size_t>(next[static_cast<std::size_t>(id)]++)] = pair[theirs];
        }
    }

    const double* data = vertices.data();
    const std::ptrdiff_t stride = vertices.outerStride();
    const double* other_data = other_vertices.data();
    const std::ptrdiff_t other_stride = other_vertices.outerStride();
    // A face of `other` that meets the edge meets the box of each face holding it: test the
    // partners of the face with fewer (a face with none: the edge is clear, below). Not inlined:
    // in the search's loop over edges it made that loop spill registers.
    const auto paired_edge_clear = [&](Index u, Index v, Index id0, Index id1) __attribute__((noinline)) {
        const auto count = [&](Index id) {
            return start[static_cast<std::size_t>(id) + 1] - start[static_cast<std::size_t>(id)];
        };
        const Index id = count(id0) <= count(id1) ? id0 : id1;
        const double* p = data + stride * u;
        const double* q = data + stride * v;
        const SegmentBox segment_box(p, q);
        // The faces whose boxes meet the edge's are tested TRIANGLE_LANES at a time.
        const double* corner[3][detail::TRIANGLE_LANES];
        int taken = 0;
        const auto batch_clear = [&] {
            const int clear = detail::segment_misses_triangles(p, q, corner[0], corner[1], corner[2], taken);
            return clear == (1 << taken) - 1;
        };
        for (Index k = start[static_cast<std::size_t>(id)]; k < start[static_cast<std::size_t>(id) + 1]; ++k) {
            const std::size_t g = static_cast<std::size_t>(partners[static_cast<std::size_t>(k)]);
            const Index* fv = &other.m_slot_vertices[3 * g];
            const double* a = other_data + other_stride * fv[0];
            const double* b = other_data + other_stride * fv[1];
            const double* c = other_data + other_stride * fv[2];
            if (segment_box.misses(a, b, c))
                continue;
            corner[0][taken] = a;
            corner[1][taken] = b;
            corner[2][taken] = c;
            if (++taken == detail::TRIANGLE_LANES) {
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
    // The search with or without path lengths, compiled apart: the test of `path` in the loop
    // over edges kept the lengths' loads and address arithmetic in it.
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
                // rarely cached at the start of a frame (the other work of a step evicts them),
                // which made this pass wait on memory: the loads of the edges of a vertex a few
                // places ahead start now, its m_edge_start entry having been prefetched when it
                // was queued.
                const Index ahead = queue[std::min(head + PREFETCH_AHEAD, tail - 1)];
                const auto ahead_edges = static_cast<std::size_t>(m_edge_start[static_cast<std::size_t>(ahead)]);
                __builtin_prefetch(m_edge_vertex.data() + ahead_edges); // may be one past the end
                __builtin_prefetch(m_edge_slots.data() + ahead_edges);
                const Index u = queue[head++];
                const Index end = m_edge_start[static_cast<std::size_t>(u) + 1];
                for (Index k = m_edge_start[static_cast<std::size_t>(u)]; k < end; ++k) {
                    const Index v = m_edge_vertex[static_cast<std::size_t>(k)];
                    Index& s = state[static_cast<std::size_t>(v)];
                    if (s != UNGROUPED)
                        continue;
                    const std::array<Index, 2>& slots = m_edge_slots[static_cast<std::size_t>(k)];
                    const Index id0 = paired_id[static_cast<std::size_t>(slots[0])];
                    const Index id1 = paired_id[static_cast<std::size_t>(slots[1])];
                    if (id0 >= 0 && id1 >= 0 && !paired_edge_clear(u, v, id0, id1))
                        continue;
                    s = number;
                    queue[tail++] = v;
                    __builtin_prefetch(&m_edge_start[static_cast<std::size_t>(v)]);
                    if constexpr (with_path) {
                        // The sum rounded up by a relative 2⁻⁴⁰, far above the rounding of its terms.
                        const double* x = data + stride * u;
                        const double* y = data + stride * v;
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
    if (path) {
        for (std::size_t i = 0; i < n; ++i)
            (*path)[i] = length_to[static_cast<std::size_t>(candidates[i])];
    }
    return static_cast<Index>(firsts.size());
}

} // namespace coro
