#include <corocontact/sim/scene_contact.hpp>

#include <corocontact/contact/broad_phase.hpp>
#include <corocontact/core/error.hpp>
#include <corocontact/core/surface_mesh.hpp>
#include <corocontact/sim/body.hpp>
#include <corocontact/sim/simulation.hpp>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cstdio>
#include <sstream>
#include <tuple>

namespace coro {

ContactSurface make_contact_surface(const Body& body)
{
    if (body.embedding().num_points() > 0)
        return ContactSurface::from_embedding(body.name(), as_positions(body.positions()), body.embedded_surface().faces,
                                              body.embedding().nodes, body.embedding().weights);
    ContactSurface surface =
        ContactSurface::from_body(body.name(), as_positions(body.positions()), boundary_faces(body.mesh()));
    // from_body numbers the body's (internal) nodes; the user sees input node indices.
    for (Index& id : surface.source_id)
        id = body.input_node(id);
    return surface;
}

std::vector<ContactSurface> make_contact_surfaces(const std::vector<Body>& bodies)
{
    std::vector<ContactSurface> surfaces;
    surfaces.reserve(bodies.size());
    for (const Body& body : bodies)
        surfaces.push_back(make_contact_surface(body));
    return surfaces;
}

std::vector<ContactSurface> make_scene_surfaces(const Scene& scene)
{
    std::vector<ContactSurface> surfaces = make_contact_surfaces(scene.bodies);
    for (std::size_t k = 0; k < scene.obstacle_meshes.size(); ++k)
        surfaces.push_back(ContactSurface::from_body("obstacle" + std::to_string(k), scene.obstacle_meshes[k].vertices,
                                                     scene.obstacle_meshes[k].faces));
    return surfaces;
}

void update_contact_surfaces(const std::vector<Body>& bodies, std::vector<ContactSurface>& surfaces)
{
    CORO_CHECK(bodies.size() <= surfaces.size(), InputError,
               "update_contact_surfaces: " << bodies.size() << " bodies for " << surfaces.size() << " surfaces");
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, bodies.size(), 1),
                      [&](const tbb::blocked_range<std::size_t>& r) {
                          for (std::size_t b = r.begin(); b < r.end(); ++b)
                              surfaces[b].update(as_positions(bodies[b].positions()));
                      });
}

void contact_components(const std::vector<ContactSurface>& surfaces, Index num_bodies,
                        std::vector<Index>& component_of_body)
{
    std::vector<Aabb> boxes;
    for (Index b = 0; b < num_bodies; ++b)
        boxes.push_back(surfaces[static_cast<std::size_t>(b)].tree.bounds());
    contact_components(boxes, component_of_body);
}

void contact_components(const std::vector<Aabb>& body_boxes, std::vector<Index>& component_of_body)
{
    contact_components(overlapping_pairs(body_boxes), static_cast<Index>(body_boxes.size()), component_of_body);
}

void contact_components(const std::vector<std::pair<Index, Index>>& overlapping, Index num_bodies,
                        std::vector<Index>& component_of_body)
{
    // Union-find with the lower body as root, so a component's root is its first body.
    std::vector<Index>& root = component_of_body;
    root.resize(static_cast<std::size_t>(num_bodies));
    for (Index b = 0; b < num_bodies; ++b)
        root[static_cast<std::size_t>(b)] = b;
    const auto find = [&](Index b) {
        while (root[static_cast<std::size_t>(b)] != b)
            b = root[static_cast<std::size_t>(b)] = root[static_cast<std::size_t>(root[static_cast<std::size_t>(b)])];
        return b;
    };
    for (const auto& [i, j] : overlapping) {
        if (std::max(i, j) >= num_bodies)
            continue;
        const Index a = find(i), c = find(j);
        root[static_cast<std::size_t>(std::max(a, c))] = std::min(a, c);
    }
    for (Index b = 0; b < num_bodies; ++b)
        root[static_cast<std::size_t>(b)] = find(b);
    // A root is its component's first body, so in body order it gets its number before the
    // rest of its component asks for it.
    Index count = 0;
    for (Index b = 0; b < num_bodies; ++b) {
        const Index first = root[static_cast<std::size_t>(b)];
        root[static_cast<std::size_t>(b)] = first == b ? count++ : root[static_cast<std::size_t>(first)];
    }
}

DetectionSettings detection_settings(const ContactSettings& contact)
{
    DetectionSettings settings;
    settings.mode = contact.mode == ContactMode::PAPER ? DetectionMode::PAPER : DetectionMode::EXACT;
    return settings;
}

std::vector<NodeContact> node_contacts(const std::vector<ContactSurface>& surfaces,
                                       const std::vector<ContactPoint>& points, const std::vector<Index>& num_vertices)
{
    std::vector<NodeContact> nodes(num_vertices.size());
    for (std::size_t b = 0; b < num_vertices.size(); ++b) {
        nodes[b].inside.assign(static_cast<std::size_t>(num_vertices[b]), 0);
        nodes[b].depth = VecX::Zero(num_vertices[b]);
    }
    for (const ContactPoint& point : points) {
        const auto b = static_cast<std::size_t>(point.body);
        if (b >= nodes.size() || surfaces[b].body_node.empty())
            continue; // a vertex of an obstacle, or of an embedded surface (no node of its own)
        const Index node = surfaces[b].body_node[static_cast<std::size_t>(point.vertex)];
        nodes[b].inside[static_cast<std::size_t>(node)] = 1;
        nodes[b].depth[node] = std::max(nodes[b].depth[node], point.depth);
    }
    return nodes;
}

std::string contacts_csv(const std::vector<ContactSurface>& surfaces, const std::vector<ContactPoint>& points)
{
    // Plane obstacles sort after every surface and are named plane<k>.
    const auto other_key = [&](const ContactTarget& other) {
        return other.is_surface() ? other.index : static_cast<Index>(surfaces.size()) + other.index;
    };
    const auto other_name = [&](Index key) {
        return key < static_cast<Index>(surfaces.size()) ? surfaces[static_cast<std::size_t>(key)].name
                                                          : "plane" + std::to_string(key - static_cast<Index>(surfaces.size()));
    };
    std::vector<std::tuple<Index, Index, Index, double>> rows;
    rows.reserve(points.size());
    for (const ContactPoint& p : points)
        rows.emplace_back(p.body, surfaces[static_cast<std::size_t>(p.body)].source_id[static_cast<std::size_t>(p.vertex)],
                          other_key(p.other), p.depth);
    std::sort(rows.begin(), rows.end());
    std::ostringstream csv;
    csv << "body,vertex,other,depth\n";
    char depth[32];
    for (const auto& [body, vertex, other, d] : rows) {
        std::snprintf(depth, sizeof depth, "%.17g", d);
        csv << surfaces[static_cast<std::size_t>(body)].name << ',' << vertex << ','
            << other_name(other) << ',' << depth << '\n';
    }
    return csv.str();
}

} // namespace coro
