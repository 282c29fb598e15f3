// The plane and slab caches of AabbTree that let nearest() skip faces and subtrees by their
// distance along a normal: built once per tree (which vertices each slab spans), recomputed by
// update_planes() for new positions.
#include <corocontact/contact/aabb_tree.hpp>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace coro {

void AabbTree::build_slab_vertices(std::size_t vertex_count)
{
    // The distinct vertices of each subtree of at most SLAB_MAX_FACES faces, in order of first
    // appearance: a slab's extent is over them, not over its faces' corners (each vertex is the
    // corner of about six faces).
    m_slab_vertex_start.assign(m_nodes.size() + 1, 0);
    m_slab_vertices.clear();
    std::vector<Index> seen_by(vertex_count, -1);
    for (std::size_t n = 0; n < m_nodes.size(); ++n) {
        const auto begin = static_cast<std::size_t>(m_node_slots[2 * n]);
        const auto end = static_cast<std::size_t>(m_node_slots[2 * n + 1]);
        if (end - begin <= static_cast<std::size_t>(SLAB_MAX_FACES))
            for (std::size_t i = 3 * begin; i < 3 * end; ++i) {
                const Index v = m_slot_vertices[i];
                if (seen_by[static_cast<std::size_t>(v)] != static_cast<Index>(n)) {
                    seen_by[static_cast<std::size_t>(v)] = static_cast<Index>(n);
                    m_slab_vertices.push_back(v);
                }
            }
        m_slab_vertex_start[n + 1] = static_cast<Index>(m_slab_vertices.size());
    }
}

void AabbTree::face_plane(const double* A, const double* B, const double* C, FacePlanes& w, int k)
{
    // In single precision: u = the normalised cross product of the edges rounded to float, the
    // offset u·A. The slack is measured: for x = A + s·e1 + t·e2 on the face, u·(x − A) =
    // s·(u·e1) + t·(u·e2) lies within max(|u·e1|, |u·e2|) of 0; the float evaluation of those
    // dot products and of the offset (from float roundings of A, e1, e2: each within 2⁻²⁴ of
    // its value) errs by less than 2⁻²¹·(|A|₁ + |e1|₁ + |e2|₁), which is added. Any error in u
    // only widens the slack; |u| ≤ 1 + 2⁻²² (correctly rounded sqrt and division).
    const float a[3] = {static_cast<float>(A[0]), static_cast<float>(A[1]), static_cast<float>(A[2])};
    const float e1[3] = {static_cast<float>(B[0] - A[0]), static_cast<float>(B[1] - A[1]), static_cast<float>(B[2] - A[2])};
    const float e2[3] = {static_cast<float>(C[0] - A[0]), static_cast<float>(C[1] - A[1]), static_cast<float>(C[2] - A[2])};
    const float n[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]};
    const float nn = n[0] * n[0] + n[1] * n[1] + n[2] * n[2];
    if (!(nn > 1e-30f) || !(nn < 1e30f)) { // degenerate (or absurd) face: never pruned by its plane
        w.normal[0][k] = w.normal[1][k] = w.normal[2][k] = 0.0f;
        w.offset[k] = 0.0f;
        w.slack[k] = std::numeric_limits<float>::infinity();
        return;
    }
    const float inv = 1.0f / std::sqrt(nn);
    const float u[3] = {n[0] * inv, n[1] * inv, n[2] * inv};
    const float off = u[0] * a[0] + u[1] * a[1] + u[2] * a[2];
    const float s1 = std::abs(u[0] * e1[0] + u[1] * e1[1] + u[2] * e1[2]);
    const float s2 = std::abs(u[0] * e2[0] + u[1] * e2[1] + u[2] * e2[2]);
    const float magnitude = std::abs(a[0]) + std::abs(a[1]) + std::abs(a[2]) + std::abs(e1[0]) + std::abs(e1[1]) +
                            std::abs(e1[2]) + std::abs(e2[0]) + std::abs(e2[1]) + std::abs(e2[2]);
    for (int j = 0; j < 3; ++j)
        w.normal[j][k] = u[j];
    w.offset[k] = off;
    w.slack[k] = (std::max(s1, s2) + magnitude * 0x1p-20f) * (1.0f + 0x1p-20f) + 0x1p-120f;
}

