// AabbTree: build, refit and the box queries. The walks the detector runs over a tree (axis
// lines, nearest points with face planes, face pairs) are in detail/.
#include <corocontact/contact/aabb_tree.hpp>

#include <corocontact/core/error.hpp>

#include "detail/nearest_search.hpp"
#include "detail/simd.hpp"
#include "detail/tree_access.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <limits>
#include <numeric>

namespace coro {

namespace {

/// Vertices per box of vertices_in_box().
constexpr std::size_t VERTEX_BLOCK = 32;
/// Subtrees of more faces get no slab: computing one costs a pass over their vertices.
constexpr Index SLAB_MAX_FACES = 1024;

Vec3 row(CRef<Positions> vertices, Index i) { return vertices.row(i).transpose(); }

} // namespace

Index AabbTree::build_node(const std::vector<Vec3>& centroids, Index begin, Index end, int depth)
{
    CORO_CHECK(depth < MAX_DEPTH, NumericalError, "AABB tree of " << m_face_of_slot.size() << " faces is deeper than "
                                                                  << MAX_DEPTH << " levels");
    const Index node = static_cast<Index>(m_nodes.size());
    m_nodes.emplace_back();
    m_node_slots.push_back(begin);
    m_node_slots.push_back(end);
    // Up to four parts, kept in range order, each a whole number of `unit` faces (the faces of a
    // full subtree: 1, 4, 16, …) but one: the largest part is split along the longest axis of
    // its centroids, as near its median as whole units allow, until there are `target` parts.
    // So a node has four children but at most one per level has fewer: walks, queries and refits
    // pay for every empty lane.
    const Index n = end - begin;
    Index unit = 1;
    while (4 * unit < n)
        unit *= 4;
    const int target = static_cast<int>((n + unit - 1) / unit);
    Index bounds[5] = {begin, end, end, end, end};
    int parts = 1;
    while (parts < target) {
        int largest = 0;
        for (int k = 1; k < parts; ++k)
            if (bounds[k + 1] - bounds[k] > bounds[largest + 1] - bounds[largest])
                largest = k;
        const Index b = bounds[largest], e = bounds[largest + 1];
        const Index units = (e - b + unit - 1) / unit;
        if (units < 2)
            break;
        Aabb spread;
        for (Index i = b; i < e; ++i)
            spread.extend(centroids[static_cast<std::size_t>(m_face_of_slot[static_cast<std::size_t>(i)])]);
        int axis = 0;
        (spread.max - spread.min).maxCoeff(&axis);
        const Index mid = b + unit * (units / 2);
        std::nth_element(m_face_of_slot.begin() + b, m_face_of_slot.begin() + mid, m_face_of_slot.begin() + e,
                         [&](Index x, Index y) {
                             const double cx = centroids[static_cast<std::size_t>(x)][axis];
                             const double cy = centroids[static_cast<std::size_t>(y)][axis];
                             return cx < cy || (cx == cy && x < y);
                         });
        for (int k = parts; k > largest; --k)
            bounds[k + 1] = bounds[k];
        bounds[largest + 1] = mid;
        ++parts;
    }
    Node& w = m_nodes[static_cast<std::size_t>(node)];
    for (int k = 0; k < 4; ++k)
        for (int c = 0; c < 3; ++c) {
            w.lo[c][k] = std::numeric_limits<float>::infinity();
            w.hi[c][k] = -std::numeric_limits<float>::infinity();
        }
    w.count = parts;
    w.face_mask = 0;
    for (int k = 0; k < 4; ++k)
        w.child[k] = -1;
    for (int k = 0; k < parts; ++k) {
        const Index b = bounds[k], e = bounds[k + 1];
        const Index child = e - b == 1 ? -1 - b : build_node(centroids, b, e, depth + 1);
        m_nodes[static_cast<std::size_t>(node)].child[k] = child;
        if (child < 0)
            m_nodes[static_cast<std::size_t>(node)].face_mask |= 1 << k;
    }
    return node;
}

void AabbTree::build(CRef<Positions> vertices, const Tris& faces)
{
    *this = AabbTree();
    if (faces.rows() == 0)
        return;
    for (Index f = 0; f < faces.rows(); ++f)
        for (int c = 0; c < 3; ++c)
            CORO_CHECK(faces(f, c) >= 0 && faces(f, c) < vertices.rows(), InputError,
                       "face " << f << " uses vertex " << faces(f, c) << ", but there are "
                               << vertices.rows() << " vertices");

    m_face_of_slot.resize(static_cast<std::size_t>(faces.rows()));
    std::iota(m_face_of_slot.begin(), m_face_of_slot.end(), Index{0});
    std::vector<Vec3> centroids(static_cast<std::size_t>(faces.rows()));
    for (Index f = 0; f < faces.rows(); ++f)
        centroids[static_cast<std::size_t>(f)] =
            (row(vertices, faces(f, 0)) + row(vertices, faces(f, 1)) + row(vertices, faces(f, 2))) / 3.0;
    m_nodes.reserve(static_cast<std::size_t>(faces.rows()) / 2 + 1);
    build_node(centroids, 0, static_cast<Index>(faces.rows()), 0);
    m_node_boxes.resize(m_nodes.size());

    // Subtree extents (children follow their parent, each subtree contiguous) and, for the
    // parallel refit, the roots of the subtrees two levels below the root.
    m_subtree_end.assign(m_nodes.size(), 0);
    for (std::size_t n = m_nodes.size(); n-- > 0;) {
        Index end = static_cast<Index>(n) + 1;
        const Node& w = m_nodes[n];
        for (int k = 0; k < w.count; ++k)
            if (w.child[k] >= 0)
                end = std::max(end, m_subtree_end[static_cast<std::size_t>(w.child[k])]);
        m_subtree_end[n] = end;
    }
    for (int k = 0; k < m_nodes[0].count; ++k) {
        const Index c = m_nodes[0].child[k];
        if (c < 0)
            continue;
        for (int j = 0; j < m_nodes[static_cast<std::size_t>(c)].count; ++j)
            if (m_nodes[static_cast<std::size_t>(c)].child[j] >= 0)
                m_task_roots.push_back(m_nodes[static_cast<std::size_t>(c)].child[j]);
    }

    m_slot_vertices.resize(3 * m_face_of_slot.size());
    for (std::size_t i = 0; i < m_face_of_slot.size(); ++i)
        for (int c = 0; c < 3; ++c)
            m_slot_vertices[3 * i + static_cast<std::size_t>(c)] = faces(m_face_of_slot[i], c);
    // Vertices in order of first appearance in the leaves: spatially coherent.
    std::vector<char> seen(static_cast<std::size_t>(vertices.rows()), 0);
    for (const Index v : m_slot_vertices)
        if (!seen[static_cast<std::size_t>(v)]) {
            seen[static_cast<std::size_t>(v)] = 1;
            m_vertex_order.push_back(v);
        }
    m_vertex_blocks.resize((m_vertex_order.size() + VERTEX_BLOCK - 1) / VERTEX_BLOCK);
    build_slabs(vertices);
    refit(vertices);
}

void AabbTree::build_slabs(CRef<Positions> vertices)
{
    // The distinct vertices of each subtree of at most SLAB_MAX_FACES faces, in order of first
    // appearance (a slab's extent is taken over them, not over its faces' corners: each vertex
    // is a corner of about six faces), and three of them far apart: the first, the one farthest
    // from it, and the one spanning the largest triangle with those two. That triangle turns
    // with its patch however the body moves, so its normal stays a good slab direction.
    m_slab_start.assign(m_nodes.size() + 1, 0);
    m_slab_corners.assign(m_nodes.size(), {0, 0, 0});
    std::vector<Index> seen_by(static_cast<std::size_t>(vertices.rows()), -1);
    for (std::size_t n = 0; n < m_nodes.size(); ++n) {
        const auto begin = static_cast<std::size_t>(m_node_slots[2 * n]);
        const auto end = static_cast<std::size_t>(m_node_slots[2 * n + 1]);
        const std::size_t first = m_slab_vertices.size();
        if (end - begin <= static_cast<std::size_t>(SLAB_MAX_FACES))
            for (std::size_t i = 3 * begin; i < 3 * end; ++i) {
                const Index v = m_slot_vertices[i];
                if (seen_by[static_cast<std::size_t>(v)] != static_cast<Index>(n)) {
                    seen_by[static_cast<std::size_t>(v)] = static_cast<Index>(n);
                    m_slab_vertices.push_back(v);
                }
            }
        m_slab_start[n + 1] = static_cast<Index>(m_slab_vertices.size());
        if (first == m_slab_vertices.size())
            continue;
        const auto x = [&](std::size_t i) { return row(vertices, m_slab_vertices[i]); };
        const auto farthest = [&](const auto& measure) {
            std::size_t best = first;
            double best_value = -1.0;
            for (std::size_t i = first; i < m_slab_vertices.size(); ++i)
                if (const double value = measure(x(i)); value > best_value) {
                    best_value = value;
                    best = i;
                }
            return best;
        };
        const Vec3 a = x(first);
        const std::size_t i1 = farthest([&](const Vec3& p) { return (p - a).squaredNorm(); });
        const Vec3 b = x(i1);
        const std::size_t i2 = farthest([&](const Vec3& p) { return (b - a).cross(p - a).squaredNorm(); });
        m_slab_corners[n] = {m_slab_vertices[first], m_slab_vertices[i1], m_slab_vertices[i2]};
    }
}

void AabbTree::refit_node(const double* data, std::ptrdiff_t stride, Index n)
{
    using detail::simd::F4;
    Node& w = m_nodes[static_cast<std::size_t>(n)];
    const F4 ulp = F4::splat(0x1p-23f), tiny = F4::splat(0x1p-126f);
    const F4 largest = F4::splat(std::numeric_limits<float>::max());
    const F4 lowest = F4::splat(-std::numeric_limits<float>::max());
    // A face's box (l, h), x, y, z in lanes 0..2, rounded outward to floats (detail::float_down
    // / float_up, three lanes at once). A bound beyond the float range converts to ±∞, and the
    // step outward from there gives NaN: min/max return their second operand then, the largest
    // finite float of that sign, so no NaN reaches a node's union.
    const auto round_down = [&](F4 l) { return min(l - (abs(l) * ulp + tiny), largest); };
    const auto round_up = [&](F4 h) { return max(h + (abs(h) * ulp + tiny), lowest); };
    // Lane k's box (x, y, z, unused) in one register each, the lanes unrolled so that the
    // boxes stay in registers; the four are transposed into the node's rows at the end.
    const auto lane = [&](int k, F4& lo, F4& hi) {
        if (k >= w.count) {
            lo = F4::splat(std::numeric_limits<float>::infinity());
            hi = F4::splat(-std::numeric_limits<float>::infinity());
            return;
        }
        const Index c = w.child[k];
        if (c >= 0) {
            const NodeBox& cb = m_node_boxes[static_cast<std::size_t>(c)];
            lo = F4::load(cb.lo);
            hi = F4::load(cb.hi);
            return;
        }
        using detail::simd::load_point;
        const Index* fv = &m_slot_vertices[3 * static_cast<std::size_t>(-1 - c)];
        const auto a = load_point(data + stride * fv[0]), b = load_point(data + stride * fv[1]);
        const auto d = load_point(data + stride * fv[2]);
        lo = round_down(detail::simd::to_float(min(min(a, b), d)));
        hi = round_up(detail::simd::to_float(max(max(a, b), d)));
    };
    F4 lo0, lo1, lo2, lo3, hi0, hi1, hi2, hi3;
    lane(0, lo0, hi0);
    lane(1, lo1, hi1);
    lane(2, lo2, hi2);
    lane(3, lo3, hi3);
    NodeBox& nb = m_node_boxes[static_cast<std::size_t>(n)];
    min(min(lo0, lo1), min(lo2, lo3)).store(nb.lo);
    max(max(hi0, hi1), max(hi2, hi3)).store(nb.hi);
    detail::simd::transpose(lo0, lo1, lo2, lo3);
    detail::simd::transpose(hi0, hi1, hi2, hi3);
    lo0.store(w.lo[0]);
    lo1.store(w.lo[1]);
    lo2.store(w.lo[2]);
    hi0.store(w.hi[0]);
    hi1.store(w.hi[1]);
    hi2.store(w.hi[2]);
}

void AabbTree::refit_range(const double* data, std::ptrdiff_t stride, Index first, Index last)
{
    for (Index n = last; n-- > first;)
        refit_node(data, stride, n);
}

void AabbTree::refit_vertex_blocks(const double* data, std::ptrdiff_t stride, std::size_t first, std::size_t last)
{
    using detail::simd::D4;
    for (std::size_t b = first; b < last; ++b) {
        const std::size_t end = std::min(m_vertex_order.size(), (b + 1) * VERTEX_BLOCK);
        D4 lo = D4::splat(std::numeric_limits<double>::infinity());
        D4 hi = D4::splat(-std::numeric_limits<double>::infinity());
        for (std::size_t i = b * VERTEX_BLOCK; i < end; ++i) {
            const D4 x = detail::simd::load_point(data + stride * m_vertex_order[i]);
            lo = min(x, lo); // as std::min(lo, x), NaN included
            hi = max(x, hi);
        }
        double l[4], h[4];
        lo.store(l);
        hi.store(h);
        m_vertex_blocks[b].min = Vec3(l[0], l[1], l[2]);
        m_vertex_blocks[b].max = Vec3(h[0], h[1], h[2]);
    }
}

void AabbTree::refit(CRef<Positions> vertices)
{
    if (m_nodes.empty())
        return;
    const double* data = vertices.data();
    const std::ptrdiff_t stride = vertices.outerStride();
    constexpr Index PARALLEL_REFIT_FACES = 1024;
    if (num_faces() < PARALLEL_REFIT_FACES || m_task_roots.size() < 2) {
        refit_range(data, stride, 0, static_cast<Index>(m_nodes.size()));
        refit_vertex_blocks(data, stride, 0, m_vertex_blocks.size());
    } else {
        // Large trees: one parallel pass over the subtrees two levels down and the vertex blocks
        // (BLOCKS_PER_TASK to a task), then the few nodes above the subtrees.
        constexpr std::size_t BLOCKS_PER_TASK = 32;
        const std::size_t subtrees = m_task_roots.size();
        const std::size_t block_tasks = (m_vertex_blocks.size() + BLOCKS_PER_TASK - 1) / BLOCKS_PER_TASK;
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, subtrees + block_tasks, 1),
                          [&](const tbb::blocked_range<std::size_t>& r) {
                              for (std::size_t i = r.begin(); i < r.end(); ++i) {
                                  if (i >= subtrees) {
                                      const std::size_t first = (i - subtrees) * BLOCKS_PER_TASK;
                                      refit_vertex_blocks(data, stride, first,
                                                          std::min(m_vertex_blocks.size(), first + BLOCKS_PER_TASK));
                                      continue;
                                  }
                                  const Index root = m_task_roots[i];
                                  refit_range(data, stride, root, m_subtree_end[static_cast<std::size_t>(root)]);
                              }
                          });
        // The root and its children: every node before the first task root and the root's node
        // children (each precedes its own subtree, and the task roots lie inside those).
        for (Index n = m_task_roots.front(); n-- > 0;)
            refit_node(data, stride, n);
        for (int k = m_nodes[0].count; k-- > 0;) {
            const Index c = m_nodes[0].child[k];
            if (c > 0 && c >= m_task_roots.front())
                refit_node(data, stride, c);
        }
        refit_node(data, stride, 0);
    }
    // The exact box of the surface: that of its vertices (the node boxes are rounded).
    m_bounds = Aabb{};
    for (const Aabb& block : m_vertex_blocks)
        m_bounds.extend(block);
}

