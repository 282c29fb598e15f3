#include <corocontact/contact/aabb.hpp>

#include <gtest/gtest.h>

using namespace coro;

TEST(BoundingBox, IsTheMinAndMaxOfTheRows)
{
    Positions p(3, 3);
    p << 1, -2, 3, //
        -4, 5, 0.5, //
        2, 0, -6;
    const Aabb box = bounding_box(p);
    EXPECT_EQ(box.min, Vec3(-4, -2, -6));
    EXPECT_EQ(box.max, Vec3(2, 5, 3));
    EXPECT_TRUE(bounding_box(Positions(0, 3)).empty());
}

TEST(Aabb, OverlapIsClosedAndSymmetric)
{
    const Aabb a{Vec3(0, 0, 0), Vec3(1, 1, 1)};
    const Aabb touching{Vec3(1, 0, 0), Vec3(2, 1, 1)};
    const Aabb apart{Vec3(1.0 + 1e-12, 0, 0), Vec3(2, 1, 1)};
    const Aabb apart_in_z{Vec3(0.5, 0.5, -2), Vec3(0.7, 0.7, -0.1)};
    EXPECT_TRUE(a.overlaps(touching));
    EXPECT_TRUE(touching.overlaps(a));
    EXPECT_FALSE(a.overlaps(apart));
    EXPECT_FALSE(apart.overlaps(a));
    EXPECT_FALSE(a.overlaps(apart_in_z));
    EXPECT_FALSE(a.overlaps(Aabb()));
    EXPECT_FALSE(Aabb().overlaps(a));
}

TEST(Aabb, IntersectionContainsExactlyTheCommonPoints)
{
    const Aabb a{Vec3(0, 0, 0), Vec3(2, 2, 2)};
    const Aabb b{Vec3(1, -1, 0.5), Vec3(3, 1.5, 1)};
    const Aabb i = a.intersection(b);
    EXPECT_EQ(i.min, Vec3(1, 0, 0.5));
    EXPECT_EQ(i.max, Vec3(2, 1.5, 1));
    EXPECT_TRUE(i.contains(Vec3(1, 0, 0.5)));
    EXPECT_FALSE(i.contains(Vec3(0.99, 1, 0.7)));
    EXPECT_TRUE(a.intersection(Aabb{Vec3(3, 3, 3), Vec3(4, 4, 4)}).empty());
    EXPECT_EQ(a.inflated(0.5).min, Vec3::Constant(-0.5));
}
