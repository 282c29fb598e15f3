#include <corocontact/solver/preconditioner.hpp>

#include <corocontact/config.hpp>
#include <corocontact/core/error.hpp>
#include <corocontact/solver/diagonal_preconditioner.hpp>

#if CORO_WITH_AMG
#include <corocontact/solver/amg_preconditioner.hpp>
#endif

#include <stdexcept>

namespace coro {

void Preconditioner::apply_rows(Index, Index, const double*, double*) const
{
    throw std::logic_error("Preconditioner::apply_rows on a preconditioner that is not chunk-local");
}

void Preconditioner::apply(const double*, double*)
{
    throw std::logic_error("Preconditioner::apply on a chunk-local preconditioner (PCG uses apply_rows)");
}

void Preconditioner::record_solve(Index, double) {}

PreconditionerTimes Preconditioner::times() const { return {}; }

std::unique_ptr<Preconditioner> make_preconditioner(PcgPreconditioner kind, [[maybe_unused]] const AmgSettings& amg)
{
    switch (kind) {
    case PcgPreconditioner::JACOBI:
        return std::make_unique<DiagonalPreconditioner>(false);
    case PcgPreconditioner::BLOCK_JACOBI:
        return std::make_unique<DiagonalPreconditioner>(true);
    case PcgPreconditioner::AMG:
#if CORO_WITH_AMG
        return std::make_unique<AmgPreconditioner>(amg);
#else
        CORO_THROW(InputError, "preconditioner = \"amg\" needs PETSc, and this build has none (configure with "
                               "CORO_WITH_AMG=ON after installing petsc-dev)");
#endif
    }
    throw std::logic_error("make_preconditioner: unknown kind");
}

const char* preconditioner_name(PcgPreconditioner kind)
{
    switch (kind) {
    case PcgPreconditioner::JACOBI:
        return "jacobi";
    case PcgPreconditioner::BLOCK_JACOBI:
        return "block_jacobi";
    case PcgPreconditioner::AMG:
        return "amg";
    }
    return "unknown";
}

} // namespace coro
