#include <corocontact/contact/aabb_tree.hpp>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <emmintrin.h>
#if defined(__AVX2__)
#include <immintrin.h>
#endif

#include <algorithm>
#include <array>

namespace coro {

namespace {

using Pairs = std::vector<std::array<Index, 2>>;

bool boxes_meet(const Aabb& a, const Aabb& b)
{
    return a.min[0] <= b.max[0] && b.min[0] <= a.max[0] && a.min[1] <= b.max[1] && b.min[1] <= a.max[1] &&
           a.min[2] <= b.max[2] && b.min[2] <= a.max[2];
}

/// A float box, one coordinate bound broadcast to each register.
struct WideBox {
    __m128 lo[3], hi[3];
};

WideBox wide_box(const Aabb& box)
{
    WideBox w;
    for (int j = 0; j < 3; ++j) {
        w.lo[j] = _mm_set1_ps(detail::float_down(box.min[j]));
        w.hi[j] = _mm_set1_ps(detail::float_up(box.max[j]));
    }
    return w;
}

/// Lane k's float box of a node, each bound broadcast.
template <class Node>
WideBox lane_box(const Node& node, int k)
{
    WideBox w;
    for (int j = 0; j < 3; ++j) {
        w.lo[j] = _mm_set1_ps(node.lo[j][k]);
        w.hi[j] = _mm_set1_ps(node.hi[j][k]);
    }
    return w;
}

/// The part of `box` in `region` (empty on an axis where they do not meet: low above high).
WideBox clipped(const WideBox& box, const WideBox& region)
{
    WideBox w;
    for (int j = 0; j < 3; ++j) {
        w.lo[j] = _mm_max_ps(box.lo[j], region.lo[j]);
        w.hi[j] = _mm_min_ps(box.hi[j], region.hi[j]);
    }
    return w;
}

#if defined(__AVX2__)
/// Bit 4i + k set: lane i of `a` and lane k of `b` have float boxes that meet each other and
/// `region` (closed), all sixteen pairs at once. Three boxes meet when, on each axis, the largest
/// lower bound is at most the smallest upper bound: the lanes are clipped to the region, then
/// compared, lanes i = 0, 1 in one register and i = 2, 3 in another, each against the four lanes
/// of `b`. Unused lanes hold empty boxes (+∞, −∞), which meet nothing.
template <class Node>
int lane_pairs_meeting(const Node& a, const Node& b, const WideBox& region)
{
    const __m256i first = _mm256_setr_epi32(0, 0, 0, 0, 1, 1, 1, 1);
    const __m256i second = _mm256_setr_epi32(2, 2, 2, 2, 3, 3, 3, 3);
    __m256 meet01 = _mm256_castsi256_ps(_mm256_set1_epi32(-1)), meet23 = meet01;
    for (int j = 0; j < 3; ++j) {
        const __m128 a_lo = _mm_max_ps(_mm_load_ps(a.lo[j]), region.lo[j]);
        const __m128 a_hi = _mm_min_ps(_mm_load_ps(a.hi[j]), region.hi[j]);
        const __m128 b_lo = _mm_max_ps(_mm_load_ps(b.lo[j]), region.lo[j]);
        const __m128 b_hi = _mm_min_ps(_mm_load_ps(b.hi[j]), region.hi[j]);
        const __m256 a_lo8 = _mm256_castps128_ps256(a_lo), a_hi8 = _mm256_castps128_ps256(a_hi);
        const __m256 b_lo8 = _mm256_set_m128(b_lo, b_lo), b_hi8 = _mm256_set_m128(b_hi, b_hi);
        const auto meet = [&](const __m256i& lanes) {
            return _mm256_and_ps(_mm256_cmp_ps(_mm256_permutevar8x32_ps(a_lo8, lanes), b_hi8, _CMP_LE_OQ),
                                 _mm256_cmp_ps(_mm256_permutevar8x32_ps(a_hi8, lanes), b_lo8, _CMP_GE_OQ));
        };
        meet01 = _mm256_and_ps(meet01, meet(first));
        meet23 = _mm256_and_ps(meet23, meet(second));
    }
    return _mm256_movemask_ps(meet01) | (_mm256_movemask_ps(meet23) << 8);
}
#endif

/// f(i, k) for each lane i of `a` and lane k of `b` whose float boxes meet each other and
/// `region`, i ascending, then k. `a_lanes_meeting(box)`, `b_lanes_meeting(box)`: the lanes of
/// `a`, of `b`, whose boxes meet `box`.
template <class Node, class ALanesMeeting, class BLanesMeeting, class F>
void for_each_lane_pair(const Node& a, [[maybe_unused]] const Node& b, const WideBox& region,
                        [[maybe_unused]] const ALanesMeeting& a_lanes_meeting,
                        [[maybe_unused]] const BLanesMeeting& b_lanes_meeting, const F& f)
{
#if defined(__AVX2__)
    for (int m = lane_pairs_meeting(a, b, region); m != 0; m &= m - 1) {
        const int bit = __builtin_ctz(static_cast<unsigned>(m));
        f(bit >> 2, bit & 3);
    }
#else
    const int b_lanes = b_lanes_meeting(region);
    if (b_lanes == 0)
        return;
    for (int ma = a_lanes_meeting(region); ma != 0; ma &= ma - 1) {
        const int i = __builtin_ctz(static_cast<unsigned>(ma));
        const WideBox lane_a = lane_box(a, i);
        for (int mb = b_lanes_meeting(lane_a) & b_lanes; mb != 0; mb &= mb - 1)
            f(i, __builtin_ctz(static_cast<unsigned>(mb)));
    }
#endif
}

} // namespace

/// The lanes of node `node` whose float box meets `box` (closed).
int AabbTree::lanes_meeting(Index node, const __m128* lo, const __m128* hi) const
{
    const WideNode& w = m_nodes[static_cast<std::size_t>(node)];
    __m128 overlap = _mm_and_ps(_mm_cmple_ps(_mm_load_ps(w.lo[0]), hi[0]), _mm_cmpge_ps(_mm_load_ps(w.hi[0]), lo[0]));
    for (int j = 1; j < 3; ++j)
        overlap = _mm_and_ps(overlap, _mm_and_ps(_mm_cmple_ps(_mm_load_ps(w.lo[j]), hi[j]),
                                                 _mm_cmpge_ps(_mm_load_ps(w.hi[j]), lo[j])));
    return _mm_movemask_ps(overlap) & ((1 << w.count) - 1);
}

void AabbTree::overlapping_faces(CRef<Positions> vertices, const AabbTree& other, CRef<Positions> other_vertices,
                                 const Aabb& region, Pairs& pairs) const
{
    overlapping_slots(other, region, pairs);
    // The pairs of the float boxes, narrowed to those of the exact boxes (a rare rejection: no
    // need for speed here, the detector takes the float pairs).
    std::size_t kept = 0;
    for (const auto& [slot_a, slot_b] : pairs) {
        const Aabb box_a = slot_box(vertices.data(), vertices.outerStride(), static_cast<std::size_t>(slot_a));
        const Aabb box_b = other.slot_box(other_vertices.data(), other_vertices.outerStride(),
                                          static_cast<std::size_t>(slot_b));
        if (box_a.overlaps(box_b) && box_a.overlaps(region) && box_b.overlaps(region))
            pairs[kept++] = {m_order[static_cast<std::size_t>(slot_a)], other.m_order[static_cast<std::size_t>(slot_b)]};
    }
    pairs.resize(kept);
}

void AabbTree::overlapping_slots(const AabbTree& other, const Aabb& region, Pairs& pairs) const
{
    pairs.clear();
    if (m_nodes.empty() || other.m_nodes.empty() || region.empty() || !boxes_meet(m_bounds, region) ||
        !boxes_meet(other.m_bounds, region) || !boxes_meet(m_bounds, other.m_bounds))
        return;
    constexpr Index PARALLEL_WALK_FACES = 1024; // from about the 10k-tet spheres' 1,728 faces
    if (num_faces() < PARALLEL_WALK_FACES) {
        walk_overlapping(other, region, 0, 0, pairs);
        return;
    }
    // Large trees: the walk's node pairs a few levels down both trees, found level by level, as
    // tasks (each level of both trees taken once: tasks that each started from the root of
    // `other` walked its top levels again, and were slower), their pairs joined in task order.
    const std::vector<std::array<Index, 2>> tasks = walk_tasks(other, region);
    std::vector<Pairs> parts(tasks.size());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, tasks.size(), 1), [&](const tbb::blocked_range<std::size_t>& r) {
        for (std::size_t t = r.begin(); t < r.end(); ++t)
            walk_overlapping(other, region, tasks[t][0], tasks[t][1], parts[t]);
    });
    std::size_t total = 0;
    for (const Pairs& part : parts)
        total += part.size();
    pairs.reserve(total);
    for (const Pairs& part : parts)
        pairs.insert(pairs.end(), part.begin(), part.end());
}

