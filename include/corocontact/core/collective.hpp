#pragma once
/// @file collective.hpp
/// @brief Failures that every process of a distributed run agrees on: a process that throws
/// while the others go on would leave them waiting in their next exchange.

#include <corocontact/core/communicator.hpp>
#include <corocontact/core/function_ref.hpp>

#include <cstdint>
#include <string>

namespace coro {

/// Runs `work` here and makes its outcome common. If it throws on any process, every process
/// throws: the lowest failing rank its own exception, the others one of the same kind
/// (InputError, OutputError, NumericalError, else std::runtime_error) with that rank's message, so rank 0
/// can report it and every process exits with the same code. Collective; `work` itself must not
/// communicate. Without a communicator (one process) it only runs `work`.
void run_collectively(Communicator* communicator, FunctionRef<void()> work);

/// Throws InputError(`message`) on every process unless `fingerprint` is the same on all: the
/// processes of a run must read the same files with the same options, or their exchanges would
/// mix different scenes or wait for each other forever. Collective; nothing without a
/// communicator.
void require_same_on_every_process(Communicator* communicator, std::uint64_t fingerprint, const std::string& message);

} // namespace coro
