#include <corocontact/core/embedding.hpp>

#include <limits>

namespace coro {

namespace {
// Barycentric weights of p in tet t.
Eigen::Vector4d barycentric(const TetMesh& mesh, Index t, const Vec3& p)
{
    const auto& x = mesh.rest_positions;
    const Vec3 x0 = x.row(mesh.tets(t, 0)).transpose();
    Mat3 edges;
    edges << x.row(mesh.tets(t, 1)).transpose() - x0, x.row(mesh.tets(t, 2)).transpose() - x0,
        x.row(mesh.tets(t, 3)).transpose() - x0;
    const Vec3 w = edges.partialPivLu().solve(p - x0);
    return {1.0 - w.sum(), w[0], w[1], w[2]};
}
} // namespace

Embedding embed_points(const TetMesh& mesh, CRef<Positions> points)
{
    // Tet boxes for a cheap first pass; points outside every box go through all tets.
    std::vector<Eigen::AlignedBox3d> boxes(static_cast<std::size_t>(mesh.num_tets()));
    for (Index t = 0; t < mesh.num_tets(); ++t)
        for (int a = 0; a < 4; ++a)
            boxes[static_cast<std::size_t>(t)].extend(mesh.rest_positions.row(mesh.tets(t, a)).transpose());

    Embedding embedding;
    embedding.nodes.resize(static_cast<std::size_t>(points.rows()));
    embedding.weights.resize(static_cast<std::size_t>(points.rows()));
    for (Index i = 0; i < points.rows(); ++i) {
        const Vec3 p = points.row(i).transpose();
        Index best = -1;
        double best_score = -std::numeric_limits<double>::infinity();
        Eigen::Vector4d best_weights = Eigen::Vector4d::Zero();
        for (const bool boxed : {true, false}) {
            for (Index t = 0; t < mesh.num_tets(); ++t) {
                if (boxed && !boxes[static_cast<std::size_t>(t)].contains(p))
                    continue;
                const Eigen::Vector4d w = barycentric(mesh, t, p);
                if (w.minCoeff() > best_score) {
                    best_score = w.minCoeff();
                    best = t;
                    best_weights = w;
                }
            }
            if (best >= 0 && best_score >= -1e-12)
                break; // inside a tet: no need for the global pass
        }
        embedding.nodes[static_cast<std::size_t>(i)] = {mesh.tets(best, 0), mesh.tets(best, 1), mesh.tets(best, 2),
                                                        mesh.tets(best, 3)};
        embedding.weights[static_cast<std::size_t>(i)] = best_weights;
    }
    return embedding;
}

Positions embedded_positions(const Embedding& embedding, CRef<Positions> nodes)
{
    Positions out(embedding.num_points(), 3);
    for (Index i = 0; i < embedding.num_points(); ++i) {
        Vec3 p = Vec3::Zero();
        for (int a = 0; a < 4; ++a)
            p += embedding.weights[static_cast<std::size_t>(i)][a] *
                 nodes.row(embedding.nodes[static_cast<std::size_t>(i)][static_cast<std::size_t>(a)]).transpose();
        out.row(i) = p.transpose();
    }
    return out;
}

} // namespace coro
