// A real data race inside a tbb::parallel_for body, for the TSan build only: proves that the
// TBB support of tools/tsan (ITT collector, hooks, tools/tsan.supp) does not hide races in our
// code. Two iterations, run by two threads, write one plain int with nothing ordering the
// writes. The ctest `tsan.DeliberateRace` passes only if ThreadSanitizer reports the second
// write (tests/tsan/CMakeLists.txt).
#include <tbb/blocked_range.h>
#include <tbb/global_control.h>
#include <tbb/parallel_for.h>
#include <tbb/partitioner.h>

#include <atomic>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <string>
#include <thread>

namespace {

int g_shared = 0;

// True once libtbb has loaded the ITT collector (it does so when the scheduler starts).
bool itt_collector_loaded()
{
    std::ifstream maps("/proc/self/maps");
    for (std::string line; std::getline(maps, line);)
        if (line.find("coro_tsan_itt") != std::string::npos)
            return true;
    return false;
}

// Waits, with relaxed loads only (no happens-before for TSan), until `done()` or 30 s passed.
template <class Done>
bool spin_until(Done done)
{
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(30);
    while (!done() && std::chrono::steady_clock::now() < deadline)
        std::this_thread::yield();
    return done();
}

// Both iterations first wait until both have started, so that two threads run them. Then
// iteration 0 writes g_shared and iteration 1 writes it after that: not at the same moment,
// which TSan can miss (each thread checks the shadow memory before the other one updates it),
// and still without any synchronisation. Returns false if no second thread came.
bool deliberate_race()
{
    std::atomic<int> started{0};
    std::atomic<bool> first_written{false};
    std::atomic<bool> two_threads{false};
    tbb::parallel_for(
        tbb::blocked_range<int>(0, 2, 1),
        [&](const tbb::blocked_range<int>& r) {
            started.fetch_add(1, std::memory_order_relaxed);
            if (spin_until([&] { return started.load(std::memory_order_relaxed) == 2; }))
                two_threads.store(true, std::memory_order_relaxed);
            if (r.begin() == 0) {
                g_shared = 0;
                std::atomic_signal_fence(std::memory_order_seq_cst); // compiler order only
                first_written.store(true, std::memory_order_relaxed);
            } else {
                spin_until([&] { return first_written.load(std::memory_order_relaxed); });
                g_shared = 1; // the race: nothing orders this write after the first one
            }
        },
        tbb::simple_partitioner());
    return two_threads.load(std::memory_order_relaxed);
}

} // namespace

int main()
{
    const tbb::global_control threads(tbb::global_control::max_allowed_parallelism, 2);
    // Start the scheduler (and with it the ITT collector) with a race-free loop.
    std::atomic<int> sum{0};
    tbb::parallel_for(0, 1000, [&](int i) { sum.fetch_add(i, std::memory_order_relaxed); });
    if (!itt_collector_loaded()) {
        std::fprintf(stderr, "deliberate_race: the ITT collector is not loaded\n");
        return 1;
    }
    std::fprintf(stderr, "deliberate_race: ITT collector loaded\n");
    if (!deliberate_race()) {
        std::fprintf(stderr, "deliberate_race: one thread ran both iterations; nothing to detect\n");
        return 1;
    }
    std::fprintf(stderr, "deliberate_race: done, g_shared = %d\n", g_shared);
    return 0;
}
