#include "exact_parity.hpp"

#include "orientation.hpp"

#include <algorithm>
#include <array>
#include <cmath>

namespace coro::detail {

namespace {

/// The exact sign of ((B − A) × (C − A))·(D − A): positive when D lies on the side that the
/// normal of (A, B, C) points to. The float value decides when it exceeds its rounding bound.
int orient3d(const double* A, const double* B, const double* C, const double* D)
{
    const FaceNormal normal = face_normal(A, B, C);
    const double d[3] = {D[0] - A[0], D[1] - A[1], D[2] - A[2]};
    const double value = normal.n[0] * d[0] + normal.n[1] * d[1] + normal.n[2] * d[2];
    const double bound =
        ORIENT3D_BOUND * (normal.permanent[0] * std::abs(d[0]) + normal.permanent[1] * std::abs(d[1]) +
                          normal.permanent[2] * std::abs(d[2])) +
        UNDERFLOW_BOUND * (1.0 + std::abs(d[0]) + std::abs(d[1]) + std::abs(d[2]));
    if (std::abs(value) > bound)
        return value > 0.0 ? 1 : -1;
    return -exact_plane_side(A, B, C, D); // that one is the sign of n·(A − D)
}

/// P exactly in the closed triangle (A, B, C), P exactly on its plane: the 2D signs in a
/// coordinate plane where the triangle's projection is not degenerate, trying first the one where
/// the float normal says it is largest (for a tiny face every float component may underflow to 0).
bool in_closed_triangle(const double* A, const double* B, const double* C, const double* P)
{
    const FaceNormal normal = face_normal(A, B, C);
    int largest = 0;
    for (int j = 1; j < 3; ++j)
        if (std::abs(normal.n[j]) > std::abs(normal.n[largest]))
            largest = j;
    for (int k = 0; k < 3; ++k) {
        const int a = (largest + k) % 3, u = (a + 1) % 3, v = (a + 2) % 3;
        const int area = exact_orient2d(A[u], A[v], B[u], B[v], C[u], C[v]);
        if (area == 0) // the face is edge-on in this projection
            continue;
        const int s0 = exact_orient2d(P[u], P[v], B[u], B[v], C[u], C[v]);
        const int s1 = exact_orient2d(P[u], P[v], C[u], C[v], A[u], A[v]);
        const int s2 = exact_orient2d(P[u], P[v], A[u], A[v], B[u], B[v]);
        return s0 * area >= 0 && s1 * area >= 0 && s2 * area >= 0;
    }
    return false; // a degenerate face: no area to be in
}

enum class SegmentMeets { MISSES, CROSSES, EDGE_OR_VERTEX };

/// How the segment P → Q (P off the surface, Q outside the surface's box) meets triangle
/// (A, B, C): through its interior, through an edge or vertex (no parity from that segment), or
/// not at all.
SegmentMeets segment_meets(const double* A, const double* B, const double* C, const double* P, const double* Q)
{
    const int sp = orient3d(A, B, C, P), sq = orient3d(A, B, C, Q);
    if (sp == 0 && sq == 0) // the segment in the face's plane
        return SegmentMeets::EDGE_OR_VERTEX;
    if (sp == 0 || sq == 0 || sp == sq) // only P (not on the face) or Q (outside its box) on the plane
        return SegmentMeets::MISSES;
    const int t0 = orient3d(P, Q, A, B), t1 = orient3d(P, Q, B, C), t2 = orient3d(P, Q, C, A);
    if ((t0 > 0 && t1 > 0 && t2 > 0) || (t0 < 0 && t1 < 0 && t2 < 0))
        return SegmentMeets::CROSSES;
    const bool positive = t0 > 0 || t1 > 0 || t2 > 0, negative = t0 < 0 || t1 < 0 || t2 < 0;
    return positive && negative ? SegmentMeets::MISSES : SegmentMeets::EDGE_OR_VERTEX;
}

} // namespace

ParityTest exact_parity_test(const ContactSurface& surface, const Vec3& point)
{
    const auto corner = [&](Index f, int c) { return surface.vertices.data() + 3 * surface.faces(f, c); };
    const double* p = point.data();
    ParityTest result;
    Vec3 lo = point, hi = point;
    for (Index f = 0; f < surface.faces.rows(); ++f) {
        const double *A = corner(f, 0), *B = corner(f, 1), *C = corner(f, 2);
        bool in_box = true;
        for (int j = 0; j < 3; ++j) {
            const double fl = std::min({A[j], B[j], C[j]}), fh = std::max({A[j], B[j], C[j]});
            lo[j] = std::min(lo[j], fl);
            hi[j] = std::max(hi[j], fh);
            in_box = in_box && fl <= p[j] && p[j] <= fh;
        }
        if (in_box && orient3d(A, B, C, p) == 0 && in_closed_triangle(A, B, C, p)) {
            result.decided = true;
            result.on_surface = true;
            return result;
        }
    }
    // Segments in directions of no special alignment to the axes or to one another, long enough
    // to end outside the box of the surface and the point.
    static constexpr std::array<std::array<double, 3>, 6> DIRECTIONS{{{1.0, 0.318, 0.147},
                                                                      {-0.271, 1.0, 0.413},
                                                                      {0.159, -0.367, 1.0},
                                                                      {-1.0, -0.233, 0.561},
                                                                      {0.437, -1.0, -0.289},
                                                                      {-0.613, 0.191, -1.0}}};
    const double reach = 2.0 * (hi - lo).norm() + 1.0;
    for (const auto& direction : DIRECTIONS) {
        double q[3];
        for (int j = 0; j < 3; ++j)
            q[j] = p[j] + reach * direction[static_cast<std::size_t>(j)];
        bool clean = true;
        bool odd = false;
        for (Index f = 0; f < surface.faces.rows() && clean; ++f) {
            const double *A = corner(f, 0), *B = corner(f, 1), *C = corner(f, 2);
            bool apart = false; // the face's box misses the segment's box
            for (int j = 0; j < 3; ++j) {
                const double sl = std::min(p[j], q[j]), sh = std::max(p[j], q[j]);
                apart = apart || std::max({A[j], B[j], C[j]}) < sl || std::min({A[j], B[j], C[j]}) > sh;
            }
            if (apart)
                continue;
            switch (segment_meets(A, B, C, p, q)) {
            case SegmentMeets::CROSSES: odd = !odd; break;
            case SegmentMeets::EDGE_OR_VERTEX: clean = false; break;
            case SegmentMeets::MISSES: break;
            }
        }
        if (clean) {
            result.decided = true;
            result.inside = odd;
            return result;
        }
    }
    return result;
}

} // namespace coro::detail
