#include "mesh_fixtures.hpp"
#include "near.hpp"

#include <corocontact/core/primitives.hpp>
#include <corocontact/fem/corotational_fem.hpp>
#include <corocontact/partition/part_layout.hpp>

#include <Eigen/Geometry>
#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <random>

using namespace coro;

namespace {
Material material()
{
    Material m;
    m.young = 2e4;
    m.poisson = 0.35;
    m.density = 3.0;
    return m;
}

// Deformed and rotated positions of the input mesh (input order).
VecX deformed(const TetMesh& mesh)
{
    std::mt19937 rng(17);
    std::uniform_real_distribution<double> u(-0.02, 0.02);
    const Mat3 r = Eigen::AngleAxisd(0.9, Vec3(1, 2, -1).normalized()).toRotationMatrix();
    VecX x(3 * mesh.num_vertices());
    for (Index v = 0; v < mesh.num_vertices(); ++v)
        x.segment<3>(3 * v) = r * (mesh.rest_positions.row(v).transpose() + Vec3(u(rng), u(rng), u(rng)));
    return x;
}

struct Partitioned {
    TetMesh mesh;
    PartLayout layout;
};
Partitioned partitioned(const TetMesh& mesh, Index parts)
{
    const PartLayout layout = make_part_layout(mesh.tets, mesh.num_vertices(), partition_tets(mesh.tets, mesh.num_vertices(), parts));
    return {reorder_mesh(mesh, layout), layout};
}
} // namespace

TEST(PartitionedAssembly, EqualsSerialReferenceEntryForEntry)
{
    const TetMesh mesh = test::irregular_box(6, 0.2, 31);
    const VecX x_input = deformed(mesh);
    std::vector<char> fixed_input(static_cast<std::size_t>(mesh.num_vertices()), 0);
    fixed_input[3] = fixed_input[40] = 1;

    // Serial reference: one part, input order.
    CorotationalFem serial(mesh, material());
    serial.update_rotations(x_input);
    BsrMatrix reference = serial.make_matrix();
    VecX f_reference(x_input.size());
    serial.assemble_with_forces(x_input, 0.7, 1.3, fixed_input, reference, f_reference);
    const Eigen::MatrixXd dense_reference = Eigen::MatrixXd(reference.to_sparse());

    const Partitioned p = partitioned(mesh, 9);
    ASSERT_GT(p.layout.num_interface_nodes(), 0);
    CorotationalFem parallel(p.mesh, material(), p.layout);
    VecX x(x_input.size());
    std::vector<char> fixed(fixed_input.size());
    for (Index v = 0; v < mesh.num_vertices(); ++v) {
        const Index old = p.layout.new_to_old_node[static_cast<std::size_t>(v)];
        x.segment<3>(3 * v) = x_input.segment<3>(3 * old);
        fixed[static_cast<std::size_t>(v)] = fixed_input[static_cast<std::size_t>(old)];
    }
    parallel.update_rotations(x);
    BsrMatrix matrix = parallel.make_matrix();
    VecX f(x.size());
    parallel.assemble_with_forces(x, 0.7, 1.3, fixed, matrix, f);
    const Eigen::MatrixXd dense = Eigen::MatrixXd(matrix.to_sparse());

    const double scale = dense_reference.cwiseAbs().maxCoeff();
    for (Index r = 0; r < mesh.num_vertices(); ++r)
        for (Index c = 0; c < mesh.num_vertices(); ++c) {
            const Index rr = p.layout.new_to_old_node[static_cast<std::size_t>(r)];
            const Index cc = p.layout.new_to_old_node[static_cast<std::size_t>(c)];
            const Mat3 block = dense.block<3, 3>(3 * r, 3 * c);
            const Mat3 expected = dense_reference.block<3, 3>(3 * rr, 3 * cc);
            ASSERT_NEAR_REL(block, expected, 1e-13 * scale, 0.0) << "block (" << r << ", " << c << ")";
        }
    for (Index v = 0; v < mesh.num_vertices(); ++v)
        ASSERT_NEAR_REL(f.segment<3>(3 * v), f_reference.segment<3>(3 * p.layout.new_to_old_node[static_cast<std::size_t>(v)]),
                        1e-12 * f_reference.cwiseAbs().maxCoeff(), 0.0);
}

TEST(PartitionedAssembly, BitwiseIdenticalForOneAndTwoThreads)
{
    const TetMesh mesh = make_sphere(Vec3::Zero(), 1.0, 10);
    const Partitioned p = partitioned(mesh, 8);
    VecX x = as_dofs(p.mesh.rest_positions);
    x += VecX::LinSpaced(x.size(), -0.01, 0.02);
    const auto run = [&](int threads) {
        std::pair<std::vector<double>, VecX> out;
        tbb::task_arena(threads).execute([&] {
            CorotationalFem fem(p.mesh, material(), p.layout);
            fem.update_rotations(x);
            BsrMatrix matrix = fem.make_matrix();
            VecX f(x.size());
            fem.assemble_with_forces(x, 1.0, 1.0, {}, matrix, f);
            out = {matrix.values(), f};
        });
        return out;
    };
    const auto one = run(1), two = run(2);
    EXPECT_EQ(one.first, two.first);
    EXPECT_TRUE(one.second == two.second);
}

