#include <corocontact/io/scene_output.hpp>

#include "detail/plane_patch.hpp"

#include <corocontact/core/embedding.hpp>
#include <corocontact/core/error.hpp>
#include <corocontact/io/block_names.hpp>
#include <corocontact/sim/scene_contact.hpp>

#include <iomanip>
#include <limits>
#include <sstream>

namespace coro {

std::vector<std::string> body_block_names(const Body& body)
{
    if (body.embedding().num_points() > 0)
        return {body.name(), surface_block_name(body.name())};
    return {body.name()};
}

std::vector<FrameBlock> body_blocks(const Scene& scene)
{
    std::vector<FrameBlock> blocks;
    blocks.reserve(scene.bodies.size());
    std::vector<Index> num_vertices;
    for (const Body& body : scene.bodies)
        num_vertices.push_back(body.num_vertices());
    const std::vector<NodeContact> contact = node_contacts(scene.surfaces, scene.contacts, num_vertices);
    for (std::size_t b = 0; b < scene.bodies.size(); ++b) {
        const Body& body = scene.bodies[b];
        // Bodies are numbered internally by METIS part; frames keep the input's order.
        const Index n_vertices = body.num_vertices(), n_tets = body.mesh().num_tets();
        const VecX displacement = body.displacements();
        const VecX stress = body.fem().von_mises_stress(body.positions());
        FrameBlock block;
        block.name = body.name();
        block.points.resize(n_vertices, 3);
        Eigen::MatrixXd u(n_vertices, 3), v(n_vertices, 3), inside(n_vertices, 1), depth(n_vertices, 1),
            force = Eigen::MatrixXd::Zero(n_vertices, 3);
        for (Index i = 0; i < n_vertices; ++i) {
            const Index row = body.input_node(i);
            block.points.row(row) = body.positions().segment<3>(3 * i).transpose();
            u.row(row) = displacement.segment<3>(3 * i).transpose();
            v.row(row) = body.velocities().segment<3>(3 * i).transpose();
            inside(row, 0) = contact[b].inside[static_cast<std::size_t>(i)];
            depth(row, 0) = contact[b].depth[i];
            if (b < scene.contact_forces.size())
                force.row(row) = scene.contact_forces[b].segment<3>(3 * i).transpose();
        }
        block.tets.resize(n_tets, 4);
        Eigen::MatrixXd von_mises(n_tets, 1), partition(n_tets, 1);
        for (Index t = 0; t < n_tets; ++t) {
            const Index row = body.input_tet(t);
            for (int a = 0; a < 4; ++a)
                block.tets(row, a) = body.input_node(body.mesh().tets(t, a));
            von_mises(row, 0) = stress[t];
            partition(row, 0) = body.part_of_tet(t);
        }
        block.point_data.push_back({"displacement", std::move(u)});
        block.point_data.push_back({"velocity", std::move(v)});
        block.point_data.push_back({"contact_inside", std::move(inside)});
        block.point_data.push_back({"contact_depth", std::move(depth)});
        block.point_data.push_back({"contact_force", std::move(force)});
        block.cell_data.push_back({"von_mises", std::move(von_mises)});
        block.cell_data.push_back({"partition", std::move(partition)});
        blocks.push_back(std::move(block));
        if (body.embedding().num_points() > 0) {
            // The embedded contact surface, where it is now, with its contact state.
            FrameBlock surface;
            surface.name = surface_block_name(body.name());
            surface.points = embedded_positions(body.embedding(), as_positions(body.positions()));
            surface.tris = body.embedded_surface().faces;
            Eigen::MatrixXd s_inside = Eigen::MatrixXd::Zero(surface.points.rows(), 1), s_depth = s_inside;
            for (const ContactPoint& point : scene.contacts)
                if (point.body == static_cast<Index>(b)) {
                    s_inside(point.vertex, 0) = 1.0;
                    s_depth(point.vertex, 0) = std::max(s_depth(point.vertex, 0), point.depth);
                }
            surface.point_data.push_back({"contact_inside", std::move(s_inside)});
            surface.point_data.push_back({"contact_depth", std::move(s_depth)});
            blocks.push_back(std::move(surface));
        }
    }
    return blocks;
}

std::pair<Vec3, Vec3> rest_bounds(const Scene& scene)
{
    Vec3 lo = Vec3::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
    const auto extend = [&](const auto& points) {
        if (points.rows() > 0) {
            lo = lo.cwiseMin(points.colwise().minCoeff().transpose());
            hi = hi.cwiseMax(points.colwise().maxCoeff().transpose());
        }
    };
    for (const Body& body : scene.bodies)
        extend(body.mesh().rest_positions);
    for (const SurfaceMesh& mesh : scene.obstacle_meshes)
        extend(mesh.vertices);
    for (const PlaneObstacle& plane : scene.planes)
        extend(plane.point.transpose());
    return {lo, hi};
}

std::vector<FrameBlock> obstacle_blocks(const Scene& scene, const std::pair<Vec3, Vec3>& bounds)
{
    std::vector<FrameBlock> blocks;
    for (std::size_t k = 0; k < scene.obstacle_meshes.size(); ++k) {
        FrameBlock block;
        block.name = obstacle_block_name(static_cast<Index>(k));
        block.points = scene.obstacle_meshes[k].vertices;
        block.tris = scene.obstacle_meshes[k].faces;
        blocks.push_back(std::move(block));
    }
    // Planes are infinite: drawn over the scene's bounds at rest, the same in every frame.
    for (std::size_t k = 0; k < scene.planes.size(); ++k)
        blocks.push_back(
            detail::plane_patch(scene.planes[k], bounds.first, bounds.second, plane_block_name(static_cast<Index>(k))));
    return blocks;
}

std::vector<FrameBlock> scene_frame(const Scene& scene)
{
    std::vector<FrameBlock> blocks = body_blocks(scene);
    for (FrameBlock& block : obstacle_blocks(scene, rest_bounds(scene)))
        blocks.push_back(std::move(block));
    return blocks;
}

std::string summary_json(const RunSummary& summary, const SummaryContext& context)
{
    std::ostringstream out;
    out << std::setprecision(9);
    out << "{\n"
        << "  \"name\": \"" << context.name << "\",\n"
        << "  \"steps\": " << summary.steps << ",\n"
        << "  \"wall_s\": " << summary.wall_s << ",\n"
        << "  \"steps_per_s\": " << summary.steps_per_s << ",\n"
        << "  \"setup_s\": " << context.setup_s << ",\n"
        << "  \"threads\": " << context.threads << ",\n"
        << "  \"bodies\": " << context.bodies << ",\n"
        << "  \"tets\": " << context.tets << ",\n"
        << "  \"ranks\": " << context.ranks << ",\n";
    double bytes = 0.0;
    for (const RankLoad& load : context.per_rank)
        bytes += load.mpi_bytes_per_step;
    out << "  \"mpi_bytes_per_step\": " << (context.per_rank.empty() ? 0.0 : bytes / context.per_rank.size()) << ",\n";
    if (!context.per_rank.empty()) {
        out << "  \"cross_rank_contacts_mean\": " << context.cross_rank_contacts_mean << ",\n"
            << "  \"per_rank\": [\n";
        for (std::size_t r = 0; r < context.per_rank.size(); ++r) {
            const RankLoad& load = context.per_rank[r];
            out << "    {\"rank\": " << r << ", \"bodies\": " << load.bodies << ", \"tets\": " << load.tets
                << ", \"mpi_bytes_per_step\": " << load.mpi_bytes_per_step
                << ", \"solve_bytes_per_step\": " << load.solve_bytes_per_step << "}"
                << (r + 1 < context.per_rank.size() ? "," : "") << "\n";
        }
        out << "  ],\n";
    }
    out << "  \"phases\": {\n"
        << "    \"rotation\": " << summary.phases.rotation << ",\n"
        << "    \"assembly\": " << summary.phases.assembly << ",\n"
        << "    \"solve\": " << summary.phases.solve << ",\n"
        << "    \"contact\": " << summary.phases.contact << ",\n"
        << "    \"output\": " << summary.phases.output << "\n"
        << "  },\n"
        << "  \"cg_iterations_mean\": " << summary.cg_iterations_mean << ",\n"
        << "  \"cg_residual_mean\": " << summary.cg_residual_mean << ",\n"
        << "  \"solves\": " << summary.solves << ",\n"
        << "  \"solves_not_converged\": " << summary.solves_not_converged << ",\n"
        << "  \"preconditioner_setups\": " << summary.preconditioner.setups << ",\n"
        << "  \"preconditioner_setup_s\": " << summary.preconditioner.setup_s << ",\n"
        << "  \"preconditioner_applies\": " << summary.preconditioner.applies << ",\n"
        << "  \"preconditioner_apply_s\": " << summary.preconditioner.apply_s << ",\n"
        << "  \"static_not_converged\": " << summary.static_not_converged << ",\n"
        << "  \"static_iterations_mean\": " << summary.static_iterations_mean << ",\n"
        << "  \"static_iterations_max\": " << summary.static_iterations_max << ",\n"
        << "  \"max_contact_depth\": " << summary.max_contact_depth << ",\n"
        << "  \"contacts_mean\": " << summary.contacts_mean << ",\n"
        << "  \"embree_disagreements\": " << summary.embree_disagreements << ",\n"
        << "  \"peak_rss_mb\": " << context.peak_rss_mb << "\n"
        << "}\n";
    return out.str();
}

} // namespace coro