void AabbTree::faces_overlapping(CRef<Positions> vertices, const Aabb& box, std::vector<Index>& out) const
{
    out.clear();
    if (m_nodes.empty() || box.empty() || !m_bounds.overlaps(box))
        return;
    // The float lanes bound the exact boxes and `box` is widened to floats, so no lane holding a
    // face whose exact box overlaps is dropped; the faces are then tested on their exact boxes.
    using detail::simd::F4;
    F4 lo[3], hi[3];
    for (int j = 0; j < 3; ++j) {
        lo[j] = F4::splat(detail::float_down(box.min[j]));
        hi[j] = F4::splat(detail::float_up(box.max[j]));
    }
    Index stack[detail::TreeAccess::STACK_SIZE];
    int top = 0;
    stack[top++] = 0;
    while (top > 0) {
        const Node& node = m_nodes[static_cast<std::size_t>(stack[--top])];
        auto meet = (F4::load(node.lo[0]) <= hi[0]) & (F4::load(node.hi[0]) >= lo[0]);
        for (int j = 1; j < 3; ++j)
            meet = meet & (F4::load(node.lo[j]) <= hi[j]) & (F4::load(node.hi[j]) >= lo[j]);
        for (int m = meet.bits() & ((1 << node.count) - 1); m != 0; m &= m - 1) {
            const int k = __builtin_ctz(static_cast<unsigned>(m));
            const Index c = node.child[k];
            if (c >= 0)
                stack[top++] = c;
            else if (detail::TreeAccess::slot_box(*this, vertices.data(), vertices.outerStride(),
                                                  static_cast<std::size_t>(-1 - c))
                         .overlaps(box))
                out.push_back(m_face_of_slot[static_cast<std::size_t>(-1 - c)]);
        }
    }
    std::sort(out.begin(), out.end());
}

