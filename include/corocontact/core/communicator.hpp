#pragma once
/// @file communicator.hpp
/// @brief The processes of a distributed run and the few operations by which they exchange
/// data, behind our own interface (DESIGN.md, "Beyond one machine: OpenMPI").
///
/// The one implementation is MPI's (include/corocontact/mpi/mpi_session.hpp, built with
/// CORO_WITH_MPI): src/mpi/ is the only code that includes mpi.h, so everything else builds and
/// runs without MPI. Every operation is collective unless it says otherwise: all processes call
/// it, in the same order. Calls come from one thread at a time (the main thread; TBB workers
/// never communicate). Nothing here sums floating-point numbers across processes: results that
/// must not depend on the process count are added by the caller in a fixed order.

#include <cstdint>
#include <vector>

namespace coro {

/// Element-wise reductions over the processes.
enum class Reduction { SUM, MIN, MAX };

class Communicator {
public:
    virtual ~Communicator() = default;

    /// This process's rank in [0, size()).
    virtual int rank() const = 0;
    /// Number of processes.
    virtual int size() const = 0;

    /// Every process's `count` values, concatenated in rank order: rank r's land at
    /// receive[displacements[r]], counts[r] of them (counts[rank()] == count).
    virtual void all_gather(const double* send, int count, double* receive, const int* counts,
                            const int* displacements) = 0;

    /// Every process's bytes, in rank order (sizes may differ).
    virtual std::vector<std::vector<char>> all_gather(const std::vector<char>& send) = 0;

    /// Every process's bytes on `root`, in rank order; the other processes get an empty list.
    virtual std::vector<std::vector<char>> gather(const std::vector<char>& send, int root) = 0;

    /// `root`'s bytes on every process (`bytes` is resized on the others).
    virtual void broadcast(std::vector<char>& bytes, int root) = 0;

    /// values[i] = reduction over the processes of values[i], on every process.
    virtual void all_reduce(std::int64_t* values, int count, Reduction reduction) = 0;
    /// Only MIN and MAX: a floating-point SUM would depend on the process count.
    virtual void all_reduce(double* values, int count, Reduction reduction) = 0;

    /// Sparse exchange of byte messages of any size: send[r] goes to rank r (an empty message
    /// costs no transfer), receive[r] is what rank r sent to this one. #size() each; a message
    /// to oneself is copied.
    virtual void exchange(const std::vector<std::vector<char>>& send, std::vector<std::vector<char>>& receive) = 0;

    /// Exchange with known partners and sizes (the halo of an iteration): send[i] goes to
    /// ranks[i], receive[i] comes from ranks[i] and must already have the size that partner
    /// sends. Only the processes named in each other's `ranks` take part (not collective); a
    /// rank appears at most once and never as this process.
    virtual void exchange(const std::vector<int>& ranks, const std::vector<std::vector<double>>& send,
                          std::vector<std::vector<double>>& receive) = 0;

    /// Payload bytes this process has received from the others so far (messages to itself and
    /// the counts that precede variable-size messages not included).
    virtual std::uint64_t bytes_received() const = 0;
};

} // namespace coro
