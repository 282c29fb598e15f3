#include "mesh_fixtures.hpp"
#include "near.hpp"

#include <corocontact/core/error.hpp>
#include <corocontact/fem/corotation.hpp>
#include <corocontact/fem/corotational_fem.hpp>
#include <corocontact/fem/tet_element.hpp>

#include <Eigen/Geometry>
#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <limits>
#include <random>
#include <string>

using namespace coro;

namespace {

Material test_material()
{
    Material m;
    m.young = 1000.0;
    m.poisson = 0.3;
    m.density = 10.0;
    return m;
}

Mat3 rotation(double degrees, const Vec3& axis)
{
    return Eigen::AngleAxisd(degrees * M_PI / 180.0, axis.normalized()).toRotationMatrix();
}

// x = R (X + small random strain field) + t
VecX deformed(const TetMesh& mesh, const Mat3& r, const Vec3& t, double strain, unsigned seed)
{
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(-strain, strain);
    Mat3 a;
    for (int i = 0; i < 9; ++i)
        a(i) = u(rng);
    VecX x(3 * mesh.num_vertices());
    for (Index v = 0; v < mesh.num_vertices(); ++v) {
        const Vec3 p = mesh.rest_positions.row(v).transpose();
        x.segment<3>(3 * v) = r * (p + a * p + Vec3(u(rng), u(rng), u(rng)) * 0.1) + t;
    }
    return x;
}

VecX forces(CorotationalFem& fem, const VecX& x)
{
    fem.update_rotations(x);
    VecX f(x.size());
    fem.internal_forces(x, f);
    return f;
}

// Reference assembly of K' = Σ R K Rᵀ with full 12×12 element matrices and explicit products.
SparseMat reference_stiffness(const TetMesh& mesh, const CorotationalFem& fem)
{
    std::vector<Eigen::Triplet<double, Index>> triplets;
    for (Index t = 0; t < mesh.num_tets(); ++t) {
        const auto& p = mesh.rest_positions;
        const TetRest rest = make_tet_rest(p.row(mesh.tets(t, 0)), p.row(mesh.tets(t, 1)),
                                           p.row(mesh.tets(t, 2)), p.row(mesh.tets(t, 3)));
        Mat12 rr = Mat12::Zero();
        for (int a = 0; a < 4; ++a)
            rr.block<3, 3>(3 * a, 3 * a) = fem.rotations()[static_cast<std::size_t>(t)];
        const Mat12 k = rr * element_stiffness(rest, fem.lambda(), fem.mu()) * rr.transpose();
        for (int a = 0; a < 4; ++a)
            for (int b = 0; b < 4; ++b)
                for (int i = 0; i < 3; ++i)
                    for (int j = 0; j < 3; ++j)
                        triplets.emplace_back(3 * mesh.tets(t, a) + i, 3 * mesh.tets(t, b) + j, k(3 * a + i, 3 * b + j));
    }
    SparseMat k(3 * mesh.num_vertices(), 3 * mesh.num_vertices());
    k.setFromTriplets(triplets.begin(), triplets.end());
    return k;
}

} // namespace

TEST(CorotationalFem, ForceIsMinusGradientOfEnergy)
{
    const TetMesh mesh = test::irregular_box(2, 0.3, 3);
    CorotationalFem fem(mesh, test_material());
    const VecX x = deformed(mesh, rotation(70, Vec3(1, 1, 0)), Vec3(1, 2, 3), 0.15, 9);
    const VecX f = forces(fem, x);
    const double h = 1e-6;
    VecX fd(x.size());
    for (Eigen::Index i = 0; i < x.size(); ++i) {
        VecX xp = x, xm = x;
        xp[i] += h;
        xm[i] -= h;
        fd[i] = -(fem.strain_energy(xp) - fem.strain_energy(xm)) / (2 * h);
    }
    EXPECT_NEAR_REL(f, fd, 1e-6 * f.cwiseAbs().maxCoeff(), 1e-6);
}

