#include <corocontact/core/surface_mesh.hpp>

#include <algorithm>
#include <array>
#include <map>
#include <utility>

namespace coro {

namespace {
struct FaceRecord {
    std::array<Index, 3> sorted;
    Index tet;
    int local;
};
} // namespace

Tris boundary_faces(const TetMesh& mesh)
{
    std::vector<FaceRecord> records;
    records.reserve(static_cast<std::size_t>(mesh.num_tets()) * 4);
    for (Index t = 0; t < mesh.num_tets(); ++t)
        for (int f = 0; f < 4; ++f) {
            std::array<Index, 3> key{mesh.tets(t, TET_FACES[f][0]), mesh.tets(t, TET_FACES[f][1]),
                                     mesh.tets(t, TET_FACES[f][2])};
            std::sort(key.begin(), key.end());
            records.push_back({key, t, f});
        }
    std::sort(records.begin(), records.end(), [](const FaceRecord& a, const FaceRecord& b) {
        return std::tie(a.sorted, a.tet, a.local) < std::tie(b.sorted, b.tet, b.local);
    });

    std::vector<std::pair<Index, int>> boundary; // (tet, local face)
    for (std::size_t i = 0; i < records.size();) {
        std::size_t j = i + 1;
        while (j < records.size() && records[j].sorted == records[i].sorted)
            ++j;
        if (j - i == 1)
            boundary.emplace_back(records[i].tet, records[i].local);
        i = j;
    }
    std::sort(boundary.begin(), boundary.end());

    Tris faces(static_cast<Index>(boundary.size()), 3);
    for (std::size_t k = 0; k < boundary.size(); ++k) {
        const auto [t, f] = boundary[k];
        for (int c = 0; c < 3; ++c)
            faces(static_cast<Index>(k), c) = mesh.tets(t, TET_FACES[f][c]);
    }
    return faces;
}

std::vector<Index> surface_vertices(const Tris& faces)
{
    std::vector<Index> vertices(faces.data(), faces.data() + faces.size());
    std::sort(vertices.begin(), vertices.end());
    vertices.erase(std::unique(vertices.begin(), vertices.end()), vertices.end());
    return vertices;
}

SurfaceCheck check_surface(const Tris& faces)
{
    // For each undirected edge: how many faces use it in each direction.
    std::map<std::pair<Index, Index>, std::array<Index, 2>> edges;
    for (Index f = 0; f < faces.rows(); ++f)
        for (int c = 0; c < 3; ++c) {
            const Index a = faces(f, c);
            const Index b = faces(f, (c + 1) % 3);
            auto& count = edges[{std::min(a, b), std::max(a, b)}];
            ++count[a < b ? 0 : 1];
        }
    SurfaceCheck check;
    for (const auto& [edge, count] : edges) {
        const Index uses = count[0] + count[1];
        if (uses == 1)
            ++check.open_edges;
        else if (uses > 2)
            ++check.nonmanifold_edges;
        else if (count[0] != 1)
            ++check.misoriented_edges;
    }
    return check;
}

double enclosed_volume(CRef<Positions> vertices, const Tris& faces)
{
    if (faces.rows() == 0)
        return 0.0;
    // The tetrahedra of the faces with a vertex of the surface, not the origin: about the origin
    // each term carries a rounding error of order eps·|x|³, which for a body far from the origin
    // (|x| ~ 1e8 for a unit cube) exceeds the volume itself and can flip its sign. The corners
    // relative to a surface vertex are exact for such a body (Sterbenz), and the errors scale
    // with the body's size.
    const Vec3 origin = vertices.row(faces(0, 0)).transpose();
    double volume = 0.0;
    for (Index f = 0; f < faces.rows(); ++f) {
        const Vec3 a = vertices.row(faces(f, 0)).transpose() - origin;
        const Vec3 b = vertices.row(faces(f, 1)).transpose() - origin;
        const Vec3 c = vertices.row(faces(f, 2)).transpose() - origin;
        volume += a.dot(b.cross(c)) / 6.0;
    }
    return volume;
}

} // namespace coro
