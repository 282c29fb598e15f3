#include "detail/embedding_check.hpp"

#include <corocontact/contact/aabb_tree.hpp>
#include <corocontact/core/error.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <sstream>
#include <utility>

namespace coro::detail {
namespace {

/// The distance from `p` to tet `nodes` of `x` (0 inside), and the tet's longest edge.
std::pair<double, double> distance_to_tet(const Vec3& p, const std::array<Index, 4>& nodes, const Positions& x)
{
    std::array<Vec3, 4> corner;
    for (std::size_t a = 0; a < 4; ++a)
        corner[a] = x.row(nodes[a]).transpose();
    double distance = std::numeric_limits<double>::infinity(), longest = 0.0;
    for (const std::array<int, 3>& face : TET_FACES) {
        const Vec3& a = corner[static_cast<std::size_t>(face[0])];
        const Vec3& b = corner[static_cast<std::size_t>(face[1])];
        const Vec3& c = corner[static_cast<std::size_t>(face[2])];
        distance = std::min(distance, (closest_point_on_triangle(p, a, b, c).point - p).norm());
        longest = std::max({longest, (b - a).norm(), (c - b).norm(), (a - c).norm()});
    }
    return {distance, longest};
}

} // namespace

void reject_surface_far_outside(const TetMesh& mesh, const SurfaceMesh& surface, const std::string& who)
{
    const Eigen::RowVector3d lo = mesh.rest_positions.colwise().minCoeff();
    const Eigen::RowVector3d hi = mesh.rest_positions.colwise().maxCoeff();
    double longest = 0.0;
    for (Index t = 0; t < mesh.num_tets(); ++t)
        for (const std::array<int, 3>& face : TET_FACES)
            longest = std::max(longest, (mesh.rest_positions.row(mesh.tets(t, face[0])) -
                                         mesh.rest_positions.row(mesh.tets(t, face[1])))
                                            .norm());
    for (Index v = 0; v < surface.vertices.rows(); ++v) {
        const Eigen::RowVector3d p = surface.vertices.row(v);
        const double outside = (p.cwiseMax(lo).cwiseMin(hi) - p).norm();
        CORO_CHECK(outside <= longest, InputError,
                   who << ": vertex " << v << " (counted from 0 in file order) lies " << outside
                       << " outside the bounding box of the body's tets, farther than their longest edge ("
                       << longest
                       << "); expected the surface on or inside the body (it moves with the tets by barycentric "
                          "weights, which extrapolate outside them): check the surface's units and the body's "
                          "transform, which applies to the surface too");
    }
}

void check_embedding(const Body& body, const std::string& who, std::vector<std::string>& warnings)
{
    const Embedding& embedding = body.embedding();
    const Positions& vertices = body.embedded_surface().vertices;
    Index outside = 0, worst = -1;
    double worst_ratio = 0.0, worst_distance = 0.0;
    for (Index i = 0; i < embedding.num_points(); ++i) {
        if (embedding.weights[static_cast<std::size_t>(i)].minCoeff() >= -1e-9)
            continue;
        const auto [distance, edge] = distance_to_tet(vertices.row(i).transpose(),
                                                      embedding.nodes[static_cast<std::size_t>(i)],
                                                      body.mesh().rest_positions);
        ++outside;
        if (distance / edge > worst_ratio) {
            worst_ratio = distance / edge;
            worst_distance = distance;
            worst = i;
        }
    }
    if (worst < 0)
        return;
    std::ostringstream text;
    text << who << ": vertex " << worst << " (counted from 0 in file order) lies " << worst_distance
         << " outside the body's tets, " << std::lround(100.0 * worst_ratio)
         << "% of the longest edge of the tet it is bound to";
    CORO_CHECK(worst_ratio <= 1.0, InputError,
               text.str() << "; expected the surface on or inside the body (it moves with the tets by barycentric "
                             "weights, which extrapolate outside them): check the surface's units and the body's "
                             "transform, which applies to the surface too");
    if (worst_ratio > EMBEDDED_GAP_WARNING)
        warnings.push_back(text.str() + " (" + std::to_string(outside) + " of " +
                           std::to_string(embedding.num_points()) + " vertices lie outside)");
}

} // namespace coro::detail
