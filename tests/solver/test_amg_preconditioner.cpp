// The AMG preconditioner in Eigen's conjugate gradients (as a preconditioner class), against
// Eigen's Jacobi-preconditioned CG and a sparse Cholesky solve of the same elasticity system.
#include "near.hpp"

#include <corocontact/core/primitives.hpp>
#include <corocontact/core/tet_mesh.hpp>
#include <corocontact/fem/corotational_fem.hpp>
#include <corocontact/solver/amg_preconditioner.hpp>

#include <Eigen/Geometry>
#include <Eigen/IterativeLinearSolvers>
#include <Eigen/SparseCholesky>
#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <random>
#include <vector>

using namespace coro;

namespace {

/// Eigen's preconditioner concept around an AmgPreconditioner set up by the caller.
class AmgForEigen {
public:
    AmgForEigen() = default;
    void attach(AmgPreconditioner& amg) { m_amg = &amg; }
    template <class M> AmgForEigen& analyzePattern(const M&) { return *this; }
    template <class M> AmgForEigen& factorize(const M&) { return *this; }
    template <class M> AmgForEigen& compute(const M&) { return *this; }
    template <class Rhs> VecX solve(const Rhs& b) const
    {
        VecX r = b, z(b.size());
        m_amg->apply(r, z);
        return z;
    }
    Eigen::ComputationInfo info() const { return Eigen::Success; }

private:
    AmgPreconditioner* m_amg = nullptr;
};

/// A clamped block of 16×4×4 cells (1,700 nodes) and its stiffness K' + (1/h²) M at a
/// rotated, stretched state, like an implicit Euler system with a large step: fixed nodes
/// projected to identity rows.
struct Elasticity {
    TetMesh mesh;
    CorotationalFem fem;
    std::vector<char> fixed;
    BsrMatrix a;
    VecX positions;
    VecX b;

    explicit Elasticity(double rotation_degrees = 30.0)
        : mesh(make_box(Vec3::Zero(), Vec3(8.0, 2.0, 2.0), {16, 4, 4})), fem(mesh, material())
    {
        fixed.assign(static_cast<std::size_t>(mesh.num_vertices()), 0);
        for (Index v = 0; v < mesh.num_vertices(); ++v)
            fixed[static_cast<std::size_t>(v)] = mesh.rest_positions(v, 0) < 1e-9 ? 1 : 0;
        const Mat3 r = Eigen::AngleAxisd(rotation_degrees * M_PI / 180.0, Vec3(0.3, 1.0, 0.2).normalized())
                           .toRotationMatrix();
        positions.resize(3 * mesh.num_vertices());
        for (Index v = 0; v < mesh.num_vertices(); ++v) {
            const Vec3 p = mesh.rest_positions.row(v).transpose();
            positions.segment<3>(3 * v) = r * Vec3(1.02 * p.x(), p.y(), p.z());
        }
        fem.update_rotations(positions);
        a = fem.make_matrix();
        fem.assemble(1.0, 1e3, fixed, a); // K' + M/h² with h = 0.03 s and ρ = 1
        std::mt19937 rng(3);
        std::uniform_real_distribution<double> u(-1.0, 1.0);
        b.resize(positions.size());
        for (Eigen::Index i = 0; i < b.size(); ++i)
            b[i] = fixed[static_cast<std::size_t>(i / 3)] ? 0.0 : u(rng);
    }

    static Material material()
    {
        Material m;
        m.young = 1e6;
        m.poisson = 0.3;
        m.density = 1.0;
        return m;
    }
};

struct CgOutcome {
    VecX x;
    Index iterations;
};

CgOutcome cg_with_amg(const SparseMat& a, const VecX& b, AmgPreconditioner& amg, double tolerance)
{
    Eigen::ConjugateGradient<SparseMat, Eigen::Lower | Eigen::Upper, AmgForEigen> cg;
    cg.setTolerance(tolerance);
    cg.setMaxIterations(10000);
    cg.compute(a);
    cg.preconditioner().attach(amg);
    VecX x = cg.solve(b);
    EXPECT_EQ(cg.info(), Eigen::Success);
    return {x, static_cast<Index>(cg.iterations())};
}

CgOutcome cg_with_jacobi(const SparseMat& a, const VecX& b, double tolerance)
{
    Eigen::ConjugateGradient<SparseMat, Eigen::Lower | Eigen::Upper, Eigen::DiagonalPreconditioner<double>> cg;
    cg.setTolerance(tolerance);
    cg.setMaxIterations(10000);
    cg.compute(a);
    VecX x = cg.solve(b);
    EXPECT_EQ(cg.info(), Eigen::Success);
    return {x, static_cast<Index>(cg.iterations())};
}

} // namespace

