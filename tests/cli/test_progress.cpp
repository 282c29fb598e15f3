// The progress line of `corocontact run` (tools/progress.hpp): it fits the terminal, and its
// ETA follows the recent steps; not on a terminal, a long loading stage is named when it ends.

#include "progress.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <string>

using coro::cli::progress_line;
using coro::cli::RecentRate;
using ::testing::HasSubstr;
using ::testing::MatchesRegex;
using ::testing::StartsWith;

TEST(ProgressLine, NeverAsWideAsTheTerminal)
{
    for (int width = 0; width <= 200; ++width)
        for (const auto& [done, total] : {std::pair<long, long>{0, 10}, {7, 200}, {1234567, 99999999}, {5, 5}})
            for (const double eta : {-1.0, 3.0, 4000.0, 1e7}) {
                const std::string line = progress_line(done, total, 12345.0, eta, width);
                EXPECT_LE(static_cast<int>(line.size()), std::max(0, width - 1))
                    << "width " << width << ": '" << line << "'";
            }
}

TEST(ProgressLine, ShowsBarStepAndEtaWhenThereIsRoom)
{
    const std::string line = progress_line(84, 200, 62.0, 80.0, 120);
    EXPECT_THAT(line, StartsWith("[############                  ]  42%  step 84/200  1 min 02 s  ETA 1 min 20 s"));
    const std::string narrow = progress_line(84, 200, 62.0, 80.0, 60);
    EXPECT_THAT(narrow, StartsWith("[")); // a shorter bar
    EXPECT_THAT(progress_line(84, 200, 62.0, 80.0, 40), StartsWith(" 42%  step 84/200")); // no bar
    EXPECT_THAT(progress_line(1, 200, 0.5, -1.0, 120), HasSubstr("ETA --"));
}

TEST(RecentRate, FollowsStepsThatSlowDown)
{
    // 100 steps of 0.01 s, then 300 of 0.05 s (contact started): 600 steps left at 0.05 s.
    RecentRate rate(10.0);
    double t = 0.0;
    long done = 0;
    rate.add(t, done);
    for (; done < 100;)
        rate.add(t += 0.01, ++done);
    for (; done < 400;)
        rate.add(t += 0.05, ++done);
    EXPECT_NEAR(rate.remaining(1000), 600 * 0.05, 1e-6);
    // The whole run's average rate (400 steps in 16 s) would have promised 24 s.
    EXPECT_NEAR(600 * t / done, 24.0, 1e-6);
}

TEST(RecentRate, UnknownBeforeTwoSamples)
{
    RecentRate rate;
    EXPECT_LT(rate.remaining(10), 0.0);
    rate.add(0.0, 0);
    EXPECT_LT(rate.remaining(10), 0.0);
    rate.add(1.0, 2);
    EXPECT_NEAR(rate.remaining(10), 4.0, 1e-12);
}

TEST(Progress, TerminalRedrawsOneLineCutToTheWidth)
{
    std::FILE* out = std::tmpfile();
    ASSERT_NE(out, nullptr);
    setenv("COLUMNS", "40", 1); // a file has no window size: the width comes from $COLUMNS
    {
        coro::cli::Progress progress(true, true, out);
        progress.status("body 'a rather long body name' (1 of 1): METIS parts and element set-up");
        progress.clear();
        progress.start_steps();
        for (long step = 1; step <= 3; ++step)
            progress.update(step, 3);
    }
    unsetenv("COLUMNS");
    std::rewind(out);
    std::string text;
    for (int c; (c = std::fgetc(out)) != EOF;)
        text += static_cast<char>(c);
    std::fclose(out);
    EXPECT_THAT(text, HasSubstr("loading: body 'a rather long"));
    EXPECT_THAT(text, HasSubstr("step 3/3"));
    EXPECT_EQ(text.back(), '\n');
    // Every drawn line (between carriage returns, without the clear-to-end escape) fits.
    std::size_t start = 0;
    while (start < text.size()) {
        std::size_t end = text.find('\r', start + 1);
        std::string line = text.substr(start, end == std::string::npos ? std::string::npos : end - start);
        for (const std::string& strip : {std::string("\r"), std::string("\033[K"), std::string("\n")})
            for (std::size_t at; (at = line.find(strip)) != std::string::npos;)
                line.erase(at, strip.size());
        EXPECT_LE(line.size(), 39u) << "'" << line << "'";
        start = end == std::string::npos ? text.size() : end;
    }
}

namespace {

/// What a Progress that is not on a terminal prints for two loading stages, when a stage
/// counts as long from `long_stage_s` seconds on.
std::string plain_loading_lines(double long_stage_s)
{
    std::FILE* out = std::tmpfile();
    if (out == nullptr)
        return "no temporary file";
    {
        coro::cli::Progress progress(true, false, out, long_stage_s);
        progress.status("body 'box' (1 of 1): meshing");
        progress.status("body 'box' (1 of 1): METIS parts and element set-up, 48 tets");
        progress.clear();
    }
    std::rewind(out);
    std::string text;
    for (int c; (c = std::fgetc(out)) != EOF;)
        text += static_cast<char>(c);
    std::fclose(out);
    return text;
}

} // namespace

TEST(Progress, NotOnATerminalALongLoadingStageGetsALineWhenItEnds)
{
    // Every stage counts as long: one plain line each, with its time, the last one at clear().
    const std::string text = plain_loading_lines(0.0);
    EXPECT_THAT(text, MatchesRegex("loading: body 'box' \\(1 of 1\\): meshing: [0-9.]+ s\n"
                                   "loading: body 'box' \\(1 of 1\\): METIS parts and element set-up, 48 tets: "
                                   "[0-9.]+ s\n"));
    // Short stages stay silent.
    EXPECT_EQ(plain_loading_lines(1e9), "");
}