// Matrices and force vectors are refilled every step: a refill over stale values (and rows
// of a node no tet uses) must give exactly what a fresh fill gives.
TEST(PartitionedAssembly, RefillOverStaleValuesEqualsFreshFill)
{
    TetMesh mesh = test::irregular_box(5, 0.2, 7);
    mesh.rest_positions.conservativeResize(mesh.num_vertices() + 1, 3);
    mesh.rest_positions.row(mesh.num_vertices() - 1) = Vec3(9.0, 9.0, 9.0).transpose(); // used by no tet
    const Partitioned p = partitioned(mesh, 6);
    ASSERT_GT(p.layout.num_interface_nodes(), 0);
    CorotationalFem fem(p.mesh, material(), p.layout);
    VecX x = as_dofs(p.mesh.rest_positions);
    x += VecX::LinSpaced(x.size(), -0.01, 0.02);
    fem.update_rotations(x);

    BsrMatrix fresh = fem.make_matrix();
    VecX f_fresh = VecX::Zero(x.size());
    fem.assemble_with_forces(x, 0.7, 1.3, {}, fresh, f_fresh);

    BsrMatrix stale = fem.make_matrix();
    std::fill(stale.values().begin(), stale.values().end(), 123.0);
    VecX f_stale = VecX::Constant(x.size(), -7.0);
    fem.assemble_with_forces(x, 0.7, 1.3, {}, stale, f_stale);
    EXPECT_EQ(stale.values(), fresh.values());
    EXPECT_TRUE(f_stale == f_fresh);

    // The unused node: mass-free identity-free row, zero force.
    const Index lonely = p.layout.old_to_new_node.back();
    EXPECT_TRUE(Mat3(fresh.block(fresh.diagonal(lonely))).isZero(0.0));
    EXPECT_TRUE(f_fresh.segment<3>(3 * lonely).isZero(0.0));

    // internal_forces() alone and assemble() alone follow the same rule.
    VecX f_alone = VecX::Constant(x.size(), 5.0);
    fem.internal_forces(x, f_alone);
    EXPECT_TRUE(f_alone == f_fresh);
    std::fill(stale.values().begin(), stale.values().end(), -1.0);
    fem.assemble(0.7, 1.3, {}, stale);
    EXPECT_EQ(stale.values(), fresh.values());
}

// Single-precision values: the element loop adds each tet's contribution in double and stores
// the sum in float, so every value is within a few float roundings of the double assembly
// (about one per contribution); bitwise the same for one and two threads; and a refill over
// stale values equals a fresh fill, also with fixed nodes.
TEST(PartitionedAssembly, SinglePrecisionIsTheDoubleAssemblyWithinFloatRoundingForAnyThreadCount)
{
    const TetMesh mesh = make_sphere(Vec3::Zero(), 1.0, 10);
    const Partitioned p = partitioned(mesh, 8);
    ASSERT_GT(p.layout.num_interface_nodes(), 0);
    VecX x = as_dofs(p.mesh.rest_positions);
    x += VecX::LinSpaced(x.size(), -0.01, 0.02);
    std::vector<char> fixed(static_cast<std::size_t>(mesh.num_vertices()), 0);
    fixed[0] = fixed[17] = 1;
    const auto run = [&](int threads, MatrixPrecision precision, double stale) {
        BsrMatrix matrix;
        tbb::task_arena(threads).execute([&] {
            CorotationalFem fem(p.mesh, material(), p.layout);
            fem.update_rotations(x);
            matrix = fem.make_matrix(precision);
            std::fill(matrix.values().begin(), matrix.values().end(), stale);
            std::fill(matrix.single_values().begin(), matrix.single_values().end(), static_cast<float>(stale));
            VecX f(x.size());
            fem.assemble_with_forces(x, 1.0, 1.0, fixed, matrix, f);
        });
        return matrix;
    };
    const BsrMatrix reference = run(2, MatrixPrecision::DOUBLE, 0.0);
    const BsrMatrix one = run(1, MatrixPrecision::SINGLE, 0.0), two = run(2, MatrixPrecision::SINGLE, 0.0);
    const BsrMatrix refilled = run(2, MatrixPrecision::SINGLE, 99.0);
    EXPECT_EQ(one.precision(), MatrixPrecision::SINGLE);
    EXPECT_EQ(one.single_values(), two.single_values());
    EXPECT_EQ(refilled.single_values(), two.single_values());
    double scale = 0.0;
    for (const double v : reference.values())
        scale = std::max(scale, std::abs(v));
    for (Index k = 0; k < reference.num_blocks(); ++k)
        ASSERT_NEAR_REL(Mat3(two.block(k)), Mat3(reference.block(k)), 1e-6 * scale, 0.0) << "block " << k;
    EXPECT_EQ(Mat3(two.block(two.diagonal(0))), Mat3::Identity()); // a fixed node's row
}
