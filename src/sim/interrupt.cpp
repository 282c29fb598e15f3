#include <corocontact/sim/interrupt.hpp>

#include <csignal>

#include <signal.h>

namespace coro {

namespace {
std::atomic<int> g_stop_signal{0};
static_assert(std::atomic<int>::is_always_lock_free, "the stop flag is set from a signal handler");

extern "C" void record_stop_signal(int signal_number)
{
    int expected = 0;
    g_stop_signal.compare_exchange_strong(expected, signal_number);
}
} // namespace

std::atomic<int>& stop_signal() { return g_stop_signal; }

void install_stop_signal_handlers()
{
    struct sigaction action {};
    action.sa_handler = record_stop_signal;
    sigemptyset(&action.sa_mask);
    action.sa_flags = SA_RESTART | SA_RESETHAND; // file I/O continues; a second signal kills
    sigaction(SIGINT, &action, nullptr);
    sigaction(SIGTERM, &action, nullptr);
}

} // namespace coro
