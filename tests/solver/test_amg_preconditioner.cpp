// The AMG preconditioner in our scene PCG, against Jacobi-PCG and a sparse Cholesky solve of the
// same elasticity systems: one body, and two bodies tied by contact coupling terms.
#include "near.hpp"

#include <corocontact/core/primitives.hpp>
#include <corocontact/core/tet_mesh.hpp>
#include <corocontact/fem/corotational_fem.hpp>
#include <corocontact/solver/amg_preconditioner.hpp>
#include <corocontact/solver/pcg.hpp>
#include <corocontact/solver/scene_matrix.hpp>

#include <Eigen/Geometry>
#include <Eigen/SparseCholesky>
#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <cmath>
#include <random>
#include <stdexcept>
#include <vector>

using namespace coro;

namespace {

/// A block of 16×4×4 cells (425 nodes) clamped at x = 0 (unless `clamped` is false), and its
/// K' + (1/h²) M at a rotated, stretched state, like an implicit Euler system with a large step:
/// fixed nodes projected to identity rows.
struct Elasticity {
    TetMesh mesh;
    CorotationalFem fem;
    std::vector<char> fixed;
    BsrMatrix a;
    VecX positions;
    VecX b;

    explicit Elasticity(double rotation_degrees = 30.0, Vec3 shift = Vec3::Zero(), bool clamped = true)
        : mesh(make_box(Vec3::Zero(), Vec3(8.0, 2.0, 2.0), {16, 4, 4})), fem(mesh, material())
    {
        fixed.assign(static_cast<std::size_t>(mesh.num_vertices()), 0);
        for (Index v = 0; v < mesh.num_vertices(); ++v)
            fixed[static_cast<std::size_t>(v)] = clamped && mesh.rest_positions(v, 0) < 1e-9 ? 1 : 0;
        positions.resize(3 * mesh.num_vertices());
        set_state(rotation_degrees);
        for (Index v = 0; v < mesh.num_vertices(); ++v)
            positions.segment<3>(3 * v) += shift;
        std::mt19937 rng(3);
        std::uniform_real_distribution<double> u(-1.0, 1.0);
        b.resize(positions.size());
        for (Eigen::Index i = 0; i < b.size(); ++i)
            b[i] = fixed[static_cast<std::size_t>(i / 3)] ? 0.0 : u(rng);
    }

    /// Rotates and stretches the block and assembles its matrix at that state.
    void set_state(double rotation_degrees)
    {
        const Mat3 r = Eigen::AngleAxisd(rotation_degrees * M_PI / 180.0, Vec3(0.3, 1.0, 0.2).normalized())
                           .toRotationMatrix();
        for (Index v = 0; v < mesh.num_vertices(); ++v) {
            const Vec3 p = mesh.rest_positions.row(v).transpose();
            positions.segment<3>(3 * v) = r * Vec3(1.02 * p.x(), p.y(), p.z());
        }
        fem.update_rotations(positions);
        if (a.num_block_rows() == 0)
            a = fem.make_matrix();
        fem.assemble(1.0, 1e3, fixed, a); // K' + M/h² with h = 0.03 s and ρ = 1
    }

