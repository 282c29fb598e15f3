#include <corocontact/contact/broad_phase.hpp>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

using namespace coro;

namespace {

std::vector<std::pair<Index, Index>> brute_force_pairs(const std::vector<Aabb>& boxes)
{
    std::vector<std::pair<Index, Index>> pairs;
    for (std::size_t i = 0; i < boxes.size(); ++i)
        for (std::size_t j = i + 1; j < boxes.size(); ++j)
            if (boxes[i].overlaps(boxes[j]))
                pairs.emplace_back(static_cast<Index>(i), static_cast<Index>(j));
    return pairs;
}

} // namespace

TEST(OverlappingPairs, EqualsBruteForceOnRandomBoxes)
{
    std::mt19937 rng(7);
    std::uniform_int_distribution<int> cell(0, 40);
    std::uniform_int_distribution<int> extent(0, 6);
    for (int trial = 0; trial < 20; ++trial) {
        std::vector<Aabb> boxes(300);
        for (std::size_t i = 0; i < boxes.size(); ++i) {
            if (i % 37 == 5)
                continue; // empty box: overlaps nothing
            // Coordinates on a coarse grid, so that many boxes touch exactly; flat boxes too.
            const Vec3 min(cell(rng), cell(rng), 0.25 * cell(rng));
            const Vec3 size(extent(rng), extent(rng), 0.25 * extent(rng));
            boxes[i] = {min, min + size};
        }
        const auto pairs = overlapping_pairs(boxes);
        const auto expected = brute_force_pairs(boxes);
        ASSERT_EQ(pairs, expected) << "trial " << trial;
        ASSERT_FALSE(expected.empty());
    }
}

TEST(OverlappingPairs, TouchingBoxesOverlapAndEmptyBoxesDoNot)
{
    std::vector<Aabb> boxes{{Vec3(0, 0, 0), Vec3(1, 1, 1)},
                            {Vec3(1, 1, 1), Vec3(2, 2, 2)}, // touches box 0 at a corner
                            Aabb(),
                            {Vec3(2.5, 0, 0), Vec3(3, 1, 1)}};
    const std::vector<std::pair<Index, Index>> expected{{0, 1}};
    EXPECT_EQ(overlapping_pairs(boxes), expected);
    EXPECT_TRUE(overlapping_pairs({}).empty());
    EXPECT_TRUE(overlapping_pairs({Aabb(), Aabb()}).empty());
}

TEST(OverlappingPairs, ShuffledRowOfBoxesGivesTheNeighbourPairs)
{
    // A row of 10,000 unit boxes, each overlapping only its two neighbours, in random order.
    std::vector<Aabb> boxes;
    for (int i = 0; i < 10000; ++i)
        boxes.push_back({Vec3(0.75 * i, 0, 0), Vec3(0.75 * i + 1, 1, 1)});
    std::shuffle(boxes.begin(), boxes.end(), std::mt19937(3));
    const auto pairs = overlapping_pairs(boxes);
    ASSERT_EQ(pairs.size(), 9999u);
    for (const auto& [i, j] : pairs) {
        ASSERT_LT(i, j);
        ASSERT_NEAR(std::abs(boxes[static_cast<std::size_t>(i)].min.x() - boxes[static_cast<std::size_t>(j)].min.x()),
                    0.75, 1e-12);
    }
}
