#include <corocontact/solver/amg_preconditioner.hpp>

#include <corocontact/core/error.hpp>

#include <petscksp.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <stdexcept>
#include <string>
#include <vector>

namespace coro {

namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point start)
{
    return std::chrono::duration<double>(Clock::now() - start).count();
}

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
// GAMG's drop tolerance for weak couplings in the aggregation graph: keep every nonzero one
// (bench_amg: 0.02 and 0.05 give the same iterations on the SOFA beam and no cheaper setup).
constexpr PetscReal THRESHOLD = 0.0;

} // namespace

struct AmgPreconditioner::Impl {
    // Pattern of the last setup, and for every scalar entry of the full matrix (CSR, row by
    // row) the index of its value in the BsrMatrix values.
    std::vector<Index> block_row_offsets;
    std::vector<Index> block_columns;
    std::vector<PetscInt> row_offsets;
    std::vector<PetscInt> columns;
    std::vector<std::size_t> source;
    std::vector<PetscScalar> values;
    Mat matrix = nullptr;
    PC pc = nullptr;
    Vec in = nullptr;
    Vec out = nullptr;
    AmgTimes times;

    ~Impl() { destroy(); }

    void destroy()
    {
        if (pc)
            PCDestroy(&pc);
        if (matrix)
            MatDestroy(&matrix);
        if (in)
            VecDestroy(&in);
        if (out)
            VecDestroy(&out);
    }

    bool same_pattern(const BsrMatrix& a) const
    {
        return matrix != nullptr && a.row_offsets() == block_row_offsets && a.columns() == block_columns;
    }

    // The full scalar CSR pattern of `a` and where each value comes from.
    void build_pattern(const BsrMatrix& a)
    {
        const Index n = a.num_block_rows();
        const bool upper = a.is_symmetric_upper();
        // Per block row: (column, block, transposed), the stored blocks and, in upper storage,
        // the mirrors of blocks above.
        std::vector<std::vector<std::array<Index, 3>>> rows(static_cast<std::size_t>(n));
        const std::vector<Index>& offsets = a.row_offsets();
        for (Index r = 0; r < n; ++r)
            for (Index k = offsets[static_cast<std::size_t>(r)]; k < offsets[static_cast<std::size_t>(r) + 1]; ++k) {
                const Index c = a.columns()[static_cast<std::size_t>(k)];
                rows[static_cast<std::size_t>(r)].push_back({c, k, 0});
                if (upper && c != r)
                    rows[static_cast<std::size_t>(c)].push_back({r, k, 1});
            }
        row_offsets.assign(1, 0);
        columns.clear();
        source.clear();
        for (Index r = 0; r < n; ++r) {
            auto& row = rows[static_cast<std::size_t>(r)];
            std::sort(row.begin(), row.end());
            for (int i = 0; i < 3; ++i) {
                for (const auto& [c, k, transposed] : row)
                    for (int j = 0; j < 3; ++j) {
                        columns.push_back(static_cast<PetscInt>(3 * c + j));
                        source.push_back(9 * static_cast<std::size_t>(k) +
                                         static_cast<std::size_t>(transposed ? 3 * j + i : 3 * i + j));
                    }
                row_offsets.push_back(static_cast<PetscInt>(columns.size()));
            }
        }
        block_row_offsets = a.row_offsets();
        block_columns = a.columns();
        values.resize(columns.size());
    }

    void fill_values(const BsrMatrix& a)
    {
        const std::vector<double>& bsr = a.values();
        for (std::size_t e = 0; e < source.size(); ++e)
            values[e] = bsr[source[e]];
    }

