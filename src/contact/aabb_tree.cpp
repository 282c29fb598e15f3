#include <corocontact/contact/aabb_tree.hpp>

#include <corocontact/core/error.hpp>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <emmintrin.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <numeric>

namespace coro {

namespace {

// Trees with fewer nodes refit serially: below this the task overhead exceeds the work.
constexpr std::size_t PARALLEL_REFIT_NODES = 16384;
// Nodes of one level per task in the parallel refit.
constexpr std::size_t REFIT_GRAIN = 1024;

Vec3 row(CRef<Positions> vertices, Index i) { return vertices.row(i).transpose(); }

TrianglePoint closest_point_on_segment(const Vec3& p, const Vec3& a, const Vec3& b)
{
    const Vec3 ab = b - a;
    const double len2 = ab.squaredNorm();
    const double s = len2 > 0.0 ? std::clamp((p - a).dot(ab) / len2, 0.0, 1.0) : 0.0;
    return {a + s * ab, Vec3(1.0 - s, s, 0.0)};
}

/// Is triangle (A, B, C) certainly farther from `p` than √`best_d2`? Its plane's distance is a
/// lower bound of its distance; the test allows for the rounding of every quantity with a wide
/// margin, so it says yes only when the exact search's squared distance of the face would not be
/// below `best_d2` either (it only saves closest_point_on_triangle calls, never changes a result).
bool beyond_plane(const Vec3& p, const double* A, const double* B, const double* C, double best_d)
{
    const double e1[3] = {B[0] - A[0], B[1] - A[1], B[2] - A[2]};
    const double e2[3] = {C[0] - A[0], C[1] - A[1], C[2] - A[2]};
    const double q[3] = {p[0] - A[0], p[1] - A[1], p[2] - A[2]};
    const double n[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]};
    const double num = n[0] * q[0] + n[1] * q[1] + n[2] * q[2];
    const double nn = n[0] * n[0] + n[1] * n[1] + n[2] * n[2];
    // |error of num| ≤ a few ε · Σ|e1||e2||q| (products of the exact inputs' differences).
    const double scale = (std::abs(e1[0]) + std::abs(e1[1]) + std::abs(e1[2])) *
                         (std::abs(e2[0]) + std::abs(e2[1]) + std::abs(e2[2])) *
                         (std::abs(q[0]) + std::abs(q[1]) + std::abs(q[2]));
    const double lower = std::abs(num) - 1e-12 * scale;
    // The computed distance of a face may err by a few ε times the coordinates' magnitude.
    const double magnitude = std::abs(p[0]) + std::abs(p[1]) + std::abs(p[2]) + std::abs(A[0]) + std::abs(A[1]) +
                             std::abs(A[2]) + std::abs(e1[0]) + std::abs(e1[1]) + std::abs(e1[2]) + std::abs(e2[0]) +
                             std::abs(e2[1]) + std::abs(e2[2]);
    const double reach = best_d * (1.0 + 1e-7) + 1e-13 * magnitude;
    return lower > 0.0 && lower * lower > nn * (reach * reach) * (1.0 + 1e-9);
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

void AabbTree::build(CRef<Positions> vertices, const Tris& faces)
{
    m_faces = faces;
    m_nodes.clear();
    m_order.resize(static_cast<std::size_t>(faces.rows()));
    std::iota(m_order.begin(), m_order.end(), Index{0});
    m_levels.clear();
    m_level_offsets.clear();
    m_vertex_order.clear();
    m_vertex_blocks.clear();
    m_face_boxes.clear();
    m_packed.clear();
    m_packed_of.clear();
    m_packed_faces.clear();
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

    // Nodes are numbered in creation order: children always after their parent.
    m_nodes.reserve(2 * static_cast<std::size_t>(faces.rows()) / MAX_LEAF_FACES + 1);
    struct Task {
        Index node, begin, end;
    };
    std::vector<Task> stack{{0, 0, static_cast<Index>(faces.rows())}};
    m_nodes.emplace_back();
    while (!stack.empty()) {
        const Task task = stack.back();
        stack.pop_back();
        Node& node = m_nodes[static_cast<std::size_t>(task.node)];
        node.begin = task.begin;
        node.end = task.end;
        if (task.end - task.begin <= MAX_LEAF_FACES)
            continue;
        Aabb spread;
        for (Index i = task.begin; i < task.end; ++i)
            spread.extend(centroids[static_cast<std::size_t>(m_order[static_cast<std::size_t>(i)])]);
        int axis = 0;
        (spread.max - spread.min).maxCoeff(&axis);
        const Index mid = task.begin + (task.end - task.begin) / 2;
        std::nth_element(m_order.begin() + task.begin, m_order.begin() + mid, m_order.begin() + task.end,
                         [&](Index a, Index b) {
                             const double ca = centroids[static_cast<std::size_t>(a)][axis];
                             const double cb = centroids[static_cast<std::size_t>(b)][axis];
                             return ca < cb || (ca == cb && a < b);
                         });
        const Index left = static_cast<Index>(m_nodes.size());
        m_nodes.emplace_back();
        const Index right = static_cast<Index>(m_nodes.size());
        m_nodes.emplace_back();
        m_nodes[static_cast<std::size_t>(task.node)].left = left;
        m_nodes[static_cast<std::size_t>(task.node)].right = right;
        // Right first on the stack so that the left subtree is laid out first.
        stack.push_back({right, mid, task.end});
        stack.push_back({left, task.begin, mid});
    }
    // Heights for the level-by-level parallel refit.
    std::vector<Index> height(m_nodes.size(), 0);
    for (std::size_t n = m_nodes.size(); n-- > 0;) {
        const Node& node = m_nodes[n];
        if (node.left >= 0)
            height[n] = 1 + std::max(height[static_cast<std::size_t>(node.left)],
                                     height[static_cast<std::size_t>(node.right)]);
    }
    const Index levels = height[0] + 1;
    CORO_CHECK(levels < 90, NumericalError, "AABB tree of " << faces.rows() << " faces is " << levels
                                                            << " levels deep");
    m_level_offsets.assign(static_cast<std::size_t>(levels) + 1, 0);
    for (const Index h : height)
        ++m_level_offsets[static_cast<std::size_t>(h) + 1];
    std::partial_sum(m_level_offsets.begin(), m_level_offsets.end(), m_level_offsets.begin());
    m_levels.resize(m_nodes.size());
    std::vector<Index> fill(m_level_offsets.begin(), m_level_offsets.end() - 1);
    for (std::size_t n = 0; n < m_nodes.size(); ++n)
        m_levels[static_cast<std::size_t>(fill[static_cast<std::size_t>(height[n])]++)] = static_cast<Index>(n);

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
    m_face_boxes.resize(m_order.size());
    m_packed_faces.resize(m_order.size());

    // Single precision traversal copy: root at 0, then sibling pairs in depth-first order from
    // slot 2 on (slot 1 stays unused so that every pair starts at an even slot: one cache line).
    m_packed.assign(m_nodes.size() + 1, PackedNode{{0, 0, 0}, {0, 0, 0}, 0, 0});
    m_packed_of.assign(m_nodes.size(), -1);
    m_packed_of[0] = 0;
    Index next = 2;
    std::vector<Index> dfs{0};
    while (!dfs.empty()) {
        const Index n = dfs.back();
        dfs.pop_back();
        const Node& node = m_nodes[static_cast<std::size_t>(n)];
        PackedNode& packed = m_packed[static_cast<std::size_t>(m_packed_of[static_cast<std::size_t>(n)])];
        if (node.left < 0) {
            packed.link = node.begin;
            packed.count = node.end - node.begin;
            continue;
        }
        CORO_ASSERT(node.right == node.left + 1);
        packed.link = next;
        packed.count = 0;
        m_packed_of[static_cast<std::size_t>(node.left)] = next;
        m_packed_of[static_cast<std::size_t>(node.right)] = next + 1;
        next += 2;
        dfs.push_back(node.right);
        dfs.push_back(node.left);
    }
    CORO_ASSERT(static_cast<std::size_t>(next) == m_packed.size());
    refit(vertices);
}

void AabbTree::pack(const Aabb& box, float* min, float* max)
{
    // Round to nearest, then step outward when that went inward: x ∓ |x|·2⁻²² lies more than
    // half a float ulp beyond x, so its nearest float does too (no libm nextafter in the loop).
    for (int k = 0; k < 3; ++k) {
        const double lo = box.min[k], hi = box.max[k];
        float flo = static_cast<float>(lo), fhi = static_cast<float>(hi);
        if (static_cast<double>(flo) > lo)
            flo = static_cast<float>(lo - std::abs(lo) * 0x1p-22 - 0x1p-140);
        if (static_cast<double>(fhi) < hi)
            fhi = static_cast<float>(hi + std::abs(hi) * 0x1p-22 + 0x1p-140);
        min[k] = flo;
        max[k] = fhi;
    }
}

void AabbTree::refit_node(CRef<Positions> vertices, Index n)
{
    Node& node = m_nodes[static_cast<std::size_t>(n)];
    PackedNode& packed = m_packed[static_cast<std::size_t>(m_packed_of[static_cast<std::size_t>(n)])];
    if (node.left >= 0) {
        node.box = m_nodes[static_cast<std::size_t>(node.left)].box;
        node.box.extend(m_nodes[static_cast<std::size_t>(node.right)].box);
        pack(node.box, packed.min, packed.max);
        return;
    }
    Aabb box;
    const double* data = vertices.data();
    const auto stride = vertices.outerStride();
    for (Index i = node.begin; i < node.end; ++i) {
        const Index f = m_order[static_cast<std::size_t>(i)];
        const double* a = data + stride * m_faces(f, 0);
        const double* b = data + stride * m_faces(f, 1);
        const double* c = data + stride * m_faces(f, 2);
        Aabb& face_box = m_face_boxes[static_cast<std::size_t>(i)];
        for (int k = 0; k < 3; ++k) {
            face_box.min[k] = std::min(std::min(a[k], b[k]), c[k]);
            face_box.max[k] = std::max(std::max(a[k], b[k]), c[k]);
        }
        box.extend(face_box);
        pack(face_box, m_packed_faces[static_cast<std::size_t>(i)].min, m_packed_faces[static_cast<std::size_t>(i)].max);
    }
    node.box = box;
    pack(box, packed.min, packed.max);
}

void AabbTree::refit(CRef<Positions> vertices)
{
    if (m_nodes.empty())
        return;
    if (m_nodes.size() < PARALLEL_REFIT_NODES) {
        for (std::size_t n = m_nodes.size(); n-- > 0;)
            refit_node(vertices, static_cast<Index>(n));
    } else {
        for (std::size_t level = 0; level + 1 < m_level_offsets.size(); ++level) {
            const auto begin = static_cast<std::size_t>(m_level_offsets[level]);
            const auto end = static_cast<std::size_t>(m_level_offsets[level + 1]);
            if (end - begin < 2 * REFIT_GRAIN) {
                for (std::size_t i = begin; i < end; ++i)
                    refit_node(vertices, m_levels[i]);
                continue;
            }
            tbb::parallel_for(tbb::blocked_range<std::size_t>(begin, end, REFIT_GRAIN),
                              [&](const tbb::blocked_range<std::size_t>& r) {
                                  for (std::size_t i = r.begin(); i < r.end(); ++i)
                                      refit_node(vertices, m_levels[i]);
                              });
        }
    }
    for (std::size_t b = 0; b < m_vertex_blocks.size(); ++b) {
        Aabb box;
        const std::size_t end = std::min(m_vertex_order.size(), (b + 1) * VERTEX_BLOCK);
        for (std::size_t i = b * VERTEX_BLOCK; i < end; ++i)
            box.extend(row(vertices, m_vertex_order[i]));
        m_vertex_blocks[b] = box;
    }
}

const Aabb& AabbTree::bounds() const
{
    static const Aabb empty;
    return m_nodes.empty() ? empty : m_nodes.front().box;
}

void AabbTree::faces_overlapping(const Aabb& box, std::vector<Index>& out) const
{
    out.clear();
    if (m_nodes.empty() || box.empty())
        return;
    Index stack[96];
    int top = 0;
    stack[top++] = 0;
    while (top > 0) {
        const Node& node = m_nodes[static_cast<std::size_t>(stack[--top])];
        if (!node.box.overlaps(box))
            continue;
        if (node.left >= 0) {
            stack[top++] = node.right;
            stack[top++] = node.left;
            continue;
        }
        for (Index i = node.begin; i < node.end; ++i)
            if (m_face_boxes[static_cast<std::size_t>(i)].overlaps(box))
                out.push_back(m_order[static_cast<std::size_t>(i)]);
    }
    std::sort(out.begin(), out.end());
}

void AabbTree::vertices_in_box(CRef<Positions> vertices, const Aabb& box, std::vector<Index>& out) const
{
    out.clear();
    if (box.empty())
        return;
    for (std::size_t b = 0; b < m_vertex_blocks.size(); ++b) {
        if (!m_vertex_blocks[b].overlaps(box))
            continue;
        const std::size_t end = std::min(m_vertex_order.size(), (b + 1) * VERTEX_BLOCK);
        for (std::size_t i = b * VERTEX_BLOCK; i < end; ++i) {
            const Index v = m_vertex_order[i];
            if (box.contains(row(vertices, v)))
                out.push_back(v);
        }
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
    if (m_packed.empty())
        return best;
    // Initial bound on the squared distance, strictly above the nearest face's computed squared
    // distance: boxes and faces at or beyond it cannot hold the answer, everything below it is
    // visited exactly as in an unbounded search (pruning only skips, never reorders), so the same
    // face wins, ties included. The hint face's distance is computed with the same formula as in
    // the search; the inflation covers the rounding of the squared distances.
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
    // Squared distance of `point` to a float box, as Σ_k max(lo_k − p_k, p_k − hi_k, 0)² in
    // double, k = 0, 1, 2 in this order; x and y in one SSE2 register (the same operations on
    // each component, so the same values as the scalar loop).
    const __m128d pxy = _mm_loadu_pd(point.data());
    const double pz = point[2];
    const __m128d zero = _mm_setzero_pd();
    const auto d2 = [&](const float* lo, const float* hi) {
        const __m128d lxy = _mm_cvtps_pd(_mm_castsi128_ps(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(lo))));
        const __m128d hxy = _mm_cvtps_pd(_mm_castsi128_ps(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(hi))));
        const __m128d dxy = _mm_max_pd(_mm_max_pd(_mm_sub_pd(lxy, pxy), _mm_sub_pd(pxy, hxy)), zero);
        const __m128d sxy = _mm_mul_pd(dxy, dxy);
        const double dz = std::max(std::max(static_cast<double>(lo[2]) - pz, pz - static_cast<double>(hi[2])), 0.0);
        return (_mm_cvtsd_f64(sxy) + _mm_cvtsd_f64(_mm_unpackhi_pd(sxy, sxy))) + dz * dz;
    };
    double best_d2 = bound_d2;
    double best_d = std::sqrt(bound_d2);
    const double* data = vertices.data();
    const auto stride = vertices.outerStride();
    Index stack[96];
    double stack_d2[96];
    int top = 0;
    stack[top] = 0;
    stack_d2[top++] = 0.0;
    while (top > 0) {
        --top;
        if (stack_d2[top] >= best_d2)
            continue;
        const PackedNode& node = m_packed[static_cast<std::size_t>(stack[top])];
        if (node.count > 0) {
            for (Index i = node.link; i < node.link + node.count; ++i) {
                const PackedBox& pb = m_packed_faces[static_cast<std::size_t>(i)];
                if (d2(pb.min, pb.max) >= best_d2)
                    continue;
                const Index f = m_order[static_cast<std::size_t>(i)];
                const double* A = data + stride * m_faces(f, 0);
                const double* B = data + stride * m_faces(f, 1);
                const double* C = data + stride * m_faces(f, 2);
                if (beyond_plane(point, A, B, C, best_d))
                    continue;
                const TrianglePoint q =
                    closest_point_on_triangle(point, Vec3(A[0], A[1], A[2]), Vec3(B[0], B[1], B[2]), Vec3(C[0], C[1], C[2]));
                const double dq = (q.point - point).squaredNorm();
                if (dq < best_d2) {
                    best_d2 = dq;
                    best_d = std::sqrt(dq);
                    best.face = f;
                    best.point = q.point;
                    best.barycentric = q.barycentric;
                }
            }
            continue;
        }
        const PackedNode& l = m_packed[static_cast<std::size_t>(node.link)];
        const PackedNode& r = m_packed[static_cast<std::size_t>(node.link) + 1];
        const double dl = d2(l.min, l.max), dr = d2(r.min, r.max);
        const bool left_near = dl <= dr;
        stack[top] = left_near ? node.link + 1 : node.link;
        stack_d2[top] = left_near ? dr : dl;
        top += (left_near ? dr : dl) < best_d2;
        stack[top] = left_near ? node.link : node.link + 1;
        stack_d2[top] = left_near ? dl : dr;
        top += (left_near ? dl : dr) < best_d2;
    }
    if (best.face < 0) // a bound below the true distance (an invalid hint): search again without it
        return bound_d2 < std::numeric_limits<double>::infinity()
                   ? nearest(vertices, point, std::numeric_limits<double>::infinity(), -1)
                   : best;
    best.distance = std::sqrt(best_d2);
    return best;
}

} // namespace coro
