#include <corocontact/core/tet_mesh.hpp>

#include <corocontact/core/error.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <tuple>

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

std::optional<std::pair<Index, Index>> find_duplicate_tet(const Tets& tets)
{
    using Key = std::pair<std::array<Index, 4>, Index>; // sorted nodes, tet
    std::vector<Key> keys(static_cast<std::size_t>(tets.rows()));
    for (Index t = 0; t < tets.rows(); ++t) {
        Key& key = keys[static_cast<std::size_t>(t)];
        key.first = {tets(t, 0), tets(t, 1), tets(t, 2), tets(t, 3)};
        std::sort(key.first.begin(), key.first.end());
        key.second = t;
    }
    std::sort(keys.begin(), keys.end());
    std::optional<std::pair<Index, Index>> first;
    for (std::size_t i = 1; i < keys.size(); ++i)
        if (keys[i].first == keys[i - 1].first && (!first || keys[i].second < first->second)) {
            std::size_t group = i - 1; // the earliest tet with these nodes comes first in its group
            while (group > 0 && keys[group - 1].first == keys[i].first)
                --group;
            first = std::make_pair(keys[group].second, keys[i].second);
        }
    return first;
}

namespace {

/// A tet's face, outward, as three ascending nodes and whether sorting them took an odd
/// permutation (`flipped`): two tets on opposite sides of a shared face list it with opposite
/// orientations, hence different `flipped`.
struct OrientedFace {
    std::array<Index, 3> nodes;
    bool flipped = false;
};

OrientedFace oriented_face(const TetMesh& mesh, Index t, const std::array<int, 3>& local)
{
    OrientedFace face{{mesh.tets(t, local[0]), mesh.tets(t, local[1]), mesh.tets(t, local[2])}};
    const auto order = [&face](std::size_t a, std::size_t b) {
        if (face.nodes[a] > face.nodes[b]) {
            std::swap(face.nodes[a], face.nodes[b]);
            face.flipped = !face.flipped;
        }
    };
    order(0, 1); // sorting network for three: every swap flips the orientation
    order(1, 2);
    order(0, 1);
    return face;
}

/// Whether two of `mesh`'s outward faces have the same `make_key(face)`.
template <class Key, class MakeKey>
bool has_repeated_key(const TetMesh& mesh, const MakeKey& make_key)
{
    std::vector<Key> keys;
    keys.reserve(4 * static_cast<std::size_t>(mesh.num_tets()));
    for (Index t = 0; t < mesh.num_tets(); ++t)
        for (const std::array<int, 3>& local : TET_FACES)
            keys.push_back(make_key(oriented_face(mesh, t, local)));
    std::sort(keys.begin(), keys.end());
    return std::adjacent_find(keys.begin(), keys.end()) != keys.end();
}

/// Whether two faces share nodes and orientation: in a valid mesh each oriented face occurs
/// once, and three tets on one face always put two on the same side. Packed keys sort two to
/// three times as fast as the records find_overlapping_tets needs to name the tets: one
/// 64-bit word for up to 2^21 nodes, a word and a half beyond.
bool has_repeated_oriented_face(const TetMesh& mesh)
{
    const auto node = [](const OrientedFace& face, std::size_t k) { return static_cast<std::uint64_t>(face.nodes[k]); };
    if (mesh.num_vertices() <= (Index{1} << 21))
        return has_repeated_key<std::uint64_t>(mesh, [&](const OrientedFace& face) {
            return (((node(face, 0) << 21 | node(face, 1)) << 21 | node(face, 2)) << 1) | (face.flipped ? 1U : 0U);
        });
    return has_repeated_key<std::pair<std::uint64_t, std::uint32_t>>(mesh, [&](const OrientedFace& face) {
        return std::make_pair(node(face, 0) << 32 | node(face, 1),
                              static_cast<std::uint32_t>(node(face, 2) << 1 | (face.flipped ? 1U : 0U)));
    });
}

} // namespace

std::optional<TetOverlap> find_overlapping_tets(const TetMesh& mesh)
{
    if (!has_repeated_oriented_face(mesh))
        return std::nullopt;
    struct Face {
        OrientedFace face;
        Index tet;
        bool operator<(const Face& other) const
        {
            return std::tie(face.nodes, tet) < std::tie(other.face.nodes, other.tet);
        }
    };
    std::vector<Face> faces;
    faces.reserve(4 * static_cast<std::size_t>(mesh.num_tets()));
    for (Index t = 0; t < mesh.num_tets(); ++t)
        for (const std::array<int, 3>& local : TET_FACES)
            faces.push_back({oriented_face(mesh, t, local), t});
    std::sort(faces.begin(), faces.end());
    std::optional<TetOverlap> first;
    for (std::size_t i = 0; i < faces.size();) {
        std::size_t end = i + 1;
        while (end < faces.size() && faces[end].face.nodes == faces[i].face.nodes)
            ++end;
        const bool more = end - i > 2;
        if ((more || (end - i == 2 && faces[i].face.flipped == faces[i + 1].face.flipped)) &&
            (!first || faces[i + 1].tet < first->second))
            first = TetOverlap{faces[i].tet, faces[i + 1].tet, faces[i].face.nodes, more};
        i = end;
    }
    return first;
}