TEST(CorotationalFem, StiffnessIsMinusForceDerivativeAtZeroStrain)
{
    // At a rigidly moved (unstrained) state the frozen-rotation stiffness K' is the exact
    // Hessian: the rotation-derivative terms are proportional to the stress, which is zero.
    const TetMesh mesh = test::irregular_box(2, 0.3, 4);
    CorotationalFem fem(mesh, test_material());
    for (const double degrees : {0.0, 35.0, 90.0, 160.0}) {
        const VecX x = deformed(mesh, rotation(degrees, Vec3(0.2, 1, 0.5)), Vec3(-1, 0, 2), 0.0, 1);
        fem.update_rotations(x);
        BsrMatrix k = fem.make_matrix();
        fem.assemble(1.0, 0.0, {}, k);
        const Eigen::MatrixXd dense = Eigen::MatrixXd(k.to_sparse());
        const double h = 1e-6;
        Eigen::MatrixXd fd(x.size(), x.size());
        for (Eigen::Index i = 0; i < x.size(); ++i) {
            VecX xp = x, xm = x;
            xp[i] += h;
            xm[i] -= h;
            fd.col(i) = -(forces(fem, xp) - forces(fem, xm)) / (2 * h);
        }
        EXPECT_NEAR_REL(dense, fd, 1e-6 * dense.cwiseAbs().maxCoeff(), 0.0) << degrees << " degrees";
    }
}

TEST(CorotationalFem, StiffnessDiffersFromForceDerivativeOnlyByStressTerms)
{
    // Under strain the frozen-rotation K' omits dR/dx terms of the order of the stress: the
    // difference to the finite-difference Jacobian shrinks in proportion to the strain.
    const TetMesh mesh = test::irregular_box(2, 0.2, 5);
    CorotationalFem fem(mesh, test_material());
    double previous = 0.0;
    for (const double strain : {0.08, 0.04, 0.02}) {
        const VecX x = deformed(mesh, rotation(50, Vec3(1, 0, 1)), Vec3::Zero(), strain, 2);
        fem.update_rotations(x);
        BsrMatrix k = fem.make_matrix();
        fem.assemble(1.0, 0.0, {}, k);
        const Eigen::MatrixXd dense = Eigen::MatrixXd(k.to_sparse());
        Eigen::MatrixXd fd(x.size(), x.size());
        for (Eigen::Index i = 0; i < x.size(); ++i) {
            VecX xp = x, xm = x;
            xp[i] += 1e-6;
            xm[i] -= 1e-6;
            fd.col(i) = -(forces(fem, xp) - forces(fem, xm)) / 2e-6;
        }
        const double difference = (dense - fd).norm() / dense.norm();
        EXPECT_LT(difference, 2.0 * strain);
        if (previous > 0.0) {
            EXPECT_NEAR(difference / previous, 0.5, 0.15) << "strain " << strain;
        }
        previous = difference;
    }
}

TEST(CorotationalFem, RigidMotionHasZeroForceWhileLinearFemDoesNot)
{
    const TetMesh mesh = test::irregular_box(3, 0.3, 6);
    CorotationalFem fem(mesh, test_material());
    const VecX x = deformed(mesh, rotation(90, Vec3(0, 0, 1)), Vec3(5, -2, 1), 0.0, 1);
    const VecX f = forces(fem, x);
    // Force scale: E · area of a cell face.
    const double scale = test_material().young / 9.0;
    EXPECT_LT(f.cwiseAbs().maxCoeff(), 1e-10 * scale);

    // Linear FEM, f = −K (x − X): the same motion produces large spurious forces.
    CorotationalFem linear(mesh, test_material()); // rotations stay identity: never updated
    VecX f_linear(x.size());
    linear.internal_forces(x, f_linear);
    EXPECT_GT(f_linear.cwiseAbs().maxCoeff(), 0.1 * scale);
}

