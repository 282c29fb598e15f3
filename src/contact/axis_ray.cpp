#include <corocontact/contact/axis_ray.hpp>

#include <corocontact/contact/winding_number.hpp>

#include "detail/axis_walk.hpp"
#include "detail/exact_parity.hpp"
#include "detail/inside_tests.hpp"
#include "detail/orientation.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace coro {

namespace {

using detail::EPS;
using detail::ORIENT2D_BOUND;
using detail::ORIENT3D_BOUND;
using detail::UNDERFLOW_BOUND;
constexpr double INF = std::numeric_limits<double>::infinity();

/// One face against the axis line of a point (exact modes).
struct FaceHit {
    enum Kind : unsigned char { MISS, CLEAN, EDGE, PARALLEL };
    Kind kind;
    bool vote;       ///< d·n > 0: the point is on the inner side of the face's plane
    bool on_surface; ///< the point is on the face (exactly on its plane, in the closed triangle)
    double distance; ///< |t|, or for PARALLEL the gap to the face's extent along the axis
    double bound;    ///< rounding bound of `distance`
};
constexpr FaceHit MISSED{FaceHit::MISS, false, false, 0.0, 0.0};

struct Frame {
    int a, u, v;
    double pa, pu, pv;
};

Frame frame_of(const Vec3& p, int axis)
{
    const int u = (axis + 1) % 3, v = (axis + 2) % 3;
    return {axis, u, v, p[axis], p[u], p[v]};
}

/// Eq. 4–6 in exact arithmetic's terms: the signed sub-areas w_i = A_i (twice the area) of the
/// point's projection with each projected edge; the projection is inside when all have the sign
/// of Af = n_axis. Each sign is trusted only beyond its rounding bound (plus `edge_relative`·|Af|).
FaceHit classify_exact(const double* A, const double* B, const double* C, const Frame& f,
                       const AxisRayTolerances& tol)
{
    FaceHit hit = MISSED;
    const double au = A[f.u] - f.pu, av = A[f.v] - f.pv;
    const double bu = B[f.u] - f.pu, bv = B[f.v] - f.pv;
    const double cu = C[f.u] - f.pu, cv = C[f.v] - f.pv;
    const double w0 = bu * cv - bv * cu;
    const double e0 = ORIENT2D_BOUND * (std::abs(bu * cv) + std::abs(bv * cu)) + UNDERFLOW_BOUND;
    const double w1 = cu * av - cv * au;
    const double e1 = ORIENT2D_BOUND * (std::abs(cu * av) + std::abs(cv * au)) + UNDERFLOW_BOUND;
    const double w2 = au * bv - av * bu;
    const double e2 = ORIENT2D_BOUND * (std::abs(au * bv) + std::abs(av * bu)) + UNDERFLOW_BOUND;

    // Face normal n = (B − A) × (C − A); n_a is the projected (doubled) area Af.
    const detail::FaceNormal normal = detail::face_normal(A, B, C);
    const double* n = normal.n;
    const double* perm = normal.permanent;
    const double na = n[f.a];
    const double na_bound = ORIENT2D_BOUND * perm[f.a] + UNDERFLOW_BOUND;
    const double n_norm = std::abs(n[0]) + std::abs(n[1]) + std::abs(n[2]);

    if (std::abs(na) <= std::max(tol.parallel_relative * n_norm, na_bound)) {
        // Parallel (or degenerate) face: met when the point's projection is on the thin projected
        // triangle, for either orientation, within rounding.
        const bool met_pos = w0 >= -e0 && w1 >= -e1 && w2 >= -e2;
        const bool met_neg = w0 <= e0 && w1 <= e1 && w2 <= e2;
        if (!met_pos && !met_neg)
            return hit;
        hit.kind = FaceHit::PARALLEL;
        const double lo = std::min({A[f.a], B[f.a], C[f.a]}), hi = std::max({A[f.a], B[f.a], C[f.a]});
        hit.distance = std::max({lo - f.pa, f.pa - hi, 0.0});
        return hit;
    }
    const double s = na > 0.0 ? 1.0 : -1.0;
    const double margin = tol.edge_relative * std::abs(na);
    const double s0 = s * w0, s1 = s * w1, s2 = s * w2;
    if (s0 < -(e0 + margin) || s1 < -(e1 + margin) || s2 < -(e2 + margin))
        return hit;
    const bool clean = s0 > e0 + margin && s1 > e1 + margin && s2 > e2 + margin;
    hit.kind = clean ? FaceHit::CLEAN : FaceHit::EDGE;

    // num = n·(A − p); t = num / n_a is the crossing's coordinate along the axis minus the
    // point's; d·n = sign(t)·n_a has the sign of num.
    double qa[3];
    qa[f.a] = A[f.a] - f.pa;
    qa[f.u] = au;
    qa[f.v] = av;
    const double num = n[0] * qa[0] + n[1] * qa[1] + n[2] * qa[2];
    const double num_bound =
        ORIENT3D_BOUND * (perm[0] * std::abs(qa[0]) + perm[1] * std::abs(qa[1]) + perm[2] * std::abs(qa[2])) +
        UNDERFLOW_BOUND * (1.0 + std::abs(qa[0]) + std::abs(qa[1]) + std::abs(qa[2]));
    const double t = std::abs(num / na);
    hit.distance = t;
    hit.bound = 1.01 * ((num_bound + t * na_bound) / (std::abs(na) - na_bound) + EPS * t) + UNDERFLOW_BOUND;
    hit.vote = num > 0.0;
    if (std::abs(num) <= num_bound) {
        // The point lies within rounding of the face's plane: the exact side decides the vote,
        // and only a point exactly on the plane and in the closed triangle is on the surface
        // (a point a rounding inside the surface is inside).
        double p[3];
        p[f.a] = f.pa;
        p[f.u] = f.pu;
        p[f.v] = f.pv;
        const int side = detail::exact_plane_side(A, B, C, p);
        if (side != 0) {
            hit.vote = side > 0;
        } else {
            const auto sign = [&](double w, double e, const double* X, const double* Y) {
                return std::abs(w) > e ? (w > 0.0 ? 1 : -1) : detail::exact_orient2d(f.pu, f.pv, X[f.u], X[f.v], Y[f.u], Y[f.v]);
            };
            const int sa = na > 0.0 ? 1 : -1; // beyond its rounding: the face is not parallel
            hit.on_surface = sa * sign(w0, e0, B, C) >= 0 && sa * sign(w1, e1, C, A) >= 0 && sa * sign(w2, e2, A, B) >= 0;
        }
    }
    return hit;
}

/// The competing crossings of one axis: keeps those that can still be within the cutoff.
class AxisHits {
public:
    AxisHits() = default;
    explicit AxisHits(double tie_relative) : m_tie(1.0 + tie_relative) {}
    /// Back to no crossing, with this tie tolerance (cheaper than a new object: no copy of the
    /// hit buffer).
    void reset(double tie_relative)
    {
        m_count = 0;
        m_any = false;
        m_overflow = false;
        m_closest = INF;
        m_clean_closest = INF;
        m_clean_face = -1;
        m_tie = 1.0 + tie_relative;
    }

