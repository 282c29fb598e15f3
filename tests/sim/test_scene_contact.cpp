// The scene's components: bodies joined through overlapping boxes, from the boxes and from a
// detection's broad phase, against a brute-force search over all pairs of boxes.
#include <corocontact/contact/contact_surface.hpp>
#include <corocontact/sim/scene_contact.hpp>

#include <gtest/gtest.h>

#include <random>
#include <vector>

using namespace coro;

namespace {
// A tetrahedron's surface with its lower corner at `corner` and edges of length `size`.
ContactSurface tetrahedron(const Vec3& corner, double size)
{
    Positions vertices(4, 3);
    vertices.row(0) = corner.transpose();
    vertices.row(1) = (corner + Vec3(size, 0.0, 0.0)).transpose();
    vertices.row(2) = (corner + Vec3(0.0, size, 0.0)).transpose();
    vertices.row(3) = (corner + Vec3(0.0, 0.0, size)).transpose();
    Tris faces(4, 3);
    faces << 0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3;
    return ContactSurface::from_body("tet", vertices, faces);
}

bool boxes_overlap(const Vec3& a, const Vec3& b, double size)
{
    return (a - b).cwiseAbs().maxCoeff() < size;
}
} // namespace

TEST(ContactComponents, JoinBodiesThroughOverlappingBoxesNumberedByFirstBody)
{
    std::mt19937 random(7);
    std::uniform_real_distribution<double> coordinate(0.0, 4.0);
    const double size = 0.5;
    for (int trial = 0; trial < 20; ++trial) {
        const Index num_bodies = 40;
        std::vector<Vec3> corners;
        std::vector<ContactSurface> surfaces;
        for (Index b = 0; b < num_bodies; ++b) {
            corners.emplace_back(coordinate(random), coordinate(random), coordinate(random));
            surfaces.push_back(tetrahedron(corners.back(), size));
        }
        // An obstacle over everything joins nothing: obstacles are not bodies.
        surfaces.push_back(tetrahedron(Vec3(-1.0, -1.0, -1.0), 20.0));

        // Brute force: flood each component from its first body.
        std::vector<Index> expected(static_cast<std::size_t>(num_bodies), -1);
        Index count = 0;
        for (Index first = 0; first < num_bodies; ++first) {
            if (expected[static_cast<std::size_t>(first)] >= 0)
                continue;
            std::vector<Index> stack{first};
            expected[static_cast<std::size_t>(first)] = count;
            while (!stack.empty()) {
                const Index b = stack.back();
                stack.pop_back();
                for (Index c = 0; c < num_bodies; ++c)
                    if (expected[static_cast<std::size_t>(c)] < 0 &&
                        boxes_overlap(corners[static_cast<std::size_t>(b)], corners[static_cast<std::size_t>(c)], size)) {
                        expected[static_cast<std::size_t>(c)] = count;
                        stack.push_back(c);
                    }
            }
            ++count;
        }
        ASSERT_GT(count, 1);
        ASSERT_LT(count, num_bodies);

        std::vector<Index> components;
        contact_components(surfaces, num_bodies, components);
        EXPECT_EQ(components, expected) << "trial " << trial;

        // The same from the broad phase of a detection (the obstacle's pairs included there),
        // as a time step takes them.
        DetectionScratch scratch;
        std::vector<ContactPoint> points;
        detect_contacts(surfaces, DetectionSettings{}, scratch, points);
        ASSERT_FALSE(scratch.overlapping_surfaces().empty());
        EXPECT_EQ(scratch.overlapping_surfaces().back().second, num_bodies) << "the obstacle meets every body";
        std::vector<Index> from_detection;
        contact_components(scratch.overlapping_surfaces(), num_bodies, from_detection);
        EXPECT_EQ(from_detection, expected) << "trial " << trial;
    }
}
