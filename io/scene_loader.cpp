#include <corocontact/io/scene_loader.hpp>

#include "detail/magnitudes.hpp"
#include "detail/memory_budget.hpp"

#include <corocontact/contact/aabb_tree.hpp>
#include <corocontact/core/error.hpp>
#include <corocontact/core/primitives.hpp>
#include <corocontact/io/mesh_readers.hpp>
#include <corocontact/io/surface_readers.hpp>
#include <corocontact/core/surface_mesh.hpp>
#include <corocontact/partition/partition.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <sstream>
#include <utility>

namespace coro {
namespace {

/// A warning when `faces` is not a closed, consistently oriented surface: contact then decides
/// inside/outside for it by the generalized winding number alone (see ContactSurface::closed).
void warn_if_open(const Tris& faces, const std::string& what, std::vector<std::string>& warnings)
{
    const SurfaceCheck check = check_surface(faces);
    if (check.closed_and_oriented())
        return;
    std::ostringstream message;
    message << what << " is not a closed, consistently oriented surface (" << check.open_edges
            << " open, " << check.nonmanifold_edges << " non-manifold, " << check.misoriented_edges
            << " misoriented edges); contact tests points against it by the winding number only";
    warnings.push_back(message.str());
}

/// Tets a generated body will have (0 for a mesh file, whose count is known once it is read),
/// and how the case says it ("cells = [2, 2, 2]").
std::pair<double, std::string> generated_tets(const BodySpec& spec)
{
    if (spec.shape == BodyShape::BOX) {
        const auto& c = spec.cells;
        return {6.0 * c[0] * c[1] * c[2], "cells = [" + std::to_string(c[0]) + ", " + std::to_string(c[1]) + ", " +
                                             std::to_string(c[2]) + "]"};
    }
    if (spec.shape == BodyShape::SPHERE) {
        const double r = spec.resolution;
        return {6.0 * r * r * r, "resolution = " + std::to_string(spec.resolution)};
    }
    return {0.0, ""};
}

/// Refuses a scene of `total_tets` that cannot fit in memory, before the allocations it drives;
/// `cause` says which body and key brought the total there.
void check_memory(double total_tets, const std::string& cause)
{
    const detail::MemoryLimit limit = detail::memory_limit();
    const double need = total_tets * detail::BYTES_PER_TET;
    CORO_CHECK(need <= limit.bytes, InputError,
               cause << ": the scene would have " << static_cast<long long>(total_tets) << " tets, which need about "
                     << detail::memory_text(need) << " of memory (" << detail::BYTES_PER_TET
                     << " bytes per tet), more than the " << detail::memory_text(limit.bytes) << " of "
                     << limit.source);
}

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

/// An embedded surface must lie on or in its body's tets: each vertex moves with the tet it is
/// bound to, by barycentric weights that extrapolate for a vertex outside. A vertex farther
/// outside than its tet's longest edge is refused; a vertex outside by more than
/// EMBEDDED_GAP_WARNING of that edge is warned about (a fine surface over coarse tets lies a
/// little outside them where the tets' faces cut the curved surface's chords).
constexpr double EMBEDDED_GAP_WARNING = 0.25;

/// The cheap part of check_embedding, before the embedding (which searches every tet for a
/// vertex outside them all): a vertex farther outside the tets' bounding box than their longest
/// edge is farther than that from every tet.
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

/// A box load is split over the nodes in its box; the share of a fixed node has no effect, so
/// less force acts than the case says.
void warn_about_loads_on_fixed_nodes(const Body& body, const BodySpec& spec, std::vector<std::string>& warnings)
{
    Vec3 lost = Vec3::Zero(), total = Vec3::Zero();
    for (const BoxLoad& load : spec.loads)
        total += load.force;
    for (Index v = 0; v < body.num_vertices(); ++v)
        if (body.fixed()[static_cast<std::size_t>(v)] != 0)
            lost += body.load_forces().segment<3>(3 * v);
    if (!(lost.stableNorm() > 1e-12 * total.stableNorm()))
        return;
    std::ostringstream message;
    message << spec.location << ": body '" << spec.name << "': " << lost.stableNorm() << " of the "
            << total.stableNorm() << " N of its [[body.load]] forces fall on fixed nodes and have no effect";
    warnings.push_back(message.str());
}

/// Surface vertices obey the bound of mesh nodes (validate_and_orient): beyond it, contact's
/// boxes, distances and areas overflow double.
void check_surface_coordinates(const SurfaceMesh& surface, const std::string& what)
{
    for (Index v = 0; v < surface.vertices.rows(); ++v) {
        const double largest = surface.vertices.row(v).cwiseAbs().maxCoeff();
        CORO_CHECK(largest <= MAX_COORDINATE, InputError,
                   what << ": vertex " << v << " has a coordinate of magnitude " << largest
                        << ", expected at most " << MAX_COORDINATE << " (vertices counted from 0 in file order)");
    }
}

/// A body whose every node lies behind a plane obstacle starts inside it: the penalty would
/// throw it out with a force of its whole depth, almost surely a normal pointing the wrong way.
void reject_bodies_behind(const CaseSpec& spec, const Scene& scene, const ObstacleSpec& plane, const Vec3& normal)
{
    for (std::size_t b = 0; b < scene.bodies.size(); ++b) {
        const Positions& x = scene.bodies[b].mesh().rest_positions;
        const Eigen::VectorXd height = (x.rowwise() - plane.point.transpose()) * normal;
        if (height.maxCoeff() >= 0.0)
            continue;
        CORO_THROW(InputError, plane.location << ": plane obstacle: body '" << spec.bodies[b].name << "' ("
                                              << spec.bodies[b].location << ") lies entirely behind the plane, "
                                              << -height.maxCoeff() << " to " << -height.minCoeff()
                                              << " below it; bodies stay on the side the normal points to: check "
                                                 "point and normal");
    }
}

} // namespace

TetMesh load_body_mesh(const BodySpec& spec, std::vector<std::string>& warnings)
{
    const std::string who = spec.location + ": body '" + spec.name + "'";
    TetMesh mesh;
    std::string source;
    try {
        switch (spec.shape) {
        case BodyShape::MESH:
            mesh = read_tet_mesh(spec.mesh);
            source = spec.mesh.string();
            break;
        case BodyShape::BOX:
            mesh = make_box(spec.box_min, spec.box_max, spec.cells);
            source = who;
            break;
        case BodyShape::SPHERE:
            mesh = make_sphere(spec.center, spec.radius, spec.resolution);
            source = who;
            break;
        }
        spec.transform.apply(mesh.rest_positions);
        const Index reoriented = validate_and_orient(mesh, source);
        if (reoriented > 0) {
            std::ostringstream message;
            message << source << ": " << reoriented << " of " << mesh.num_tets()
                    << " tets had negative volume and were reoriented";
            warnings.push_back(message.str());
        }
        if (spec.shape == BodyShape::MESH && spec.surface.empty())
            warn_if_open(boundary_faces(mesh), who + ": the boundary of mesh " + source, warnings);
    } catch (const InputError& error) {
        if (spec.shape == BodyShape::MESH)
            throw InputError(who + " (mesh " + spec.mesh.string() + "): " + error.what());
        throw InputError(who + ": " + error.what());
    }
    return mesh;
}

LoadedScene load_scene(const CaseSpec& spec)
{
    // Generated bodies first: their size is known before anything is allocated.
    double total_tets = 0.0;
    for (const BodySpec& body_spec : spec.bodies) {
        const auto [tets, key] = generated_tets(body_spec);
        total_tets += tets;
        if (tets > 0.0)
            check_memory(total_tets, body_spec.location + ": body '" + body_spec.name + "': " + key);
    }
    LoadedScene loaded;
    for (const BodySpec& body_spec : spec.bodies) {
        const TetMesh mesh = load_body_mesh(body_spec, loaded.warnings);
        if (body_spec.shape == BodyShape::MESH) {
            total_tets += mesh.num_tets();
            check_memory(total_tets, body_spec.location + ": body '" + body_spec.name + "': mesh " +
                                         body_spec.mesh.string() + " has " + std::to_string(mesh.num_tets()) +
                                         " tets");
        }
        detail::check_magnitudes(spec, body_spec, mesh);
        Body body(mesh, body_spec, default_num_parts(mesh.num_tets(), spec.solver.parts_per_thread));
        if (!body_spec.surface.empty()) {
            SurfaceMesh surface;
            try {
                surface = read_surface(body_spec.surface);
            } catch (const InputError& error) {
                throw InputError(body_spec.location + ": body '" + body_spec.name + "': surface " +
                                 body_spec.surface.string() + ": " + error.what());
            }
            const std::string who =
                body_spec.location + ": body '" + body_spec.name + "': surface " + body_spec.surface.string();
            warn_if_open(surface.faces, who, loaded.warnings);
            body_spec.transform.apply(surface.vertices);
            check_surface_coordinates(surface, who);
            reject_surface_far_outside(body.mesh(), surface, who);
            body.embed_surface(std::move(surface));
            check_embedding(body, who, loaded.warnings);
        }
        const std::vector<Index> unused = unreferenced_vertices(body.mesh());
        for (const Index v : unused)
            body.fix_vertex(v);
        if (!unused.empty())
            loaded.warnings.push_back(body_spec.location + ": body '" + body_spec.name + "': " +
                                      std::to_string(unused.size()) +
                                      " nodes belong to no tet; they are held fixed");
        warn_about_loads_on_fixed_nodes(body, body_spec, loaded.warnings);
        loaded.scene.bodies.push_back(std::move(body));
    }
    for (const ObstacleSpec& obstacle : spec.obstacles) {
        if (obstacle.type == ObstacleType::PLANE) {
            const Vec3 normal = obstacle.normal.normalized();
            loaded.scene.planes.push_back({obstacle.point, normal});
            if (spec.contact.enabled)
                reject_bodies_behind(spec, loaded.scene, obstacle, normal);
            continue;
        }
        SurfaceMesh surface;
        try {
            surface = read_surface(obstacle.mesh);
        } catch (const InputError& error) {
            throw InputError(obstacle.location + ": obstacle mesh " + obstacle.mesh.string() + ": " + error.what());
        }
        check_surface_coordinates(surface, obstacle.location + ": obstacle mesh " + obstacle.mesh.string());
        const SurfaceCheck check = check_surface(surface.faces);
        CORO_CHECK(check.closed_and_oriented(), InputError,
                   obstacle.location << ": obstacle mesh " << obstacle.mesh.string()
                                     << " is not a closed, consistently oriented surface (" << check.open_edges
                                     << " open, " << check.nonmanifold_edges << " non-manifold, "
                                     << check.misoriented_edges << " misoriented edges)");
        if (enclosed_volume(surface.vertices, surface.faces) < 0.0) {
            surface.faces.col(1).swap(surface.faces.col(2));
            loaded.warnings.push_back(obstacle.location + ": obstacle mesh " + obstacle.mesh.string() +
                                      " had inward normals; its faces were flipped");
        }
        loaded.scene.obstacle_meshes.push_back(std::move(surface));
    }
    return loaded;
}

} // namespace coro