    SceneMatrix scene() const
    {
        SceneMatrix s({&a});
        s.set_node_positions({&positions});
        return s;
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

/// Two blocks end to end: the clamped one, and a free one whose x = 0 face is tied by penalty
/// coupling terms k(u_i − u_j) to the first one's x = 8 face, so the pair acts as one beam.
struct TiedPair {
    Elasticity left{30.0};
    Elasticity right{30.0, Vec3::Zero(), false};
    SceneMatrix scene{{&left.a, &right.a}};
    VecX b;

    TiedPair()
    {
        scene.set_node_positions({&left.positions, &right.positions});
        scene.set_components({0, 0}); // tied: one component
        std::vector<std::pair<Index, Index>> ties;
        for (Index i = 0; i < left.mesh.num_vertices(); ++i) {
            if (std::abs(left.mesh.rest_positions(i, 0) - 8.0) > 1e-9)
                continue;
            for (Index j = 0; j < right.mesh.num_vertices(); ++j)
                if (right.mesh.rest_positions(j, 0) < 1e-9 &&
                    (left.mesh.rest_positions.row(i).tail<2>() - right.mesh.rest_positions.row(j).tail<2>()).norm() < 1e-9)
                    ties.emplace_back(i, scene.offset(1) + j);
        }
        // A stiff spring between each tied pair: shares i (+1) and j (−1) of K = 10⁵ I.
        ContactCoupling& coupling = scene.coupling();
        std::vector<Index> share_offsets{0};
        for (std::size_t t = 0; t < ties.size(); ++t)
            share_offsets.push_back(share_offsets.back() + 2);
        coupling.reset(share_offsets);
        for (std::size_t t = 0; t < ties.size(); ++t) {
            const auto [i, j] = ties[t];
            const auto term = static_cast<Index>(t);
            coupling.stiffness(term) = 1e5 * Mat3::Identity();
            coupling.share(term, 0) = {i, i, 1.0};
            coupling.share(term, 1) = {j, j, -1.0};
        }
        coupling.finish();
        b.resize(scene.num_dofs());
        b << left.b, right.b;
    }
};

/// The whole scene matrix, every entry, as an Eigen matrix.
SparseMat assembled(const SceneMatrix& scene)
{
    std::vector<Eigen::Triplet<double, Index>> triplets;
    for (Index body = 0; body < scene.num_bodies(); ++body) {
        const SparseMat m = scene.body_matrix(body).to_sparse();
        for (Index k = 0; k < m.outerSize(); ++k)
            for (SparseMat::InnerIterator it(m, k); it; ++it)
                triplets.emplace_back(3 * scene.offset(body) + it.row(), 3 * scene.offset(body) + it.col(), it.value());
    }
    CouplingBlocks coupling;
    scene.coupling().blocks(scene.num_block_rows(), coupling);
    for (Index k = 0; k < coupling.size(); ++k)
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j)
                triplets.emplace_back(3 * coupling.block(k).row + i, 3 * coupling.block(k).column + j,
                                      coupling.block(k).value(i, j));
    SparseMat whole(scene.num_dofs(), scene.num_dofs());
    whole.setFromTriplets(triplets.begin(), triplets.end());
    return whole;
}

/// The same matrix as one body in upper storage (blocks with a non-zero entry, and the diagonal).
BsrMatrix as_one_body(const SparseMat& whole)
{
    const Index n = static_cast<Index>(whole.rows() / 3);
    std::vector<std::vector<Index>> rows(static_cast<std::size_t>(n));
    for (Index r = 0; r < n; ++r)
        rows[static_cast<std::size_t>(r)].push_back(r);
    for (Index k = 0; k < whole.outerSize(); ++k)
        for (SparseMat::InnerIterator it(whole, k); it; ++it)
            if (it.col() / 3 > it.row() / 3)
                rows[static_cast<std::size_t>(it.row() / 3)].push_back(static_cast<Index>(it.col() / 3));
    std::vector<Index> offsets{0}, columns;
    for (auto& row : rows) {
        std::sort(row.begin(), row.end());
        row.erase(std::unique(row.begin(), row.end()), row.end());
        columns.insert(columns.end(), row.begin(), row.end());
        offsets.push_back(static_cast<Index>(columns.size()));
    }
    BsrMatrix a = BsrMatrix::symmetric_upper(offsets, columns);
    for (Index r = 0; r < n; ++r)
        for (Index k = offsets[static_cast<std::size_t>(r)]; k < offsets[static_cast<std::size_t>(r) + 1]; ++k) {
            Block3 block;
            for (int i = 0; i < 3; ++i)
                for (int j = 0; j < 3; ++j)
                    block(i, j) = whole.coeff(3 * r + i, 3 * columns[static_cast<std::size_t>(k)] + j);
            a.set_block(k, block);
        }
    return a;
}

PcgSettings converged(PcgPreconditioner kind, double tolerance)
{
    PcgSettings settings;
    settings.max_iterations = 10000;
    settings.tolerance = tolerance;
    settings.preconditioner = kind;
    return settings;
}

} // namespace

TEST(AmgPreconditioner, ConvergesInFarFewerIterationsThanJacobiToTheDirectSolution)
{
    const Elasticity problem;
    const SceneMatrix scene = problem.scene();
    const double tolerance = 1e-10;
    PcgSolver amg, jacobi;
    VecX x_amg = VecX::Zero(problem.b.size()), x_jacobi = x_amg;
    const PcgResult with_amg = amg.solve(scene, problem.b, x_amg, converged(PcgPreconditioner::AMG, tolerance));
    const PcgResult with_jacobi =
        jacobi.solve(scene, problem.b, x_jacobi, converged(PcgPreconditioner::JACOBI, tolerance));
    const VecX direct = Eigen::SimplicialLDLT<SparseMat>(problem.a.to_sparse()).solve(problem.b);
    const PreconditionerTimes times = amg.preconditioner_times();
    std::printf("PCG to %.0e: AMG %d iterations (set-up %.3f s, %d V-cycles %.3f s), Jacobi %d iterations\n", tolerance,
                static_cast<int>(with_amg.iterations), times.setup_s, static_cast<int>(times.applies), times.apply_s,
                static_cast<int>(with_jacobi.iterations));
    EXPECT_TRUE(with_amg.converged);
    EXPECT_LT(5 * with_amg.iterations, with_jacobi.iterations);
    EXPECT_NEAR_REL(x_amg, direct, 1e-7 * direct.cwiseAbs().maxCoeff(), 0.0);
    EXPECT_EQ(times.setups, 1);
    EXPECT_EQ(times.applies, with_amg.iterations + 1);
}

TEST(AmgPreconditioner, IsSymmetricAndPositiveDefinite)
{
    // PCG needs M⁻¹ symmetric positive definite: uᵀ M⁻¹ v = vᵀ M⁻¹ u and uᵀ M⁻¹ u > 0, with the
    // finest level on the scene matrix and on PETSc's copy.
    const TiedPair pair;
    for (const bool scene_fine_level : {true, false}) {
        AmgSettings settings;
        settings.scene_fine_level = scene_fine_level;
        AmgPreconditioner amg(settings);
        amg.prepare(pair.scene);
        std::mt19937 rng(5);
        std::uniform_real_distribution<double> d(-1.0, 1.0);
        VecX u(pair.b.size()), v(pair.b.size()), mu(u.size()), mv(u.size());
        for (Eigen::Index i = 0; i < u.size(); ++i) {
            u[i] = d(rng);
            v[i] = d(rng);
        }
        amg.apply(u.data(), mu.data());
        amg.apply(v.data(), mv.data());
        EXPECT_NEAR(u.dot(mv), v.dot(mu), 1e-10 * std::abs(u.dot(mv)));
        EXPECT_GT(u.dot(mu), 0.0);
    }
}

TEST(AmgPreconditioner, BuildsItsHierarchyFromTheBodiesAndTheCouplingBlocks)
{
    // Two tied bodies give the same V-cycle, bit for bit, as one body holding the same matrix:
    // PETSc's copy holds the coupling blocks too (the finest level on that copy here, so that
    // the whole cycle is PETSc's).
    const TiedPair pair;
    const SparseMat whole = assembled(pair.scene);
    const BsrMatrix merged = as_one_body(whole);
    VecX positions(pair.scene.num_dofs());
    positions << pair.left.positions, pair.right.positions;
    SceneMatrix one({&merged});
    one.set_node_positions({&positions});

    AmgSettings settings;
    settings.scene_fine_level = false;
    AmgPreconditioner from_scene(settings), from_one(settings);
    from_scene.prepare(pair.scene);
    from_one.prepare(one);
    VecX z_scene(pair.b.size()), z_one(pair.b.size());
    from_scene.apply(pair.b.data(), z_scene.data());
    from_one.apply(pair.b.data(), z_one.data());
    EXPECT_TRUE(z_scene == z_one);

    // And the scene PCG with it converges to the direct solution of the whole tied system.
    PcgSolver pcg;
    VecX x = VecX::Zero(pair.b.size());
    const PcgResult result = pcg.solve(pair.scene, pair.b, x, converged(PcgPreconditioner::AMG, 1e-10));
    const VecX direct = Eigen::SimplicialLDLT<SparseMat>(whole).solve(pair.b);
    EXPECT_TRUE(result.converged);
    EXPECT_LT(result.iterations, 40);
    EXPECT_NEAR_REL(x, direct, 1e-7 * direct.cwiseAbs().maxCoeff(), 0.0);
}

TEST(AmgPreconditioner, FinestLevelFollowsTheCurrentMatrixBetweenSetups)
{
    // Without a new set-up, a V-cycle on the scene's finest level sees changed matrix values;
    // one on PETSc's copy does not.
    for (const bool scene_fine_level : {true, false}) {
        Elasticity problem(30.0);
        const SceneMatrix scene = problem.scene();
        AmgSettings settings;
        settings.scene_fine_level = scene_fine_level;
        AmgPreconditioner amg(settings);
        amg.prepare(scene);
        VecX before(problem.b.size()), after(problem.b.size());
        amg.apply(problem.b.data(), before.data());
        problem.set_state(45.0);
        amg.prepare(scene); // no set-up due: the hierarchy is kept
        amg.apply(problem.b.data(), after.data());
        EXPECT_EQ(amg.times().setups, 1);
        EXPECT_EQ(scene_fine_level, !(before == after)) << "scene_fine_level " << scene_fine_level;
    }
}

TEST(AmgPreconditioner, ReusesItsHierarchyUntilAskedAndThenRebuilds)
{
    // The hierarchy of one state preconditions the matrix of a later, more rotated state; the
    // solves still converge to the direct solution, and a requested set-up rebuilds it.
    Elasticity problem(30.0);
    const SceneMatrix scene = problem.scene();
    PcgSolver pcg;
    const PcgSettings settings = converged(PcgPreconditioner::AMG, 1e-8);
    VecX x = VecX::Zero(problem.b.size());
    pcg.solve(scene, problem.b, x, settings);
    problem.set_state(40.0);
    x.setZero();
    const PcgResult stale = pcg.solve(scene, problem.b, x, settings);
    const VecX direct = Eigen::SimplicialLDLT<SparseMat>(problem.a.to_sparse()).solve(problem.b);
    EXPECT_TRUE(stale.converged);
    EXPECT_NEAR_REL(x, direct, 1e-5 * direct.cwiseAbs().maxCoeff(), 0.0);
    EXPECT_EQ(pcg.preconditioner_times().setups, 1);

    AmgPreconditioner amg;
    amg.prepare(scene);
    amg.request_setup();
    amg.prepare(scene);
    EXPECT_EQ(amg.times().setups, 2);
}

TEST(AmgPreconditioner, PcgRebuildsTheHierarchyWhenItsSolvesSlowDown)
{
    // A hierarchy built for a mass-dominated matrix preconditions a stiffness-dominated one
    // badly: that solve still converges, takes many more iterations per decade, and the next
    // solve starts with a new set-up, after which the iterations drop again.
    Elasticity problem(30.0);
    const SceneMatrix scene = problem.scene();
    problem.fem.assemble(1e-4, 1e3, problem.fixed, problem.a);
    PcgSolver pcg;
    const PcgSettings settings = converged(PcgPreconditioner::AMG, 1e-8);
    VecX x = VecX::Zero(problem.b.size());
    const PcgResult first = pcg.solve(scene, problem.b, x, settings);
    problem.fem.assemble(1.0, 1e3, problem.fixed, problem.a);
    x.setZero();
    const PcgResult stale = pcg.solve(scene, problem.b, x, settings);
    EXPECT_EQ(pcg.preconditioner_times().setups, 1);
    x.setZero();
    const PcgResult rebuilt = pcg.solve(scene, problem.b, x, settings);
    std::printf("AMG iterations: %d on its own matrix, %d with that hierarchy on a stiffer one, %d after the "
                "rebuild\n",
                static_cast<int>(first.iterations), static_cast<int>(stale.iterations),
                static_cast<int>(rebuilt.iterations));
    EXPECT_TRUE(stale.converged);
    EXPECT_TRUE(rebuilt.converged);
    EXPECT_EQ(pcg.preconditioner_times().setups, 2);
    EXPECT_GT(stale.iterations, 2 * rebuilt.iterations);
    const VecX direct = Eigen::SimplicialLDLT<SparseMat>(problem.a.to_sparse()).solve(problem.b);
    EXPECT_NEAR_REL(x, direct, 1e-6 * direct.cwiseAbs().maxCoeff(), 0.0);
}

TEST(AmgPreconditioner, EachComponentKeepsItsOwnRecurrence)
{
    // Two bodies that do not touch, two components, one V-cycle over both: the body warm-started
    // at its solution takes no iteration and keeps its bits, the other converges to its own
    // direct solution, exactly as if each were solved alone.
    const Elasticity moving(30.0), resting(45.0, Vec3(20.0, 0.0, 0.0));
    SceneMatrix scene({&moving.a, &resting.a});
    scene.set_node_positions({&moving.positions, &resting.positions});
    const VecX direct_moving = Eigen::SimplicialLDLT<SparseMat>(moving.a.to_sparse()).solve(moving.b);
    const VecX direct_resting = Eigen::SimplicialLDLT<SparseMat>(resting.a.to_sparse()).solve(resting.b);
    VecX b(scene.num_dofs()), x(scene.num_dofs());
    b << moving.b, resting.b;
    x << VecX::Zero(moving.b.size()), direct_resting;
    PcgSolver pcg;
    const PcgResult result = pcg.solve(scene, b, x, converged(PcgPreconditioner::AMG, 1e-9));
    EXPECT_TRUE(result.converged);
    EXPECT_TRUE(x.tail(direct_resting.size()) == direct_resting);
    EXPECT_NEAR_REL(VecX(x.head(direct_moving.size())), direct_moving, 1e-7 * direct_moving.cwiseAbs().maxCoeff(), 0.0);
    EXPECT_LT(result.iterations, 40);
}

TEST(AmgPreconditioner, SameBitsForEveryThreadCount)
{
    const TiedPair pair;
    std::vector<VecX> solutions;
    for (const int threads : {1, 2}) {
        tbb::task_arena arena(threads);
        arena.execute([&] {
            PcgSolver pcg;
            VecX x = VecX::Zero(pair.b.size());
            pcg.solve(pair.scene, pair.b, x, converged(PcgPreconditioner::AMG, 1e-10));
            solutions.push_back(x);
        });
    }
    ASSERT_EQ(solutions.size(), 2u);
    EXPECT_TRUE(solutions[0] == solutions[1]);
}

TEST(AmgPreconditioner, RejectsAMatrixWithoutPositionsAndApplyBeforePrepare)
{
    const Elasticity problem;
    AmgPreconditioner amg;
    VecX z(problem.b.size());
    EXPECT_THROW(amg.apply(problem.b.data(), z.data()), std::logic_error);
    const SceneMatrix bare({&problem.a});
    EXPECT_THROW(amg.prepare(bare), std::invalid_argument);
    EXPECT_THROW(AmgPreconditioner(AmgSettings{1.0, 2, 2, 1, 0.0, true}), std::invalid_argument);
}

TEST(HierarchyReuse, RebuildsWhenIterationsPerDecadeGrowPastTheFactor)
{
    HierarchyReuse reuse(1.5);
    EXPECT_TRUE(reuse.setup_due());
    reuse.record_setup();
    EXPECT_FALSE(reuse.setup_due());
    reuse.record_solve(12, 1e-6); // baseline: 2 iterations per decade
    reuse.record_solve(6, 1e-2);  // a better warm start: fewer iterations, the same rate
    reuse.record_solve(10, 1e-3); // 3.3 per decade: 1.67 × the baseline
    EXPECT_TRUE(reuse.setup_due());
    reuse.record_setup();
    EXPECT_FALSE(reuse.setup_due());
    reuse.record_solve(10, 0.1);  // a capped solve: 10 per decade, the new baseline
    reuse.record_solve(10, 0.2);  // 14.3 per decade: 1.43 ×, still fine
    EXPECT_FALSE(reuse.setup_due());
    reuse.record_solve(0, 1.0);   // started converged: says nothing
    EXPECT_FALSE(reuse.setup_due());
    reuse.record_solve(10, 1.0);  // no reduction at all
    EXPECT_TRUE(reuse.setup_due());
}
