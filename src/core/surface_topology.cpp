#include <corocontact/core/surface_topology.hpp>

#include <algorithm>
#include <numeric>
#include <tuple>
#include <vector>

namespace coro {
namespace {

/// Union-find over 0..n−1 with path halving.
class DisjointSets {
public:
    explicit DisjointSets(std::size_t n) : m_parent(n) { std::iota(m_parent.begin(), m_parent.end(), 0); }

    std::size_t find(std::size_t i)
    {
        while (m_parent[i] != i)
            i = m_parent[i] = m_parent[m_parent[i]];
        return i;
    }

    void join(std::size_t a, std::size_t b) { m_parent[find(a)] = find(b); }

private:
    std::vector<std::size_t> m_parent;
};

/// One side of a face: the undirected edge (low, high) and the face's corners at its ends.
struct FaceEdge {
    Index low, high;
    std::size_t corner_low, corner_high; ///< corner = 3·face + local vertex
    bool operator<(const FaceEdge& o) const
    {
        return std::tie(low, high, corner_low) < std::tie(o.low, o.high, o.corner_low);
    }
};

} // namespace

SurfaceTopology surface_topology(const Tris& faces)
{
    SurfaceTopology topology;
    const auto n_faces = static_cast<std::size_t>(faces.rows());
    topology.faces = static_cast<Index>(n_faces);
    topology.edge_check = check_surface(faces);
    if (n_faces == 0)
        return topology;

    std::vector<FaceEdge> sides;
    sides.reserve(3 * n_faces);
    for (std::size_t f = 0; f < n_faces; ++f)
        for (int c = 0; c < 3; ++c) {
            const int d = (c + 1) % 3;
            const Index a = faces(static_cast<Index>(f), c), b = faces(static_cast<Index>(f), d);
            const std::size_t ca = 3 * f + static_cast<std::size_t>(c), cb = 3 * f + static_cast<std::size_t>(d);
            sides.push_back(a < b ? FaceEdge{a, b, ca, cb} : FaceEdge{b, a, cb, ca});
        }
    std::sort(sides.begin(), sides.end());

    // Faces sharing an edge are one piece; their corners at each end of it are one fan of that
    // end vertex. A vertex with more than one fan is a pinch point.
    DisjointSets pieces(n_faces), fans(3 * n_faces);
    for (std::size_t i = 0; i < sides.size();) {
        std::size_t j = i + 1;
        for (; j < sides.size() && sides[j].low == sides[i].low && sides[j].high == sides[i].high; ++j) {
            pieces.join(sides[i].corner_low / 3, sides[j].corner_low / 3);
            fans.join(sides[i].corner_low, sides[j].corner_low);
            fans.join(sides[i].corner_high, sides[j].corner_high);
        }
        ++topology.edges;
        i = j;
    }
    for (std::size_t f = 0; f < n_faces; ++f)
        topology.components += pieces.find(f) == f ? 1 : 0;

    std::vector<std::pair<Index, std::size_t>> vertex_fans; // (vertex, fan root) of every corner
    vertex_fans.reserve(3 * n_faces);
    for (std::size_t corner = 0; corner < 3 * n_faces; ++corner)
        vertex_fans.emplace_back(faces(static_cast<Index>(corner / 3), static_cast<Index>(corner % 3)), fans.find(corner));
    std::sort(vertex_fans.begin(), vertex_fans.end());
    vertex_fans.erase(std::unique(vertex_fans.begin(), vertex_fans.end()), vertex_fans.end());
    for (std::size_t i = 0; i < vertex_fans.size();) {
        std::size_t j = i + 1;
        while (j < vertex_fans.size() && vertex_fans[j].first == vertex_fans[i].first)
            ++j;
        ++topology.vertices;
        topology.nonmanifold_vertices += j - i > 1 ? 1 : 0;
        i = j;
    }
    return topology;
}

} // namespace coro
