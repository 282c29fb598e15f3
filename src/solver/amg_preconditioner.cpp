#include <corocontact/solver/amg_preconditioner.hpp>

#include <corocontact/core/error.hpp>
#include <corocontact/solver/scene_matrix.hpp>

#include <petscksp.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <stdexcept>
#include <string>
#include <tuple>
#include <vector>

namespace coro {

void HierarchyReuse::record_solve(Index iterations, double reduction)
{
    if (iterations <= 0)
        return; // a solve that started converged says nothing about the hierarchy
    // Iterations per decade of reduction; a solve that reduced nothing counts as very slow.
    const double decades = reduction > 0.0 && reduction < 1.0 ? -std::log10(reduction) : 1e-3;
    const double rate = static_cast<double>(iterations) / std::max(decades, 1e-3);
    if (m_baseline < 0.0)
        m_baseline = rate;
    else if (rate > m_growth * m_baseline)
        m_due = true;
}

namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point start)
{
    return std::chrono::duration<double>(Clock::now() - start).count();
}

std::size_t at(Index i) { return static_cast<std::size_t>(i); }

// PETSc for the whole process: initialised on first use, finalised at exit (which also
// finalises MPI when PETSc was the one to initialise it).
class PetscSession {
public:
    static void ensure() { static PetscSession session; }
    ~PetscSession()
    {
        if (m_owned)
            PetscFinalize();
    }
    PetscSession(const PetscSession&) = delete;
    PetscSession& operator=(const PetscSession&) = delete;

private:
    PetscSession()
    {
        PetscBool initialised = PETSC_FALSE;
        PetscInitialized(&initialised);
        if (initialised)
            return;
        // Our own SIGINT/SIGTERM handling stays in charge; errors come back as codes.
        PetscOptionsSetValue(nullptr, "-no_signal_handler", nullptr);
        const PetscErrorCode code = PetscInitializeNoArguments();
        CORO_CHECK(code == 0, NumericalError, "AMG preconditioner: PETSc failed to initialise (error " << code << ")");
        PetscPushErrorHandler(PetscReturnErrorHandler, nullptr);
        m_owned = true;
    }
    bool m_owned = false;
};

void check(PetscErrorCode code, const char* what)
{
    if (code == 0)
        return;
    const char* text = nullptr;
    PetscErrorMessage(code, &text, nullptr);
    CORO_THROW(NumericalError, "AMG preconditioner: PETSc " << what << " failed: " << (text ? text : "unknown error")
                                                            << " (error " << code << ")");
}

constexpr PetscInt BLOCK = 3;

// Where one 3×3 block lives in PETSc's scalar CSR: entry (i, j) at base + i·stride + j (every
// scalar row of a block row holds the same block columns, three entries per block).
struct ScalarBlock {
    PetscInt base = 0;
    PetscInt stride = 0;
};

} // namespace

struct AmgPreconditioner::Impl {
    AmgSettings settings;
    HierarchyReuse reuse;
    const SceneMatrix* scene = nullptr; // of the solve in progress
    PreconditionerTimes times;

    // PETSc's copy: the whole scene matrix in scalar CSR, and where every stored block of the
    // bodies (its mirror below the diagonal too) and every coupling block goes in it.
    std::vector<PetscInt> row_offsets;
    std::vector<PetscInt> columns;
    std::vector<PetscScalar> values;
    std::vector<Index> body_block_offsets;  // #bodies+1: body b's blocks are [b], [b+1)
    std::vector<ScalarBlock> upper_targets; // per body block
    std::vector<ScalarBlock> mirror_targets; // per body block (off-diagonal ones)
    CouplingBlocks coupling;                   // the scene's contact coupling as blocks
    std::vector<ScalarBlock> coupling_targets; // per coupling block
    VecX positions; // #3N scene node positions of the last set-up
    std::vector<Block3> diagonal_blocks; // #N scratch of scene_diagonal()
    KSP fine_smoother = nullptr;         // the finest level's smoother (owned by pc)

