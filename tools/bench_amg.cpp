// bench_amg: algebraic multigrid preconditioners on our implicit Euler systems, against our
// Jacobi-PCG, all solved to the same relative residual ‖b − Ax‖/‖b‖ from the same warm start.
//
//   bench_amg CASE.toml [--steps N] [--samples K] [--body NAME|all] [--tolerance T] [--threads N]
//             [--repeat R] [--only TEXT]
//
// The case's bodies (contact off) take N implicit Euler steps under gravity, each solved by our
// Jacobi-PCG to the tolerance; the systems (M + hC + h²K') v = rhs of K steps spread over the
// run are kept (--body all: the bodies' systems side by side, one block-diagonal matrix, as
// the scene system will hold them). On every kept system, in one run:
//   ours      PcgSolver, Jacobi and block-Jacobi (TBB threads)
//   hypre     BoomerAMG in hypre's PCG: scalar; systems (3 unknowns per node); nodal coarsening;
//             nodal with rigid-body interpolation vectors (MFEM's elasticity options)
//   petsc     GAMG in PETSc's CG, block size 3: without and with the rigid-body near-null
//             space (MatNullSpaceCreateRigidBody)
//   ours + AmgPreconditioner  our PCG iteration (TBB SpMV and vector passes) around the GAMG
//             component of src/solver
// and the reuse of the first system's hierarchy on the later ones. The methods run interleaved,
// R times (medians at the end); --only keeps the methods whose label contains one of the
// comma-separated TEXT parts ("ours,hypre systems,petsc gamg rigid-body thr 0.0", ...). hypre and PETSc run in one process without threads (the
// Debian builds of both have no OpenMP).
#include "implicit_euler_system.hpp"

#include <corocontact/io/case_reader.hpp>
#include <corocontact/io/scene_loader.hpp>
#include <corocontact/solver/scene_matrix.hpp>
#include <corocontact/solver/pcg.hpp>
#include <corocontact/solver/vector_ops.hpp>

#include <HYPRE.h>
#include <HYPRE_parcsr_ls.h>
#include <HYPRE_utilities.h>
#include <_hypre_parcsr_ls.h> // HYPRE_BoomerAMGSetSmoothInterpVectors, ...InterpRefine (as MFEM uses them)
#include <mpi.h>
#include <petscksp.h>

#include <tbb/global_control.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <deque>
#include <functional>
#include <string>
#include <vector>

namespace {

using namespace coro;
using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point start)
{
    return std::chrono::duration<double>(Clock::now() - start).count();
}

/// One linear system A v = b with what the preconditioners may use.
struct System {
    SparseMat a;     // every block (upper storage expanded)
    BsrMatrix bsr;   // as our PCG takes it
    VecX b;
    VecX x0;         // warm start (the velocities before the step)
    VecX positions;  // #3N node positions, for the rigid-body modes
    Index step = 0;
};

struct Row {
    std::string method;
    Index step = 0;
    double setup_s = 0.0;
    double solve_s = 0.0;
    Index iterations = 0;
    double residual = 0.0; // true ‖b − Ax‖/‖b‖ of the returned x
};

double true_residual(const System& s, const VecX& x) { return (s.b - s.a * x).norm() / s.b.norm(); }

void print(const Row& r)
{
    std::printf("%-34s step %4d  setup %8.3f s  solve %8.3f s  total %8.3f s  iterations %5d  residual %.2e\n",
                r.method.c_str(), static_cast<int>(r.step), r.setup_s, r.solve_s, r.setup_s + r.solve_s,
                static_cast<int>(r.iterations), r.residual);
    std::fflush(stdout);
}

// ---------------------------------------------------------------------------------------------
// Ours.

Row ours(const System& s, PcgPreconditioner kind, double tolerance)
{
    PcgSolver pcg;
    PcgSettings settings;
    settings.max_iterations = 100000;
    settings.tolerance = tolerance;
    settings.preconditioner = kind;
    VecX x = s.x0;
    const auto start = Clock::now();
    const PcgResult result = pcg.solve(s.bsr, s.b, x, settings);
    Row row;
    row.method = std::string("ours ") + preconditioner_name(kind);
    row.step = s.step;
    row.solve_s = seconds_since(start);
    row.iterations = result.iterations;
    row.residual = true_residual(s, x);
    return row;
}

