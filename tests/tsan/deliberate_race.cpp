// A real data race inside a tbb::parallel_for body, for the TSan build only: proves that the
// TBB support of tools/tsan (ITT collector, hooks, tools/tsan.supp) does not hide races in our
// code. Two iterations, run by two threads at the same time, write one plain int. The ctest
// `tsan.DeliberateRace` passes only if ThreadSanitizer reports that write (tests/tsan/CMakeLists.txt).
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

// Each iteration waits (relaxed atomics: no happens-before for TSan) until both have started,
// so that two threads run them, then writes g_shared. Returns false if no second thread came.
bool deliberate_race()
{
    std::atomic<int> started{0};
    std::atomic<bool> both{false};
    tbb::parallel_for(
        tbb::blocked_range<int>(0, 2, 1),
        [&](const tbb::blocked_range<int>& r) {
            started.fetch_add(1, std::memory_order_relaxed);
            const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(30);
            while (started.load(std::memory_order_relaxed) < 2 && std::chrono::steady_clock::now() < deadline)
                std::this_thread::yield();
            if (started.load(std::memory_order_relaxed) == 2)
                both.store(true, std::memory_order_relaxed);
            g_shared = r.begin(); // the race
        },
        tbb::simple_partitioner());
    return both.load(std::memory_order_relaxed);
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