    Mat matrix = nullptr; // PETSc's copy (AIJ)
    Mat fine = nullptr;   // the finest level's operator: a shell around the scene matrix
    PC pc = nullptr;
    Vec in = nullptr;
    Vec out = nullptr;

    explicit Impl(const AmgSettings& s) : settings(s), reuse(s.growth) {}
    ~Impl() { destroy(); }
    Impl(const Impl&) = delete;
    Impl& operator=(const Impl&) = delete;

    void destroy()
    {
        if (pc)
            PCDestroy(&pc);
        if (fine)
            MatDestroy(&fine);
        if (matrix)
            MatDestroy(&matrix);
        if (in)
            VecDestroy(&in);
        if (out)
            VecDestroy(&out);
    }

    // The diagonal of the scene matrix (contact included) into d: the finest level's Jacobi.
    static PetscErrorCode scene_diagonal(Mat shell, Vec d)
    {
        void* context = nullptr;
        PetscErrorCode code = MatShellGetContext(shell, &context);
        if (code)
            return code;
        Impl& impl = *static_cast<Impl*>(context);
        PetscScalar* da = nullptr;
        if ((code = VecGetArray(d, &da)))
            return code;
        try {
            for_each_chunk(impl.scene->chunks(), [&](Index c, Index begin, Index end) {
                Block3* blocks = impl.diagonal_blocks.data() + begin;
                impl.scene->diagonal_blocks(c, blocks);
                for (Index r = begin; r < end; ++r)
                    for (int i = 0; i < 3; ++i)
                        da[3 * r + i] = blocks[r - begin](i, i);
            });
        } catch (...) {
            code = PETSC_ERR_LIB;
        }
        VecRestoreArray(d, &da);
        return code;
    }

    static PetscErrorCode multiply_scene(Mat shell, Vec x, Vec y)
    {
        void* context = nullptr;
        PetscErrorCode code = MatShellGetContext(shell, &context);
        if (code)
            return code;
        const Impl& impl = *static_cast<const Impl*>(context);
        const PetscScalar* xa = nullptr;
        PetscScalar* ya = nullptr;
        if ((code = VecGetArrayRead(x, &xa)) || (code = VecGetArray(y, &ya)))
            return code;
        try {
            impl.scene->multiply(xa, ya, nullptr);
        } catch (...) {
            code = PETSC_ERR_LIB;
        }
        VecRestoreArray(y, &ya);
        VecRestoreArrayRead(x, &xa);
        return code;
    }