// ---------------------------------------------------------------------------------------------
// hypre.

struct HypreMatrix {
    HYPRE_IJMatrix ij = nullptr;
    HYPRE_ParCSRMatrix parcsr = nullptr;
    explicit HypreMatrix(const SparseMat& a)
    {
        const HYPRE_BigInt last = static_cast<HYPRE_BigInt>(a.rows()) - 1;
        HYPRE_IJMatrixCreate(MPI_COMM_WORLD, 0, last, 0, last, &ij);
        HYPRE_IJMatrixSetObjectType(ij, HYPRE_PARCSR);
        std::vector<HYPRE_Int> sizes(static_cast<std::size_t>(a.rows()));
        for (Eigen::Index r = 0; r < a.rows(); ++r)
            sizes[static_cast<std::size_t>(r)] = static_cast<HYPRE_Int>(a.outerIndexPtr()[r + 1] - a.outerIndexPtr()[r]);
        HYPRE_IJMatrixSetRowSizes(ij, sizes.data());
        HYPRE_IJMatrixInitialize(ij);
        std::vector<HYPRE_BigInt> rows(static_cast<std::size_t>(a.rows())), cols(a.outerIndexPtr()[a.rows()]);
        for (Eigen::Index r = 0; r < a.rows(); ++r)
            rows[static_cast<std::size_t>(r)] = r;
        for (std::size_t k = 0; k < cols.size(); ++k)
            cols[k] = a.innerIndexPtr()[k];
        HYPRE_IJMatrixSetValues(ij, static_cast<HYPRE_Int>(a.rows()), sizes.data(), rows.data(), cols.data(),
                                a.valuePtr());
        HYPRE_IJMatrixAssemble(ij);
        void* object = nullptr;
        HYPRE_IJMatrixGetObject(ij, &object);
        parcsr = static_cast<HYPRE_ParCSRMatrix>(object);
    }
    ~HypreMatrix() { HYPRE_IJMatrixDestroy(ij); }
    HypreMatrix(const HypreMatrix&) = delete;
    HypreMatrix& operator=(const HypreMatrix&) = delete;
};

struct HypreVector {
    HYPRE_IJVector ij = nullptr;
    HYPRE_ParVector par = nullptr;
    Eigen::Index size = 0;
    explicit HypreVector(const VecX& v) : size(v.size())
    {
        const HYPRE_BigInt last = static_cast<HYPRE_BigInt>(v.size()) - 1;
        HYPRE_IJVectorCreate(MPI_COMM_WORLD, 0, last, &ij);
        HYPRE_IJVectorSetObjectType(ij, HYPRE_PARCSR);
        HYPRE_IJVectorInitialize(ij);
        std::vector<HYPRE_BigInt> rows(static_cast<std::size_t>(v.size()));
        for (Eigen::Index i = 0; i < v.size(); ++i)
            rows[static_cast<std::size_t>(i)] = i;
        HYPRE_IJVectorSetValues(ij, static_cast<HYPRE_Int>(v.size()), rows.data(), v.data());
        HYPRE_IJVectorAssemble(ij);
        void* object = nullptr;
        HYPRE_IJVectorGetObject(ij, &object);
        par = static_cast<HYPRE_ParVector>(object);
    }
    VecX values() const
    {
        const Eigen::Index n = size;
        VecX v(n);
        std::vector<HYPRE_BigInt> rows(static_cast<std::size_t>(n));
        for (Eigen::Index i = 0; i < n; ++i)
            rows[static_cast<std::size_t>(i)] = i;
        HYPRE_IJVectorGetValues(ij, static_cast<HYPRE_Int>(n), rows.data(), v.data());
        return v;
    }
    ~HypreVector() { HYPRE_IJVectorDestroy(ij); }
    HypreVector(const HypreVector&) = delete;
    HypreVector& operator=(const HypreVector&) = delete;
};

/// One BoomerAMG configuration (hypre's reference manual names the options).
struct HypreVariant {
    const char* name;
    int functions = 1;         ///< SetNumFunctions: 3 = the systems (unknown) approach
    int nodal = 0;             ///< SetNodal: nodal coarsening with this block norm (0: off)
    bool rigid_body = false;   ///< rotations as interpolation vectors (GM-2), MFEM's elasticity options
    double threshold = 0.5;    ///< SetStrongThreshold
    int relax = 8;             ///< SetRelaxType: 8 l1 symmetric Gauss–Seidel, 18 l1-Jacobi, 16 Chebyshev
    int aggressive = 0;        ///< SetAggNumLevels: aggressive coarsening on this many levels
};

