#include <corocontact/sim/divergence_check.hpp>

#include <corocontact/core/error.hpp>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <utility>

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

double min_rest_volume(const Body& body)
{
    const std::vector<double>& volumes = body.fem().volumes();
    return volumes.empty() ? 0.0 : *std::min_element(volumes.begin(), volumes.end());
}

DivergenceFinding find_in_body(const Body& body, const DivergenceLimits& limits, double min_volume)
{
    const double* x = body.positions().data();
    DivergenceFinding finding;

    // J = det(D_s) / (6 V). Most tets have 0 < det < hi·6·V_min and pass without reading their
    // rest volume; only the others are divided by their own.
    const Index* tets = body.mesh().tets.data(); // #T×4 row-major
    const double* volumes = body.fem().volumes().data();
    const double lo = limits.min_volume_ratio, hi = limits.max_volume_ratio;
    const double surely_small = hi * 6.0 * min_volume;
    const Lowest tet = tbb::parallel_reduce(
        tbb::blocked_range<Index>(0, body.mesh().num_tets(), TET_GRAIN), Lowest{},
        [&](const tbb::blocked_range<Index>& range, Lowest found) {
            for (Index t = range.begin(); t != range.end(); ++t) {
                const Index* corners = tets + 4 * static_cast<std::ptrdiff_t>(t);
                const double* p0 = x + 3 * corners[0];
                const double* p1 = x + 3 * corners[1];
                const double* p2 = x + 3 * corners[2];
                const double* p3 = x + 3 * corners[3];
                const double a0 = p1[0] - p0[0], a1 = p1[1] - p0[1], a2 = p1[2] - p0[2];
                const double b0 = p2[0] - p0[0], b1 = p2[1] - p0[1], b2 = p2[2] - p0[2];
                const double c0 = p3[0] - p0[0], c1 = p3[1] - p0[1], c2 = p3[2] - p0[2];
                const double det = a0 * (b1 * c2 - b2 * c1) + a1 * (b2 * c0 - b0 * c2) + a2 * (b0 * c1 - b1 * c0);
                if (det > 0.0 && det < surely_small)
                    continue;
                // det D_m = 6 V (rest tets are positively oriented).
                const double ratio = det / (6.0 * volumes[t]);
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
    // A NaN or Inf J comes from a non-finite position (rare: the solvers check velocities):
    // name the lowest input node instead.
    if (!std::isfinite(finding.volume_ratio) && !body.positions().allFinite()) {
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
        finding.element = -1;
        finding.volume_ratio = node.value;
    }
    return finding;
}

} // namespace

DivergenceCheck::DivergenceCheck(const std::vector<Body>& bodies, const DivergenceLimits& limits) : m_limits(limits)
{
    for (const Body& body : bodies)
        m_min_volumes.push_back(min_rest_volume(body));
}

DivergenceFinding DivergenceCheck::find(const std::vector<Body>& bodies, std::size_t b) const
{
    return find_in_body(bodies[b], m_limits, m_min_volumes[b]);
}

void DivergenceCheck::check(const std::vector<Body>& bodies)
{
    // All bodies at once (a large body's tets split further inside find()), then the first
    // finding in body order.
    m_findings.resize(bodies.size());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, bodies.size(), 1), [&](const tbb::blocked_range<std::size_t>& range) {
        for (std::size_t b = range.begin(); b != range.end(); ++b)
            m_findings[b] = find(bodies, b);
    });
    for (std::size_t b = 0; b < bodies.size(); ++b) {
        const Body& body = bodies[b];
        const DivergenceFinding& finding = m_findings[b];
        if (!finding.found())
            continue;
        std::ostringstream message;
        message << "body '" << body.name() << "': ";
        const double j = finding.volume_ratio;
        if (finding.node >= 0)
            message << "position of node " << finding.node << " (mesh file order) is " << j;
        else if (j <= m_limits.min_volume_ratio)
            message << "element " << finding.element << " (mesh file order) inverted beyond recovery: det F = " << j
                    << " (limit " << m_limits.min_volume_ratio << ")";
        else
            message << "element " << finding.element << " (mesh file order) "
                    << (std::isfinite(j) ? "blown up" : "degenerate") << ": det F = " << j << " (limit "
                    << m_limits.max_volume_ratio << ")";
        throw NumericalError(detail::with_source_location(message.str(), __FILE__, __LINE__), static_cast<Index>(b));
    }
}

std::string locate_non_finite(const Body& body)
{
    for (const auto& [what, values] : {std::pair<const char*, const VecX*>{"position", &body.positions()},
                                       std::pair<const char*, const VecX*>{"velocity", &body.velocities()}}) {
        if (values->allFinite())
            continue;
        Index input = std::numeric_limits<Index>::max();
        double value = 0.0;
        for (Index v = 0; v < body.num_vertices(); ++v)
            for (int d = 0; d < 3; ++d)
                if (!std::isfinite((*values)[3 * v + d]) && body.input_node(v) < input) {
                    input = body.input_node(v);
                    value = (*values)[3 * v + d];
                }
        std::ostringstream message;
        message << "body '" << body.name() << "': " << what << " of node " << input << " (mesh file order) is "
                << value;
        return message.str();
    }
    return {};
}

DivergenceFinding find_divergence(const Body& body, const DivergenceLimits& limits)
{
    return find_in_body(body, limits, min_rest_volume(body));
}

void check_divergence(const std::vector<Body>& bodies, const DivergenceLimits& limits)
{
    DivergenceCheck(bodies, limits).check(bodies);
}

} // namespace coro
