#pragma once
// Progress of a run on stderr: on a terminal one line, redrawn in place and cut to the
// terminal's width; otherwise (a log, a pipe) plain lines: a loading stage that took long when
// it ends, a step line at most every 5 s. The ETA comes from the steps of the last few seconds,
// so a run whose steps slow down (contact starting) is not promised an early end.

#include <sys/ioctl.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <deque>
#include <string>
#include <utility>

namespace coro::cli {

/// Columns of the terminal on `fd`; else $COLUMNS; else 80.
inline int terminal_width(int fd)
{
    winsize size{};
    if (ioctl(fd, TIOCGWINSZ, &size) == 0 && size.ws_col > 0)
        return size.ws_col;
    if (const char* columns = std::getenv("COLUMNS")) {
        const int value = std::atoi(columns);
        if (value > 0)
            return value;
    }
    return 80;
}

/// "4.2 s", "12 s", "3 min 05 s", "2 h 07 min".
inline std::string format_seconds(double s)
{
    char buffer[32];
    const long whole = static_cast<long>(std::max(0.0, s) + 0.5);
    if (s < 9.95)
        std::snprintf(buffer, sizeof buffer, "%.1f s", std::max(0.0, s));
    else if (whole < 60)
        std::snprintf(buffer, sizeof buffer, "%ld s", whole);
    else if (whole < 3600)
        std::snprintf(buffer, sizeof buffer, "%ld min %02ld s", whole / 60, whole % 60);
    else
        std::snprintf(buffer, sizeof buffer, "%ld h %02ld min", whole / 3600, whole % 3600 / 60);
    return buffer;
}

/// Time left from the rate of the recent steps: the samples of the last `window` seconds (at
/// least the last two samples) give steps per second.
class RecentRate {
public:
    explicit RecentRate(double window_s = 10.0) : m_window(window_s) {}

    /// `done` steps were complete at time `t` [s] (t and done non-decreasing).
    void add(double t, long done)
    {
        m_samples.emplace_back(t, done);
        while (m_samples.size() > 2 && t - m_samples[1].first >= m_window)
            m_samples.pop_front();
    }

    /// Seconds until `total` at the recent rate; negative when unknown (fewer than two samples
    /// or no step in the window).
    double remaining(long total) const
    {
        if (m_samples.size() < 2)
            return -1.0;
        const auto& [t0, done0] = m_samples.front();
        const auto& [t1, done1] = m_samples.back();
        if (done1 <= done0 || t1 <= t0)
            return -1.0;
        return static_cast<double>(total - done1) * (t1 - t0) / static_cast<double>(done1 - done0);
    }

private:
    double m_window;
    std::deque<std::pair<double, long>> m_samples;
};

/// The terminal line: "[####    ]  42%  step 84/200  1.2 s  ETA 3 s", at most `width` − 1
/// characters (a line as wide as the terminal wraps on some terminals): the bar shrinks first,
/// then goes, then the text is cut.
inline std::string progress_line(long done, long total, double elapsed_s, double eta_s, int width)
{
    const long percent = total > 0 ? 100 * done / total : 0;
    char text[160];
    std::snprintf(text, sizeof text, " %3ld%%  step %ld/%ld  %s  ETA %s", percent, done, total,
                  format_seconds(elapsed_s).c_str(), eta_s < 0.0 ? "--" : format_seconds(eta_s).c_str());
    std::string line = text;
    const int room = std::max(0, width - 1);
    const int bar = std::min(30, room - static_cast<int>(line.size()) - 2);
    if (bar >= 5) {
        const int filled = total > 0 ? static_cast<int>(bar * done / total) : 0;
        line = "[" + std::string(static_cast<std::size_t>(filled), '#') +
               std::string(static_cast<std::size_t>(bar - filled), ' ') + "]" + line;
    } else if (!line.empty()) {
        line.erase(0, 1); // the space that separated it from the bar
    }
    if (static_cast<int>(line.size()) > room)
        line.resize(static_cast<std::size_t>(room));
    return line;
}

class Progress {
public:
    using Clock = std::chrono::steady_clock;

    /// @param[in] enabled        false with --quiet: nothing is printed
    /// @param[in] terminal       whether `out` is a terminal
    /// @param[in] long_stage_s   not on a terminal, a loading stage that took at least this
    ///                           long [s] gets a line when it ends
    Progress(bool enabled, bool terminal, std::FILE* out = stderr, double long_stage_s = 2.0)
        : m_enabled(enabled), m_terminal(terminal), m_out(out), m_long_stage_s(long_stage_s)
    {
    }