TEST(CorotationalFem, AssemblyEqualsReferenceTripleProducts)
{
    const TetMesh mesh = test::irregular_box(3, 0.3, 8);
    CorotationalFem fem(mesh, test_material());
    const VecX x = deformed(mesh, rotation(120, Vec3(1, -1, 2)), Vec3(0, 1, 0), 0.1, 3);
    fem.update_rotations(x);
    BsrMatrix k = fem.make_matrix();
    fem.assemble(1.0, 0.0, {}, k);
    const Eigen::MatrixXd reference = Eigen::MatrixXd(reference_stiffness(mesh, fem));
    EXPECT_NEAR_REL(Eigen::MatrixXd(k.to_sparse()), reference, 1e-12 * reference.cwiseAbs().maxCoeff(), 0.0);

    // Internal forces are affine in x with the rotations frozen: f(x) = f(0) − K'x.
    VecX f(x.size()), f0(x.size());
    fem.internal_forces(x, f);
    fem.internal_forces(VecX::Zero(x.size()), f0);
    EXPECT_NEAR_REL(f, VecX(f0 - reference * x), 1e-10 * f0.cwiseAbs().maxCoeff(), 0.0);
}

TEST(CorotationalFem, MassAndFixedNodeProjection)
{
    const TetMesh mesh = test::irregular_box(2, 0.2, 9);
    CorotationalFem fem(mesh, test_material());
    EXPECT_NEAR(fem.lumped_masses().sum(), test_material().density * 1.0, 1e-12);

    std::vector<char> fixed(static_cast<std::size_t>(mesh.num_vertices()), 0);
    fixed[4] = 1;
    BsrMatrix a = fem.make_matrix();
    fem.assemble(2.0, 3.0, fixed, a);
    const Eigen::MatrixXd dense = Eigen::MatrixXd(a.to_sparse());
    EXPECT_NEAR_REL(dense, dense.transpose(), 1e-12, 0.0);
    for (Eigen::Index j = 0; j < dense.cols(); ++j)
        for (int d = 0; d < 3; ++d)
            EXPECT_EQ(dense(12 + d, j), (j == 12 + d) ? 1.0 : 0.0);
    // A free node's diagonal holds 3·m on top of 2·K'.
    BsrMatrix k = fem.make_matrix();
    fem.assemble(1.0, 0.0, {}, k);
    const Eigen::MatrixXd stiffness = Eigen::MatrixXd(k.to_sparse());
    EXPECT_NEAR(dense(0, 0), 2.0 * stiffness(0, 0) + 3.0 * fem.lumped_masses()[0], 1e-9);
}

TEST(CorotationalFem, SameResultsWithOneAndTwoThreads)
{
    const TetMesh mesh = test::irregular_box(8, 0.15, 10);
    const VecX x = deformed(mesh, rotation(30, Vec3(1, 2, 0)), Vec3::Zero(), 0.1, 4);
    const auto run = [&](int threads) {
        tbb::task_arena arena(threads);
        std::pair<std::vector<double>, VecX> result;
        arena.execute([&] {
            CorotationalFem fem(mesh, test_material());
            fem.update_rotations(x);
            BsrMatrix k = fem.make_matrix();
            fem.assemble(0.5, 1.0, {}, k);
            VecX f(x.size());
            fem.internal_forces(x, f);
            result = {k.values(), f};
        });
        return result;
    };
    const auto one = run(1);
    const auto two = run(2);
    EXPECT_EQ(one.first, two.first);
    EXPECT_TRUE(one.second == two.second);
}