    void create(const BsrMatrix& a)
    {
        destroy();
        build_pattern(a);
        fill_values(a);
        const auto n = static_cast<PetscInt>(a.num_dofs());
        check(MatCreate(PETSC_COMM_SELF, &matrix), "MatCreate");
        check(MatSetSizes(matrix, n, n, n, n), "MatSetSizes");
        check(MatSetBlockSize(matrix, BLOCK), "MatSetBlockSize");
        check(MatSetType(matrix, MATSEQAIJ), "MatSetType");
        check(MatSeqAIJSetPreallocationCSR(matrix, row_offsets.data(), columns.data(), values.data()),
              "MatSeqAIJSetPreallocationCSR");
        check(VecCreateSeqWithArray(PETSC_COMM_SELF, BLOCK, n, nullptr, &in), "VecCreateSeqWithArray");
        check(VecCreateSeqWithArray(PETSC_COMM_SELF, BLOCK, n, nullptr, &out), "VecCreateSeqWithArray");
        check(PCCreate(PETSC_COMM_SELF, &pc), "PCCreate");
        check(PCSetType(pc, PCGAMG), "PCSetType");
        PetscReal threshold = THRESHOLD;
        check(PCGAMGSetThreshold(pc, &threshold, 1), "PCGAMGSetThreshold");
        // GAMG's defaults are completed by PCSetFromOptions (without it the smoothers differ and
        // the setup costs four times as much); the prefix keeps other options out of it.
        check(PCSetOptionsPrefix(pc, "corocontact_amg_"), "PCSetOptionsPrefix");
        check(PCSetFromOptions(pc), "PCSetFromOptions");
    }

    void refill(const BsrMatrix& a)
    {
        fill_values(a);
        PetscScalar* data = nullptr;
        check(MatSeqAIJGetArray(matrix, &data), "MatSeqAIJGetArray");
        std::copy(values.begin(), values.end(), data);
        check(MatSeqAIJRestoreArray(matrix, &data), "MatSeqAIJRestoreArray");
    }

    void set_near_null_space(CRef<VecX> positions)
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
};

AmgPreconditioner::AmgPreconditioner() : m_impl(std::make_unique<Impl>()) {}
AmgPreconditioner::~AmgPreconditioner() = default;
AmgPreconditioner::AmgPreconditioner(AmgPreconditioner&&) noexcept = default;
AmgPreconditioner& AmgPreconditioner::operator=(AmgPreconditioner&&) noexcept = default;

bool AmgPreconditioner::ready() const { return m_impl && m_impl->pc != nullptr && m_impl->times.setups > 0; }

const AmgTimes& AmgPreconditioner::times() const { return m_impl->times; }

void AmgPreconditioner::setup(const BsrMatrix& a, CRef<VecX> positions)
{
    if (positions.size() != a.num_dofs())
        throw std::invalid_argument("AmgPreconditioner::setup: " + std::to_string(positions.size()) +
                                    " position values for a matrix of " + std::to_string(a.num_dofs()) + " DOFs");
    PetscSession::ensure();
    const auto start = Clock::now();
    Impl& impl = *m_impl;
    if (impl.same_pattern(a))
        impl.refill(a);
    else
        impl.create(a);
    impl.set_near_null_space(positions);
    check(PCSetOperators(impl.pc, impl.matrix, impl.matrix), "PCSetOperators");
    check(PCSetUp(impl.pc), "PCSetUp (GAMG hierarchy)");
    impl.times.setup_s += seconds_since(start);
    ++impl.times.setups;
}

void AmgPreconditioner::apply(CRef<VecX> r, Eigen::Ref<VecX> z)
{
    Impl& impl = *m_impl;
    if (!ready())
        throw std::logic_error("AmgPreconditioner::apply before setup");
    const auto dofs = static_cast<Eigen::Index>(impl.row_offsets.size() - 1);
    if (r.size() != dofs || z.size() != r.size())
        throw std::invalid_argument("AmgPreconditioner::apply: vectors of " + std::to_string(r.size()) + " and " +
                                    std::to_string(z.size()) + " values for " +
                                    std::to_string(impl.row_offsets.size() - 1) + " DOFs");
    const auto start = Clock::now();
    check(VecPlaceArray(impl.in, r.data()), "VecPlaceArray");
    check(VecPlaceArray(impl.out, z.data()), "VecPlaceArray");
    const PetscErrorCode code = PCApply(impl.pc, impl.in, impl.out);
    VecResetArray(impl.in);
    VecResetArray(impl.out);
    check(code, "PCApply (V-cycle)");
    impl.times.apply_s += seconds_since(start);
    ++impl.times.applies;
}

} // namespace coro
