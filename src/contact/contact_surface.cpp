#include <corocontact/contact/contact_surface.hpp>

#include <corocontact/core/error.hpp>
#include <corocontact/core/surface_mesh.hpp>

#include "detail/tree_access.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <utility>

namespace coro {

SurfaceEdges surface_edges(const Tris& faces, Index num_vertices)
{
    // (low end, high end, face) of every face side; sorted, the sides of one edge are adjacent.
    std::vector<std::array<Index, 3>> sides;
    sides.reserve(3 * static_cast<std::size_t>(faces.rows()));
    for (Index f = 0; f < faces.rows(); ++f)
        for (int c = 0; c < 3; ++c) {
            const Index a = faces(f, c), b = faces(f, (c + 1) % 3);
            if (a != b)
                sides.push_back({std::min(a, b), std::max(a, b), f});
        }
    std::sort(sides.begin(), sides.end());
    std::vector<std::array<Index, 4>> edges; // low end, high end, the first and last of its faces
    for (std::size_t i = 0, j = 0; i < sides.size(); i = j) {
        while (j < sides.size() && sides[j][0] == sides[i][0] && sides[j][1] == sides[i][1])
            ++j;
        edges.push_back({sides[i][0], sides[i][1], sides[i][2], sides[j - 1][2]});
    }
    SurfaceEdges out;
    const auto n = static_cast<std::size_t>(num_vertices);
    out.start.assign(n + 1, 0);
    for (const auto& e : edges) {
        ++out.start[static_cast<std::size_t>(e[0]) + 1];
        ++out.start[static_cast<std::size_t>(e[1]) + 1];
    }
    for (std::size_t v = 0; v < n; ++v)
        out.start[v + 1] += out.start[v];
    out.vertex.resize(2 * edges.size());
    out.faces.resize(2 * edges.size());
    std::vector<Index> next(out.start.begin(), out.start.end() - 1);
    for (const auto& e : edges) // by (low, high): each vertex's edges come ordered by their other end
        for (int end = 0; end < 2; ++end) {
            const auto k = static_cast<std::size_t>(next[static_cast<std::size_t>(e[end])]++);
            out.vertex[k] = e[1 - end];
            out.faces[k] = {e[2], e[3]};
        }
    return out;
}

namespace {

/// surface_edges() with the faces' tree slots filled.
SurfaceEdges tree_edges(const Tris& faces, CRef<Positions> vertices, const AabbTree& tree)
{
    SurfaceEdges edges = surface_edges(faces, static_cast<Index>(vertices.rows()));
    const std::vector<Index>& face_of_slot = detail::TreeAccess::face_of_slot(tree);
    std::vector<Index> slot_of(face_of_slot.size());
    for (std::size_t s = 0; s < face_of_slot.size(); ++s)
        slot_of[static_cast<std::size_t>(face_of_slot[s])] = static_cast<Index>(s);
    edges.tree_slots.resize(edges.faces.size());
    for (std::size_t k = 0; k < edges.faces.size(); ++k)
        edges.tree_slots[k] = {slot_of[static_cast<std::size_t>(edges.faces[k][0])],
                               slot_of[static_cast<std::size_t>(edges.faces[k][1])]};
    return edges;
}

} // namespace

ContactSurface ContactSurface::from_body(std::string name, CRef<Positions> body_positions, const Tris& faces)
{
    ContactSurface surface;
    surface.name = std::move(name);
    for (Index f = 0; f < faces.rows(); ++f)
        for (int c = 0; c < 3; ++c)
            CORO_CHECK(faces(f, c) >= 0 && faces(f, c) < body_positions.rows(), InputError,
                       surface.name << ": surface face " << f << " uses node " << faces(f, c)
                                    << ", but the body has " << body_positions.rows() << " nodes");
    surface.body_node = surface_vertices(faces);
    surface.source_id = surface.body_node;
    std::vector<Index> local(static_cast<std::size_t>(body_positions.rows()), -1);
    for (std::size_t i = 0; i < surface.body_node.size(); ++i)
        local[static_cast<std::size_t>(surface.body_node[i])] = static_cast<Index>(i);
    surface.faces.resize(faces.rows(), 3);
    for (Index f = 0; f < faces.rows(); ++f)
        for (int c = 0; c < 3; ++c)
            surface.faces(f, c) = local[static_cast<std::size_t>(faces(f, c))];
    surface.vertices.resize(static_cast<Index>(surface.body_node.size()), 3);
    for (std::size_t i = 0; i < surface.body_node.size(); ++i)
        surface.vertices.row(static_cast<Index>(i)) = body_positions.row(surface.body_node[i]);
    surface.closed = faces.rows() > 0 && check_surface(surface.faces).closed_and_oriented();
    surface.tree.build(surface.vertices, surface.faces);
    surface.edges = tree_edges(surface.faces, surface.vertices, surface.tree);
    return surface;
}

ContactSurface ContactSurface::from_embedding(std::string name, CRef<Positions> body_positions, const Tris& faces,
                                             std::vector<std::array<Index, 4>> nodes,
                                             std::vector<Eigen::Vector4d> weights)
{
    ContactSurface surface;
    surface.name = std::move(name);
    surface.faces = faces;
    surface.embed_nodes = std::move(nodes);
    surface.embed_weights = std::move(weights);
    surface.source_id.resize(surface.embed_nodes.size());
    for (std::size_t i = 0; i < surface.source_id.size(); ++i)
        surface.source_id[i] = static_cast<Index>(i);
    surface.vertices.resize(static_cast<Index>(surface.embed_nodes.size()), 3);
    surface.update_vertices(body_positions);
    surface.closed = faces.rows() > 0 && check_surface(surface.faces).closed_and_oriented();
    surface.tree.build(surface.vertices, surface.faces);
    surface.edges = tree_edges(surface.faces, surface.vertices, surface.tree);
    return surface;
}

void ContactSurface::update_vertices(CRef<Positions> body_positions)
{
    for (std::size_t i = 0; i < embed_nodes.size(); ++i) {
        Vec3 p = Vec3::Zero();
        for (std::size_t a = 0; a < 4; ++a)
            p += embed_weights[i][static_cast<Eigen::Index>(a)] * body_positions.row(embed_nodes[i][a]).transpose();
        vertices.row(static_cast<Index>(i)) = p.transpose();
    }
}

void ContactSurface::update(CRef<Positions> body_positions)
{
    if (!embed_nodes.empty()) {
        update_vertices(body_positions);
        tree.refit(vertices);
        return;
    }
    // Through raw pointers: Eigen's row assignment cost three times the loads and stores.
    const double* from = body_positions.data();
    const std::ptrdiff_t from_stride = body_positions.outerStride();
    double* to = vertices.data();
    const auto copy = [&](std::size_t first, std::size_t last) {
        for (std::size_t i = first; i < last; ++i) {
            CORO_ASSERT(body_node[i] < body_positions.rows());
            const double* x = from + from_stride * body_node[i];
            double* y = to + 3 * i;
            y[0] = x[0];
            y[1] = x[1];
            y[2] = x[2];
        }
    };
    constexpr std::size_t PARALLEL_COPY_VERTICES = 2048;
    if (body_node.size() < PARALLEL_COPY_VERTICES)
        copy(0, body_node.size());
    else
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, body_node.size(), PARALLEL_COPY_VERTICES / 2),
                          [&](const tbb::blocked_range<std::size_t>& r) { copy(r.begin(), r.end()); });
    tree.refit(vertices);
}

void update_surfaces(std::vector<ContactSurface>& surfaces, const std::vector<Eigen::Map<const Positions>>& positions)
{
    CORO_CHECK(positions.size() <= surfaces.size(), InputError,
               "update_surfaces: " << positions.size() << " position sets for " << surfaces.size() << " surfaces");
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, positions.size(), 1),
                      [&](const tbb::blocked_range<std::size_t>& r) {
                          for (std::size_t b = r.begin(); b < r.end(); ++b)
                              surfaces[b].update(positions[b]);
                      });
}

void update_surfaces(std::vector<ContactSurface>& surfaces, const std::vector<Positions>& positions)
{
    std::vector<Eigen::Map<const Positions>> maps;
    maps.reserve(positions.size());
    for (const Positions& p : positions)
        maps.emplace_back(p.data(), p.rows(), 3);
    update_surfaces(surfaces, maps);
}

} // namespace coro
