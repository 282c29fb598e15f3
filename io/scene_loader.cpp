#include <corocontact/io/scene_loader.hpp>

#include "detail/embedding_check.hpp"
#include "detail/memory_budget.hpp"

#include <corocontact/core/error.hpp>
#include <corocontact/core/primitives.hpp>
#include <corocontact/io/magnitudes.hpp>
#include <corocontact/io/mesh_readers.hpp>
#include <corocontact/io/surface_readers.hpp>
#include <corocontact/core/surface_mesh.hpp>
#include <corocontact/partition/partition.hpp>

#include <algorithm>
#include <map>
#include <sstream>
#include <tuple>

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

/// A closed, consistently oriented surface whose normals point inward (negative enclosed volume)
/// is turned outward, with a warning: contact takes the side its normals point to as the outside,
/// so inward normals would put every other body's vertex inside it "outside" (no contact ever).
void orient_outward(SurfaceMesh& surface, const std::string& what, std::vector<std::string>& warnings)
{
    if (!check_surface(surface.faces).closed_and_oriented() || !(enclosed_volume(surface.vertices, surface.faces) < 0.0))
        return;
    surface.faces.col(1).swap(surface.faces.col(2));
    warnings.push_back(what + " had inward normals; its faces were flipped");
}

/// A warning when nodes of tets lie exactly where other nodes lie: the tets on either side are
/// then separate pieces that touch without being joined, and move apart under load.
void warn_if_coincident(const TetMesh& mesh, const std::string& what, std::vector<std::string>& warnings)
{
    const std::vector<std::array<Index, 2>> pairs = coincident_vertices(mesh);
    if (pairs.empty())
        return;
    const auto [first, other] = pairs.front();
    std::ostringstream message;
    message << what << ": " << pairs.size() << (pairs.size() == 1 ? " node lies" : " nodes lie")
            << " exactly where another node lies (e.g. nodes " << first << " and " << other
            << ", counted from 0 in file order); they are not joined, so the tets on either side are separate "
               "pieces that can move apart: merge duplicate nodes in the mesher";
    warnings.push_back(message.str());
}

/// A warning for a body whose nodes all lie where an earlier body's lie (a second body made from
/// the first one's mesh without a translate): their surfaces coincide, no vertex of one is inside
/// the other, and contact never separates them.
void warn_about_coincident_bodies(const CaseSpec& spec, const Scene& scene, std::vector<std::string>& warnings)
{
    using Key = std::tuple<Index, double, double, double, double, double, double>; // nodes, box
    std::map<Key, std::size_t> first_with;
    for (std::size_t b = 0; b < scene.bodies.size(); ++b) {
        const Positions& x = scene.bodies[b].mesh().rest_positions;
        const Vec3 lo = x.colwise().minCoeff().transpose(), hi = x.colwise().maxCoeff().transpose();
        const auto [first, fresh] =
            first_with.emplace(Key{static_cast<Index>(x.rows()), lo.x(), lo.y(), lo.z(), hi.x(), hi.y(), hi.z()}, b);
        if (fresh || x != scene.bodies[first->second].mesh().rest_positions)
            continue;
        warnings.push_back(spec.bodies[b].location + ": body '" + spec.bodies[b].name + "' lies exactly where body '" +
                           spec.bodies[first->second].name +
                           "' lies (the same nodes at the same places); their surfaces coincide, so no vertex of "
                           "one is inside the other and contact never separates them: give one a translate");
    }
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
                                              << " behind it; bodies stay on the side the normal points to: check "
                                                 "point and normal");
    }
}

/// Static analysis solves K' u = f once per load step, and K' is singular when the fixed nodes
/// (those of tets; nodes of no tet are fixed but hold nothing) leave a rigid motion free: none
/// leaves all six, all on one line the rotation about it. Named here instead of as a solver
/// breakdown later.
void check_static_support(const Body& body, const BodySpec& spec, const std::vector<Index>& unused)
{
    std::vector<char> holds = body.fixed();
    for (const Index v : unused)
        holds[static_cast<std::size_t>(v)] = 0;
    const Positions& rest = body.mesh().rest_positions;
    std::vector<Index> fixed;
    for (Index v = 0; v < static_cast<Index>(holds.size()); ++v)
        if (holds[static_cast<std::size_t>(v)] != 0)
            fixed.push_back(v);
    const std::string who = spec.location + ": body '" + spec.name + "'";
    const std::string remedy = "add a [[body.fixed]] box (nodes inside it do not move) that holds it, or "
                               "use analysis = \"dynamic\"";
    CORO_CHECK(!fixed.empty(), InputError,
               who << ": static analysis, but no node of the body is fixed, so its rigid-body motion is "
                      "unconstrained and there is no equilibrium to solve for; "
                   << remedy);
    // Collinear within a tolerance relative to the body's size: the farthest fixed node from
    // the first spans the line, and no fixed node is off it.
    const double size = (rest.colwise().maxCoeff() - rest.colwise().minCoeff()).norm();
    const double tolerance = 1e-9 * size;
    const Vec3 origin = rest.row(fixed.front()).transpose();
    Vec3 direction = Vec3::Zero();
    for (const Index v : fixed) {
        const Vec3 d = rest.row(v).transpose() - origin;
        if (d.norm() > direction.norm())
            direction = d;
    }
    double off_line = 0.0;
    if (direction.norm() > tolerance) {
        const Vec3 axis = direction.normalized();
        for (const Index v : fixed) {
            const Vec3 d = rest.row(v).transpose() - origin;
            off_line = std::max(off_line, (d - d.dot(axis) * axis).norm());
        }
    }
    CORO_CHECK(off_line > tolerance, InputError,
               who << ": static analysis, but its " << fixed.size() << " fixed node"
                   << (fixed.size() == 1 ? " leaves" : "s lie on one line, which leaves")
                   << " the rotation about " << (fixed.size() == 1 ? "it" : "that line")
                   << " unconstrained, so there is no equilibrium to solve for; " << remedy);
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
        if (spec.shape == BodyShape::MESH)
            warn_if_coincident(mesh, who + ": mesh " + source, warnings);
        if (spec.shape == BodyShape::MESH && spec.surface.empty())
            warn_if_open(boundary_faces(mesh), who + ": the boundary of mesh " + source, warnings);
    } catch (const InputError& error) {
        if (spec.shape == BodyShape::MESH)
            throw InputError(who + " (mesh " + spec.mesh.string() + "): " + error.what());
        throw InputError(who + ": " + error.what());
    }
    return mesh;
}