// The three rotations of the nodes about the origin (hypre adds the translations itself through
// the nodal systems approach), as hypre vectors.
std::vector<VecX> rotation_modes(const VecX& positions)
{
    std::vector<VecX> modes(3, VecX::Zero(positions.size()));
    for (Eigen::Index v = 0; v < positions.size() / 3; ++v) {
        const Vec3 p = positions.segment<3>(3 * v);
        modes[0].segment<3>(3 * v) = Vec3(0.0, -p.z(), p.y());
        modes[1].segment<3>(3 * v) = Vec3(p.z(), 0.0, -p.x());
        modes[2].segment<3>(3 * v) = Vec3(-p.y(), p.x(), 0.0);
    }
    return modes;
}

HYPRE_Int no_setup(HYPRE_Solver, HYPRE_ParCSRMatrix, HYPRE_ParVector, HYPRE_ParVector) { return 0; }

/// hypre's PCG with BoomerAMG. With `reuse` the hierarchy of `reuse_from` serves `s`.
class HypreAmg {
public:
    HypreAmg(const HypreVariant& variant, const System& setup_system) : m_variant(variant)
    {
        HYPRE_BoomerAMGCreate(&m_amg);
        HYPRE_BoomerAMGSetMaxIter(m_amg, 1);
        HYPRE_BoomerAMGSetTol(m_amg, 0.0);
        HYPRE_BoomerAMGSetPrintLevel(m_amg, 0);
        HYPRE_BoomerAMGSetCoarsenType(m_amg, 10); // HMIS
        HYPRE_BoomerAMGSetInterpType(m_amg, 6);   // extended+i
        HYPRE_BoomerAMGSetPMaxElmts(m_amg, 4);
        HYPRE_BoomerAMGSetRelaxType(m_amg, variant.relax);
        HYPRE_BoomerAMGSetNumSweeps(m_amg, 1);
        HYPRE_BoomerAMGSetAggNumLevels(m_amg, variant.aggressive);
        HYPRE_BoomerAMGSetStrongThreshold(m_amg, variant.threshold);
        HYPRE_BoomerAMGSetNumFunctions(m_amg, variant.functions);
        if (variant.nodal > 0) {
            HYPRE_BoomerAMGSetNodal(m_amg, variant.nodal);
            HYPRE_BoomerAMGSetNodalDiag(m_amg, 1);
        }
        if (variant.rigid_body) {
            HYPRE_BoomerAMGSetCycleRelaxType(m_amg, 8, 3);
            HYPRE_BoomerAMGSetInterpVecVariant(m_amg, 2);
            HYPRE_BoomerAMGSetInterpVecQMax(m_amg, 4);
            HYPRE_BoomerAMGSetSmoothInterpVectors(m_amg, 1);
            HYPRE_BoomerAMGSetInterpRefine(m_amg, 1);
            for (const VecX& mode : rotation_modes(setup_system.positions))
                m_modes.push_back(std::make_unique<HypreVector>(mode));
            for (const auto& mode : m_modes)
                m_mode_vectors.push_back(mode->par);
            HYPRE_BoomerAMGSetInterpVectors(m_amg, static_cast<HYPRE_Int>(m_mode_vectors.size()),
                                            m_mode_vectors.data());
        }
        m_matrix = std::make_unique<HypreMatrix>(setup_system.a);
        HypreVector b(setup_system.b), x(setup_system.x0);
        const auto start = Clock::now();
        HYPRE_BoomerAMGSetup(m_amg, m_matrix->parcsr, b.par, x.par);
        m_setup_s = seconds_since(start);
    }
    ~HypreAmg() { HYPRE_BoomerAMGDestroy(m_amg); }
    HypreAmg(const HypreAmg&) = delete;
    HypreAmg& operator=(const HypreAmg&) = delete;

