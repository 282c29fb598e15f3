#include <corocontact/contact/aabb_tree.hpp>

#include <corocontact/core/error.hpp>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <emmintrin.h>
#if defined(__AVX2__)
#include <immintrin.h>
#endif

#include <algorithm>
#include <array>
#include <cmath>
#include <numeric>

namespace coro {

namespace {

Vec3 row(CRef<Positions> vertices, Index i) { return vertices.row(i).transpose(); }

TrianglePoint closest_point_on_segment(const Vec3& p, const Vec3& a, const Vec3& b)
{
    const Vec3 ab = b - a;
    const double len2 = ab.squaredNorm();
    const double s = len2 > 0.0 ? std::clamp((p - a).dot(ab) / len2, 0.0, 1.0) : 0.0;
    return {a + s * ab, Vec3(1.0 - s, s, 0.0)};
}

} // namespace

TrianglePoint closest_point_on_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c)
{
    // Ericson, RTCD §5.1.5: find the Voronoi region of p.
    const Vec3 ab = b - a, ac = c - a, ap = p - a;
    const double d1 = ab.dot(ap), d2 = ac.dot(ap);
    if (d1 <= 0.0 && d2 <= 0.0)
        return {a, Vec3(1, 0, 0)};
    const Vec3 bp = p - b;
    const double d3 = ab.dot(bp), d4 = ac.dot(bp);
    if (d3 >= 0.0 && d4 <= d3)
        return {b, Vec3(0, 1, 0)};
    const double vc = d1 * d4 - d3 * d2;
    if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) {
        const double s = d1 / (d1 - d3);
        return {a + s * ab, Vec3(1.0 - s, s, 0.0)};
    }
    const Vec3 cp = p - c;
    const double d5 = ab.dot(cp), d6 = ac.dot(cp);
    if (d6 >= 0.0 && d5 <= d6)
        return {c, Vec3(0, 0, 1)};
    const double vb = d5 * d2 - d1 * d6;
    if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) {
        const double s = d2 / (d2 - d6);
        return {a + s * ac, Vec3(1.0 - s, 0.0, s)};
    }
    const double va = d3 * d6 - d5 * d4;
    if (va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0) {
        const double s = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return {b + s * (c - b), Vec3(0.0, 1.0 - s, s)};
    }
    const double sum = va + vb + vc;
    if (!(sum > 0.0)) { // degenerate (collinear) triangle: the nearest of its three edges
        TrianglePoint best = closest_point_on_segment(p, a, b);
        TrianglePoint e = closest_point_on_segment(p, b, c);
        e.barycentric = Vec3(0.0, e.barycentric[0], e.barycentric[1]);
        if ((e.point - p).squaredNorm() < (best.point - p).squaredNorm())
            best = e;
        e = closest_point_on_segment(p, c, a);
        e.barycentric = Vec3(e.barycentric[1], 0.0, e.barycentric[0]);
        if ((e.point - p).squaredNorm() < (best.point - p).squaredNorm())
            best = e;
        return best;
    }
    const double v = vb / sum, w = vc / sum;
    return {a + v * ab + w * ac, Vec3(1.0 - v - w, v, w)};
}

