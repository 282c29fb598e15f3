#include <corocontact/contact/axis_ray.hpp>

#include <algorithm>
#include <cmath>

namespace coro {

namespace {

// Points handled together: a detector block; the arrays below live on the stack.
constexpr Index CHUNK = 256;
// A new point's empty cube is walked for only when it would hold the previous point or one of
// the next LOOKAHEAD points: a smaller one would decide nothing but its own centre.
constexpr int LOOKAHEAD = 2;

struct EmptyCube {
    Vec3 lo, hi;
    int centre; ///< the point it was walked for
    bool holds(const Vec3& p) const
    {
        return lo[0] <= p[0] && p[0] <= hi[0] && lo[1] <= p[1] && p[1] <= hi[1] && lo[2] <= p[2] && p[2] <= hi[2];
    }
};

double chebyshev(const Vec3& a, const Vec3& b) { return (a - b).cwiseAbs().maxCoeff(); }

Index shared_chunk(const ContactSurface& surface, const Vec3* points, int count, const AxisRayTolerances& tol,
                   InsideTest* results)
{
    Aabb box;
    for (int i = 0; i < count; ++i)
        box.extend(points[i]);
    EmptyCube cubes[CHUNK];
    int n_cubes = 0;
    int decider[CHUNK]; // the earlier point whose answer point i takes (i itself when tested)
    int tested[CHUNK];
    int n_tested = 0;
    Index hint = -1;
    for (int i = 0; i < count; ++i) {
        const Vec3& p = points[i];
        decider[i] = i;
        for (int c = n_cubes; c-- > 0;) // the latest cubes are the likeliest (spatial order)
            if (cubes[c].holds(p)) {
                decider[i] = cubes[c].centre;
                break;
            }
        if (decider[i] != i)
            continue;
        // Outside every cube: its own cube, walked for when it would reach the previous point or
        // one of the next ones (the largest needed holds every point of the chunk), joins it to
        // the previous point; else a segment to that point which meets no face does; else a test.
        const double reach_previous = i > 0 ? chebyshev(points[i - 1], p) : INFINITY;
        double reach = reach_previous;
        for (int k = i + 1; k < std::min(count, i + 1 + LOOKAHEAD); ++k)
            reach = std::min(reach, chebyshev(points[k], p));
        if (reach < INFINITY) {
            const double cover = std::max((p - box.min).maxCoeff(), (box.max - p).maxCoeff());
            const double h = surface.tree.empty_cube(surface.vertices, p, reach, std::max(reach, cover), &hint);
            if (h > 0.0) {
                cubes[n_cubes++] = {p.array() - h, p.array() + h, i};
                if (i > 0 && cubes[n_cubes - 1].holds(points[i - 1])) {
                    decider[i] = i - 1;
                    continue;
                }
            }
        }
        if (i > 0 && surface.tree.segment_clear(surface.vertices, points[i - 1], p))
            decider[i] = i - 1;
        else
            tested[n_tested++] = i;
    }

    Vec3 tested_points[CHUNK];
    InsideTest tested_results[CHUNK];
    for (int t = 0; t < n_tested; ++t)
        tested_points[t] = points[tested[t]];
    inside_tests(surface, tested_points, n_tested, DetectionMode::EXACT, {}, tol, tested_results);
    for (int t = 0; t < n_tested; ++t)
        results[tested[t]] = tested_results[t];
    for (int i = 0; i < count; ++i) {
        const int d = decider[i];
        if (d == i)
            continue;
        InsideTest& r = results[i];
        r = InsideTest();
        r.inside = results[d].inside;
        r.deciding_axis = DECIDED_BY_NEIGHBOUR;
        r.crossing_face = results[d].crossing_face;
        // Some point of the surface lies within the neighbour's bound of it; the sum is rounded
        // up by a relative 10⁻¹² (far above the rounding of the two terms).
        r.surface_distance_bound = (results[d].surface_distance_bound + (points[i] - points[d]).norm()) * (1.0 + 1e-12);
    }
    return count - n_tested;
}

} // namespace

Index inside_tests_shared(const ContactSurface& surface, const Vec3* points, Index count, DetectionMode mode,
                          const std::vector<Index>& candidate_faces, const AxisRayTolerances& tolerances,
                          InsideTest* results)
{
    if (mode != DetectionMode::EXACT || !surface.closed) {
        inside_tests(surface, points, count, mode, candidate_faces, tolerances, results);
        return 0;
    }
    Index shared = 0;
    for (Index i = 0; i < count; i += CHUNK)
        shared += shared_chunk(surface, points + i, static_cast<int>(std::min(CHUNK, count - i)), tolerances,
                               results + i);
    return shared;
}

} // namespace coro