void AabbTree::update_planes(CRef<Positions> vertices) const
{
    if (m_planes_current)
        return;
    m_planes.resize(m_nodes.size());
    const double* data = vertices.data();
    const std::ptrdiff_t stride = vertices.outerStride();
    // Area-weighted face normals per slot, and per node their sum and the sum of their lengths
    // (bottom-up: children follow their parents): a node slab's direction is its sum.
    std::vector<Vec3> normals(m_order.size());
    std::vector<double> lengths(m_order.size());
    const auto normals_of = [&](std::size_t begin, std::size_t end) {
        for (std::size_t i = begin; i < end; ++i) {
            const Index* fv = &m_slot_vertices[3 * i];
            const Vec3 a(data + stride * fv[0]), b(data + stride * fv[1]), c(data + stride * fv[2]);
            normals[i] = (b - a).cross(c - a);
            lengths[i] = normals[i].norm();
        }
    };
    std::vector<Vec3> node_sum(m_nodes.size());
    std::vector<double> node_total(m_nodes.size());
    const auto sums = [&] {
        for (std::size_t n = m_nodes.size(); n-- > 0;) {
            const WideNode& w = m_nodes[n];
            Vec3 sum = Vec3::Zero();
            double total = 0.0;
            for (int k = 0; k < w.count; ++k) {
                const Index c = w.child[k];
                if (c < 0) {
                    sum += normals[static_cast<std::size_t>(-1 - c)];
                    total += lengths[static_cast<std::size_t>(-1 - c)];
                } else {
                    sum += node_sum[static_cast<std::size_t>(c)];
                    total += node_total[static_cast<std::size_t>(c)];
                }
            }
            node_sum[n] = sum;
            node_total[n] = total;
        }
    };
    // A child node's slab: along the unit direction u of its faces' summed normals, the range of
    // u·x over its faces' vertices (so over its faces), stored as offset ± slack with the float
    // rounding of u and the offset and the double rounding of u·x covered. Only for nodes whose
    // normals spread little (|sum| > 0.7·Σ|n|, within about 45°): wider patches get no slab
    // (slack +∞), their box bounds as well.
    const auto slab_of = [&](Index node, FacePlanes& fp, int k) {
        fp.normal[0][k] = fp.normal[1][k] = fp.normal[2][k] = 0.0f;
        fp.offset[k] = 0.0f;
        fp.slack[k] = std::numeric_limits<float>::infinity();
        const Vec3& sum = node_sum[static_cast<std::size_t>(node)];
        const double len = sum.norm();
        if (!(len > 0.7 * node_total[static_cast<std::size_t>(node)]) || !std::isfinite(len))
            return;
        const auto begin = static_cast<std::size_t>(m_slab_vertex_start[static_cast<std::size_t>(node)]);
        const auto end = static_cast<std::size_t>(m_slab_vertex_start[static_cast<std::size_t>(node) + 1]);
        if (begin == end) // more than SLAB_MAX_FACES faces
            return;
        const float u[3] = {static_cast<float>(sum[0] / len), static_cast<float>(sum[1] / len),
                            static_cast<float>(sum[2] / len)};
        const double ud[3] = {u[0], u[1], u[2]};
        double lo = std::numeric_limits<double>::infinity(), hi = -lo;
        for (std::size_t i = begin; i < end; ++i) {
            const double* x = data + stride * m_slab_vertices[i];
            const double t = ud[0] * x[0] + ud[1] * x[1] + ud[2] * x[2];
            lo = std::min(lo, t);
            hi = std::max(hi, t);
        }
        // Bounds |x| of every coordinate x of the node's vertices (they lie in its float box).
        const NodeBounds& box = m_node_bounds[static_cast<std::size_t>(node)];
        double magnitude = 0.0;
        for (int j = 0; j < 3; ++j)
            magnitude += std::abs(static_cast<double>(box.lo[j])) + std::abs(static_cast<double>(box.hi[j]));
        const double mid = 0.5 * (lo + hi);
        const float off = static_cast<float>(mid);
        const double slack = 0.5 * (hi - lo) + std::abs(static_cast<double>(off) - mid) + 1e-14 * magnitude;
        for (int j = 0; j < 3; ++j)
            fp.normal[j][k] = u[j];
        fp.offset[k] = off;
        fp.slack[k] = detail::float_up(slack);
    };
    const auto planes_of = [&](std::size_t n) {
        const WideNode& w = m_nodes[n];
        FacePlanes& fp = m_planes[n];
        for (int k = 0; k < 4; ++k) {
            const Index c = k < w.count ? w.child[k] : 0;
            if (k >= w.count) {
                fp.normal[0][k] = fp.normal[1][k] = fp.normal[2][k] = 0.0f;
                fp.offset[k] = 0.0f;
                fp.slack[k] = std::numeric_limits<float>::infinity();
            } else if (c >= 0) {
                slab_of(c, fp, k);
            } else {
                const Index* fv = &m_slot_vertices[3 * static_cast<std::size_t>(-1 - c)];
                face_plane(data + stride * fv[0], data + stride * fv[1], data + stride * fv[2], fp, k);
            }
        }
    };
    // Every node's planes depend only on its own faces: any split gives the same result.
    constexpr std::size_t GRAIN = 512;
    if (m_nodes.size() < 4 * GRAIN) {
        normals_of(0, normals.size());
        sums();
        for (std::size_t n = 0; n < m_nodes.size(); ++n)
            planes_of(n);
    } else {
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, normals.size(), 4 * GRAIN),
                          [&](const tbb::blocked_range<std::size_t>& r) { normals_of(r.begin(), r.end()); });
        sums();
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, m_nodes.size(), GRAIN),
                          [&](const tbb::blocked_range<std::size_t>& r) {
                              for (std::size_t n = r.begin(); n < r.end(); ++n)
                                  planes_of(n);
                          });
    }
    m_planes_current = true;
}

} // namespace coro