    /// Largest distance along the axis still of interest.
    double cutoff() const { return m_closest * m_tie; }

    void add(const FaceHit& h, Index face)
    {
        if (h.kind == FaceHit::MISS)
            return;
        m_any = true;
        if (h.kind != FaceHit::PARALLEL)
            m_closest = std::min(m_closest, h.distance + h.bound);
        // Of equally close clean crossings the lowest face wins, whatever the visiting order.
        if (h.kind == FaceHit::CLEAN && (h.distance + h.bound < m_clean_closest ||
                                         (h.distance + h.bound == m_clean_closest && face < m_clean_face))) {
            m_clean_closest = h.distance + h.bound;
            m_clean_face = face;
        }
        if (lower(h) > cutoff())
            return;
        if (m_count == CAPACITY) {
            compact();
            if (m_count == CAPACITY) {
                m_overflow = true;
                return;
            }
        }
        m_hits[m_count++] = h;
    }

    AxisOutcome decide() const
    {
        if (!m_any)
            return AxisOutcome::NO_HIT;
        const double cut = cutoff();
        bool degenerate = m_overflow || m_closest == INF;
        int votes[2] = {0, 0};
        for (int i = 0; i < m_count; ++i) {
            const FaceHit& h = m_hits[i];
            if (lower(h) > cut)
                continue;
            if (h.on_surface)
                return AxisOutcome::ON_SURFACE;
            if (h.kind != FaceHit::CLEAN)
                degenerate = true;
            else
                ++votes[h.vote ? 1 : 0];
        }
        if (degenerate || (votes[0] > 0 && votes[1] > 0) || votes[0] + votes[1] == 0)
            return AxisOutcome::DEGENERATE;
        return votes[1] > 0 ? AxisOutcome::INSIDE : AxisOutcome::OUTSIDE;
    }