    Row solve(const System& s, double tolerance, bool reused)
    {
        HypreMatrix a(s.a);
        HypreVector b(s.b), x(s.x0);
        HYPRE_Solver pcg = nullptr;
        HYPRE_ParCSRPCGCreate(MPI_COMM_WORLD, &pcg);
        HYPRE_PCGSetTol(pcg, tolerance);
        HYPRE_PCGSetAbsoluteTol(pcg, 0.0);
        HYPRE_PCGSetTwoNorm(pcg, 1);
        HYPRE_PCGSetMaxIter(pcg, 10000);
        HYPRE_PCGSetPrintLevel(pcg, 0);
        HYPRE_ParCSRPCGSetPrecond(pcg, HYPRE_BoomerAMGSolve, no_setup, m_amg);
        HYPRE_ParCSRPCGSetup(pcg, a.parcsr, b.par, x.par);
        const auto start = Clock::now();
        HYPRE_ParCSRPCGSolve(pcg, a.parcsr, b.par, x.par);
        Row row;
        row.solve_s = seconds_since(start);
        HYPRE_Int iterations = 0;
        HYPRE_PCGGetNumIterations(pcg, &iterations);
        HYPRE_ParCSRPCGDestroy(pcg);
        row.method = std::string("hypre ") + m_variant.name + (reused ? " (reused)" : "");
        row.step = s.step;
        row.setup_s = reused ? 0.0 : m_setup_s;
        row.iterations = iterations;
        row.residual = true_residual(s, x.values());
        return row;
    }

private:
    HypreVariant m_variant;
    HYPRE_Solver m_amg = nullptr;
    std::unique_ptr<HypreMatrix> m_matrix;
    std::vector<std::unique_ptr<HypreVector>> m_modes;
    std::vector<HYPRE_ParVector> m_mode_vectors;
    double m_setup_s = 0.0;
};

// ---------------------------------------------------------------------------------------------
// PETSc.

