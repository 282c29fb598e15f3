// AabbTree::overlapping_faces: the walk of two trees together.
#include <corocontact/contact/aabb_tree.hpp>

#include "detail/simd.hpp"
#include "detail/tree_access.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <array>
#include <vector>

namespace coro {

namespace {

using detail::TreeAccess;
using detail::simd::F4;
using Pairs = std::vector<std::array<Index, 2>>;
using Node = TreeAccess::Node;

/// A float box, each coordinate bound in all four lanes.
struct WideBox {
    F4 lo[3], hi[3];
};

WideBox wide_box(const Aabb& box)
{
    WideBox w;
    for (int j = 0; j < 3; ++j) {
        w.lo[j] = F4::splat(detail::float_down(box.min[j]));
        w.hi[j] = F4::splat(detail::float_up(box.max[j]));
    }
    return w;
}

/// Lane k's float box of a node clipped to `region` (empty on an axis where they do not meet:
/// low above high).
WideBox clipped_lane(const Node& node, int k, const WideBox& region)
{
    WideBox w;
    for (int j = 0; j < 3; ++j) {
        w.lo[j] = max(F4::splat(node.lo[j][k]), region.lo[j]);
        w.hi[j] = min(F4::splat(node.hi[j][k]), region.hi[j]);
    }
    return w;
}

/// The lanes of `node` whose float box meets `box` (closed).
int lanes_meeting(const Node& node, const WideBox& box)
{
    auto meet = (F4::load(node.lo[0]) <= box.hi[0]) & (F4::load(node.hi[0]) >= box.lo[0]);
    for (int j = 1; j < 3; ++j)
        meet = meet & (F4::load(node.lo[j]) <= box.hi[j]) & (F4::load(node.hi[j]) >= box.lo[j]);
    return meet.bits() & ((1 << node.count) - 1);
}

/// f(i, k) for each lane i of `a` and lane k of `b` whose float boxes meet each other and
/// `region`, i ascending, then k.
template <class F>
void for_each_lane_pair(const Node& a, const Node& b, const WideBox& region, const F& f)
{
    for (int m = detail::simd::box_pairs_meeting({a.lo, a.hi}, {b.lo, b.hi}, region.lo, region.hi); m != 0;
         m &= m - 1) {
        const int bit = __builtin_ctz(static_cast<unsigned>(m));
        f(bit >> 2, bit & 3);
    }
}

/// The node pairs (a's, b's) from which the walk runs in parallel, into `level` (`next` is
/// working memory): together they lead to every pair of faces, each once, in an order fixed by
/// the trees.
void walk_tasks(const AabbTree& ta, const AabbTree& tb, const WideBox& region, std::vector<std::array<Index, 2>>& level,
                std::vector<std::array<Index, 2>>& next)
{
    // Enough tasks for two threads to share the walk evenly, however the overlap is spread.
    constexpr std::size_t MIN_TASKS = 16;
    constexpr int MAX_LEVELS = 4;
    const auto& nodes_a = TreeAccess::nodes(ta);
    const auto& nodes_b = TreeAccess::nodes(tb);
    level.assign(1, {0, 0});
    for (int depth = 0; depth < MAX_LEVELS && level.size() < MIN_TASKS; ++depth) {
        next.clear();
        bool split = false;
        for (const auto& [na, nb] : level) {
            const Node& a = nodes_a[static_cast<std::size_t>(na)];
            const Node& b = nodes_b[static_cast<std::size_t>(nb)];
            // A pair with a face lane among its children stays whole (the walk takes faces).
            const std::size_t before = next.size();
            bool faces = false;
            for_each_lane_pair(a, b, region, [&](int i, int k) {
                faces = faces || ((a.face_mask >> i) & 1) || ((b.face_mask >> k) & 1);
                next.push_back({a.child[i], b.child[k]});
            });
            if (faces) {
                next.resize(before);
                next.push_back({na, nb});
            } else {
                split = true;
            }
        }
        level.swap(next);
        if (!split)
            break;
    }
}

/// The slot pairs below node a_root of `ta` and b_root of `tb`, appended to `pairs`.
void walk(const AabbTree& ta, const AabbTree& tb, const WideBox& region, Index a_root, Index b_root, Pairs& pairs)
{
    // Float boxes bound the exact ones and the region is widened to floats, so a lane is dropped
    // only when its exact box misses; a pair of faces is taken when their float boxes meet (an
    // exact test would read six corners per pair, and almost never fail).
    const auto& nodes_a = TreeAccess::nodes(ta);
    const auto& nodes_b = TreeAccess::nodes(tb);
    // The pairs gather on the stack and join `pairs` a block at a time: pushed one by one, the
    // growth of the many small vectors of a parallel walk costs as much as its box tests.
    constexpr int BLOCK = 256;
    std::array<Index, 2> block[BLOCK];
    int in_block = 0;
    const auto emit = [&](Index slot_a, Index slot_b) {
        block[in_block++] = {slot_a, slot_b};
        if (in_block == BLOCK) {
            pairs.insert(pairs.end(), block, block + BLOCK);
            in_block = 0;
        }
    };
    // One face, its float box `box` (a lane box of a node: it bounds the face's exact box),
    // against a subtree of the other tree.
    Index face_stack[TreeAccess::STACK_SIZE];
    const auto face_against = [&](const std::vector<Node>& nodes, Index root, const WideBox& box, auto&& emit_slot) {
        int top = 0;
        face_stack[top++] = root;
        while (top > 0) {
            const Node& w = nodes[static_cast<std::size_t>(face_stack[--top])];
            for (int m = lanes_meeting(w, box); m != 0; m &= m - 1) {
                const int k = __builtin_ctz(static_cast<unsigned>(m));
                if ((w.face_mask >> k) & 1)
                    emit_slot(-1 - w.child[k]);
                else
                    face_stack[top++] = w.child[k];
            }
        }
    };
    // Each pair taken pushes at most 16 and goes one level down both trees.
    std::array<Index, 2> stack[16 * 60 + 1];
    int top = 0;
    stack[top++] = {a_root, b_root};
    while (top > 0) {
        const auto [na, nb] = stack[--top];
        const Node& a = nodes_a[static_cast<std::size_t>(na)];
        const Node& b = nodes_b[static_cast<std::size_t>(nb)];
        for_each_lane_pair(a, b, region, [&](int i, int k) {
            const bool is_face_a = (a.face_mask >> i) & 1;
            const bool is_face_b = (b.face_mask >> k) & 1;
            if (!is_face_a && !is_face_b) {
                stack[top++] = {a.child[i], b.child[k]};
            } else if (is_face_a && is_face_b) {
                emit(-1 - a.child[i], -1 - b.child[k]);
            } else if (is_face_a) {
                const Index slot_a = -1 - a.child[i];
                face_against(nodes_b, b.child[k], clipped_lane(a, i, region), [&](Index slot_b) { emit(slot_a, slot_b); });
            } else {
                const Index slot_b = -1 - b.child[k];
                face_against(nodes_a, a.child[i], clipped_lane(b, k, region), [&](Index slot_a) { emit(slot_a, slot_b); });
            }
        });
    }
    pairs.insert(pairs.end(), block, block + in_block);
}

} // namespace

void detail::overlapping_slots(const AabbTree& a, const AabbTree& b, const Aabb& region, Pairs& pairs,
                               SlotWalkScratch& scratch)
{
    pairs.clear();
    const auto& nodes_a = TreeAccess::nodes(a);
    const auto& nodes_b = TreeAccess::nodes(b);
    if (nodes_a.empty() || nodes_b.empty() || region.empty() || !a.bounds().overlaps(region) ||
        !b.bounds().overlaps(region) || !a.bounds().overlaps(b.bounds()))
        return;
    const WideBox wide_region = wide_box(region);
    constexpr Index PARALLEL_WALK_FACES = 1024;
    if (a.num_faces() < PARALLEL_WALK_FACES) {
        walk(a, b, wide_region, 0, 0, pairs);
        return;
    }
    // Large trees: the walk's node pairs a few levels down both trees, found level by level
    // (each level of both trees taken once), as tasks, their pairs joined in task order.
    const std::vector<std::array<Index, 2>>& tasks = scratch.tasks;
    walk_tasks(a, b, wide_region, scratch.tasks, scratch.next_level);
    std::vector<Pairs>& parts = scratch.parts;
    if (parts.size() < tasks.size())
        parts.resize(tasks.size());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, tasks.size(), 1), [&](const tbb::blocked_range<std::size_t>& r) {
        for (std::size_t t = r.begin(); t < r.end(); ++t) {
            parts[t].clear();
            walk(a, b, wide_region, tasks[t][0], tasks[t][1], parts[t]);
        }
    });
    std::size_t total = 0;
    for (std::size_t t = 0; t < tasks.size(); ++t)
        total += parts[t].size();
    pairs.reserve(total);
    for (std::size_t t = 0; t < tasks.size(); ++t)
        pairs.insert(pairs.end(), parts[t].begin(), parts[t].end());
}

void detail::overlapping_slots(const AabbTree& a, const AabbTree& b, const Aabb& region, Pairs& pairs)
{
    SlotWalkScratch scratch;
    overlapping_slots(a, b, region, pairs, scratch);
}

void AabbTree::overlapping_faces(const AabbTree& other, const Aabb& region, Pairs& pairs) const
{
    detail::overlapping_slots(*this, other, region, pairs);
    for (auto& [a, b] : pairs) {
        a = m_face_of_slot[static_cast<std::size_t>(a)];
        b = other.m_face_of_slot[static_cast<std::size_t>(b)];
    }
}

} // namespace coro