Index validate_and_orient(TetMesh& mesh, const std::string& source)
{
    const Index n_vertices = mesh.num_vertices();
    CORO_CHECK(mesh.num_tets() > 0, InputError,
               source << ": the mesh has no tetrahedra (expected at least one 4-node tet)");
    for (Index v = 0; v < n_vertices; ++v)
        for (int d = 0; d < 3; ++d) {
            const double x = mesh.rest_positions(v, d);
            CORO_CHECK(std::isfinite(x), InputError,
                       source << ": node " << v << " has a non-finite coordinate " << x
                              << " (expected a finite number; nodes counted from 0 in file order)");
            CORO_CHECK(std::abs(x) <= MAX_COORDINATE, InputError,
                       source << ": node " << v << " has the coordinate " << x << ", expected a magnitude of at most "
                              << MAX_COORDINATE
                              << " (the volumes of larger tets overflow double; nodes counted from 0 in file order)");
        }

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
    CORO_CHECK(min_volume > 0.0, InputError,
               source << ": the tets' edges are " << mean_edge
                      << " long on average, so short that their volumes underflow double (rescale the mesh)");

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
    if (const auto overlap = find_overlapping_tets(mesh)) {
        // A tet listed twice overlaps its copy across all four faces: say so plainly.
        if (const auto duplicate = find_duplicate_tet(mesh.tets))
            CORO_THROW(InputError, source << ": tet " << duplicate->second << " has the same 4 nodes as tet "
                                          << duplicate->first
                                          << " (expected every tet once; tets counted from 0 in file order)");
        const std::array<Index, 3>& f = overlap->face;
        if (overlap->shared_by_more)
            CORO_THROW(InputError, source << ": more than two tets share the face (" << f[0] << ", " << f[1] << ", "
                                          << f[2] << "), among them tets " << overlap->first << " and "
                                          << overlap->second
                                          << ": the mesh overlaps itself (tets and nodes counted from 0 in file order)");
        CORO_THROW(InputError, source << ": tets " << overlap->first << " and " << overlap->second
                                      << " lie on the same side of their shared face (" << f[0] << ", " << f[1] << ", "
                                      << f[2] << "): the mesh overlaps itself (tets and nodes counted from 0 in file order)");
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

namespace {

/// Per node, 1 when a tet references it.
std::vector<char> referenced_flags(const TetMesh& mesh)
{
    std::vector<char> used(static_cast<std::size_t>(mesh.num_vertices()), 0);
    for (Index t = 0; t < mesh.num_tets(); ++t)
        for (int a = 0; a < 4; ++a)
            used[static_cast<std::size_t>(mesh.tets(t, a))] = 1;
    return used;
}

} // namespace

std::vector<Index> unreferenced_vertices(const TetMesh& mesh)
{
    const std::vector<char> used = referenced_flags(mesh);
    std::vector<Index> unused;
    for (Index v = 0; v < mesh.num_vertices(); ++v)
        if (!used[static_cast<std::size_t>(v)])
            unused.push_back(v);
    return unused;
}

std::vector<std::array<Index, 2>> coincident_vertices(const TetMesh& mesh)
{
    const std::vector<char> used = referenced_flags(mesh);
    std::vector<Index> order;
    for (Index v = 0; v < mesh.num_vertices(); ++v)
        if (used[static_cast<std::size_t>(v)])
            order.push_back(v);
    const auto& x = mesh.rest_positions;
    const auto position = [&](Index v) { return std::make_tuple(x(v, 0), x(v, 1), x(v, 2)); };
    std::sort(order.begin(), order.end(), [&](Index a, Index b) {
        return std::make_pair(position(a), a) < std::make_pair(position(b), b);
    });
    std::vector<std::array<Index, 2>> pairs;
    for (std::size_t first = 0, i = 1; i < order.size(); ++i) {
        if (position(order[i]) != position(order[first]))
            first = i;
        else
            pairs.push_back({order[first], order[i]});
    }
    return pairs;
}

} // namespace coro
