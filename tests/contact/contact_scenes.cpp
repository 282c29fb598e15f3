#include "contact_scenes.hpp"

#include <corocontact/core/primitives.hpp>

#include <cmath>
#include <stdexcept>

namespace coro::test {

ContactSurface surface_of(const TetMesh& mesh, const std::string& name)
{
    return ContactSurface::from_body(name, mesh.rest_positions, boundary_faces(mesh));
}

ContactSurface surface_of(const SurfaceMesh& mesh, const std::string& name)
{
    return ContactSurface::from_body(name, mesh.vertices, mesh.faces);
}

SurfaceMesh make_torus(const Vec3& center, double R, double r, int nu, int nv)
{
    SurfaceMesh mesh;
    mesh.vertices.resize(nu * nv, 3);
    for (int i = 0; i < nu; ++i)
        for (int j = 0; j < nv; ++j) {
            const double u = 2.0 * M_PI * i / nu, v = 2.0 * M_PI * j / nv;
            mesh.vertices.row(i * nv + j) =
                (center + Vec3((R + r * std::cos(v)) * std::cos(u), (R + r * std::cos(v)) * std::sin(u),
                               r * std::sin(v)))
                    .transpose();
        }
    mesh.faces.resize(2 * nu * nv, 3);
    const auto id = [&](int i, int j) { return static_cast<Index>(((i + nu) % nu) * nv + (j + nv) % nv); };
    for (int i = 0; i < nu; ++i)
        for (int j = 0; j < nv; ++j) {
            // (u, v) → outward: ∂u × ∂v points out of the tube.
            mesh.faces.row(2 * (i * nv + j)) << id(i, j), id(i + 1, j), id(i + 1, j + 1);
            mesh.faces.row(2 * (i * nv + j) + 1) << id(i, j), id(i + 1, j + 1), id(i, j + 1);
        }
    return mesh;
}

Positions twist_and_bend(CRef<Positions> positions, double twist, double bend_radius)
{
    Positions out(positions.rows(), 3);
    for (Eigen::Index i = 0; i < positions.rows(); ++i) {
        const double x = positions(i, 0), y = positions(i, 1), z = positions(i, 2);
        const double angle = twist * x;
        const double yt = std::cos(angle) * y - std::sin(angle) * z;
        const double zt = std::sin(angle) * y + std::cos(angle) * z;
        const double phi = x / bend_radius;
        out.row(i) << (bend_radius - yt) * std::sin(phi), bend_radius - (bend_radius - yt) * std::cos(phi), zt;
    }
    return out;
}

bool ray_parity_inside(CRef<Positions> vertices, const Tris& faces, const Vec3& point, std::mt19937& rng)
{
    std::normal_distribution<double> normal;
    for (int attempt = 0; attempt < 100; ++attempt) {
        const Vec3 d = Vec3(normal(rng), normal(rng), normal(rng)).normalized();
        int crossings = 0;
        bool clean = true;
        for (Index f = 0; f < faces.rows() && clean; ++f) {
            const Vec3 a = vertices.row(faces(f, 0)).transpose();
            const Vec3 e1 = vertices.row(faces(f, 1)).transpose() - a;
            const Vec3 e2 = vertices.row(faces(f, 2)).transpose() - a;
            const Vec3 h = d.cross(e2);
            const double det = e1.dot(h);
            const double scale = e1.norm() * e2.norm();
            if (std::abs(det) < 1e-12 * scale)
                continue; // parallel: a generic direction meets it only in its plane, measure zero
            const Vec3 s = point - a;
            const double u = s.dot(h) / det;
            const Vec3 q = s.cross(e1);
            const double v = d.dot(q) / det;
            const double t = e2.dot(q) / det;
            const double w = 1.0 - u - v;
            constexpr double margin = 1e-9;
            if (u < -margin || v < -margin || w < -margin)
                continue;
            if (u < margin || v < margin || w < margin || std::abs(t) < 1e-12)
                clean = false; // near an edge, a vertex, or the start: draw another direction
            else if (t > 0.0)
                ++crossings;
        }
        if (clean)
            return crossings % 2 == 1;
    }
    throw std::runtime_error("ray_parity_inside: no clean direction found");
}

SurfaceMesh random_triangles(int count, std::mt19937& rng)
{
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    std::uniform_real_distribution<double> size(-0.15, 0.15);
    SurfaceMesh mesh;
    mesh.vertices.resize(3 * count, 3);
    mesh.faces.resize(count, 3);
    for (int f = 0; f < count; ++f) {
        const Vec3 c(unit(rng), unit(rng), unit(rng));
        const double scale = f % 10 == 0 ? 3.0 : 1.0; // a few large ones
        for (int k = 0; k < 3; ++k)
            mesh.vertices.row(3 * f + k) = (c + scale * Vec3(size(rng), size(rng), size(rng))).transpose();
        mesh.faces.row(f) << 3 * f, 3 * f + 1, 3 * f + 2;
    }
    return mesh;
}

Vec3 random_point(const Vec3& min, const Vec3& max, std::mt19937& rng)
{
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    return min + Vec3(unit(rng), unit(rng), unit(rng)).cwiseProduct(max - min);
}

std::vector<Vec3> candidate_points(const ContactSurface& a, const ContactSurface& b)
{
    std::vector<Index> order;
    a.tree.vertices_in_box(a.vertices, a.tree.bounds().intersection(b.tree.bounds()), order);
    std::vector<Vec3> points;
    for (const Index v : order)
        points.push_back(a.vertices.row(v).transpose());
    return points;
}

ContactSurface deformed_ball(const Vec3& center, double radius, Index resolution, double wobble, const std::string& name)
{
    TetMesh mesh = make_sphere(center, radius, resolution);
    for (Index v = 0; v < mesh.num_vertices(); ++v) {
        const Vec3 d = mesh.rest_positions.row(v).transpose() - center;
        mesh.rest_positions.row(v) =
            (center + d * (1.0 + wobble * std::sin(3 * d.x()) * std::cos(2 * d.y() + d.z()))).transpose();
    }
    return surface_of(mesh, name);
}

} // namespace coro::test
