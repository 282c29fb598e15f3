#pragma once
/// @file nearest_search.hpp
/// @brief The nearest-point search of a tree: branch and bound over the node boxes and, given a
/// face-plane cache, over the planes of the faces and the slabs of small subtrees, which prune
/// far better than boxes where a surface is curved or tilted to the axes.

#include <corocontact/contact/aabb_tree.hpp>

#include <atomic>
#include <cstdint>
#include <limits>
#include <memory>
#include <vector>

namespace coro::detail {

/// For each child lane of one node: a unit normal u (to float precision), an offset and a slack
/// such that every point x of the child (a face, or the faces of a child node) has
/// |u·x − offset| ≤ slack − 2⁻²⁰·|offset|. The margin 2⁻²⁰·|offset| covers the float rounding of
/// u·p − offset in the search; slack +∞ (and u = 0) where there is no useful plane: an unused
/// lane, a degenerate face, a subtree of many faces.
struct FacePlanes {
    float normal[3][4];
    float offset[4];
    float slack[4];
};

/// The face planes of one tree at one set of positions, computed node by node when a search
/// first needs them (most searches reach only a part of a surface), from any thread: a thread
/// claims a node, computes it, and publishes it; a search that meets a node another thread is
/// computing goes on without its planes. The answers of the searches never depend on which
/// planes they had, only their work does.
class FacePlaneCache {
public:
    FacePlaneCache() = default;
    FacePlaneCache(FacePlaneCache&&) noexcept = default;
    FacePlaneCache& operator=(FacePlaneCache&&) noexcept = default;

    /// Forgets every node's planes, for new positions of `tree` (or another tree): O(1) unless
    /// the node count changed. Not concurrently with get().
    void reset(const AabbTree& tree);

    /// The planes of node `node` for the positions at data + stride·v; null while another
    /// thread computes them.
    const FacePlanes* get(std::size_t node, const AabbTree& tree, const double* data, std::ptrdiff_t stride)
    {
        if (m_stamp[node].load(std::memory_order_acquire) == ready())
            return &m_planes[node];
        return claim(node, tree, data, stride);
    }

private:
    std::uint32_t ready() const { return 2 * m_epoch + 1; }
    std::uint32_t busy() const { return 2 * m_epoch; }
    const FacePlanes* claim(std::size_t node, const AabbTree& tree, const double* data, std::ptrdiff_t stride);

    std::vector<FacePlanes> m_planes;
    std::unique_ptr<std::atomic<std::uint32_t>[]> m_stamp; // per node: busy(), ready(), or stale
    std::size_t m_size = 0;
    std::uint32_t m_epoch = 0;
};

/// The planes of the children of `node` (see FacePlanes) for the positions at data + stride·v.
void compute_face_planes(const AabbTree& tree, std::size_t node, const double* data, std::ptrdiff_t stride,
                         FacePlanes& planes);

/// Nearest-point searches in one tree at one set of positions.
class NearestSearch {
public:
    /// @param[in] planes  null: prune by boxes only (AabbTree::nearest)
    NearestSearch(const AabbTree& tree, CRef<Positions> vertices, FacePlaneCache* planes)
        : m_tree(tree), m_data(vertices.data()), m_stride(vertices.outerStride()), m_planes(planes)
    {
    }

    /// AabbTree::nearest's answer, bit for bit, found with less work from a start: the search
    /// begins with the hint face as the best so far and with `distance_bound` as a cutoff
    /// (inflated by a relative 10⁻⁶ on its square, so that faces tied at the bound are still
    /// visited), and skips what lies beyond.
    /// @param[in] distance_bound  a distance within which some point of the surface is known to
    ///                            lie (e.g. a face crossing of an axis line through `point`), +∞
    ///                            for none; a wrong one costs a second search, not the answer
    /// @param[in] hint_face       a face of `faces` likely near `point` (e.g. the previous
    ///                            query's answer), −1 for none
    /// @param[in] faces           the surface's faces (the tree's build() argument: the walk does
    ///                            not measure the hint face again), for the hint
    NearestPoint find(const Vec3& point, double distance_bound = std::numeric_limits<double>::infinity(),
                      Index hint_face = -1, const Tris* faces = nullptr) const;

    /// Points per packet of find_packet().
    static constexpr int PACKET = 8;

    /// find() of `count` points (1 ≤ count ≤ PACKET) in one walk of the tree, each with its own
    /// bounds and its own best so far: a node is entered when some point needs it, and each
    /// point meets the faces its own search would (within its final best). Same answers as
    /// find(), bit for bit; cheaper when the points are close together (their searches share
    /// most nodes).
    void find_packet(const Vec3* points, int count, const double* distance_bounds, const Index* hint_faces,
                     const Tris* faces, NearestPoint* out) const;

private:
    const AabbTree& m_tree;
    const double* m_data;
    std::ptrdiff_t m_stride;
    FacePlaneCache* m_planes;
};

} // namespace coro::detail
