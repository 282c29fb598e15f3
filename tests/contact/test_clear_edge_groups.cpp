#include "contact_scenes.hpp"

#include <corocontact/contact/aabb_tree.hpp>
#include <corocontact/contact/winding_number.hpp>
#include <corocontact/core/primitives.hpp>

#include "detail/clear_edge_groups.hpp"
#include "detail/tree_access.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <vector>

using namespace coro;
using namespace coro::test;

namespace {

using Pairs = std::vector<std::array<Index, 2>>;

Aabb face_box(const ContactSurface& s, Index f)
{
    Aabb box;
    for (int c = 0; c < 3; ++c)
        box.extend(s.vertices.row(s.faces(f, c)).transpose());
    return box;
}

/// Every (face of a, face of b) whose boxes overlap each other and both meet `region`.
Pairs brute_force_pairs(const ContactSurface& a, const ContactSurface& b, const Aabb& region)
{
    std::vector<Aabb> boxes_b;
    for (Index g = 0; g < b.faces.rows(); ++g)
        boxes_b.push_back(face_box(b, g));
    Pairs pairs;
    for (Index f = 0; f < a.faces.rows(); ++f) {
        const Aabb box_a = face_box(a, f);
        if (!box_a.overlaps(region))
            continue;
        for (Index g = 0; g < b.faces.rows(); ++g)
            if (box_a.overlaps(boxes_b[static_cast<std::size_t>(g)]) && boxes_b[static_cast<std::size_t>(g)].overlaps(region))
                pairs.push_back({f, g});
    }
    return pairs;
}

Pairs sorted(Pairs pairs)
{
    std::sort(pairs.begin(), pairs.end());
    return pairs;
}

/// clear_edge_groups() of a's candidates against b, as each candidate's decider: the index of
/// its group's first candidate. Checks the groups' numbering on the way.
std::vector<Index> deciders(const ContactSurface& a, const ContactSurface& b, const Pairs& pairs,
                            detail::PairColumn column, const std::vector<Index>& candidates, std::vector<double>* path,
                            detail::GroupScratch* scratch = nullptr)
{
    std::vector<Index> group, firsts;
    detail::GroupScratch own;
    const Index groups = detail::clear_edge_groups(a, b, pairs, column, candidates, scratch ? *scratch : own, group,
                                                   firsts, path);
    EXPECT_EQ(static_cast<std::size_t>(groups), firsts.size());
    EXPECT_EQ(group.size(), candidates.size());
    EXPECT_TRUE(std::is_sorted(firsts.begin(), firsts.end()));
    std::vector<Index> decider(group.size());
    for (std::size_t i = 0; i < group.size(); ++i) {
        EXPECT_TRUE(group[i] >= 0 && group[i] < groups) << "candidate " << i;
        decider[i] = firsts[static_cast<std::size_t>(group[i])];
    }
    for (Index g = 0; g < groups; ++g)
        EXPECT_EQ(group[static_cast<std::size_t>(firsts[static_cast<std::size_t>(g)])], g) << "group " << g;
    return decider;
}

void expect_pairs_match_brute_force(const ContactSurface& a, const ContactSurface& b, const Aabb& region)
{
    Pairs pairs;
    a.tree.overlapping_faces(b.tree, region, pairs);
    const Pairs expected = brute_force_pairs(a, b, region);
    ASSERT_GT(expected.size(), 50u);
    Pairs again;
    a.tree.overlapping_faces(b.tree, region, again);
    EXPECT_EQ(again, pairs); // the same order every time
    // Every pair of exact boxes is there, each once, and others only where the boxes meet within
    // float rounding (here: when grown by a relative 10⁻⁶).
    const Pairs got = sorted(pairs);
    EXPECT_TRUE(std::adjacent_find(got.begin(), got.end()) == got.end()) << "a pair twice";
    EXPECT_TRUE(std::includes(got.begin(), got.end(), expected.begin(), expected.end()));
    const double grow = 1e-6 * (region.max - region.min).norm();
    for (const auto& [f, g] : got)
        EXPECT_TRUE(face_box(a, f).inflated(grow).overlaps(face_box(b, g)) &&
                    face_box(a, f).inflated(grow).overlaps(region) && face_box(b, g).inflated(grow).overlaps(region))
            << "faces " << f << ", " << g;
}

/// The groups of a's candidates against b, checked: a group's vertices are all inside b or all
/// outside (generalized winding number, independent of the grouping), a vertex on b's surface
/// stands alone, and each path bounds the distance to the decider. Returns the group count.
Index expect_groups_agree_with_winding_numbers(const ContactSurface& a, const ContactSurface& b)
{
    const Aabb region = a.tree.bounds().intersection(b.tree.bounds());
    std::vector<Index> candidates;
    a.tree.vertices_in_box(a.vertices, region, candidates);
    Pairs pairs;
    detail::overlapping_slots(a.tree, b.tree, region, pairs);
    std::vector<double> path;
    const std::vector<Index> decider = deciders(a, b, pairs, detail::PairColumn::FIRST, candidates, &path);
    EXPECT_EQ(decider.size(), candidates.size());
    EXPECT_EQ(path.size(), candidates.size());
    Index firsts = 0;
    std::vector<double> winding(candidates.size());
    for (std::size_t i = 0; i < candidates.size(); ++i)
        winding[i] = winding_number(b.vertices, b.faces, a.vertices.row(candidates[i]).transpose());
    for (std::size_t i = 0; i < candidates.size(); ++i) {
        const auto d = static_cast<std::size_t>(decider[i]);
        EXPECT_LE(d, i);
        EXPECT_EQ(decider[d], static_cast<Index>(d)) << "candidate " << i;
        firsts += d == i ? 1 : 0;
        if (d == i) {
            EXPECT_EQ(path[i], 0.0);
            continue;
        }
        const Vec3 p = a.vertices.row(candidates[i]).transpose();
        const Vec3 q = a.vertices.row(candidates[d]).transpose();
        EXPECT_GE(path[i], (p - q).norm()) << "candidate " << i;
        EXPECT_EQ(winding[i] > 0.5, winding[d] > 0.5) << "candidate " << i << " (w " << winding[i]
                                                       << ") shares the answer of " << d << " (w " << winding[d] << ")";
    }
    return firsts;
}

TEST(OverlappingFaces, MatchesBruteForceOnOverlappingBalls)
{
    const ContactSurface a = deformed_ball(Vec3::Zero(), 1.0, 9, 0.06, "a");
    const ContactSurface b = deformed_ball(Vec3(0.9, 0.1, -0.05), 0.8, 8, 0.05, "b");
    const Aabb overlap = a.tree.bounds().intersection(b.tree.bounds());
    expect_pairs_match_brute_force(a, b, overlap);
    expect_pairs_match_brute_force(b, a, overlap);
    // A smaller region across the intersection curve: only the pairs whose faces both meet it.
    expect_pairs_match_brute_force(a, b, Aabb{Vec3(0.45, 0.5, -0.3), Vec3(0.85, 0.95, 0.3)});
}

TEST(OverlappingFaces, MatchesBruteForceForTreesOfDifferentDepths)
{
    // Faces of the shallow tree meet nodes of the deep one, and the other way round.
    const ContactSurface ball = deformed_ball(Vec3::Zero(), 1.0, 10, 0.06, "ball");
    const ContactSurface box = surface_of(make_box(Vec3(0.5, -0.6, -0.4), Vec3(1.3, 0.5, 0.6), {1, 2, 1}), "box");
    const Aabb overlap = ball.tree.bounds().intersection(box.tree.bounds());
    expect_pairs_match_brute_force(ball, box, overlap);
    expect_pairs_match_brute_force(box, ball, overlap);
}

TEST(OverlappingFaces, MatchesBruteForceWithParallelTasks)
{
    // Over 1024 faces: the walk runs as tasks from node pairs a few levels down both trees.
    const ContactSurface a = deformed_ball(Vec3::Zero(), 1.0, 20, 0.06, "a");
    const ContactSurface b = deformed_ball(Vec3(1.0, 0.05, -0.03), 1.0, 12, 0.05, "b");
    ASSERT_GE(a.tree.num_faces(), 1024);
    expect_pairs_match_brute_force(a, b, a.tree.bounds().intersection(b.tree.bounds()));
}

TEST(OverlappingFaces, MatchesBruteForceWithParallelTasksAgainstAShallowTree)
{
    // The box's tree has faces one level below its root: the node pairs that reach them stay
    // whole tasks.
    const ContactSurface ball = deformed_ball(Vec3::Zero(), 1.0, 20, 0.06, "ball");
    const ContactSurface box = surface_of(make_box(Vec3(0.5, -0.6, -0.4), Vec3(1.3, 0.5, 0.6), {1, 1, 1}), "box");
    ASSERT_GE(ball.tree.num_faces(), 1024);
    const Aabb overlap = ball.tree.bounds().intersection(box.tree.bounds());
    expect_pairs_match_brute_force(ball, box, overlap);
    expect_pairs_match_brute_force(box, ball, overlap);
}

TEST(OverlappingFaces, EmptyWhenTheBoxesMiss)
{
    const ContactSurface a = deformed_ball(Vec3::Zero(), 1.0, 6, 0.0, "a");
    const ContactSurface b = deformed_ball(Vec3(3, 0, 0), 1.0, 6, 0.0, "b");
    Pairs pairs{{1, 2}};
    a.tree.overlapping_faces(b.tree, a.tree.bounds().intersection(b.tree.bounds()), pairs);
    EXPECT_TRUE(pairs.empty());
}

TEST(ClearEdgeGroups, GroupsAgreeWithWindingNumbersInDeepOverlap)
{
    const ContactSurface a = deformed_ball(Vec3::Zero(), 1.0, 10, 0.06, "a");
    const ContactSurface b = deformed_ball(Vec3(0.7, 0.1, -0.05), 0.9, 9, 0.05, "b");
    // Inside and outside both occur, in a handful of groups.
    const Index ab = expect_groups_agree_with_winding_numbers(a, b);
    const Index ba = expect_groups_agree_with_winding_numbers(b, a);
    EXPECT_GE(ab, 2);
    EXPECT_GE(ba, 2);
    EXPECT_LE(ab, 20);
    EXPECT_LE(ba, 20);
}

TEST(ClearEdgeGroups, GroupsAgreeWithWindingNumbersOnATwistedBarThroughATorus)
{
    const ContactSurface torus = surface_of(make_torus(Vec3::Zero(), 1.0, 0.35, 48, 24), "torus");
    TetMesh bar = make_box(Vec3(-1.6, -0.15, -0.15), Vec3(1.6, 0.15, 0.15), {32, 3, 3});
    bar.rest_positions = twist_and_bend(bar.rest_positions, 0.8, 4.0);
    const ContactSurface b = surface_of(bar, "bar");
    EXPECT_GE(expect_groups_agree_with_winding_numbers(b, torus), 3); // out, in, out, in, out
    EXPECT_GE(expect_groups_agree_with_winding_numbers(torus, b), 2);
}

TEST(ClearEdgeGroups, GroupsDoNotDependOnEarlierCallsWithTheSameScratch)
{
    // The grouping keeps its arrays from call to call: a call after others, on other surfaces
    // and over larger regions, gives what it gives with a fresh scratch.
    const ContactSurface a = deformed_ball(Vec3::Zero(), 1.0, 10, 0.06, "a");
    const ContactSurface b = deformed_ball(Vec3(0.7, 0.1, -0.05), 0.9, 9, 0.05, "b");
    const Aabb small{Vec3(0.3, 0.3, -0.4), Vec3(0.9, 1.0, 0.4)};
    struct Groups {
        std::vector<Index> decider;
        std::vector<double> path;
    };
    const auto groups = [](const ContactSurface& s, const ContactSurface& other, const Aabb& region,
                           detail::GroupScratch* scratch) {
        std::vector<Index> candidates;
        s.tree.vertices_in_box(s.vertices, region, candidates);
        Pairs pairs;
        detail::overlapping_slots(s.tree, other.tree, region, pairs);
        Groups g;
        g.decider = deciders(s, other, pairs, detail::PairColumn::FIRST, candidates, &g.path, scratch);
        return g;
    };
    const Aabb overlap = a.tree.bounds().intersection(b.tree.bounds());
    const std::array<std::array<const ContactSurface*, 2>, 3> calls{{{&b, &a}, {&a, &b}, {&a, &b}}};
    const std::array<Aabb, 3> regions{overlap, overlap, small};
    std::array<Groups, 3> fresh;
    for (std::size_t c = 0; c < calls.size(); ++c)
        fresh[c] = groups(*calls[c][0], *calls[c][1], regions[c], nullptr);
    ASSERT_GT(fresh[2].decider.size(), 20u);
    ASSERT_LT(fresh[2].decider.size(), fresh[1].decider.size() / 2);
    detail::GroupScratch shared;
    for (int round = 0; round < 2; ++round)
        for (std::size_t c = 0; c < calls.size(); ++c) {
            const Groups after = groups(*calls[c][0], *calls[c][1], regions[c], &shared);
            EXPECT_EQ(after.decider, fresh[c].decider) << "call " << c;
            EXPECT_EQ(after.path, fresh[c].path) << "call " << c;
        }
}

TEST(ClearEdgeGroups, VerticesOnTheOtherSurfaceStandAlone)
{
    // B's −x face is the plane x = 1 through A's +x face, shifted by a quarter cell in y and z:
    // A's vertices there lie on B's faces, edges and vertices.
    const ContactSurface a = surface_of(make_box(Vec3::Zero(), Vec3::Ones(), {2, 2, 2}), "a");
    const ContactSurface b = surface_of(make_box(Vec3(1, 0.25, 0.25), Vec3(2, 0.75, 1.25), {2, 2, 2}), "b");
    const Aabb region = a.tree.bounds().intersection(b.tree.bounds());
    std::vector<Index> candidates;
    a.tree.vertices_in_box(a.vertices, region, candidates);
    ASSERT_FALSE(candidates.empty());
    Pairs pairs;
    detail::overlapping_slots(a.tree, b.tree, region, pairs);
    std::vector<double> path;
    const std::vector<Index> decider = deciders(a, b, pairs, detail::PairColumn::FIRST, candidates, &path);
    int on_surface = 0;
    for (std::size_t i = 0; i < candidates.size(); ++i) {
        const Vec3 p = a.vertices.row(candidates[i]).transpose();
        if (!(p.x() == 1.0 && p.y() >= 0.25 && p.y() <= 0.75 && p.z() >= 0.25 && p.z() <= 1.25))
            continue;
        ++on_surface;
        EXPECT_EQ(decider[i], static_cast<Index>(i)) << "vertex " << p.transpose();
        for (std::size_t j = 0; j < candidates.size(); ++j)
            EXPECT_TRUE(j == i || decider[j] != static_cast<Index>(i)) << "vertex " << p.transpose();
    }
    EXPECT_EQ(on_surface, 2); // (1, 0.5, 0.5) and (1, 0.5, 1)

    // The other way round, with b's slots in the second column of the pairs.
    Pairs reversed = pairs;
    for (auto& pair : reversed)
        std::swap(pair[0], pair[1]);
    std::vector<Index> b_candidates;
    b.tree.vertices_in_box(b.vertices, region, b_candidates);
    const std::vector<Index> b_decider = deciders(b, a, pairs, detail::PairColumn::SECOND, b_candidates, &path);
    for (std::size_t i = 0; i < b_candidates.size(); ++i)
        EXPECT_EQ(b_decider[i], static_cast<Index>(i)); // all of B's candidates lie on A's +x face
    EXPECT_EQ(deciders(b, a, reversed, detail::PairColumn::FIRST, b_candidates, &path), b_decider);
}

} // namespace
