#include <corocontact/contact/contact_surface.hpp>

#include <corocontact/core/error.hpp>
#include <corocontact/core/surface_mesh.hpp>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <utility>

namespace coro {

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