    /// Steps done before this process started (a restarted run).
    void set_first(long first) { m_first = first; }

    /// What is being done before the first step (loading a body, building trees); the stage
    /// before it has ended. On a terminal it replaces the line (no clock: it would stand still
    /// until the next stage); otherwise the stage that ended gets a plain line if it was long.
    void status(const std::string& what)
    {
        if (!m_enabled)
            return;
        end_stage();
        m_stage = what;
        m_stage_start = Clock::now();
        if (m_terminal)
            draw(cut("loading: " + what, terminal_width(fileno(m_out)) - 1));
    }

    /// The time loop starts now: elapsed time and ETA count from here.
    void start_steps()
    {
        m_start = m_last_print = Clock::now();
        m_rate = RecentRate();
        m_rate.add(0.0, m_first);
    }

    /// Loading has ended: removes a status line from the terminal (before other messages are
    /// printed), or reports the last stage if it was long.
    void clear()
    {
        if (m_enabled)
            end_stage();
        if (m_pending_newline)
            std::fputs("\r\033[K", m_out);
        m_pending_newline = false;
        std::fflush(m_out);
    }

    /// Ends a line left without its newline (a run stopped early).
    void finish()
    {
        if (m_pending_newline)
            std::fputc('\n', m_out);
        m_pending_newline = false;
        std::fflush(m_out);
    }

    void update(long done, long total)
    {
        if (!m_enabled || total <= 0)
            return;
        const auto now = Clock::now();
        const double elapsed = seconds(m_start, now);
        m_rate.add(elapsed, done);
        const double since_print = seconds(m_last_print, now);
        const bool last = done == total;
        if (m_terminal) {
            if (since_print < 0.1 && !last)
                return;
            draw(progress_line(done, total, elapsed, m_rate.remaining(total), terminal_width(fileno(m_out))));
            if (last)
                finish();
        } else {
            if (since_print < 5.0 && !last)
                return;
            const double eta = m_rate.remaining(total);
            std::fprintf(m_out, "step %ld/%ld (%ld%%), %s elapsed, ETA %s\n", done, total, 100 * done / total,
                         format_seconds(elapsed).c_str(), eta < 0.0 ? "--" : format_seconds(eta).c_str());
            std::fflush(m_out);
        }
        m_last_print = now;
    }

private:
    static double seconds(Clock::time_point from, Clock::time_point to)
    {
        return std::chrono::duration<double>(to - from).count();
    }

    /// Not on a terminal: "loading: body 'box' (1 of 1): METIS parts and element set-up,
    /// 2058000 tets: 8.8 s" for a stage that took long, when it ends.
    void end_stage()
    {
        if (m_stage.empty())
            return;
        const double took = seconds(m_stage_start, Clock::now());
        if (!m_terminal && took >= m_long_stage_s) {
            std::fprintf(m_out, "loading: %s: %s\n", m_stage.c_str(), format_seconds(took).c_str());
            std::fflush(m_out);
        }
        m_stage.clear();
    }

    /// At most `room` bytes, not ending inside a UTF-8 character (body names may be UTF-8).
    static std::string cut(std::string text, int room)
    {
        std::size_t size = static_cast<std::size_t>(std::max(0, room));
        if (text.size() <= size)
            return text;
        while (size > 0 && (static_cast<unsigned char>(text[size]) & 0xC0) == 0x80)
            --size;
        text.resize(size);
        return text;
    }

    /// Redraws the line in place: carriage return, the text, clear to the end of the line.
    void draw(const std::string& line)
    {
        std::fprintf(m_out, "\r%s\033[K", line.c_str());
        std::fflush(m_out);
        m_pending_newline = true;
    }

    bool m_enabled;
    bool m_terminal;
    std::FILE* m_out;
    double m_long_stage_s;
    std::string m_stage; ///< the loading stage under way, empty if none
    Clock::time_point m_stage_start;
    long m_first = 0;
    bool m_pending_newline = false;
    RecentRate m_rate;
    Clock::time_point m_start = Clock::now();
    Clock::time_point m_last_print = m_start;
};

} // namespace coro::cli
