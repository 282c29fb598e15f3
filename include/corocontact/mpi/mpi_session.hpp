#pragma once
/// @file mpi_session.hpp
/// @brief MPI for the lifetime of a process, and the Communicator over MPI_COMM_WORLD.
///
/// Built only with CORO_WITH_MPI. MPI is started only when an MPI launcher (mpirun, mpiexec,
/// srun) started the process, which it tells through its environment (OMPI_COMM_WORLD_SIZE,
/// PMIX_RANK, PMI_SIZE): a process started alone runs without MPI and pays nothing for it (an
/// MPI singleton start costs 0.5 to 2 s here).

#include <corocontact/core/communicator.hpp>

#include <memory>

namespace coro {

class MpiSession {
public:
    /// MPI_Init_thread with MPI_THREAD_FUNNELED (only the main thread communicates) when the
    /// process was started by an MPI launcher; otherwise nothing.
    /// @throws std::runtime_error if MPI cannot give that thread level
    MpiSession(int& argc, char**& argv);
    /// MPI_Finalize, when MPI was started.
    ~MpiSession();
    MpiSession(const MpiSession&) = delete;
    MpiSession& operator=(const MpiSession&) = delete;

    /// The processes of the run (MPI_COMM_WORLD), or null when the process runs without MPI.
    /// Owned by the session.
    Communicator* communicator() { return m_communicator.get(); }

private:
    std::unique_ptr<Communicator> m_communicator;
};

/// Whether the environment shows that an MPI launcher started this process.
bool started_by_mpi_launcher();

} // namespace coro
