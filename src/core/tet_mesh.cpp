#include <corocontact/core/tet_mesh.hpp>

#include <corocontact/core/error.hpp>

#include <cmath>

namespace coro {

double signed_volume(const Vec3& x0, const Vec3& x1, const Vec3& x2, const Vec3& x3)
{
    Mat3 edges;
    edges << x1 - x0, x2 - x0, x3 - x0;
    return edges.determinant() / 6.0;
}

double signed_volume(const TetMesh& mesh, Index t)
{
    const auto& p = mesh.rest_positions;
    const auto& tet = mesh.tets.row(t);
    return signed_volume(p.row(tet(0)).transpose(), p.row(tet(1)).transpose(),
                         p.row(tet(2)).transpose(), p.row(tet(3)).transpose());
}

double total_volume(const TetMesh& mesh)
{
    double volume = 0.0;
    for (Index t = 0; t < mesh.num_tets(); ++t)
        volume += signed_volume(mesh, t);
    return volume;
}

Index validate_and_orient(TetMesh& mesh, const std::string& source)
{
    const Index n_vertices = mesh.num_vertices();
    CORO_CHECK(mesh.num_tets() > 0, InputError,
               source << ": the mesh has no tetrahedra (expected at least one 4-node tet)");
    for (Index v = 0; v < n_vertices; ++v)
        for (int d = 0; d < 3; ++d)
            CORO_CHECK(std::isfinite(mesh.rest_positions(v, d)), InputError,
                       source << ": node " << v << " has a non-finite coordinate "
                              << mesh.rest_positions(v, d) << " (expected a finite number; nodes counted from 0 in file order)");

    double edge_sum = 0.0;
    for (Index t = 0; t < mesh.num_tets(); ++t) {
        for (int a = 0; a < 4; ++a) {
            const Index v = mesh.tets(t, a);
            CORO_CHECK(v >= 0 && v < n_vertices, InputError,
                       source << ": tet " << t << " refers to node " << v
                              << ", expected an index in [0, " << n_vertices << ") (tets and nodes counted from 0 in file order)");
            for (int b = 0; b < a; ++b)
                CORO_CHECK(mesh.tets(t, b) != v, InputError,
                           source << ": tet " << t << " repeats node " << v
                                  << " (expected 4 distinct nodes; tets and nodes counted from 0 in file order)");
        }
        const auto& p = mesh.rest_positions;
        edge_sum += (p.row(mesh.tets(t, 1)) - p.row(mesh.tets(t, 0))).norm();
    }
    const double mean_edge = edge_sum / mesh.num_tets();
    const double min_volume = 1e-12 * mean_edge * mean_edge * mean_edge;

    Index reoriented = 0;
    for (Index t = 0; t < mesh.num_tets(); ++t) {
        const double volume = signed_volume(mesh, t);
        CORO_CHECK(std::abs(volume) > min_volume, InputError,
                   source << ": tet " << t << " has zero volume (" << volume
                          << "; expected |volume| > " << min_volume << "; tets counted from 0 in file order)");
        if (volume < 0.0) {
            std::swap(mesh.tets(t, 2), mesh.tets(t, 3));
            ++reoriented;
        }
    }
    return reoriented;
}

double mean_ratio_quality(const TetMesh& mesh, Index t)
{
    const auto& p = mesh.rest_positions;
    double edges = 0.0;
    for (int a = 0; a < 4; ++a)
        for (int b = a + 1; b < 4; ++b)
            edges += (p.row(mesh.tets(t, a)) - p.row(mesh.tets(t, b))).squaredNorm();
    const double volume = signed_volume(mesh, t);
    const double magnitude = 12.0 * std::cbrt(9.0 * volume * volume) / edges;
    return volume < 0.0 ? -magnitude : magnitude;
}

std::vector<Index> unreferenced_vertices(const TetMesh& mesh)
{
    std::vector<char> used(static_cast<std::size_t>(mesh.num_vertices()), 0);
    for (Index t = 0; t < mesh.num_tets(); ++t)
        for (int a = 0; a < 4; ++a)
            used[static_cast<std::size_t>(mesh.tets(t, a))] = 1;
    std::vector<Index> unused;
    for (Index v = 0; v < mesh.num_vertices(); ++v)
        if (!used[static_cast<std::size_t>(v)])
            unused.push_back(v);
    return unused;
}

} // namespace coro