    // Builds the scalar CSR pattern of `a` and the targets of its blocks.
    void build_pattern(const SceneMatrix& a)
    {
        enum Kind : Index { UPPER, MIRROR, COUPLING };
        struct Source {
            Index column, kind, index; // index: scene-wide body block, or coupling block
            bool operator<(const Source& o) const
            {
                return std::tie(column, kind, index) < std::tie(o.column, o.kind, o.index);
            }
        };
        const Index n = a.num_block_rows();
        body_block_offsets.assign(1, 0);
        for (Index b = 0; b < a.num_bodies(); ++b)
            body_block_offsets.push_back(body_block_offsets.back() + a.body_matrix(b).num_blocks());

        // Sources per block row, counted then filled (CSR).
        std::vector<Index> offsets(at(n) + 1, 0);
        for (Index b = 0; b < a.num_bodies(); ++b) {
            const BsrMatrix& m = a.body_matrix(b);
            const Index shift = a.offset(b);
            for (Index r = 0; r < m.num_block_rows(); ++r)
                for (Index k = m.row_offsets()[at(r)]; k < m.row_offsets()[at(r) + 1]; ++k) {
                    ++offsets[at(shift + r) + 1];
                    if (m.columns()[at(k)] != r)
                        ++offsets[at(shift + m.columns()[at(k)]) + 1];
                }
        }
        for (Index k = 0; k < coupling.size(); ++k)
            ++offsets[at(coupling.block(k).row) + 1];
        for (std::size_t r = 0; r < at(n); ++r)
            offsets[r + 1] += offsets[r];
        std::vector<Source> sources(at(offsets.back()));
        std::vector<Index> fill(offsets.begin(), offsets.end() - 1);
        for (Index b = 0; b < a.num_bodies(); ++b) {
            const BsrMatrix& m = a.body_matrix(b);
            const Index shift = a.offset(b);
            for (Index r = 0; r < m.num_block_rows(); ++r)
                for (Index k = m.row_offsets()[at(r)]; k < m.row_offsets()[at(r) + 1]; ++k) {
                    const Index c = m.columns()[at(k)], g = body_block_offsets[at(b)] + k;
                    sources[at(fill[at(shift + r)]++)] = {shift + c, UPPER, g};
                    if (c != r)
                        sources[at(fill[at(shift + c)]++)] = {shift + r, MIRROR, g};
                }
        }
        for (Index k = 0; k < coupling.size(); ++k) {
            const CouplingBlocks::Entry& e = coupling.block(k);
            sources[at(fill[at(e.row)]++)] = {e.column, COUPLING, k};
        }

        upper_targets.assign(at(body_block_offsets.back()), {});
        mirror_targets.assign(at(body_block_offsets.back()), {});
        coupling_targets.assign(at(coupling.size()), {});
        row_offsets.assign(1, 0);
        columns.clear();
        std::vector<Index> row_columns;
        for (Index r = 0; r < n; ++r) {
            const auto first = sources.begin() + offsets[at(r)], last = sources.begin() + offsets[at(r) + 1];
            std::sort(first, last);
            row_columns.clear();
            for (auto s = first; s != last; ++s)
                if (row_columns.empty() || row_columns.back() != s->column)
                    row_columns.push_back(s->column);
            const auto row_start = static_cast<PetscInt>(columns.size());
            const auto stride = static_cast<PetscInt>(3 * row_columns.size());
            Index position = -1;
            Index previous = -1;
            for (auto s = first; s != last; ++s) {
                if (s->column != previous) {
                    ++position;
                    previous = s->column;
                }
                const ScalarBlock target{row_start + 3 * static_cast<PetscInt>(position), stride};
                if (s->kind == UPPER)
                    upper_targets[at(s->index)] = target;
                else if (s->kind == MIRROR)
                    mirror_targets[at(s->index)] = target;
                else
                    coupling_targets[at(s->index)] = target;
            }
            for (int i = 0; i < 3; ++i) {
                for (const Index c : row_columns)
                    for (int j = 0; j < 3; ++j)
                        columns.push_back(static_cast<PetscInt>(3 * c + j));
                row_offsets.push_back(static_cast<PetscInt>(columns.size()));
            }
        }
        values.assign(columns.size(), 0.0);
    }