    /// More competing crossings than fit were met: the only result that may depend on the
    /// order in which the faces came (decide() then says DEGENERATE).
    bool overflowed() const { return m_overflow; }

    /// The closest clean crossing (distance plus rounding bound, face); +∞, −1 if none.
    double clean_closest() const { return m_clean_closest; }
    Index clean_face() const { return m_clean_face; }

private:
    static double lower(const FaceHit& h) { return h.distance - h.bound; }
    void compact()
    {
        const double cut = cutoff();
        int kept = 0;
        for (int i = 0; i < m_count; ++i)
            if (lower(m_hits[i]) <= cut)
                m_hits[kept++] = m_hits[i];
        m_count = kept;
    }

    static constexpr int CAPACITY = 32;
    FaceHit m_hits[CAPACITY]; // NOLINT: filled up to m_count only
    int m_count = 0;
    bool m_any = false;
    bool m_overflow = false;
    double m_closest = INF;
    double m_clean_closest = INF;
    Index m_clean_face = -1;
    double m_tie = 1.0;
};

const double* vertex_ptr(const ContactSurface& s, Index v) { return s.vertices.data() + 3 * static_cast<std::ptrdiff_t>(v); }

/// Closest clean crossing of the last exact-mode axis test (see InsideTest).
struct Crossing {
    double bound = INF;
    Index face = -1;
};

AxisOutcome axis_test_exact(const ContactSurface& surface, const Vec3& point, int axis,
                            const AxisRayTolerances& tol, Crossing* crossing = nullptr)
{
    const Frame f = frame_of(point, axis);
    AxisHits hits(tol.tie_relative);
    detail::faces_on_axis_line(surface.tree, surface.vertices, point, axis, 0.0, [&](Index face, const Index* corners) {
        hits.add(classify_exact(vertex_ptr(surface, corners[0]), vertex_ptr(surface, corners[1]),
                                vertex_ptr(surface, corners[2]), f, tol),
                 face);
        return hits.cutoff();
    });
    if (crossing)
        *crossing = {hits.clean_closest(), hits.clean_face()};
    return hits.decide();
}

AxisOutcome axis_test_brute_force(const ContactSurface& surface, const Vec3& point, int axis,
                                  const AxisRayTolerances& tol, Crossing* crossing = nullptr)
{
    const Frame f = frame_of(point, axis);
    AxisHits hits(tol.tie_relative);
    const Tris& faces = surface.faces;
    for (Index face = 0; face < faces.rows(); ++face) {
        const double* A = vertex_ptr(surface, faces(face, 0));
        const double* B = vertex_ptr(surface, faces(face, 1));
        const double* C = vertex_ptr(surface, faces(face, 2));
        // Eq. 4, closed: the bounding rectangle of the projected face.
        if (f.pu < std::min({A[f.u], B[f.u], C[f.u]}) || f.pu > std::max({A[f.u], B[f.u], C[f.u]}) ||
            f.pv < std::min({A[f.v], B[f.v], C[f.v]}) || f.pv > std::max({A[f.v], B[f.v], C[f.v]}))
            continue;
        hits.add(classify_exact(A, B, C, f, tol), face);
    }
    if (crossing)
        *crossing = {hits.clean_closest(), hits.clean_face()};
    return hits.decide();
}

AxisOutcome axis_test_paper(const ContactSurface& surface, const Vec3& point, int axis,
                            const std::vector<Index>& candidate_faces, const AxisRayTolerances& tol)
{
    const Frame f = frame_of(point, axis);
    const Tris& faces = surface.faces;
    double best = INF;
    bool inside = false;
    for (const Index face : candidate_faces) {
        const double* A = vertex_ptr(surface, faces(face, 0));
        const double* B = vertex_ptr(surface, faces(face, 1));
        const double* C = vertex_ptr(surface, faces(face, 2));
        // Eq. 4: strict inequalities against the bounding rectangle.
        if (!(f.pu > std::min({A[f.u], B[f.u], C[f.u]}) && f.pu < std::max({A[f.u], B[f.u], C[f.u]}) &&
              f.pv > std::min({A[f.v], B[f.v], C[f.v]}) && f.pv < std::max({A[f.v], B[f.v], C[f.v]})))
            continue;
        // Eq. 5/6 with areas doubled: A1 + A2 + A3 = Af inside, > Af outside.
        const double au = A[f.u] - f.pu, av = A[f.v] - f.pv;
        const double bu = B[f.u] - f.pu, bv = B[f.v] - f.pv;
        const double cu = C[f.u] - f.pu, cv = C[f.v] - f.pv;
        const double a1 = std::abs(bu * cv - bv * cu);
        const double a2 = std::abs(cu * av - cv * au);
        const double a3 = std::abs(au * bv - av * bu);
        const Vec3 e1(B[0] - A[0], B[1] - A[1], B[2] - A[2]);
        const Vec3 e2(C[0] - A[0], C[1] - A[1], C[2] - A[2]);
        const Vec3 n = e1.cross(e2);
        const double af = std::abs(n[axis]);
        if (af == 0.0 || a1 + a2 + a3 > (1.0 + tol.area_relative) * af)
            continue;
        const double num = n.dot(Vec3(A[0], A[1], A[2]) - point);
        const double t = std::abs(num / n[axis]);
        if (t < best) {
            best = t;
            inside = num > 0.0; // d·n > 0
        }
    }
    if (best == INF)
        return AxisOutcome::NO_HIT;
    return inside ? AxisOutcome::INSIDE : AxisOutcome::OUTSIDE;
}

} // namespace

