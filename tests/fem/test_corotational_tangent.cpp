#include "mesh_fixtures.hpp"
#include "near.hpp"

#include <corocontact/fem/corotational_fem.hpp>
#include <corocontact/fem/corotational_tangent.hpp>
#include <corocontact/partition/part_layout.hpp>
#include <corocontact/partition/partition.hpp>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <random>

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

// x = R (X + A X + noise) + t: a rotated state with strains of about `strain`, in tension and
// compression both.
VecX deformed(const TetMesh& mesh, const Mat3& r, const Vec3& t, const Mat3& a, double noise, unsigned seed)
{
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(-noise, noise);
    VecX x(3 * mesh.num_vertices());
    for (Index v = 0; v < mesh.num_vertices(); ++v) {
        const Vec3 p = mesh.rest_positions.row(v).transpose();
        x.segment<3>(3 * v) = r * (p + a * p + Vec3(u(rng), u(rng), u(rng))) + t;
    }
    return x;
}

Mat3 random_strain(double strain, unsigned seed)
{
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(-strain, strain);
    Mat3 a;
    for (int i = 0; i < 9; ++i)
        a(i) = u(rng);
    return a;
}

VecX forces(CorotationalFem& fem, const VecX& x)
{
    fem.update_rotations(x);
    VecX f(x.size());
    fem.internal_forces(x, f);
    return f;
}

// −∂f/∂x by central differences, rotations re-evaluated at every perturbed state.
Eigen::MatrixXd fd_jacobian(CorotationalFem& fem, const VecX& x)
{
    const double h = 1e-6;
    Eigen::MatrixXd fd(x.size(), x.size());
    for (Eigen::Index i = 0; i < x.size(); ++i) {
        VecX xp = x, xm = x;
        xp[i] += h;
        xm[i] -= h;
        fd.col(i) = -(forces(fem, xp) - forces(fem, xm)) / (2 * h);
    }
    fem.update_rotations(x);
    return fd;
}

Eigen::MatrixXd tangent(CorotationalFem& fem, const VecX& x, TangentDefiniteness kind,
                        const std::vector<char>& fixed = {})
{
    fem.update_rotations(x);
    CorotationalTangent assembler(fem);
    BsrMatrix k = fem.make_matrix();
    assembler.assemble(fem, x, fixed, kind, k);
    return Eigen::MatrixXd(k.to_sparse());
}

double smallest_eigenvalue(const Eigen::MatrixXd& a)
{
    return Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(a).eigenvalues().minCoeff();
}

} // namespace

TEST(CorotationalTangent, ExactTangentEqualsFiniteDifferencesOfTheForce)
{
    // Large rotation, strains of up to 15 % in tension and compression: the finite-difference
    // Jacobian is matched entry by entry, and so is its symmetry (the full matrix is compared,
    // while only the upper blocks are stored).
    const TetMesh mesh = test::irregular_box(2, 0.3, 11);
    CorotationalFem fem(mesh, test_material());
    for (const unsigned seed : {1u, 2u, 3u}) {
        const VecX x = deformed(mesh, rotation(40.0 * seed, Vec3(1, 2, -1)), Vec3(1, -2, 0.5),
                                random_strain(0.15, seed), 0.03, seed);
        const Eigen::MatrixXd exact = tangent(fem, x, TangentDefiniteness::EXACT);
        const Eigen::MatrixXd fd = fd_jacobian(fem, x);
        EXPECT_NEAR_REL(exact, fd, 1e-6 * exact.cwiseAbs().maxCoeff(), 0.0) << "seed " << seed;
    }
}

TEST(CorotationalTangent, DiffersFromTheFrozenRotationStiffnessUnderStrain)
{
    // The premise of Newton: K' alone misses terms of the order of the stress.
    const TetMesh mesh = test::irregular_box(2, 0.3, 12);
    CorotationalFem fem(mesh, test_material());
    const VecX x = deformed(mesh, rotation(60, Vec3(0, 1, 1)), Vec3::Zero(), random_strain(0.1, 4), 0.02, 4);
    const Eigen::MatrixXd exact = tangent(fem, x, TangentDefiniteness::EXACT);
    BsrMatrix k = fem.make_matrix();
    fem.assemble(1.0, 0.0, {}, k);
    const Eigen::MatrixXd frozen = Eigen::MatrixXd(k.to_sparse());
    const Eigen::MatrixXd fd = fd_jacobian(fem, x);
    EXPECT_GT((frozen - fd).norm(), 100.0 * (exact - fd).norm());
}

TEST(CorotationalTangent, ProjectedEqualsExactInUniformTension)
{
    // Every element stretched (S − I positive definite): all m_k > 0, nothing to clamp.
    const TetMesh mesh = test::irregular_box(2, 0.2, 13);
    CorotationalFem fem(mesh, test_material());
    Mat3 stretch = Mat3::Zero();
    stretch.diagonal() << 0.10, 0.05, 0.08;
    const VecX x = deformed(mesh, rotation(75, Vec3(1, 0, 0)), Vec3(0, 1, 0), stretch, 0.0, 5);
    const Eigen::MatrixXd exact = tangent(fem, x, TangentDefiniteness::EXACT);
    const Eigen::MatrixXd projected = tangent(fem, x, TangentDefiniteness::PROJECTED);
    EXPECT_NEAR_REL(projected, exact, 1e-12 * exact.cwiseAbs().maxCoeff(), 0.0);
}