    void add(const ScalarBlock& target, const Block3& value, bool transposed)
    {
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j)
                values[at(static_cast<Index>(target.base + i * target.stride + j))] +=
                    transposed ? value(j, i) : value(i, j);
    }

    void fill_values(const SceneMatrix& a)
    {
        std::fill(values.begin(), values.end(), 0.0);
        for (Index b = 0; b < a.num_bodies(); ++b) {
            const BsrMatrix& m = a.body_matrix(b);
            for (Index r = 0; r < m.num_block_rows(); ++r)
                for (Index k = m.row_offsets()[at(r)]; k < m.row_offsets()[at(r) + 1]; ++k) {
                    const Index g = body_block_offsets[at(b)] + k;
                    const Block3 value = m.block(k);
                    add(upper_targets[at(g)], value, false);
                    if (m.columns()[at(k)] != r)
                        add(mirror_targets[at(g)], value, true);
                }
        }
        for (Index k = 0; k < coupling.size(); ++k)
            add(coupling_targets[at(k)], coupling.block(k).value, false);
    }

    void gather_positions(const SceneMatrix& a)
    {
        positions.resize(a.num_dofs());
        for (Index b = 0; b < a.num_bodies(); ++b) {
            const VecX* p = a.node_positions(b);
            if (!p)
                throw std::invalid_argument("AmgPreconditioner: the scene matrix has no node positions "
                                            "(SceneMatrix::set_node_positions)");
            positions.segment(3 * a.offset(b), p->size()) = *p;
        }
    }

    void set_near_null_space()
    {
        Vec coordinates = nullptr;
        check(VecCreateSeqWithArray(PETSC_COMM_SELF, BLOCK, static_cast<PetscInt>(positions.size()), positions.data(),
                                    &coordinates),
              "VecCreateSeqWithArray");
        MatNullSpace space = nullptr;
        const PetscErrorCode code = MatNullSpaceCreateRigidBody(coordinates, &space);
        VecDestroy(&coordinates);
        check(code, "MatNullSpaceCreateRigidBody");
        const PetscErrorCode set = MatSetNearNullSpace(matrix, space);
        MatNullSpaceDestroy(&space);
        check(set, "MatSetNearNullSpace");
    }

    void setup(const SceneMatrix& a)
    {
        gather_positions(a);
        destroy();
        a.coupling().blocks(a.num_block_rows(), coupling);
        build_pattern(a);
        fill_values(a);
        const auto n = static_cast<PetscInt>(a.num_dofs());
        check(MatCreate(PETSC_COMM_SELF, &matrix), "MatCreate");
        check(MatSetSizes(matrix, n, n, n, n), "MatSetSizes");
        check(MatSetBlockSize(matrix, BLOCK), "MatSetBlockSize");
        check(MatSetType(matrix, MATSEQAIJ), "MatSetType");
        check(MatSeqAIJSetPreallocationCSR(matrix, row_offsets.data(), columns.data(), values.data()),
              "MatSeqAIJSetPreallocationCSR");
        set_near_null_space();
        if (settings.scene_fine_level) {
            check(MatCreateShell(PETSC_COMM_SELF, n, n, n, n, this, &fine), "MatCreateShell");
            check(MatShellSetOperation(fine, MATOP_MULT, reinterpret_cast<void (*)(void)>(&multiply_scene)),
                  "MatShellSetOperation");
            check(MatShellSetOperation(fine, MATOP_GET_DIAGONAL, reinterpret_cast<void (*)(void)>(&scene_diagonal)),
                  "MatShellSetOperation");
            diagonal_blocks.resize(at(a.num_block_rows()));
            check(MatSetBlockSize(fine, BLOCK), "MatSetBlockSize");
        }
        check(VecCreateSeqWithArray(PETSC_COMM_SELF, BLOCK, n, nullptr, &in), "VecCreateSeqWithArray");
        check(VecCreateSeqWithArray(PETSC_COMM_SELF, BLOCK, n, nullptr, &out), "VecCreateSeqWithArray");
        check(PCCreate(PETSC_COMM_SELF, &pc), "PCCreate");
        check(PCSetType(pc, PCGAMG), "PCSetType");
        PetscReal threshold = settings.threshold;
        check(PCGAMGSetThreshold(pc, &threshold, 1), "PCGAMGSetThreshold");
        check(PCGAMGSetNSmooths(pc, settings.aggregation_smoothing), "PCGAMGSetNSmooths");
        // GAMG's defaults are completed by PCSetFromOptions (without it the smoothers differ and
        // the setup costs four times as much); the prefix keeps other options out of it.
        check(PCSetOptionsPrefix(pc, "corocontact_amg_"), "PCSetOptionsPrefix");
        check(PCSetFromOptions(pc), "PCSetFromOptions");
        check(PCSetOperators(pc, fine ? fine : matrix, matrix), "PCSetOperators");
        check(PCSetUseAmat(pc, PETSC_TRUE), "PCSetUseAmat");
        check(PCSetUp(pc), "PCSetUp (GAMG hierarchy)");
        PetscInt levels = 0;
        check(PCMGGetLevels(pc, &levels), "PCMGGetLevels");
        for (PetscInt level = 1; level < levels; ++level) { // level 0 is the coarsest (a direct solve)
            KSP smoother = nullptr;
            check(PCMGGetSmoother(pc, level, &smoother), "PCMGGetSmoother");
            const int degree = level + 1 == levels ? settings.fine_degree : settings.coarse_degree;
            check(KSPSetTolerances(smoother, PETSC_DEFAULT, PETSC_DEFAULT, PETSC_DEFAULT, degree), "KSPSetTolerances");
        }
        fine_smoother = nullptr;
        if (fine && levels > 1) {
            // The finest smoother's Jacobi takes the scene's own diagonal, renewed before every
            // solve (refresh_fine_level): new contact terms are on it from the first solve on.
            check(PCMGGetSmoother(pc, levels - 1, &fine_smoother), "PCMGGetSmoother");
            check(KSPSetOperators(fine_smoother, fine, fine), "KSPSetOperators");
        }
    }

    // Before a solve with the kept hierarchy: the finest smoother's Jacobi from the current
    // diagonal (assembling the shell raises its state, so PETSc sets the Jacobi up anew).
    void refresh_fine_level()
    {
        if (!fine_smoother)
            return;
        check(MatAssemblyBegin(fine, MAT_FINAL_ASSEMBLY), "MatAssemblyBegin");
        check(MatAssemblyEnd(fine, MAT_FINAL_ASSEMBLY), "MatAssemblyEnd");
        PC jacobi = nullptr;
        check(KSPGetPC(fine_smoother, &jacobi), "KSPGetPC");
        check(PCSetUp(jacobi), "PCSetUp (finest level Jacobi)");
    }
};