Index AabbTree::build_node(const std::vector<Vec3>& centroids, Index begin, Index end, int depth)
{
    CORO_CHECK(depth < MAX_DEPTH, NumericalError, "AABB tree of " << m_faces.rows() << " faces is deeper than "
                                                                  << MAX_DEPTH << " levels");
    const Index node = static_cast<Index>(m_nodes.size());
    m_nodes.emplace_back();
    m_node_slots.push_back(begin);
    m_node_slots.push_back(end);
    // Up to four parts, kept in range order, each a whole number of `unit` faces (the faces of a
    // full subtree: 1, 4, 16, …) but one: the largest part is split along the longest axis of
    // its centroids, as near its median as whole units allow, until there are `target` parts.
    // So every node holds four children but at most one per level: splits at the plain median
    // left many nodes two faces or two subtrees (853 nodes over 1,728 faces, where 577 can do),
    // and every walk, query and refit paid for their empty lanes.
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
            spread.extend(centroids[static_cast<std::size_t>(m_order[static_cast<std::size_t>(i)])]);
        int axis = 0;
        (spread.max - spread.min).maxCoeff(&axis);
        const Index mid = b + unit * (units / 2);
        std::nth_element(m_order.begin() + b, m_order.begin() + mid, m_order.begin() + e, [&](Index x, Index y) {
            const double cx = centroids[static_cast<std::size_t>(x)][axis];
            const double cy = centroids[static_cast<std::size_t>(y)][axis];
            return cx < cy || (cx == cy && x < y);
        });
        for (int k = parts; k > largest; --k)
            bounds[k + 1] = bounds[k];
        bounds[largest + 1] = mid;
        ++parts;
    }
    WideNode& w = m_nodes[static_cast<std::size_t>(node)];
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
    m_faces = faces;
    m_nodes.clear();
    m_node_bounds.clear();
    m_subtree_end.clear();
    m_task_roots.clear();
    m_order.resize(static_cast<std::size_t>(faces.rows()));
    std::iota(m_order.begin(), m_order.end(), Index{0});
    m_vertex_order.clear();
    m_vertex_blocks.clear();
    m_slot_vertices.clear();
    m_planes.clear();
    m_planes_current = false;
    m_slab_vertex_start.clear();
    m_slab_vertices.clear();
    m_node_slots.clear();
    m_edge_start.clear();
    m_edge_vertex.clear();
    m_edge_slots.clear();
    m_bounds = Aabb{};
    if (faces.rows() == 0)
        return;
    for (Index f = 0; f < faces.rows(); ++f)
        for (int c = 0; c < 3; ++c)
            CORO_CHECK(faces(f, c) >= 0 && faces(f, c) < vertices.rows(), InputError,
                       "face " << f << " uses vertex " << faces(f, c) << ", but there are "
                               << vertices.rows() << " vertices");

    std::vector<Vec3> centroids(static_cast<std::size_t>(faces.rows()));
    for (Index f = 0; f < faces.rows(); ++f)
        centroids[static_cast<std::size_t>(f)] =
            (row(vertices, faces(f, 0)) + row(vertices, faces(f, 1)) + row(vertices, faces(f, 2))) / 3.0;
    m_nodes.reserve(static_cast<std::size_t>(faces.rows()) / 2 + 1);
    build_node(centroids, 0, static_cast<Index>(faces.rows()), 0);
    m_node_bounds.resize(m_nodes.size());

    // Subtree extents (children follow their parent, each subtree contiguous) and, for the
    // parallel refit, the roots of the subtrees two levels below the root.
    m_subtree_end.assign(m_nodes.size(), 0);
    for (std::size_t n = m_nodes.size(); n-- > 0;) {
        Index end = static_cast<Index>(n) + 1;
        const WideNode& w = m_nodes[n];
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

    // Vertices in order of first appearance in the leaves: spatially coherent.
    std::vector<char> seen(static_cast<std::size_t>(vertices.rows()), 0);
    for (const Index f : m_order)
        for (int c = 0; c < 3; ++c) {
            const Index v = faces(f, c);
            if (!seen[static_cast<std::size_t>(v)]) {
                seen[static_cast<std::size_t>(v)] = 1;
                m_vertex_order.push_back(v);
            }
        }
    m_vertex_blocks.resize((m_vertex_order.size() + VERTEX_BLOCK - 1) / VERTEX_BLOCK);
    m_slot_vertices.resize(3 * m_order.size());
    for (std::size_t i = 0; i < m_order.size(); ++i)
        for (int c = 0; c < 3; ++c)
            m_slot_vertices[3 * i + static_cast<std::size_t>(c)] = faces(m_order[i], c);
    build_edges(static_cast<std::size_t>(vertices.rows()));
    build_slab_vertices(static_cast<std::size_t>(vertices.rows()));
    refit(vertices);
}

