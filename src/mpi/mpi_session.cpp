#include <corocontact/mpi/mpi_session.hpp>

#include <mpi.h>

#include <climits>
#include <cstdlib>
#include <cstring>
#include <stdexcept>
#include <string>

namespace coro {

namespace {

constexpr int TAG_BYTES = 1;  // variable-size messages (exchange of bytes)
constexpr int TAG_VALUES = 2; // known-size messages (the halo)

int as_count(std::size_t size, const char* what)
{
    if (size > static_cast<std::size_t>(INT_MAX))
        throw std::length_error(std::string("MPI: a message of ") + what + " holds " + std::to_string(size) +
                                " items, more than one MPI call can send");
    return static_cast<int>(size);
}

std::size_t at(int i) { return static_cast<std::size_t>(i); }

/// Communicator over MPI_COMM_WORLD: each operation is one or two MPI calls.
class MpiCommunicator final : public Communicator {
public:
    MpiCommunicator()
    {
        MPI_Comm_rank(MPI_COMM_WORLD, &m_rank);
        MPI_Comm_size(MPI_COMM_WORLD, &m_size);
    }

    int rank() const override { return m_rank; }
    int size() const override { return m_size; }

    void all_gather(const double* send, int count, double* receive, const int* counts,
                    const int* displacements) override
    {
        MPI_Allgatherv(send, count, MPI_DOUBLE, receive, counts, displacements, MPI_DOUBLE, MPI_COMM_WORLD);
        for (int r = 0; r < m_size; ++r)
            if (r != m_rank)
                m_bytes += sizeof(double) * static_cast<std::uint64_t>(counts[r]);
    }

    std::vector<std::vector<char>> all_gather(const std::vector<char>& send) override
    {
        std::vector<int> counts(at(m_size)), displacements(at(m_size));
        const int count = as_count(send.size(), "bytes");
        MPI_Allgather(&count, 1, MPI_INT, counts.data(), 1, MPI_INT, MPI_COMM_WORLD);
        std::vector<char> all(total(counts, displacements));
        MPI_Allgatherv(send.data(), count, MPI_BYTE, all.data(), counts.data(), displacements.data(), MPI_BYTE,
                       MPI_COMM_WORLD);
        count_received(counts);
        return split(all, counts, displacements);
    }

    std::vector<std::vector<char>> gather(const std::vector<char>& send, int root) override
    {
        std::vector<int> counts(at(m_size)), displacements(at(m_size));
        const int count = as_count(send.size(), "bytes");
        MPI_Gather(&count, 1, MPI_INT, counts.data(), 1, MPI_INT, root, MPI_COMM_WORLD);
        std::vector<char> all(m_rank == root ? total(counts, displacements) : 0);
        MPI_Gatherv(send.data(), count, MPI_BYTE, all.data(), counts.data(), displacements.data(), MPI_BYTE, root,
                    MPI_COMM_WORLD);
        if (m_rank != root)
            return {};
        count_received(counts);
        return split(all, counts, displacements);
    }

    void broadcast(std::vector<char>& bytes, int root) override
    {
        int count = m_rank == root ? as_count(bytes.size(), "bytes") : 0;
        MPI_Bcast(&count, 1, MPI_INT, root, MPI_COMM_WORLD);
        bytes.resize(at(count));
        MPI_Bcast(bytes.data(), count, MPI_BYTE, root, MPI_COMM_WORLD);
        if (m_rank != root)
            m_bytes += static_cast<std::uint64_t>(count);
    }

    void all_reduce(std::int64_t* values, int count, Reduction reduction) override
    {
        MPI_Allreduce(MPI_IN_PLACE, values, count, MPI_INT64_T, operation(reduction), MPI_COMM_WORLD);
        m_bytes += sizeof(std::int64_t) * static_cast<std::uint64_t>(count);
    }

    void all_reduce(double* values, int count, Reduction reduction) override
    {
        if (reduction == Reduction::SUM)
            throw std::logic_error("Communicator::all_reduce: a floating-point sum over processes depends on "
                                   "their number; add gathered values in a fixed order instead");
        MPI_Allreduce(MPI_IN_PLACE, values, count, MPI_DOUBLE, operation(reduction), MPI_COMM_WORLD);
        m_bytes += sizeof(double) * static_cast<std::uint64_t>(count);
    }

