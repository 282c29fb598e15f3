#pragma once
/// @file interrupt.hpp
/// @brief SIGINT/SIGTERM as a request to stop: the handler only records the signal, and the
/// time loop (Simulation::run with RunControl::stop) finishes its step, writes that step's
/// frame and returns, so the series and the summary stay complete.

#include <atomic>

namespace coro {

/// Installs handlers for SIGINT and SIGTERM that store the signal number in stop_signal().
/// The handlers are one-shot (SA_RESETHAND): a second signal of the same kind terminates the
/// process at once, as if no handler were installed. Call from the main thread, once; a
/// failing sigaction() leaves the default action in place.
void install_stop_signal_handlers();

/// 0 while no stop was requested, else the number of the first signal received. Lock-free, so
/// a signal handler may set it.
std::atomic<int>& stop_signal();

} // namespace coro