AxisOutcome axis_test(const ContactSurface& surface, const Vec3& point, int axis, DetectionMode mode,
                      const std::vector<Index>& candidate_faces, const AxisRayTolerances& tolerances)
{
    switch (mode) {
    case DetectionMode::PAPER:
        return axis_test_paper(surface, point, axis, candidate_faces, tolerances);
    case DetectionMode::BRUTE_FORCE:
        return axis_test_brute_force(surface, point, axis, tolerances);
    case DetectionMode::EXACT:
        break;
    }
    return axis_test_exact(surface, point, axis, tolerances);
}

namespace {

/// Records an axis outcome in `result`; true when it decides (see inside_test()).
bool settle(AxisOutcome outcome, int axis, const Crossing& crossing, DetectionMode mode, InsideTest& result)
{
    switch (outcome) {
    case AxisOutcome::INSIDE:
    case AxisOutcome::OUTSIDE:
        result.inside = outcome == AxisOutcome::INSIDE;
        result.decided_by = decided_by_axis(axis);
        result.surface_distance_bound = crossing.bound;
        result.crossing_face = crossing.face;
        return true;
    case AxisOutcome::ON_SURFACE:
        result.on_surface = true;
        result.decided_by = decided_by_axis(axis);
        return true;
    case AxisOutcome::NO_HIT:
        if (mode != DetectionMode::PAPER) {
            result.decided_by = decided_by_axis(axis);
            return true;
        }
        return false;
    case AxisOutcome::DEGENERATE:
        return false;
    }
    return false;
}

/// inside_test() of a closed surface from axis `first_axis` on.
InsideTest inside_test_from(const ContactSurface& surface, const Vec3& point, int first_axis, DetectionMode mode,
                            const std::vector<Index>& candidate_faces, const AxisRayTolerances& tolerances)
{
    InsideTest result;
    for (int axis = first_axis; axis < 3; ++axis) {
        Crossing crossing;
        const AxisOutcome outcome =
            mode == DetectionMode::EXACT         ? axis_test_exact(surface, point, axis, tolerances, &crossing)
            : mode == DetectionMode::BRUTE_FORCE ? axis_test_brute_force(surface, point, axis, tolerances, &crossing)
                                                 : axis_test_paper(surface, point, axis, candidate_faces, tolerances);
        if (settle(outcome, axis, crossing, mode, result))
            return result;
    }
    if (mode != DetectionMode::PAPER) {
        const detail::ParityTest parity = detail::exact_parity_test(surface, point);
        if (parity.decided) {
            result.inside = parity.inside;
            result.on_surface = parity.on_surface;
            result.decided_by = DecidedBy::EXACT_PARITY;
        } else { // every segment tried met an edge or a vertex: not seen, but not impossible
            result.inside = winding_number(surface.vertices, surface.faces, point) > 0.5;
            result.decided_by = DecidedBy::WINDING_NUMBER;
        }
    }
    return result;
}

/// Exact mode, closed surface: the x axes of up to AXIS_PACKET points in one tree walk; the
/// points that x does not decide go on alone (y, z, winding number).
void inside_tests_packet(const ContactSurface& surface, const Vec3* points, int count,
                         const AxisRayTolerances& tol, InsideTest* results)
{
    constexpr int N = detail::AXIS_PACKET;
    AxisHits hits[N];
    Frame frames[N];
    for (int q = 0; q < count; ++q) {
        hits[q].reset(tol.tie_relative);
        frames[q] = frame_of(points[q], 0);
    }
    const auto visit = [&](int q, Index face, const Index* corners) {
        AxisHits& h = hits[q];
        h.add(classify_exact(vertex_ptr(surface, corners[0]), vertex_ptr(surface, corners[1]),
                             vertex_ptr(surface, corners[2]), frames[q], tol),
              face);
        return h.cutoff();
    };
    detail::faces_on_axis_lines(surface.tree, surface.vertices, points, count, 0, 0.0, visit);
    for (int q = 0; q < count; ++q) {
        InsideTest& result = results[q];
        result = InsideTest();
        Crossing crossing;
        AxisOutcome outcome;
        if (hits[q].overflowed()) { // the one order-dependent case: the single walk's answer
            outcome = axis_test_exact(surface, points[q], 0, tol, &crossing);
        } else {
            outcome = hits[q].decide();
            crossing = {hits[q].clean_closest(), hits[q].clean_face()};
        }
        if (!settle(outcome, 0, crossing, DetectionMode::EXACT, result))
            result = inside_test_from(surface, points[q], 1, DetectionMode::EXACT, {}, tol);
    }
}

} // namespace

InsideTest inside_test(const ContactSurface& surface, const Vec3& point, DetectionMode mode,
                       const std::vector<Index>& candidate_faces, const AxisRayTolerances& tolerances)
{
    if (!surface.closed) {
        InsideTest result;
        result.inside = winding_number(surface.vertices, surface.faces, point) > 0.5;
        result.decided_by = DecidedBy::WINDING_NUMBER;
        return result;
    }
    return inside_test_from(surface, point, 0, mode, candidate_faces, tolerances);
}

void detail::inside_tests(const ContactSurface& surface, const Vec3* points, Index count, DetectionMode mode,
                          const std::vector<Index>& candidate_faces, const AxisRayTolerances& tolerances,
                          InsideTest* results)
{
    if (mode != DetectionMode::EXACT || !surface.closed) {
        for (Index i = 0; i < count; ++i)
            results[i] = inside_test(surface, points[i], mode, candidate_faces, tolerances);
        return;
    }
    for (Index i = 0; i < count; i += detail::AXIS_PACKET) {
        const int n = static_cast<int>(std::min<Index>(detail::AXIS_PACKET, count - i));
        inside_tests_packet(surface, points + i, n, tolerances, results + i);
    }
}

} // namespace coro
