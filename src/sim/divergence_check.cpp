#include <corocontact/sim/divergence_check.hpp>

#include <corocontact/core/error.hpp>

#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace coro {

namespace {

constexpr Index NODE_GRAIN = 8192;
constexpr Index TET_GRAIN = 4096;
constexpr Index NONE = std::numeric_limits<Index>::max();

// The lowest input index found so far and its value; joins keep the lower index, so the result
// is the same for any split of the range.
struct Lowest {
    Index index = NONE;
    double value = 0.0;
    void offer(Index i, double v)
    {
        if (i < index) {
            index = i;
            value = v;
        }
    }
};

Lowest lower(const Lowest& a, const Lowest& b) { return b.index < a.index ? b : a; }

} // namespace

DivergenceFinding find_divergence(const Body& body, const DivergenceLimits& limits)
{
    const double* x = body.positions().data();
    DivergenceFinding finding;

    // Non-finite positions (rare: the solvers check velocities), lowest input node first.
    if (!body.positions().allFinite()) {
        const Lowest node = tbb::parallel_reduce(
            tbb::blocked_range<Index>(0, body.num_vertices(), NODE_GRAIN), Lowest{},
            [&](const tbb::blocked_range<Index>& range, Lowest found) {
                for (Index v = range.begin(); v != range.end(); ++v)
                    for (int d = 0; d < 3; ++d)
                        if (!std::isfinite(x[3 * v + d])) {
                            found.offer(body.input_node(v), x[3 * v + d]);
                            break;
                        }
                return found;
            },
            lower);
        finding.node = node.index;
        finding.volume_ratio = node.value;
        return finding;
    }

    const Tets& tets = body.mesh().tets;
    const std::vector<double>& volumes = body.fem().volumes();
    const double lo = limits.min_volume_ratio, hi = limits.max_volume_ratio;
    const Lowest tet = tbb::parallel_reduce(
        tbb::blocked_range<Index>(0, body.mesh().num_tets(), TET_GRAIN), Lowest{},
        [&](const tbb::blocked_range<Index>& range, Lowest found) {
            for (Index t = range.begin(); t != range.end(); ++t) {
                const double* p0 = x + 3 * tets(t, 0);
                const double* p1 = x + 3 * tets(t, 1);
                const double* p2 = x + 3 * tets(t, 2);
                const double* p3 = x + 3 * tets(t, 3);
                const double a[3] = {p1[0] - p0[0], p1[1] - p0[1], p1[2] - p0[2]};
                const double b[3] = {p2[0] - p0[0], p2[1] - p0[1], p2[2] - p0[2]};
                const double c[3] = {p3[0] - p0[0], p3[1] - p0[1], p3[2] - p0[2]};
                const double det = a[0] * (b[1] * c[2] - b[2] * c[1]) + a[1] * (b[2] * c[0] - b[0] * c[2]) +
                                   a[2] * (b[0] * c[1] - b[1] * c[0]);
                // det D_m = 6 V (rest tets are positively oriented).
                const double ratio = det / (6.0 * volumes[static_cast<std::size_t>(t)]);
                if (!(ratio > lo && ratio < hi))
                    found.offer(body.input_tet(t), ratio);
            }
            return found;
        },
        lower);
    if (tet.index != NONE) {
        finding.element = tet.index;
        finding.volume_ratio = tet.value;
    }
    return finding;
}

void check_divergence(const std::vector<Body>& bodies, const DivergenceLimits& limits)
{
    for (const Body& body : bodies) {
        const DivergenceFinding finding = find_divergence(body, limits);
        if (finding.node >= 0)
            CORO_THROW(NumericalError, "body '" << body.name() << "': position of node " << finding.node
                                                << " (mesh file order) is " << finding.volume_ratio);
        if (finding.element < 0)
            continue;
        const double j = finding.volume_ratio;
        if (j <= limits.min_volume_ratio)
            CORO_THROW(NumericalError, "body '" << body.name() << "': element " << finding.element
                                                << " (mesh file order) inverted beyond recovery: det F = " << j
                                                << " (limit " << limits.min_volume_ratio << ")");
        CORO_THROW(NumericalError, "body '" << body.name() << "': element " << finding.element
                                            << " (mesh file order) "
                                            << (std::isfinite(j) ? "blown up" : "degenerate") << ": det F = " << j
                                            << " (limit " << limits.max_volume_ratio << ")");
    }
}

} // namespace coro