LoadedScene load_scene(const CaseSpec& spec, const LoadProgress& progress)
{
    const auto report = [&](const std::string& stage) {
        if (progress)
            progress(stage);
    };
    // Generated bodies first: their size is known before anything is allocated.
    double total_tets = 0.0;
    for (const BodySpec& body_spec : spec.bodies) {
        const auto [tets, key] = detail::generated_tets(body_spec);
        total_tets += tets;
        if (tets > 0.0)
            detail::check_memory(total_tets, body_spec.location + ": body '" + body_spec.name + "': " + key);
    }
    LoadedScene loaded;
    for (std::size_t b = 0; b < spec.bodies.size(); ++b) {
        const BodySpec& body_spec = spec.bodies[b];
        const std::string which =
            "body '" + body_spec.name + "' (" + std::to_string(b + 1) + " of " + std::to_string(spec.bodies.size()) + ")";
        report(which + ": " +
               (body_spec.shape == BodyShape::MESH ? "reading " + body_spec.mesh.filename().string() : "meshing"));
        const TetMesh mesh = load_body_mesh(body_spec, loaded.warnings);
        if (body_spec.shape == BodyShape::MESH) {
            total_tets += mesh.num_tets();
            detail::check_memory(total_tets, body_spec.location + ": body '" + body_spec.name + "': mesh " +
                                         body_spec.mesh.string() + " has " + std::to_string(mesh.num_tets()) +
                                         " tets");
        }
        check_magnitudes(spec, body_spec, mesh);
        report(which + ": METIS parts and element set-up, " + std::to_string(mesh.num_tets()) +
               (mesh.num_tets() == 1 ? " tet" : " tets"));
        Body body(mesh, body_spec, default_num_parts(mesh.num_tets(), spec.solver.parts_per_thread),
                  spec.solver.matrix_precision);
        if (!body_spec.surface.empty()) {
            report(which + ": embedding " + body_spec.surface.filename().string());
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
            orient_outward(surface, who, loaded.warnings);
            detail::reject_surface_far_outside(body.mesh(), surface, who);
            body.embed_surface(std::move(surface));
            detail::check_embedding(body, who, loaded.warnings);
        }
        const std::vector<Index> unused = unreferenced_vertices(body.mesh());
        if (spec.simulation.analysis == Analysis::STATIC)
            check_static_support(body, body_spec, unused);
        for (const Index v : unused)
            body.fix_vertex(v);
        if (!unused.empty())
            loaded.warnings.push_back(body_spec.location + ": body '" + body_spec.name + "': " +
                                      std::to_string(unused.size()) +
                                      " nodes belong to no tet; they are held fixed");
        warn_about_loads_on_fixed_nodes(body, body_spec, loaded.warnings);
        loaded.scene.bodies.push_back(std::move(body));
    }
    if (spec.contact.enabled)
        warn_about_coincident_bodies(spec, loaded.scene, loaded.warnings);
    for (const ObstacleSpec& obstacle : spec.obstacles) {
        if (obstacle.type == ObstacleType::PLANE) {
            const Vec3 normal = obstacle.normal.normalized();
            loaded.scene.planes.push_back({obstacle.point, normal});
            if (spec.contact.enabled)
                reject_bodies_behind(spec, loaded.scene, obstacle, normal);
            continue;
        }
        report("obstacle: reading " + obstacle.mesh.filename().string());
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
        orient_outward(surface, obstacle.location + ": obstacle mesh " + obstacle.mesh.string(), loaded.warnings);
        loaded.scene.obstacle_meshes.push_back(std::move(surface));
    }
    return loaded;
}

} // namespace coro