TEST(CorotationalTangent, ProjectedIsPositiveDefiniteWhereExactIsNot)
{
    // Strong uniform compression makes the geometric term negative enough for the exact
    // Hessian of the clamped body to lose definiteness; the projected one stays above K'.
    const TetMesh mesh = test::irregular_box(2, 0.2, 14);
    CorotationalFem fem(mesh, test_material());
    std::vector<char> fixed(static_cast<std::size_t>(mesh.num_vertices()), 0);
    for (Index v = 0; v < mesh.num_vertices(); ++v)
        fixed[static_cast<std::size_t>(v)] = mesh.rest_positions(v, 0) < 1e-9 ? 1 : 0;
    Mat3 squeeze = Mat3::Zero();
    squeeze.diagonal() << -0.45, 0.0, 0.0;
    const VecX x = deformed(mesh, Mat3::Identity(), Vec3::Zero(), squeeze, 0.0, 6);
    const Eigen::MatrixXd exact = tangent(fem, x, TangentDefiniteness::EXACT, fixed);
    const Eigen::MatrixXd projected = tangent(fem, x, TangentDefiniteness::PROJECTED, fixed);
    fem.update_rotations(x);
    BsrMatrix k = fem.make_matrix();
    fem.assemble(1.0, 0.0, fixed, k);
    const Eigen::MatrixXd frozen = Eigen::MatrixXd(k.to_sparse());
    EXPECT_LT(smallest_eigenvalue(exact), 0.0);
    EXPECT_GT(smallest_eigenvalue(projected), 0.0);
    EXPECT_GT(smallest_eigenvalue(projected - frozen), -1e-9 * frozen.norm());
}

TEST(CorotationalTangent, FixedNodesAreProjectedOut)
{
    const TetMesh mesh = test::irregular_box(2, 0.3, 15);
    CorotationalFem fem(mesh, test_material());
    std::vector<char> fixed(static_cast<std::size_t>(mesh.num_vertices()), 0);
    fixed[0] = fixed[5] = 1;
    const VecX x = deformed(mesh, rotation(30, Vec3(0, 0, 1)), Vec3::Zero(), random_strain(0.1, 7), 0.02, 7);
    const Eigen::MatrixXd free = tangent(fem, x, TangentDefiniteness::EXACT);
    const Eigen::MatrixXd held = tangent(fem, x, TangentDefiniteness::EXACT, fixed);
    for (Index v = 0; v < mesh.num_vertices(); ++v)
        for (Index w = 0; w < mesh.num_vertices(); ++w) {
            const bool touched = fixed[static_cast<std::size_t>(v)] || fixed[static_cast<std::size_t>(w)];
            const Mat3 expected = !touched ? Mat3(free.block<3, 3>(3 * v, 3 * w))
                                  : v == w ? Mat3(Mat3::Identity())
                                           : Mat3(Mat3::Zero());
            ASSERT_NEAR_REL(Mat3(held.block<3, 3>(3 * v, 3 * w)), expected, 1e-12 * free.norm(), 0.0)
                << "block (" << v << ", " << w << ")";
        }
}

TEST(CorotationalTangent, SameBitsForOneAndTwoThreadsOverParts)
{
    const TetMesh mesh = test::irregular_box(4, 0.3, 16);
    const TetPartition parts = partition_tets(mesh.tets, mesh.num_vertices(), 4);
    const PartLayout layout = make_part_layout(mesh.tets, mesh.num_vertices(), parts);
    const TetMesh reordered = reorder_mesh(mesh, layout);
    CorotationalFem fem(reordered, test_material(), layout);
    const VecX x = deformed(reordered, rotation(50, Vec3(1, 1, 1)), Vec3::Zero(), random_strain(0.1, 8), 0.02, 8);
    fem.update_rotations(x);
    CorotationalTangent assembler(fem);
    std::vector<std::vector<double>> values;
    for (const int threads : {1, 2}) {
        tbb::task_arena arena(threads);
        BsrMatrix k = fem.make_matrix();
        arena.execute([&] { assembler.assemble(fem, x, {}, TangentDefiniteness::PROJECTED, k); });
        values.push_back(k.values());
    }
    EXPECT_EQ(values[0], values[1]);
}

TEST(CorotationalTangent, InvertedElementGivesAFiniteSymmetricTangent)
{
    // Node 3 pushed through the opposite face: det F < 0, R is the sign-fixed rotation and
    // tr S · I − S may be singular; the tangent stays finite and the projected one semi-definite.
    const TetMesh mesh = test::unit_tet();
    CorotationalFem fem(mesh, test_material());
    VecX x = fem.rest_dofs();
    x.segment<3>(9) = Vec3(0.2, 0.2, -0.5);
    for (const TangentDefiniteness kind : {TangentDefiniteness::EXACT, TangentDefiniteness::PROJECTED}) {
        const Eigen::MatrixXd k = tangent(fem, x, kind);
        ASSERT_TRUE(k.allFinite());
        EXPECT_NEAR_REL(k, Eigen::MatrixXd(k.transpose()), 1e-12 * k.norm(), 0.0);
        if (kind == TangentDefiniteness::PROJECTED) {
            EXPECT_GT(smallest_eigenvalue(k), -1e-9 * k.norm());
        }
    }
}
