#pragma once
/// @file tree_access.hpp
/// @brief The inside of AabbTree for the walks of the contact library (axis lines, nearest
/// points, face pairs, face planes), and the single precision rounding they share.

#include <corocontact/contact/aabb_tree.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <limits>
#include <vector>

namespace coro::detail {

/// `x` rounded to a float no greater (down) or no smaller (up): the nearest float, then a step
/// of at least one ulp outward (a few ulps looser than needed). A value above the float range
/// rounds down to the largest float, one below it up to the lowest (the step from ±∞ gives NaN,
/// which fails the comparison). A comparison, not std::fmin/fmax: those are library calls.
inline float float_down(double x)
{
    const float f = static_cast<float>(x);
    const float down = f - (std::abs(f) * 0x1p-23f + 0x1p-126f);
    return down < std::numeric_limits<float>::max() ? down : std::numeric_limits<float>::max();
}
inline float float_up(double x)
{
    const float f = static_cast<float>(x);
    const float up = f + (std::abs(f) * 0x1p-23f + 0x1p-126f);
    return up > -std::numeric_limits<float>::max() ? up : -std::numeric_limits<float>::max();
}
/// A float threshold no smaller than `x` ≥ 0, with a relative margin of 2⁻¹⁸ (covers the
/// rounding of the single precision lower bounds compared against it); +∞ from 10³⁸ on.
inline float float_threshold(double x)
{
    if (!(x < 1e38))
        return std::numeric_limits<float>::infinity();
    return static_cast<float>(x) * (1.0f + 0x1p-18f);
}

/// Read access to a tree's nodes and slots (see AabbTree's private members).
struct TreeAccess {
    using Node = AabbTree::Node;
    using NodeBox = AabbTree::NodeBox;
    /// Entries a walk's stack needs: each pop pushes at most 4 and goes one level down.
    static constexpr int STACK_SIZE = 3 * AabbTree::MAX_DEPTH + 4;

    static const std::vector<Node>& nodes(const AabbTree& t) { return t.m_nodes; }
    static const std::vector<NodeBox>& node_boxes(const AabbTree& t) { return t.m_node_boxes; }
    static const std::vector<Index>& node_slots(const AabbTree& t) { return t.m_node_slots; }
    static const std::vector<Index>& face_of_slot(const AabbTree& t) { return t.m_face_of_slot; }
    static const Index* slot_vertices(const AabbTree& t, std::size_t slot) { return &t.m_slot_vertices[3 * slot]; }
    static const std::vector<Index>& slab_start(const AabbTree& t) { return t.m_slab_start; }
    static const std::vector<Index>& slab_vertices(const AabbTree& t) { return t.m_slab_vertices; }
    static const std::vector<std::array<Index, 3>>& slab_corners(const AabbTree& t) { return t.m_slab_corners; }

    /// The exact box of the face in `slot`, its corners at data + stride·v (3 doubles each).
    static Aabb slot_box(const AabbTree& t, const double* data, std::ptrdiff_t stride, std::size_t slot)
    {
        const Index* fv = slot_vertices(t, slot);
        const double* a = data + stride * fv[0];
        const double* b = data + stride * fv[1];
        const double* c = data + stride * fv[2];
        Aabb box; // operands in the order of the SIMD min/max of the refit (the same with a NaN)
        for (int j = 0; j < 3; ++j) {
            box.min[j] = std::min(c[j], std::min(b[j], a[j]));
            box.max[j] = std::max(c[j], std::max(b[j], a[j]));
        }
        return box;
    }
};

/// The working memory of overlapping_slots() on large trees, kept from call to call: the node
/// pairs from which the walk runs as tasks, and each task's face pairs (never shrinks).
struct SlotWalkScratch {
    std::vector<std::array<Index, 2>> tasks, next_level;
    std::vector<std::vector<std::array<Index, 2>>> parts;
};

/// AabbTree::overlapping_faces with each face as its slot in its tree (no lookup of its index:
/// what the grouping takes, whose reads of a face's corners then stay in slot order).
/// @param[out] slot_pairs  (slot in `a`, slot in `b`), each pair once; old content replaced,
///                         capacity kept
/// @param[in,out] scratch  working memory
void overlapping_slots(const AabbTree& a, const AabbTree& b, const Aabb& region,
                       std::vector<std::array<Index, 2>>& slot_pairs, SlotWalkScratch& scratch);

/// The same with a scratch of its own.
void overlapping_slots(const AabbTree& a, const AabbTree& b, const Aabb& region,
                       std::vector<std::array<Index, 2>>& slot_pairs);

/// Pushes the child nodes among `lanes` of `node` (face lanes are skipped), each with its key,
/// the largest key first, so that they are popped in the order of their keys.
inline void push_by_key(const TreeAccess::Node& node, int lanes, const float* keys, Index* stack, float* stack_keys,
                        int& top)
{
    for (int m = lanes & ~node.face_mask; m != 0;) {
        int far = __builtin_ctz(static_cast<unsigned>(m));
        for (int rest = m & (m - 1); rest != 0; rest &= rest - 1) {
            const int k = __builtin_ctz(static_cast<unsigned>(rest));
            if (keys[k] > keys[far])
                far = k;
        }
        stack[top] = node.child[far];
        stack_keys[top++] = keys[far];
        m &= ~(1 << far);
    }
}

} // namespace coro::detail