AmgPreconditioner::AmgPreconditioner(const AmgSettings& settings) : m_impl(std::make_unique<Impl>(settings))
{
    if (!(settings.growth > 1.0) || settings.fine_degree < 1 || settings.coarse_degree < 1 ||
        settings.aggregation_smoothing < 0 || !(settings.threshold >= 0.0))
        throw std::invalid_argument("AmgPreconditioner: growth must exceed 1, the smoother degrees be ≥ 1, "
                                    "aggregation_smoothing and threshold ≥ 0");
}

AmgPreconditioner::~AmgPreconditioner() = default;

PreconditionerTimes AmgPreconditioner::times() const { return m_impl->times; }

void AmgPreconditioner::request_setup() { m_impl->reuse = HierarchyReuse(m_impl->settings.growth); }

void AmgPreconditioner::record_solve(Index iterations, double reduction)
{
    m_impl->reuse.record_solve(iterations, reduction);
}

void AmgPreconditioner::prepare(const SceneMatrix& a)
{
    Impl& impl = *m_impl;
    impl.scene = &a;
    const bool rows_changed = impl.matrix == nullptr || static_cast<Index>(impl.positions.size()) != a.num_dofs();
    if (!impl.reuse.setup_due() && !rows_changed) {
        impl.refresh_fine_level();
        return;
    }
    PetscSession::ensure();
    const auto start = Clock::now();
    impl.setup(a);
    impl.reuse.record_setup();
    impl.times.setup_s += seconds_since(start);
    ++impl.times.setups;
}

void AmgPreconditioner::apply(const double* r, double* z)
{
    Impl& impl = *m_impl;
    if (impl.pc == nullptr)
        throw std::logic_error("AmgPreconditioner::apply before prepare");
    const auto start = Clock::now();
    check(VecPlaceArray(impl.in, r), "VecPlaceArray");
    check(VecPlaceArray(impl.out, z), "VecPlaceArray");
    const PetscErrorCode code = PCApply(impl.pc, impl.in, impl.out);
    VecResetArray(impl.in);
    VecResetArray(impl.out);
    check(code, "PCApply (V-cycle)");
    impl.times.apply_s += seconds_since(start);
    ++impl.times.applies;
}

} // namespace coro