void AabbTree::vertices_in_box(CRef<Positions> vertices, const Aabb& box, std::vector<Index>& out) const
{
    out.clear();
    if (box.empty())
        return;
    using detail::simd::D4;
    // Whether the point at p (3 doubles) lies in `box` (closed), without a branch per bound; the
    // fourth lanes hold 0 on all sides.
    const D4 box_min = detail::simd::load_point(box.min.data()), box_max = detail::simd::load_point(box.max.data());
    const auto contains = [&](const double* p) {
        const D4 x = detail::simd::load_point(p);
        return ((x >= box_min) & (x <= box_max)).bits() == 0xf;
    };
    for (std::size_t b = 0; b < m_vertex_blocks.size(); ++b) {
        if (!m_vertex_blocks[b].overlaps(box))
            continue;
        const std::size_t end = std::min(m_vertex_order.size(), (b + 1) * VERTEX_BLOCK);
        const Aabb& block = m_vertex_blocks[b];
        if (box.contains(block.min) && box.contains(block.max)) { // every vertex of the block
            out.insert(out.end(), m_vertex_order.begin() + static_cast<std::ptrdiff_t>(b * VERTEX_BLOCK),
                       m_vertex_order.begin() + static_cast<std::ptrdiff_t>(end));
            continue;
        }
        // Each vertex written, the count advanced when it is inside: whether it is varies along
        // the block, a branch on it would be mispredicted often.
        std::size_t count = out.size();
        out.resize(count + (end - b * VERTEX_BLOCK));
        Index* const kept = out.data();
        for (std::size_t i = b * VERTEX_BLOCK; i < end; ++i) {
            const Index v = m_vertex_order[i];
            kept[count] = v;
            count += contains(vertices.data() + vertices.outerStride() * v) ? 1 : 0;
        }
        out.resize(count);
    }
}

NearestPoint AabbTree::nearest(CRef<Positions> vertices, const Vec3& point) const
{
    return detail::NearestSearch(*this, vertices, nullptr).find(point);
}

} // namespace coro