TEST(AmgPreconditioner, ConvergesInFarFewerIterationsThanJacobiToTheDirectSolution)
{
    const Elasticity problem;
    const SparseMat a = problem.a.to_sparse();
    AmgPreconditioner amg;
    amg.setup(problem.a, problem.positions);
    const double tolerance = 1e-10;
    const CgOutcome with_amg = cg_with_amg(a, problem.b, amg, tolerance);
    const CgOutcome with_jacobi = cg_with_jacobi(a, problem.b, tolerance);
    const VecX direct = Eigen::SimplicialLDLT<SparseMat>(a).solve(problem.b);
    std::printf("CG to %.0e: AMG %d iterations (setup %.3f s, %d V-cycles %.3f s), Jacobi %d iterations\n", tolerance,
                static_cast<int>(with_amg.iterations), amg.times().setup_s, static_cast<int>(amg.times().applies),
                amg.times().apply_s, static_cast<int>(with_jacobi.iterations));
    EXPECT_LT(5 * with_amg.iterations, with_jacobi.iterations);
    EXPECT_NEAR_REL(with_amg.x, direct, 1e-7 * direct.cwiseAbs().maxCoeff(), 0.0);
    EXPECT_EQ(amg.times().setups, 1);
    EXPECT_EQ(amg.times().applies, with_amg.iterations + 1);
}

TEST(AmgPreconditioner, IsSymmetricAndPositiveDefinite)
{
    // PCG needs M⁻¹ symmetric positive definite: uᵀ M⁻¹ v = vᵀ M⁻¹ u and uᵀ M⁻¹ u > 0.
    const Elasticity problem;
    AmgPreconditioner amg;
    amg.setup(problem.a, problem.positions);
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> d(-1.0, 1.0);
    VecX u(problem.b.size()), v(problem.b.size()), mu(u.size()), mv(u.size());
    for (Eigen::Index i = 0; i < u.size(); ++i) {
        u[i] = d(rng);
        v[i] = d(rng);
    }
    amg.apply(u, mu);
    amg.apply(v, mv);
    EXPECT_NEAR(u.dot(mv), v.dot(mu), 1e-10 * std::abs(u.dot(mv)));
    EXPECT_GT(u.dot(mu), 0.0);
}

TEST(AmgPreconditioner, ReusedHierarchyStillConvergesAndNewPatternStartsAfresh)
{
    // The hierarchy of one state preconditions the matrix of a later, more rotated state;
    // then a setup with another pattern (a different mesh) rebuilds everything.
    const Elasticity before(30.0), after(40.0);
    AmgPreconditioner amg;
    amg.setup(before.a, before.positions);
    const CgOutcome stale = cg_with_amg(after.a.to_sparse(), after.b, amg, 1e-8);
    const VecX direct = Eigen::SimplicialLDLT<SparseMat>(after.a.to_sparse()).solve(after.b);
    EXPECT_NEAR_REL(stale.x, direct, 1e-5 * direct.cwiseAbs().maxCoeff(), 0.0);

    amg.setup(after.a, after.positions); // same pattern: values refilled
    const CgOutcome rebuilt = cg_with_amg(after.a.to_sparse(), after.b, amg, 1e-8);
    EXPECT_LE(rebuilt.iterations, stale.iterations);

    const TetMesh small = make_box(Vec3::Zero(), Vec3(1.0, 1.0, 1.0), {3, 3, 3});
    CorotationalFem fem(small, Elasticity::material());
    BsrMatrix k = fem.make_matrix();
    fem.assemble(1.0, 1e3, {}, k);
    amg.setup(k, fem.rest_dofs());
    const VecX b = VecX::Ones(k.num_dofs());
    const CgOutcome other = cg_with_amg(k.to_sparse(), b, amg, 1e-10);
    const VecX other_direct = Eigen::SimplicialLDLT<SparseMat>(k.to_sparse()).solve(b);
    EXPECT_NEAR_REL(other.x, other_direct, 1e-7 * other_direct.cwiseAbs().maxCoeff(), 0.0);
    EXPECT_EQ(amg.times().setups, 3);
}

TEST(AmgPreconditioner, SameBitsForEveryThreadCountAndEverySetup)
{
    const Elasticity problem;
    std::vector<VecX> outputs;
    for (const int threads : {1, 2}) {
        tbb::task_arena arena(threads);
        arena.execute([&] {
            AmgPreconditioner amg;
            amg.setup(problem.a, problem.positions);
            VecX z(problem.b.size());
            amg.apply(problem.b, z);
            outputs.push_back(z);
        });
    }
    ASSERT_EQ(outputs.size(), 2u);
    EXPECT_TRUE(outputs[0] == outputs[1]);
}

TEST(AmgPreconditioner, RejectsMismatchedSizesAndApplyBeforeSetup)
{
    const Elasticity problem;
    AmgPreconditioner amg;
    VecX z(problem.b.size());
    EXPECT_THROW(amg.apply(problem.b, z), std::logic_error);
    EXPECT_THROW(amg.setup(problem.a, VecX::Zero(6)), std::invalid_argument);
    amg.setup(problem.a, problem.positions);
    VecX short_z(3);
    EXPECT_THROW(amg.apply(problem.b, short_z), std::invalid_argument);
}

TEST(HierarchyReuse, RebuildsWhenIterationsGrowPastTheFactor)
{
    HierarchyReuse reuse(1.5);
    EXPECT_TRUE(reuse.setup_due());
    reuse.record_setup();
    EXPECT_FALSE(reuse.setup_due());
    reuse.record_solve(10); // baseline
    reuse.record_solve(15); // 1.5×: still fine
    EXPECT_FALSE(reuse.setup_due());
    reuse.record_solve(16);
    EXPECT_TRUE(reuse.setup_due());
    reuse.record_setup();
    EXPECT_FALSE(reuse.setup_due());
    reuse.record_solve(20); // a new baseline
    reuse.record_solve(29);
    EXPECT_FALSE(reuse.setup_due());
}