#define PETSC_OK(call)                                                                                       \
    do {                                                                                                     \
        const PetscErrorCode code_ = (call);                                                                 \
        if (code_ != 0) {                                                                                    \
            std::fprintf(stderr, "PETSc error %d in %s\n", static_cast<int>(code_), #call);                  \
            std::exit(1);                                                                                    \
        }                                                                                                    \
    } while (0)

Mat petsc_matrix(const SparseMat& a)
{
    // AIJ with block size 3 (GAMG's aggregation does not take BAIJ in this version).
    Mat m;
    const auto n = static_cast<PetscInt>(a.rows());
    std::vector<PetscInt> nnz(static_cast<std::size_t>(n));
    for (PetscInt r = 0; r < n; ++r)
        nnz[static_cast<std::size_t>(r)] = a.outerIndexPtr()[r + 1] - a.outerIndexPtr()[r];
    PETSC_OK(MatCreateSeqAIJ(PETSC_COMM_SELF, n, n, 0, nnz.data(), &m));
    PETSC_OK(MatSetBlockSize(m, 3));
    for (PetscInt r = 0; r < n; ++r) {
        const PetscInt begin = a.outerIndexPtr()[r], count = a.outerIndexPtr()[r + 1] - begin;
        std::vector<PetscInt> cols(a.innerIndexPtr() + begin, a.innerIndexPtr() + begin + count);
        PETSC_OK(MatSetValues(m, 1, &r, count, cols.data(), a.valuePtr() + begin, INSERT_VALUES));
    }
    PETSC_OK(MatAssemblyBegin(m, MAT_FINAL_ASSEMBLY));
    PETSC_OK(MatAssemblyEnd(m, MAT_FINAL_ASSEMBLY));
    return m;
}

Vec petsc_vector(const VecX& v, PetscInt block_size = 1)
{
    Vec out;
    PETSC_OK(VecCreateSeq(PETSC_COMM_SELF, static_cast<PetscInt>(v.size()), &out));
    PETSC_OK(VecSetBlockSize(out, block_size));
    PetscScalar* data = nullptr;
    PETSC_OK(VecGetArray(out, &data));
    std::copy(v.data(), v.data() + v.size(), data);
    PETSC_OK(VecRestoreArray(out, &data));
    return out;
}

VecX values(Vec v)
{
    PetscInt n = 0;
    PETSC_OK(VecGetSize(v, &n));
    const PetscScalar* data = nullptr;
    PETSC_OK(VecGetArrayRead(v, &data));
    VecX out = Eigen::Map<const VecX>(data, n);
    PETSC_OK(VecRestoreArrayRead(v, &data));
    return out;
}

/// PETSc's CG with GAMG; with the rigid-body near-null space if asked. Setup on one system,
/// solves on any (reusing the hierarchy: KSPSetReusePreconditioner).
class PetscGamg {
public:
    PetscGamg(bool rigid_body, const System& setup_system, const char* threshold) : m_rigid_body(rigid_body)
    {
        m_threshold = threshold;
        PETSC_OK(PetscOptionsSetValue(nullptr, "-pc_gamg_threshold", threshold));
        m_matrix = petsc_matrix(setup_system.a);
        if (rigid_body) {
            Vec coordinates = petsc_vector(setup_system.positions, 3);
            MatNullSpace space;
            PETSC_OK(MatNullSpaceCreateRigidBody(coordinates, &space));
            PETSC_OK(MatSetNearNullSpace(m_matrix, space));
            PETSC_OK(MatNullSpaceDestroy(&space));
            PETSC_OK(VecDestroy(&coordinates));
        }
        PETSC_OK(KSPCreate(PETSC_COMM_SELF, &m_ksp));
        PETSC_OK(KSPSetType(m_ksp, KSPCG));
        PETSC_OK(KSPSetOperators(m_ksp, m_matrix, m_matrix));
        PC pc;
        PETSC_OK(KSPGetPC(m_ksp, &pc));
        PETSC_OK(PCSetType(pc, PCGAMG));
        PETSC_OK(KSPSetNormType(m_ksp, KSP_NORM_UNPRECONDITIONED));
        PETSC_OK(KSPSetInitialGuessNonzero(m_ksp, PETSC_TRUE));
        PETSC_OK(KSPSetFromOptions(m_ksp));
        const auto start = Clock::now();
        PETSC_OK(KSPSetUp(m_ksp));
        PETSC_OK(PCSetUp(pc));
        m_setup_s = seconds_since(start);
    }
    ~PetscGamg()
    {
        KSPDestroy(&m_ksp);
        MatDestroy(&m_matrix);
    }
    PetscGamg(const PetscGamg&) = delete;
    PetscGamg& operator=(const PetscGamg&) = delete;

    Row solve(const System& s, double tolerance, bool reused)
    {
        Mat a = nullptr;
        if (reused) {
            a = petsc_matrix(s.a);
            PETSC_OK(KSPSetReusePreconditioner(m_ksp, PETSC_TRUE));
            PETSC_OK(KSPSetOperators(m_ksp, a, m_matrix)); // new operator, old preconditioner
        }
        Vec b = petsc_vector(s.b, 3), x = petsc_vector(s.x0, 3);
        PETSC_OK(KSPSetTolerances(m_ksp, tolerance, 0.0, PETSC_DEFAULT, 10000));
        const auto start = Clock::now();
        PETSC_OK(KSPSolve(m_ksp, b, x));
        Row row;
        row.solve_s = seconds_since(start);
        PetscInt iterations = 0;
        PETSC_OK(KSPGetIterationNumber(m_ksp, &iterations));
        row.method = std::string("petsc gamg ") + (m_rigid_body ? "rigid-body" : "no-nullspace") + " thr " +
                     m_threshold + (reused ? " (reused)" : "");
        row.step = s.step;
        row.setup_s = reused ? 0.0 : m_setup_s;
        row.iterations = iterations;
        row.residual = true_residual(s, values(x));
        VecDestroy(&b);
        VecDestroy(&x);
        if (a)
            MatDestroy(&a);
        return row;
    }

private:
    bool m_rigid_body;
    std::string m_threshold;
    Mat m_matrix = nullptr;
    KSP m_ksp = nullptr;
    double m_setup_s = 0.0;
};

// ---------------------------------------------------------------------------------------------

/// The bodies' systems as one block-diagonal system in upper storage, as our PCG takes it
/// (one body: its own matrix, with its chunks).
System combine(std::vector<Body>& bodies, const std::vector<Index>& chosen, const std::vector<VecX>& rhs, Index step)
{
    System s;
    if (chosen.size() == 1) {
        s.bsr = bodies[static_cast<std::size_t>(chosen[0])].system_matrix();
    } else {
        std::vector<Index> row_offsets{0}, columns;
        std::vector<double> values;
        Index node_offset = 0;
        for (const Index k : chosen) {
            const BsrMatrix& a = bodies[static_cast<std::size_t>(k)].system_matrix();
            for (Index r = 0; r < a.num_block_rows(); ++r) {
                for (Index j = a.row_offsets()[static_cast<std::size_t>(r)]; j < a.row_offsets()[static_cast<std::size_t>(r) + 1]; ++j)
                    columns.push_back(node_offset + a.columns()[static_cast<std::size_t>(j)]);
                row_offsets.push_back(static_cast<Index>(columns.size()));
            }
            values.insert(values.end(), a.values().begin(), a.values().end());
            node_offset += a.num_block_rows();
        }
        s.bsr = BsrMatrix::symmetric_upper(row_offsets, columns);
        s.bsr.values() = values;
    }
    s.a = s.bsr.to_sparse();
    const Eigen::Index n = s.bsr.num_dofs();
    s.b.resize(n);
    s.x0.resize(n);
    s.positions.resize(n);
    Eigen::Index at = 0;
    for (const Index k : chosen) {
        const Body& body = bodies[static_cast<std::size_t>(k)];
        const Eigen::Index size = body.positions().size();
        s.b.segment(at, size) = rhs[static_cast<std::size_t>(k)];
        s.x0.segment(at, size) = body.velocities();
        s.positions.segment(at, size) = body.positions();
        at += size;
    }
    s.step = step;
    return s;
}

/// A variant of our AMG preconditioner, as the bench labels it.
struct AmgVariant {
    std::string name;
    AmgSettings settings;
};

/// PcgSolver with the AMG preconditioner on the system as a one-body scene; the set-up the
/// solve made (if any) is reported apart from the solve.
Row ours_with_amg(const System& s, PcgSolver& pcg, const AmgVariant& variant, double tolerance, bool reused)
{
    SceneMatrix scene({&s.bsr});
    scene.set_node_positions({&s.positions});
    PcgSettings settings;
    settings.max_iterations = 10000;
    settings.tolerance = tolerance;
    settings.preconditioner = PcgPreconditioner::AMG;
    settings.amg = variant.settings;
    const PreconditionerTimes before = pcg.preconditioner_times();
    VecX x = s.x0;
    const auto start = Clock::now();
    const PcgResult result = pcg.solve(scene, s.b, x, settings);
    const double seconds = seconds_since(start);
    const PreconditionerTimes after = pcg.preconditioner_times();
    Row row;
    row.method = "ours amg " + variant.name + (reused ? " (reused)" : "");
    row.step = s.step;
    row.setup_s = after.setup_s - before.setup_s;
    row.solve_s = seconds - row.setup_s;
    row.iterations = result.iterations;
    row.residual = true_residual(s, x);
    return row;
}

int run(int argc, char** argv)
{
    std::string case_file, body_name, only;
    Index steps = 20, samples = 3, repeat = 1;
    double tolerance = 1e-6;
    int threads = 2;
    for (int i = 1; i < argc; ++i) {
        const std::string arg = argv[i];
        const auto next = [&]() -> std::string {
            if (i + 1 >= argc) {
                std::fprintf(stderr, "bench_amg: %s needs a value\n", arg.c_str());
                std::exit(2);
            }
            return argv[++i];
        };
        if (arg == "--steps")
            steps = std::stoi(next());
        else if (arg == "--samples")
            samples = std::stoi(next());
        else if (arg == "--body")
            body_name = next();
        else if (arg == "--tolerance")
            tolerance = std::stod(next());
        else if (arg == "--repeat")
            repeat = std::stoi(next());
        else if (arg == "--only")
            only = next();
        else if (arg == "--threads")
            threads = std::stoi(next());
        else if (arg.rfind("-", 0) != 0 && case_file.empty())
            case_file = arg;
    }
    if (case_file.empty()) {
        std::fprintf(stderr, "usage: bench_amg CASE.toml [--steps N] [--samples K] [--body NAME|all] "
                             "[--tolerance T] [--threads N] [--repeat R] [--only TEXT]\n");
        return 2;
    }
    tbb::global_control control(tbb::global_control::max_allowed_parallelism, static_cast<std::size_t>(threads));
    CaseSpec spec = read_case(case_file);
    spec.contact.enabled = false;
    LoadedScene loaded = load_scene(spec);
    std::vector<Body>& bodies = loaded.scene.bodies;
    std::vector<Index> chosen;
    for (Index k = 0; k < static_cast<Index>(bodies.size()); ++k)
        if (body_name == "all" || bodies[static_cast<std::size_t>(k)].name() == body_name ||
            (body_name.empty() && k == 0))
            chosen.push_back(k);
    Index tets = 0, nodes = 0;
    for (const Index k : chosen) {
        tets += bodies[static_cast<std::size_t>(k)].mesh().num_tets();
        nodes += bodies[static_cast<std::size_t>(k)].num_vertices();
    }
    std::printf("bench_amg: %s, %zu bodies, %d tets, %d nodes, dt %g, %d steps, tolerance %g, %d TBB threads\n",
                case_file.c_str(), chosen.size(), static_cast<int>(tets), static_cast<int>(nodes), spec.simulation.dt,
                static_cast<int>(steps), tolerance, threads);

    // Advance the bodies with converged Jacobi-PCG; keep the systems of `samples` steps.
    std::vector<System> systems;
    PcgSettings settings;
    settings.max_iterations = 100000;
    settings.tolerance = tolerance;
    settings.preconditioner = PcgPreconditioner::JACOBI;
    for (Index step = 1; step <= steps; ++step) {
        std::vector<VecX> rhs(bodies.size());
        for (const Index k : chosen)
            rhs[static_cast<std::size_t>(k)] =
                bench::implicit_euler_system(bodies[static_cast<std::size_t>(k)], spec.simulation.dt, spec.simulation.gravity);
        const bool keep = samples <= 1 ? step == 1 : (step - 1) % std::max<Index>(1, (steps - 1) / (samples - 1)) == 0;
        if (keep && static_cast<Index>(systems.size()) < samples)
            systems.push_back(combine(bodies, chosen, rhs, step));
        for (const Index k : chosen) {
            Body& body = bodies[static_cast<std::size_t>(k)];
            body.project_fixed(body.velocities());
            body.pcg().solve(body.system_matrix(), rhs[static_cast<std::size_t>(k)], body.velocities(), settings);
            body.positions() += spec.simulation.dt * body.velocities();
        }
    }
    std::printf("kept the systems of steps");
    for (const System& s : systems)
        std::printf(" %d", static_cast<int>(s.step));
    std::printf(" (%d unknowns, %ld stored entries)\n\n", static_cast<int>(systems[0].b.size()),
                static_cast<long>(systems[0].a.nonZeros()));

    // Every method on every kept system, interleaved, `repeat` times; then the medians.
    using Method = std::function<std::vector<Row>()>;
    std::deque<std::pair<std::string, Method>> methods; // (a vector trips GCC 12's -Warray-bounds here)
    for (const PcgPreconditioner kind : {PcgPreconditioner::JACOBI, PcgPreconditioner::BLOCK_JACOBI})
        methods.emplace_back(std::string("ours ") + preconditioner_name(kind), [&, kind] {
            std::vector<Row> rows;
            for (const System& s : systems)
                rows.push_back(ours(s, kind, tolerance));
            return rows;
        });
    std::vector<AmgVariant> amg_variants;
    for (const bool scene_fine_level : {true, false})
        for (const int smoothing : {1, 0})
            for (const int fine : {1, 2, 3, 4})
                for (const int coarse : {1, 2}) {
                    AmgVariant variant;
                    variant.settings.scene_fine_level = scene_fine_level;
                    variant.settings.fine_degree = fine;
                    variant.settings.coarse_degree = coarse;
                    variant.settings.aggregation_smoothing = smoothing;
                    variant.name = std::string(scene_fine_level ? "scene-fine" : "petsc-fine") +
                                   (smoothing ? " sa" : " plain") + " cheb" + std::to_string(fine) + "/" +
                                   std::to_string(coarse);
                    amg_variants.push_back(variant);
                }
    for (const AmgVariant& variant : amg_variants)
        methods.emplace_back("ours amg " + variant.name, [&, variant] {
            std::vector<Row> rows;
            for (const System& s : systems) {
                PcgSolver fresh;
                rows.push_back(ours_with_amg(s, fresh, variant, tolerance, false));
            }
            PcgSolver first;
            ours_with_amg(systems.front(), first, variant, tolerance, false);
            for (std::size_t i = 1; i < systems.size(); ++i)
                rows.push_back(ours_with_amg(systems[i], first, variant, tolerance, true));
            return rows;
        });
    const std::vector<HypreVariant> hypre_variants{
        {"scalar", 1, 0, false, 0.5, 8, 0},
        {"systems", 3, 0, false, 0.5, 8, 0},
        {"systems thr0.8", 3, 0, false, 0.8, 8, 0},
        {"systems l1-jacobi", 3, 0, false, 0.5, 18, 0},
        {"systems aggressive", 3, 0, false, 0.5, 8, 1},
        {"nodal", 3, 4, false, 0.5, 8, 0},
        {"nodal+rbm", 3, 4, true, 0.5, 8, 0},
    };
    for (const HypreVariant& variant : hypre_variants)
        methods.emplace_back(std::string("hypre ") + variant.name, [&, variant] {
            std::vector<Row> rows;
            for (const System& s : systems) {
                HypreAmg fresh(variant, s);
                rows.push_back(fresh.solve(s, tolerance, false));
            }
            HypreAmg first(variant, systems.front());
            for (std::size_t i = 1; i < systems.size(); ++i)
                rows.push_back(first.solve(systems[i], tolerance, true));
            return rows;
        });
    for (const bool rigid_body : {false, true})
        for (const char* threshold : {"0.0", "0.02", "0.05"}) {
            if (!rigid_body && std::string(threshold) != "0.0")
                continue;
            methods.emplace_back(std::string("petsc gamg ") + (rigid_body ? "rigid-body" : "no-nullspace") + " thr " +
                                     threshold,
                                 [&, rigid_body, threshold] {
                                     std::vector<Row> rows;
                                     for (const System& s : systems) {
                                         PetscGamg fresh(rigid_body, s, threshold);
                                         rows.push_back(fresh.solve(s, tolerance, false));
                                     }
                                     PetscGamg first(rigid_body, systems.front(), threshold);
                                     for (std::size_t i = 1; i < systems.size(); ++i)
                                         rows.push_back(first.solve(systems[i], tolerance, true));
                                     return rows;
                                 });
        }
    // --only: comma-separated parts of labels; a label is run if it contains one of them.
    const auto selected = [&](const std::string& label) {
        if (only.empty())
            return true;
        std::size_t from = 0;
        while (from <= only.size()) {
            const std::size_t comma = std::min(only.find(',', from), only.size());
            if (label.find(only.substr(from, comma - from)) != std::string::npos)
                return true;
            from = comma + 1;
        }
        return false;
    };
    std::vector<std::string> keys;
    std::vector<std::vector<Row>> samples_of; // per key
    for (Index r = 0; r < repeat; ++r)
        for (const auto& [label, method] : methods) {
            if (!selected(label))
                continue;
            for (const Row& row : method()) {
                print(row);
                const std::string key = row.method + " @" + std::to_string(row.step);
                const auto it = std::find(keys.begin(), keys.end(), key);
                if (it == keys.end()) {
                    keys.push_back(key);
                    samples_of.push_back({row});
                } else {
                    samples_of[static_cast<std::size_t>(it - keys.begin())].push_back(row);
                }
            }
        }
    std::printf("\nmedians over %d repeats:\n", static_cast<int>(repeat));
    for (std::vector<Row>& rows : samples_of) {
        const auto median = [&](auto field) {
            std::vector<double> v;
            for (const Row& row : rows)
                v.push_back(field(row));
            std::sort(v.begin(), v.end());
            return v[v.size() / 2];
        };
        Row row = rows.front();
        row.setup_s = median([](const Row& x) { return x.setup_s; });
        row.solve_s = median([](const Row& x) { return x.solve_s; });
        print(row);
    }
    return 0;
}

} // namespace

int main(int argc, char** argv)
{
    MPI_Init(&argc, &argv);
    PetscInitializeNoArguments();
    HYPRE_Init();
    int status = 0;
    try {
        status = run(argc, argv);
    } catch (const std::exception& e) {
        std::fprintf(stderr, "bench_amg: %s\n", e.what());
        status = 2;
    }
    HYPRE_Finalize();
    PetscFinalize();
    MPI_Finalize();
    return status;
}
