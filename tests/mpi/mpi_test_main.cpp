// GoogleTest main of the MPI suites, run under mpirun: MPI is started before the tests and ended
// after them. Rank 0 prints the usual report; the other ranks print only their failures, with
// their rank. `--threads N` sets the TBB thread count of every rank.
#include "mpi_test_env.hpp"

#include <corocontact/mpi/mpi_session.hpp>

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <cstdio>
#include <cstring>
#include <memory>
#include <string>

namespace {

coro::Communicator* g_world = nullptr;

/// Prints failed assertions with the rank, for ranks other than 0.
class RankFailurePrinter : public ::testing::EmptyTestEventListener {
public:
    explicit RankFailurePrinter(int rank) : m_rank(rank) {}
    void OnTestPartResult(const ::testing::TestPartResult& result) override
    {
        if (result.failed())
            std::fprintf(stderr, "[rank %d] %s:%d: failure\n%s\n", m_rank, result.file_name() ? result.file_name() : "?",
                         result.line_number(), result.summary());
    }

private:
    int m_rank;
};

} // namespace

coro::Communicator& coro::test::world() { return *g_world; }

int main(int argc, char** argv)
{
    coro::MpiSession session(argc, argv);
    if (session.communicator() == nullptr) {
        std::fprintf(stderr, "%s: run me under mpirun (e.g. mpirun -np 2 %s)\n", argv[0], argv[0]);
        return 1;
    }
    g_world = session.communicator();
    ::testing::InitGoogleTest(&argc, argv);
    std::unique_ptr<tbb::global_control> threads;
    for (int i = 1; i + 1 < argc; ++i)
        if (std::strcmp(argv[i], "--threads") == 0)
            threads = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism,
                                                            static_cast<std::size_t>(std::stoul(argv[i + 1])));
    if (g_world->rank() != 0) {
        ::testing::TestEventListeners& listeners = ::testing::UnitTest::GetInstance()->listeners();
        delete listeners.Release(listeners.default_result_printer());
        listeners.Append(new RankFailurePrinter(g_world->rank()));
    }
    return RUN_ALL_TESTS();
}
