#pragma once
// The processes of an MPI test run (mpi_test_main.cpp starts MPI before the tests).

#include <corocontact/core/communicator.hpp>

namespace coro::test {

/// MPI_COMM_WORLD of the test run.
Communicator& world();

} // namespace coro::test
