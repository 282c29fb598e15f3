#pragma once
// Progress of a run on stderr: a bar with ETA on a terminal, plain periodic lines otherwise.

#include <chrono>
#include <cstdio>
#include <string>

namespace coro::cli {

class Progress {
public:
    Progress(bool enabled, bool terminal) : m_enabled(enabled), m_terminal(terminal) {}

    /// Steps done before this process started (a restarted run): the ETA counts from here.
    void set_first(long first) { m_first = first; }

    /// Ends a bar left without its newline (a run stopped early).
    void finish()
    {
        if (m_pending_newline)
            std::fputc('\n', stderr);
        m_pending_newline = false;
    }

    void update(long done, long total)
    {
        if (!m_enabled || total <= 0)
            return;
        const auto now = std::chrono::steady_clock::now();
        const double elapsed = std::chrono::duration<double>(now - m_start).count();
        const double since_print = std::chrono::duration<double>(now - m_last_print).count();
        const bool last = done == total;
        if (m_terminal) {
            if (since_print < 0.1 && !last)
                return;
            const int width = 30;
            const int filled = static_cast<int>(width * done / total);
            const double eta = remaining(elapsed, done, total);
            std::fprintf(stderr, "\r[%s%s] %3ld%%  step %ld/%ld  %.1f s  ETA %s   ",
                         std::string(static_cast<std::size_t>(filled), '#').c_str(),
                         std::string(static_cast<std::size_t>(width - filled), ' ').c_str(),
                         100 * done / total, done, total, elapsed, format_seconds(eta).c_str());
            if (last)
                std::fputc('\n', stderr);
            m_pending_newline = !last;
        } else {
            // Plain lines: at most one every 5 s, plus the last.
            if (since_print < 5.0 && !last)
                return;
            const double eta = remaining(elapsed, done, total);
            std::fprintf(stderr, "step %ld/%ld (%ld%%), %.1f s elapsed, ETA %s\n", done, total,
                         100 * done / total, elapsed, format_seconds(eta).c_str());
        }
        std::fflush(stderr);
        m_last_print = now;
    }

private:
    double remaining(double elapsed, long done, long total) const
    {
        const long here = done - m_first;
        return here > 0 ? elapsed * static_cast<double>(total - done) / static_cast<double>(here) : 0.0;
    }

    static std::string format_seconds(double s)
    {
        char buffer[32];
        if (s < 60)
            std::snprintf(buffer, sizeof buffer, "%.0f s", s);
        else
            std::snprintf(buffer, sizeof buffer, "%d min %02d s", static_cast<int>(s) / 60, static_cast<int>(s) % 60);
        return buffer;
    }

    bool m_enabled;
    bool m_terminal;
    long m_first = 0;
    bool m_pending_newline = false;
    std::chrono::steady_clock::time_point m_start = std::chrono::steady_clock::now();
    std::chrono::steady_clock::time_point m_last_print = m_start;
};

} // namespace coro::cli
