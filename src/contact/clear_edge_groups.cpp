#include <corocontact/contact/aabb_tree.hpp>

#include "segment_triangle.hpp"

#include <cmath>

namespace coro {

Index AabbTree::clear_edge_groups(CRef<Positions> vertices, const AabbTree& other, CRef<Positions> other_vertices,
                                  const std::vector<std::array<Index, 2>>& face_pairs, int column,
                                  const std::vector<Index>& candidates, std::vector<Index>& decider,
                                  std::vector<double>* path) const
{
    const std::size_t n = candidates.size();
    decider.assign(n, -1);
    if (path)
        path->assign(n, 0.0);

    // The faces of `other` paired with each face of this surface, by slot (of both trees).
    const auto mine = static_cast<std::size_t>(column), theirs = 1 - mine;
    std::vector<Index> partner_start(m_order.size() + 1, 0);
    for (const auto& pair : face_pairs)
        ++partner_start[static_cast<std::size_t>(m_slot_of_face[static_cast<std::size_t>(pair[mine])]) + 1];
    for (std::size_t s = 0; s < m_order.size(); ++s)
        partner_start[s + 1] += partner_start[s];
    std::vector<Index> partners(face_pairs.size());
    {
        std::vector<Index> next(partner_start.begin(), partner_start.end() - 1);
        for (const auto& pair : face_pairs)
            partners[static_cast<std::size_t>(next[static_cast<std::size_t>(
                m_slot_of_face[static_cast<std::size_t>(pair[mine])])]++)] =
                other.m_slot_of_face[static_cast<std::size_t>(pair[theirs])];
    }
    const auto partner_count = [&](Index slot) {
        return partner_start[static_cast<std::size_t>(slot) + 1] - partner_start[static_cast<std::size_t>(slot)];
    };

    const double* data = vertices.data();
    const std::ptrdiff_t stride = vertices.outerStride();
    const double* other_data = other_vertices.data();
    const std::ptrdiff_t other_stride = other_vertices.outerStride();
    // A face of `other` that meets the edge meets the box of each face holding it: test the
    // partners of the face with fewer (none: the edge is clear).
    const auto edge_clear = [&](Index u, const VertexEdge& e) {
        const Index slot = partner_count(e.slot[0]) <= partner_count(e.slot[1]) ? e.slot[0] : e.slot[1];
        const Index first = partner_start[static_cast<std::size_t>(slot)];
        const Index last = partner_start[static_cast<std::size_t>(slot) + 1];
        if (first == last)
            return true;
        const double* p = data + stride * u;
        const double* q = data + stride * e.vertex;
        const double lo[3] = {std::min(p[0], q[0]), std::min(p[1], q[1]), std::min(p[2], q[2])};
        const double hi[3] = {std::max(p[0], q[0]), std::max(p[1], q[1]), std::max(p[2], q[2])};
        for (Index k = first; k < last; ++k) {
            const std::size_t g = static_cast<std::size_t>(partners[static_cast<std::size_t>(k)]);
            const Aabb& fb = other.m_face_boxes[g];
            if (fb.min[0] > hi[0] || fb.min[1] > hi[1] || fb.min[2] > hi[2] || fb.max[0] < lo[0] ||
                fb.max[1] < lo[1] || fb.max[2] < lo[2])
                continue;
            const Index* fv = &other.m_slot_vertices[3 * g];
            if (!detail::segment_misses_triangle(p, q, other_data + other_stride * fv[0],
                                                 other_data + other_stride * fv[1], other_data + other_stride * fv[2]))
                return false;
        }
        return true;
    };

    // Breadth-first from each candidate not yet grouped, in the order given.
    std::vector<Index> local(m_edge_start.empty() ? 0 : m_edge_start.size() - 1, -1);
    for (std::size_t i = 0; i < n; ++i)
        local[static_cast<std::size_t>(candidates[i])] = static_cast<Index>(i);
    std::vector<Index> queue;
    queue.reserve(n);
    Index groups = 0;
    for (std::size_t i = 0; i < n; ++i) {
        if (decider[i] >= 0)
            continue;
        ++groups;
        decider[i] = static_cast<Index>(i);
        queue.assign(1, static_cast<Index>(i));
        for (std::size_t head = 0; head < queue.size(); ++head) {
            const Index a = queue[head];
            const Index u = candidates[static_cast<std::size_t>(a)];
            for (Index k = m_edge_start[static_cast<std::size_t>(u)]; k < m_edge_start[static_cast<std::size_t>(u) + 1];
                 ++k) {
                const VertexEdge& e = m_edges[static_cast<std::size_t>(k)];
                const Index b = local[static_cast<std::size_t>(e.vertex)];
                if (b < 0 || decider[static_cast<std::size_t>(b)] >= 0 || !edge_clear(u, e))
                    continue;
                decider[static_cast<std::size_t>(b)] = static_cast<Index>(i);
                queue.push_back(b);
                if (!path)
                    continue;
                // The sum rounded up by a relative 2⁻⁴⁰, far above the rounding of its terms.
                const double* x = data + stride * u;
                const double* y = data + stride * e.vertex;
                const double length =
                    std::sqrt((x[0] - y[0]) * (x[0] - y[0]) + (x[1] - y[1]) * (x[1] - y[1]) + (x[2] - y[2]) * (x[2] - y[2]));
                std::vector<double>& p = *path;
                p[static_cast<std::size_t>(b)] = (p[static_cast<std::size_t>(a)] + length) * (1.0 + 0x1p-40);
            }
        }
    }
    return groups;
}

} // namespace coro