void AabbTree::build_edges(std::size_t vertex_count)
{
    // (low end, high end, slot) of every face side; sorted, the sides of one edge are adjacent.
    std::vector<std::array<Index, 3>> sides;
    sides.reserve(m_slot_vertices.size());
    for (std::size_t slot = 0; slot < m_order.size(); ++slot)
        for (std::size_t c = 0; c < 3; ++c) {
            const Index a = m_slot_vertices[3 * slot + c], b = m_slot_vertices[3 * slot + (c + 1) % 3];
            if (a != b) // a face with a repeated vertex has no edge there
                sides.push_back({std::min(a, b), std::max(a, b), static_cast<Index>(slot)});
        }
    std::sort(sides.begin(), sides.end());
    std::vector<std::array<Index, 4>> edges; // low end, high end, two of its faces' slots
    for (std::size_t i = 0, j = 0; i < sides.size(); i = j) {
        while (j < sides.size() && sides[j][0] == sides[i][0] && sides[j][1] == sides[i][1])
            ++j;
        edges.push_back({sides[i][0], sides[i][1], sides[i][2], sides[j - 1][2]});
    }
    m_edge_start.assign(vertex_count + 1, 0);
    for (const auto& e : edges) {
        ++m_edge_start[static_cast<std::size_t>(e[0]) + 1];
        ++m_edge_start[static_cast<std::size_t>(e[1]) + 1];
    }
    for (std::size_t v = 0; v < vertex_count; ++v)
        m_edge_start[v + 1] += m_edge_start[v];
    m_edge_vertex.resize(2 * edges.size());
    m_edge_slots.resize(2 * edges.size());
    std::vector<Index> next(m_edge_start.begin(), m_edge_start.end() - 1);
    for (const auto& e : edges)
        for (int end = 0; end < 2; ++end) {
            const auto k = static_cast<std::size_t>(next[static_cast<std::size_t>(e[end])]++);
            m_edge_vertex[k] = e[1 - end];
            m_edge_slots[k] = {e[2], e[3]};
        }
}

