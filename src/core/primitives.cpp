#include <corocontact/core/primitives.hpp>

#include <corocontact/core/error.hpp>

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>

namespace coro {

namespace {

// The 6 tets of the Kuhn subdivision of a unit cube whose corners are numbered by bits
// (x = bit 0, y = bit 1, z = bit 2): each follows one axis permutation from corner 0 to 7.
constexpr std::array<std::array<int, 3>, 6> AXIS_ORDERS{
    {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}}};

TetMesh structured_grid(const std::array<Index, 3>& cells)
{
    const Index nx = cells[0] + 1, ny = cells[1] + 1, nz = cells[2] + 1;
    TetMesh mesh;
    mesh.rest_positions.resize(nx * ny * nz, 3);
    for (Index k = 0; k < nz; ++k)
        for (Index j = 0; j < ny; ++j)
            for (Index i = 0; i < nx; ++i)
                mesh.rest_positions.row(i + nx * (j + ny * k)) << i, j, k;

    mesh.tets.resize(6 * cells[0] * cells[1] * cells[2], 4);
    Index t = 0;
    for (Index k = 0; k < cells[2]; ++k)
        for (Index j = 0; j < cells[1]; ++j)
            for (Index i = 0; i < cells[0]; ++i)
                for (std::size_t p = 0; p < AXIS_ORDERS.size(); ++p) {
                    std::array<Index, 3> corner{i, j, k};
                    std::array<Index, 4> nodes{};
                    nodes[0] = corner[0] + nx * (corner[1] + ny * corner[2]);
                    for (int s = 0; s < 3; ++s) {
                        ++corner[static_cast<std::size_t>(AXIS_ORDERS[p][static_cast<std::size_t>(s)])];
                        nodes[static_cast<std::size_t>(s) + 1] = corner[0] + nx * (corner[1] + ny * corner[2]);
                    }
                    // Odd axis permutations give negatively oriented tets: swap two nodes.
                    const bool odd = (p == 1 || p == 2 || p == 5);
                    if (odd)
                        std::swap(nodes[2], nodes[3]);
                    mesh.tets.row(t++) << nodes[0], nodes[1], nodes[2], nodes[3];
                }
    return mesh;
}

// Smooth map of the cube surface point q (‖q‖∞ = 1) onto the unit sphere.
Vec3 cube_to_sphere(const Vec3& q)
{
    const double x2 = q.x() * q.x(), y2 = q.y() * q.y(), z2 = q.z() * q.z();
    return {q.x() * std::sqrt(std::max(0.0, 1.0 - y2 / 2.0 - z2 / 2.0 + y2 * z2 / 3.0)),
            q.y() * std::sqrt(std::max(0.0, 1.0 - z2 / 2.0 - x2 / 2.0 + z2 * x2 / 3.0)),
            q.z() * std::sqrt(std::max(0.0, 1.0 - x2 / 2.0 - y2 / 2.0 + x2 * y2 / 3.0))};
}

} // namespace

TetMesh make_box(const Vec3& min, const Vec3& max, const std::array<Index, 3>& cells)
{
    for (int d = 0; d < 3; ++d) {
        CORO_CHECK(cells[static_cast<std::size_t>(d)] >= 1, InputError,
                   "box: cells[" << d << "] = " << cells[static_cast<std::size_t>(d)]
                                 << ", expected an integer >= 1");
        CORO_CHECK(min[d] < max[d], InputError,
                   "box: min[" << d << "] = " << min[d] << " is not below max[" << d
                               << "] = " << max[d]);
    }
    TetMesh mesh = structured_grid(cells);
    for (Index v = 0; v < mesh.num_vertices(); ++v)
        for (int d = 0; d < 3; ++d)
            mesh.rest_positions(v, d) =
                min[d] + (max[d] - min[d]) * mesh.rest_positions(v, d) / cells[static_cast<std::size_t>(d)];
    return mesh;
}

TetMesh make_sphere(const Vec3& center, double radius, Index resolution)
{
    CORO_CHECK(radius > 0.0, InputError, "sphere: radius = " << radius << ", expected > 0");
    CORO_CHECK(resolution >= 2, InputError,
               "sphere: resolution = " << resolution << ", expected an integer >= 2");
    TetMesh mesh = structured_grid({resolution, resolution, resolution});
    const double half = 0.5 * resolution;
    for (Index v = 0; v < mesh.num_vertices(); ++v) {
        const Vec3 p = (mesh.rest_positions.row(v).transpose().array() - half) / half; // in [-1,1]³
        const double shell = p.cwiseAbs().maxCoeff();
        const Vec3 mapped = shell > 0.0 ? Vec3(shell * cube_to_sphere(p / shell)) : Vec3::Zero();
        mesh.rest_positions.row(v) = (center + radius * mapped).transpose();
    }
    return mesh;
}

void BodyTransform::apply(Eigen::Ref<Positions> positions) const
{
    Mat3 rotation = Mat3::Identity();
    if (rotate_degrees != 0.0) {
        CORO_CHECK(rotate_axis.norm() > 0.0, InputError, "rotate_axis must not be zero");
        rotation = Eigen::AngleAxisd(rotate_degrees * M_PI / 180.0, rotate_axis.normalized())
                       .toRotationMatrix();
    }
    for (Eigen::Index v = 0; v < positions.rows(); ++v)
        positions.row(v) = (rotation * (scale * positions.row(v).transpose()) + translate).transpose();
}

} // namespace coro