    void exchange(const std::vector<std::vector<char>>& send, std::vector<std::vector<char>>& receive) override
    {
        std::vector<int> send_counts(at(m_size)), receive_counts(at(m_size));
        for (int r = 0; r < m_size; ++r)
            send_counts[at(r)] = as_count(send[at(r)].size(), "bytes");
        MPI_Alltoall(send_counts.data(), 1, MPI_INT, receive_counts.data(), 1, MPI_INT, MPI_COMM_WORLD);
        receive.resize(at(m_size));
        m_requests.clear();
        for (int r = 0; r < m_size; ++r) {
            receive[at(r)].resize(at(receive_counts[at(r)]));
            if (r == m_rank || receive_counts[at(r)] == 0)
                continue;
            m_requests.emplace_back();
            MPI_Irecv(receive[at(r)].data(), receive_counts[at(r)], MPI_BYTE, r, TAG_BYTES, MPI_COMM_WORLD,
                      &m_requests.back());
            m_bytes += static_cast<std::uint64_t>(receive_counts[at(r)]);
        }
        for (int r = 0; r < m_size; ++r) {
            if (r == m_rank || send_counts[at(r)] == 0)
                continue;
            m_requests.emplace_back();
            MPI_Isend(send[at(r)].data(), send_counts[at(r)], MPI_BYTE, r, TAG_BYTES, MPI_COMM_WORLD,
                      &m_requests.back());
        }
        receive[at(m_rank)] = send[at(m_rank)];
        MPI_Waitall(static_cast<int>(m_requests.size()), m_requests.data(), MPI_STATUSES_IGNORE);
    }

    void exchange(const std::vector<int>& ranks, const std::vector<std::vector<double>>& send,
                  std::vector<std::vector<double>>& receive) override
    {
        const std::size_t n = ranks.size();
        m_requests.resize(2 * n);
        for (std::size_t i = 0; i < n; ++i) {
            MPI_Irecv(receive[i].data(), as_count(receive[i].size(), "values"), MPI_DOUBLE, ranks[i], TAG_VALUES,
                      MPI_COMM_WORLD, &m_requests[i]);
            m_bytes += sizeof(double) * static_cast<std::uint64_t>(receive[i].size());
        }
        for (std::size_t i = 0; i < n; ++i)
            MPI_Isend(send[i].data(), as_count(send[i].size(), "values"), MPI_DOUBLE, ranks[i], TAG_VALUES,
                      MPI_COMM_WORLD, &m_requests[n + i]);
        m_statuses.resize(2 * n);
        MPI_Waitall(static_cast<int>(2 * n), m_requests.data(), m_statuses.data());
        for (std::size_t i = 0; i < n; ++i) {
            int count = 0;
            MPI_Get_count(&m_statuses[i], MPI_DOUBLE, &count);
            if (at(count) != receive[i].size())
                throw std::logic_error("Communicator::exchange: rank " + std::to_string(ranks[i]) + " sent " +
                                       std::to_string(count) + " values, " + std::to_string(receive[i].size()) +
                                       " expected");
        }
    }

    std::uint64_t bytes_received() const override { return m_bytes; }

private:
    static MPI_Op operation(Reduction reduction)
    {
        switch (reduction) {
        case Reduction::SUM: return MPI_SUM;
        case Reduction::MIN: return MPI_MIN;
        case Reduction::MAX: return MPI_MAX;
        }
        return MPI_SUM;
    }

    /// Fills the displacements of `counts` and returns their total.
    static std::size_t total(const std::vector<int>& counts, std::vector<int>& displacements)
    {
        std::size_t sum = 0;
        for (std::size_t r = 0; r < counts.size(); ++r) {
            displacements[r] = as_count(sum, "bytes");
            sum += at(counts[r]);
        }
        return sum;
    }

    static std::vector<std::vector<char>> split(const std::vector<char>& all, const std::vector<int>& counts,
                                                const std::vector<int>& displacements)
    {
        std::vector<std::vector<char>> parts(counts.size());
        for (std::size_t r = 0; r < counts.size(); ++r)
            parts[r].assign(all.begin() + displacements[r], all.begin() + displacements[r] + counts[r]);
        return parts;
    }

    void count_received(const std::vector<int>& counts)
    {
        for (int r = 0; r < m_size; ++r)
            if (r != m_rank)
                m_bytes += static_cast<std::uint64_t>(counts[at(r)]);
    }

    int m_rank = 0;
    int m_size = 1;
    std::uint64_t m_bytes = 0;
    std::vector<MPI_Request> m_requests;
    std::vector<MPI_Status> m_statuses;
};

} // namespace

bool started_by_mpi_launcher()
{
    for (const char* variable : {"OMPI_COMM_WORLD_SIZE", "PMIX_RANK", "PMI_SIZE"})
        if (std::getenv(variable) != nullptr)
            return true;
    return false;
}

MpiSession::MpiSession(int& argc, char**& argv)
{
    if (!started_by_mpi_launcher())
        return;
    int provided = MPI_THREAD_SINGLE;
    MPI_Init_thread(&argc, &argv, MPI_THREAD_FUNNELED, &provided);
    if (provided < MPI_THREAD_FUNNELED) {
        MPI_Finalize();
        throw std::runtime_error("MPI: this MPI library gives no MPI_THREAD_FUNNELED support, which the TBB "
                                 "threads next to MPI need");
    }
    m_communicator = std::make_unique<MpiCommunicator>();
}

MpiSession::~MpiSession()
{
    if (!m_communicator)
        return;
    m_communicator.reset();
    MPI_Finalize();
}

} // namespace coro