void AabbTree::refit_node(const double* data, std::ptrdiff_t stride, Index n)
{
    WideNode& w = m_nodes[static_cast<std::size_t>(n)];
    const __m128 abs_mask = _mm_castsi128_ps(_mm_set1_epi32(0x7fffffff));
    const __m128 ulp = _mm_set1_ps(0x1p-23f), tiny = _mm_set1_ps(0x1p-126f);
    const __m128 largest = _mm_set1_ps(std::numeric_limits<float>::max());
    const __m128 lowest = _mm_set1_ps(-std::numeric_limits<float>::max());
    // A face's box (l, h), x, y, z in lanes 0..2, rounded outward to floats (detail::float_down
    // / float_up, three lanes at once). A bound beyond the float range converts to ±∞, and the
    // step outward from there gives NaN: min/max return their second operand then, the largest
    // finite float of that sign, so no NaN reaches a node's union.
    const auto round_down = [&](__m128 l) {
        return _mm_min_ps(_mm_sub_ps(l, _mm_add_ps(_mm_mul_ps(_mm_and_ps(l, abs_mask), ulp), tiny)), largest);
    };
    const auto round_up = [&](__m128 h) {
        return _mm_max_ps(_mm_add_ps(h, _mm_add_ps(_mm_mul_ps(_mm_and_ps(h, abs_mask), ulp), tiny)), lowest);
    };
    // Lane k's box, x, y, z, 0 in one register (empty for the unused lanes), four of them
    // transposed into the node's rows at the end; the lanes unrolled, so that the boxes stay in
    // registers.
    const auto lane = [&](int k, __m128& lo, __m128& hi) {
        if (k >= w.count) {
            lo = _mm_set1_ps(std::numeric_limits<float>::infinity());
            hi = _mm_set1_ps(-std::numeric_limits<float>::infinity());
            return;
        }
        const Index c = w.child[k];
        if (c >= 0) {
            const NodeBounds& cb = m_node_bounds[static_cast<std::size_t>(c)];
            lo = _mm_load_ps(cb.lo);
            hi = _mm_load_ps(cb.hi);
            return;
        }
        const Index* fv = &m_slot_vertices[3 * static_cast<std::size_t>(-1 - c)];
#if defined(__AVX2__)
        // AVX: (x, y, z, 0) in one register; a point is 3 doubles, loaded without reading past
        // them.
        const __m256i xyz = _mm256_setr_epi64x(-1, -1, -1, 0);
        const __m256d a = _mm256_maskload_pd(data + stride * fv[0], xyz);
        const __m256d b = _mm256_maskload_pd(data + stride * fv[1], xyz);
        const __m256d d = _mm256_maskload_pd(data + stride * fv[2], xyz);
        lo = round_down(_mm256_cvtpd_ps(_mm256_min_pd(_mm256_min_pd(a, b), d)));
        hi = round_up(_mm256_cvtpd_ps(_mm256_max_pd(_mm256_max_pd(a, b), d)));
#else
        // SSE2: (x, y) in one register, z in the low half of another.
        const double* a = data + stride * fv[0];
        const double* b = data + stride * fv[1];
        const double* d = data + stride * fv[2];
        const __m128d a_xy = _mm_loadu_pd(a), b_xy = _mm_loadu_pd(b), d_xy = _mm_loadu_pd(d);
        const __m128d a_z = _mm_load_sd(a + 2), b_z = _mm_load_sd(b + 2), d_z = _mm_load_sd(d + 2);
        lo = round_down(_mm_movelh_ps(_mm_cvtpd_ps(_mm_min_pd(_mm_min_pd(a_xy, b_xy), d_xy)),
                                      _mm_cvtpd_ps(_mm_min_sd(_mm_min_sd(a_z, b_z), d_z))));
        hi = round_up(_mm_movelh_ps(_mm_cvtpd_ps(_mm_max_pd(_mm_max_pd(a_xy, b_xy), d_xy)),
                                    _mm_cvtpd_ps(_mm_max_sd(_mm_max_sd(a_z, b_z), d_z))));
#endif
    };
    __m128 lo0, lo1, lo2, lo3, hi0, hi1, hi2, hi3;
    lane(0, lo0, hi0);
    lane(1, lo1, hi1);
    lane(2, lo2, hi2);
    lane(3, lo3, hi3);
    // The node's own box, the union of its lanes (each already rounded outward).
    NodeBounds& nb = m_node_bounds[static_cast<std::size_t>(n)];
    _mm_store_ps(nb.lo, _mm_min_ps(_mm_min_ps(lo0, lo1), _mm_min_ps(lo2, lo3)));
    _mm_store_ps(nb.hi, _mm_max_ps(_mm_max_ps(hi0, hi1), _mm_max_ps(hi2, hi3)));
    _MM_TRANSPOSE4_PS(lo0, lo1, lo2, lo3);
    _MM_TRANSPOSE4_PS(hi0, hi1, hi2, hi3);
    _mm_store_ps(w.lo[0], lo0);
    _mm_store_ps(w.lo[1], lo1);
    _mm_store_ps(w.lo[2], lo2);
    _mm_store_ps(w.hi[0], hi0);
    _mm_store_ps(w.hi[1], hi1);
    _mm_store_ps(w.hi[2], hi2);
}

void AabbTree::refit_range(const double* data, std::ptrdiff_t stride, Index first, Index last)
{
    for (Index n = last; n-- > first;)
        refit_node(data, stride, n);
}