std::vector<std::array<Index, 2>> AabbTree::walk_tasks(const AabbTree& other, const Aabb& region) const
{
    // Enough tasks for two threads to share the walk evenly, however the overlap is spread.
    constexpr std::size_t MIN_TASKS = 16;
    constexpr int MAX_LEVELS = 4;
    const WideBox wide_region = wide_box(region);
    std::vector<std::array<Index, 2>> level{{0, 0}}, next;
    for (int depth = 0; depth < MAX_LEVELS && level.size() < MIN_TASKS; ++depth) {
        next.clear();
        bool split = false;
        for (const auto& [na, nb] : level) {
            const WideNode& a = m_nodes[static_cast<std::size_t>(na)];
            const WideNode& b = other.m_nodes[static_cast<std::size_t>(nb)];
            // A pair with a face lane among its children stays whole (the walk takes faces).
            const std::size_t before = next.size();
            bool faces = false;
            for_each_lane_pair(
                a, b, wide_region, [&](const WideBox& box) { return lanes_meeting(na, box.lo, box.hi); },
                [&](const WideBox& box) { return other.lanes_meeting(nb, box.lo, box.hi); },
                [&](int i, int k) {
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
    return level;
}

void AabbTree::walk_overlapping(const AabbTree& other, const Aabb& region, Index a_root, Index b_root,
                                Pairs& slots) const
{
    // Float boxes bound the exact ones and the region is widened to floats, so a lane is dropped
    // only when its exact box misses; a pair of faces is taken when their float boxes meet (no
    // exact test: it read six corners per pair and almost never failed).
    const WideBox wide_region = wide_box(region);
    // The pairs gather on the stack and join `slots` a block at a time: pushed one by one, the
    // growth of the many small vectors of a parallel walk cost as much as its box tests.
    constexpr int BLOCK = 256;
    std::array<Index, 2> block[BLOCK];
    int in_block = 0;
    const auto emit = [&](Index slot_a, Index slot_b) {
        block[in_block++] = {slot_a, slot_b};
        if (in_block == BLOCK) {
            slots.insert(slots.end(), block, block + BLOCK);
            in_block = 0;
        }
    };
    // One face, its float box `box` (a lane box of a node: it bounds the face's exact box),
    // against a subtree of the other tree.
    Index face_stack[STACK_SIZE];
    const auto face_against = [&](const AabbTree& tree, Index root, const WideBox& box, auto&& emit_slot) {
        int top = 0;
        face_stack[top++] = root;
        while (top > 0) {
            const Index node = face_stack[--top];
            const WideNode& w = tree.m_nodes[static_cast<std::size_t>(node)];
            for (int m = tree.lanes_meeting(node, box.lo, box.hi); m != 0; m &= m - 1) {
                const int k = __builtin_ctz(static_cast<unsigned>(m));
                if ((w.face_mask >> k) & 1)
                    emit_slot(-1 - w.child[k]);
                else
                    face_stack[top++] = w.child[k];
            }
        }
    };
    // Each pair taken pushes at most 16 and goes one level down both trees.
    std::array<Index, 2> stack[16 * MAX_DEPTH + 1];
    int top = 0;
    stack[top++] = {a_root, b_root};
    while (top > 0) {
        const auto [na, nb] = stack[--top];
        const WideNode& a = m_nodes[static_cast<std::size_t>(na)];
        const WideNode& b = other.m_nodes[static_cast<std::size_t>(nb)];
        // Lane pairs (i, k) whose boxes meet each other and the region, i ascending, then k.
        const auto take = [&](int i, int k) {
            const bool face_a = (a.face_mask >> i) & 1;
            const bool face_b = (b.face_mask >> k) & 1;
            if (!face_a && !face_b) {
                stack[top++] = {a.child[i], b.child[k]};
            } else if (face_a && face_b) {
                emit(-1 - a.child[i], -1 - b.child[k]);
            } else if (face_a) {
                const Index slot_a = -1 - a.child[i];
                face_against(other, b.child[k], clipped(lane_box(a, i), wide_region),
                             [&](Index slot_b) { emit(slot_a, slot_b); });
            } else {
                const Index slot_b = -1 - b.child[k];
                face_against(*this, a.child[i], clipped(lane_box(b, k), wide_region),
                             [&](Index slot_a) { emit(slot_a, slot_b); });
            }
        };
        for_each_lane_pair(
            a, b, wide_region, [&](const WideBox& box) { return lanes_meeting(na, box.lo, box.hi); },
            [&](const WideBox& box) { return other.lanes_meeting(nb, box.lo, box.hi); }, take);
    }
    slots.insert(slots.end(), block, block + in_block);
}

} // namespace coro