// The element loop runs 4 tets per AVX2 pack where it can (the last pack of a part padded):
// every tet's rotation must be the one polar_rotation gives for that tet alone, also for the
// inverted tets whose lanes go to the SVD while the others iterate.
TEST(CorotationalFem, EveryTetRotationEqualsItsOwnPolarRotation)
{
    const TetMesh mesh = test::irregular_box(3, 0.3, 11); // 162 tets: the last pack holds 2
    ASSERT_NE(mesh.num_tets() % 4, 0);
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> u(-0.25, 0.25); // cells are 1/3 wide: some tets invert
    VecX x = deformed(mesh, rotation(70, Vec3(0, 1, 1)), Vec3(1, 0, 0), 0.05, 6);
    for (Eigen::Index i = 0; i < x.size(); ++i)
        x[i] += u(rng);

    CorotationalFem fem(mesh, test_material());
    fem.update_rotations(x);
    Index inverted = 0;
    for (Index t = 0; t < mesh.num_tets(); ++t) {
        Mat34 nodes;
        for (int a = 0; a < 4; ++a)
            nodes.col(a) = x.segment<3>(3 * mesh.tets(t, a));
        const auto& p = mesh.rest_positions;
        const TetRest rest = make_tet_rest(p.row(mesh.tets(t, 0)), p.row(mesh.tets(t, 1)), p.row(mesh.tets(t, 2)),
                                           p.row(mesh.tets(t, 3)));
        const Mat3 f = nodes * shape_gradients(rest).transpose();
        inverted += f.determinant() < 0.0 ? 1 : 0;
        const Mat3& r = fem.rotations()[static_cast<std::size_t>(t)];
        EXPECT_NEAR_REL(r, polar_rotation(f, Mat3::Identity()), 1e-10, 0.0) << "tet " << t;
        EXPECT_NEAR(r.determinant(), 1.0, 1e-12) << "tet " << t;
    }
    EXPECT_GT(inverted, 5); // the SVD lanes were exercised
    EXPECT_LT(inverted, mesh.num_tets() / 2);
}

TEST(CorotationalFem, NonFiniteNodeNamesTheFirstTetHoldingIt)
{
    const TetMesh mesh = test::irregular_box(3, 0.3, 12);
    VecX x = deformed(mesh, Mat3::Identity(), Vec3::Zero(), 0.01, 7);
    const Index node = mesh.tets(mesh.num_tets() - 3, 2);
    Index first = 0;
    while ((mesh.tets.row(first).array() != node).all())
        ++first;
    x[3 * node + 1] = std::numeric_limits<double>::quiet_NaN();
    CorotationalFem fem(mesh, test_material());
    try {
        fem.update_rotations(x);
        FAIL() << "no NumericalError";
    } catch (const NumericalError& e) {
        EXPECT_NE(std::string(e.what()).find("tet " + std::to_string(first) + ":"), std::string::npos) << e.what();
    }
}

// The fused pass (rotate a chunk, assemble it) must give exactly what the two passes give.
TEST(CorotationalFem, FusedRotationAndAssemblyEqualsTwoPasses)
{
    const TetMesh mesh = test::irregular_box(4, 0.3, 13); // 384 tets: 12 chunks of 32
    const VecX x = deformed(mesh, rotation(40, Vec3(1, 0, 1)), Vec3(0, 0, 1), 0.1, 8);
    std::vector<char> fixed(static_cast<std::size_t>(mesh.num_vertices()), 0);
    fixed[3] = 1;

    CorotationalFem two_passes(mesh, test_material());
    two_passes.update_rotations(x);
    BsrMatrix a = two_passes.make_matrix();
    VecX fa(x.size());
    two_passes.assemble_with_forces(x, 0.3, 1.7, fixed, a, fa);

    CorotationalFem fused(mesh, test_material());
    BsrMatrix b = fused.make_matrix();
    VecX fb(x.size());
    fused.rotate_and_assemble_with_forces(x, 0.3, 1.7, fixed, b, fb);
    EXPECT_EQ(fused.rotations(), two_passes.rotations());
    EXPECT_EQ(b.values(), a.values());
    EXPECT_TRUE(fb == fa);
}