void AabbTree::refit(CRef<Positions> vertices)
{
    m_planes_current = false;
    if (m_nodes.empty())
        return;
    const double* data = vertices.data();
    const std::ptrdiff_t stride = vertices.outerStride();
    // The box of each VERTEX_BLOCK consecutive vertices of m_vertex_order, blocks [first, last).
    const auto vertex_blocks = [&](std::size_t first, std::size_t last) {
        for (std::size_t b = first; b < last; ++b) {
            const std::size_t end = std::min(m_vertex_order.size(), (b + 1) * VERTEX_BLOCK);
            Aabb& block = m_vertex_blocks[b];
#if defined(__AVX2__)
            // (x, y, z, 0) in one register: a point is 3 doubles, loaded without reading past them.
            const __m256i xyz = _mm256_setr_epi64x(-1, -1, -1, 0);
            __m256d lo = _mm256_set1_pd(std::numeric_limits<double>::infinity());
            __m256d hi = _mm256_set1_pd(-std::numeric_limits<double>::infinity());
            for (std::size_t i = b * VERTEX_BLOCK; i < end; ++i) {
                const __m256d x = _mm256_maskload_pd(data + stride * m_vertex_order[i], xyz);
                lo = _mm256_min_pd(x, lo); // as std::min(lo, x)
                hi = _mm256_max_pd(x, hi);
            }
            alignas(32) double l[4], h[4];
            _mm256_store_pd(l, lo);
            _mm256_store_pd(h, hi);
            block.min = Vec3(l[0], l[1], l[2]);
            block.max = Vec3(h[0], h[1], h[2]);
#else
            double lo[3] = {std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity(),
                            std::numeric_limits<double>::infinity()};
            double hi[3] = {-lo[0], -lo[1], -lo[2]};
            for (std::size_t i = b * VERTEX_BLOCK; i < end; ++i) {
                const double* x = data + stride * m_vertex_order[i];
                for (int j = 0; j < 3; ++j) {
                    lo[j] = std::min(lo[j], x[j]);
                    hi[j] = std::max(hi[j], x[j]);
                }
            }
            block.min = Vec3(lo[0], lo[1], lo[2]);
            block.max = Vec3(hi[0], hi[1], hi[2]);
#endif
        }
    };
    constexpr Index PARALLEL_REFIT_FACES = 1024;
    if (num_faces() < PARALLEL_REFIT_FACES || m_task_roots.size() < 2) {
        refit_range(data, stride, 0, static_cast<Index>(m_nodes.size()));
        vertex_blocks(0, m_vertex_blocks.size());
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
                                      vertex_blocks(first, std::min(m_vertex_blocks.size(), first + BLOCKS_PER_TASK));
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

const Aabb& AabbTree::bounds() const { return m_bounds; }

void AabbTree::faces_overlapping(CRef<Positions> vertices, const Aabb& box, std::vector<Index>& out) const
{
    out.clear();
    if (m_nodes.empty() || box.empty() || !m_bounds.overlaps(box))
        return;
    // The float lanes bound the exact boxes and `box` is widened to floats, so no lane holding a
    // face whose exact box overlaps is dropped; the faces are then tested on their exact boxes.
    __m128 lo[3], hi[3];
    for (int j = 0; j < 3; ++j) {
        lo[j] = _mm_set1_ps(detail::float_down(box.min[j]));
        hi[j] = _mm_set1_ps(detail::float_up(box.max[j]));
    }
    Index stack[STACK_SIZE];
    int top = 0;
    stack[top++] = 0;
    while (top > 0) {
        const Index n = stack[--top];
        const WideNode& node = m_nodes[static_cast<std::size_t>(n)];
        for (int m = lanes_meeting(n, lo, hi); m != 0; m &= m - 1) {
            const int k = __builtin_ctz(static_cast<unsigned>(m));
            const Index c = node.child[k];
            if (c >= 0)
                stack[top++] = c;
            else if (slot_box(vertices.data(), vertices.outerStride(), static_cast<std::size_t>(-1 - c)).overlaps(box))
                out.push_back(m_order[static_cast<std::size_t>(-1 - c)]);
        }
    }
    std::sort(out.begin(), out.end());
}

void AabbTree::vertices_in_box(CRef<Positions> vertices, const Aabb& box, std::vector<Index>& out) const
{
    out.clear();
    if (box.empty())
        return;
    // Whether the point at p (3 doubles) lies in `box` (closed), without a branch per bound.
#if defined(__AVX2__)
    const __m256i xyz = _mm256_setr_epi64x(-1, -1, -1, 0); // no load past a point or a bound
    const __m256d box_min = _mm256_maskload_pd(box.min.data(), xyz), box_max = _mm256_maskload_pd(box.max.data(), xyz);
    const auto contains = [&](const double* p) {
        const __m256d x = _mm256_maskload_pd(p, xyz); // fourth lanes 0 on all sides: never outside
        return _mm256_movemask_pd(_mm256_or_pd(_mm256_cmp_pd(x, box_min, _CMP_NGE_UQ),
                                               _mm256_cmp_pd(x, box_max, _CMP_NLE_UQ))) == 0;
    };
#else
    const auto contains = [&](const double* p) {
        return (box.min[0] <= p[0]) & (box.min[1] <= p[1]) & (box.min[2] <= p[2]) & (p[0] <= box.max[0]) &
               (p[1] <= box.max[1]) & (p[2] <= box.max[2]);
    };
#endif
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
        // the block, a branch on it was mispredicted often.
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

AabbTree::Nearest AabbTree::nearest(CRef<Positions> vertices, const Vec3& point) const
{
    return nearest(vertices, point, std::numeric_limits<double>::infinity(), -1);
}

AabbTree::Nearest AabbTree::nearest(CRef<Positions> vertices, const Vec3& point, double distance_bound,
                                    Index hint_face) const
{
    Nearest best;
    if (m_nodes.empty())
        return best;
    // Initial bound on the squared distance, at or above the nearest face's computed squared
    // distance: boxes strictly beyond it cannot hold the answer. Of faces with the same computed
    // squared distance the smallest index wins, so neither the bound nor the traversal order can
    // change the answer. The hint face's distance is computed with the same formula as in the
    // search; the inflation covers the rounding of the squared distances.
    double bound_d2 = std::numeric_limits<double>::infinity();
    if (distance_bound < std::numeric_limits<double>::infinity())
        bound_d2 = distance_bound * distance_bound * (1.0 + 1e-6) + std::numeric_limits<double>::min();
    if (hint_face >= 0 && hint_face < m_faces.rows()) {
        const TrianglePoint q = closest_point_on_triangle(point, row(vertices, m_faces(hint_face, 0)),
                                                          row(vertices, m_faces(hint_face, 1)),
                                                          row(vertices, m_faces(hint_face, 2)));
        bound_d2 = std::min(bound_d2, (q.point - point).squaredNorm() * (1.0 + 1e-6) +
                                          std::numeric_limits<double>::min());
    }
    // Squared distances of the point to four single precision boxes at once. The point is
    // widened to a float interval [p_lo, p_hi] containing it, so the float result is at most the
    // exact squared distance times (1 + 2⁻²¹); a box is skipped only when that is above the
    // threshold, float_threshold(best_d2) ≥ best_d2·(1 + 2⁻¹⁹): it then lies strictly farther
    // than the best face, ties included.
    const __m128 p_lo[3] = {_mm_set1_ps(detail::float_down(point[0])), _mm_set1_ps(detail::float_down(point[1])),
                            _mm_set1_ps(detail::float_down(point[2]))};
    const __m128 p_hi[3] = {_mm_set1_ps(detail::float_up(point[0])), _mm_set1_ps(detail::float_up(point[1])),
                            _mm_set1_ps(detail::float_up(point[2]))};
    const __m128 zero = _mm_setzero_ps();
    const __m128 p_f[3] = {_mm_set1_ps(static_cast<float>(point[0])), _mm_set1_ps(static_cast<float>(point[1])),
                           _mm_set1_ps(static_cast<float>(point[2]))};
    const __m128 p_error = _mm_set1_ps(
        static_cast<float>((std::abs(point[0]) + std::abs(point[1]) + std::abs(point[2])) * 0x1p-20) + 0x1p-120f);
    double best_d2 = bound_d2;
    float threshold = detail::float_threshold(best_d2);
    const double* data = vertices.data();
    const auto stride = vertices.outerStride();
    Index stack[STACK_SIZE];
    float stack_d2[STACK_SIZE];
    int top = 0;
    stack[top] = 0;
    stack_d2[top++] = 0.0f;
    alignas(16) float d2[4];
    while (top > 0) {
        --top;
        if (stack_d2[top] > threshold)
            continue;
        const std::size_t node_index = static_cast<std::size_t>(stack[top]);
        const WideNode& node = m_nodes[node_index];
        __m128 sum = zero;
        for (int j = 0; j < 3; ++j) {
            const __m128 d = _mm_max_ps(_mm_max_ps(_mm_sub_ps(_mm_load_ps(node.lo[j]), p_hi[j]),
                                                   _mm_sub_ps(p_lo[j], _mm_load_ps(node.hi[j]))),
                                        zero);
            sum = _mm_add_ps(sum, _mm_mul_ps(d, d));
        }
        // A child whose plane slab lies beyond the threshold is skipped too: its key is the larger
        // of the two lower bounds, so that the stack pops the nearest by the tighter one first.
        // |u·p − offset| is computed in float from p's rounding; the error of that (a few float
        // ulps of |p|₁ + |offset|, taken 8 times over) is subtracted.
        if (m_planes_current) {
            const FacePlanes& fp = m_planes[node_index];
            __m128 dot = _mm_sub_ps(_mm_mul_ps(_mm_load_ps(fp.normal[0]), p_f[0]), _mm_load_ps(fp.offset));
            dot = _mm_add_ps(dot, _mm_mul_ps(_mm_load_ps(fp.normal[1]), p_f[1]));
            dot = _mm_add_ps(dot, _mm_mul_ps(_mm_load_ps(fp.normal[2]), p_f[2]));
            const __m128 abs_mask = _mm_castsi128_ps(_mm_set1_epi32(0x7fffffff));
            const __m128 error = _mm_add_ps(p_error, _mm_mul_ps(_mm_and_ps(_mm_load_ps(fp.offset), abs_mask),
                                                                _mm_set1_ps(0x1p-20f)));
            const __m128 lower = _mm_sub_ps(_mm_sub_ps(_mm_and_ps(dot, abs_mask), _mm_load_ps(fp.slack)), error);
            // (1 − 2⁻¹⁸)·lower ≤ the distance (|u| ≤ 1 + 2⁻²²).
            const __m128 scaled = _mm_mul_ps(_mm_max_ps(lower, zero), _mm_set1_ps(1.0f - 0x1p-18f));
            sum = _mm_max_ps(sum, _mm_mul_ps(scaled, scaled));
        }
        const int mask = _mm_movemask_ps(_mm_cmple_ps(sum, _mm_set1_ps(threshold))) & ((1 << node.count) - 1);
        if (mask == 0)
            continue;
        _mm_store_ps(d2, sum);
        // Faces first (lane order: of equally near faces the smallest index wins anyway), then
        // the child nodes, the nearest on top of the stack.
        int faces = mask & node.face_mask;
        for (; faces != 0; faces &= faces - 1) {
            const int k = __builtin_ctz(static_cast<unsigned>(faces));
            if (d2[k] > threshold)
                continue;
            const Index* fv = &m_slot_vertices[3 * static_cast<std::size_t>(-1 - node.child[k])];
            const double* A = data + stride * fv[0];
            const double* B = data + stride * fv[1];
            const double* C = data + stride * fv[2];
            const TrianglePoint q =
                closest_point_on_triangle(point, Vec3(A[0], A[1], A[2]), Vec3(B[0], B[1], B[2]), Vec3(C[0], C[1], C[2]));
            const double dq = (q.point - point).squaredNorm();
            const Index f = m_order[static_cast<std::size_t>(-1 - node.child[k])];
            if (dq < best_d2 || (dq == best_d2 && f < best.face)) {
                best_d2 = dq;
                threshold = detail::float_threshold(best_d2);
                best.face = f;
                best.point = q.point;
                best.barycentric = q.barycentric;
            }
        }
        push_children(node, mask, d2, stack, stack_d2, top);
    }
    if (best.face < 0) // a bound below the true distance (an invalid hint): search again without it
        return bound_d2 < std::numeric_limits<double>::infinity()
                   ? nearest(vertices, point, std::numeric_limits<double>::infinity(), -1)
                   : best;
    best.distance = std::sqrt(best_d2);
    return best;
}

} // namespace coro
