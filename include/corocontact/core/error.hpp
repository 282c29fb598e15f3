#pragma once
/// @file error.hpp
/// @brief Exceptions and checking macros.
///
/// Bad input (files, case TOML, meshes, options) throws InputError; the message gives the
/// input location first (`path:line`, body, element), then the failed condition. Non-finite
/// numbers and degenerate elements throw NumericalError. For developers, the messages of
/// CORO_CHECK and CORO_THROW can end in their source location (` [case_reader.cpp:353]`):
/// see set_source_locations_shown().

#include <cstdint>
#include <sstream>
#include <stdexcept>
#include <string>

namespace coro {

/// Bad input: the command line maps it to exit code 2.
class InputError : public std::runtime_error {
public:
    using std::runtime_error::runtime_error;
};

/// The output could not be written (disk full, no permission, the output folder in use by
/// another run): the command line maps it to exit code 4. The message names the path and the
/// system's reason.
class OutputError : public std::runtime_error {
public:
    using std::runtime_error::runtime_error;
};

/// A numerical failure (NaN, Inf, an inverted element): in a time loop it means divergence
/// and maps to exit code 3.
class NumericalError : public std::runtime_error {
public:
    using std::runtime_error::runtime_error;
    /// A failure found in one body: `body` indexes the bodies of the scene it was found in (so
    /// that of several processes' failures the one of the first body in case order is told).
    NumericalError(const std::string& message, std::int32_t body) : std::runtime_error(message), m_body(body) {}
    /// The body of the failure, −1 when it concerns none.
    std::int32_t body() const { return m_body; }

private:
    std::int32_t m_body = -1;
};

/// Whether the messages of CORO_CHECK / CORO_THROW end in ` [file.cpp:line]`. Initially on
/// when the environment variable CORO_DEBUG is set to anything but "" or "0", else off (users
/// read the input location, not ours). Affects exceptions thrown after the call; thread-safe.
void set_source_locations_shown(bool shown);
/// The current setting of set_source_locations_shown().
bool source_locations_shown();

namespace detail {
/// Builds "message [file:line]" for the macros below, or returns `message` unchanged when
/// source_locations_shown() is false.
std::string with_source_location(const std::string& message, const char* file, int line);
} // namespace detail

} // namespace coro

/// Throws `Err` with a streamed message when `cond` is false; stays on in Release.
/// Usage: CORO_CHECK(n > 0, InputError, path << ":" << line << ": expected n > 0, got " << n);
#define CORO_CHECK(cond, Err, msg)                                                           \
    do {                                                                                     \
        if (!(cond)) {                                                                       \
            std::ostringstream coro_check_stream_;                                           \
            coro_check_stream_ << msg;                                                       \
            throw ::coro::Err(::coro::detail::with_source_location(coro_check_stream_.str(), \
                                                                   __FILE__, __LINE__));     \
        }                                                                                    \
    } while (false)

/// Throws `Err` with a streamed message unconditionally.
#define CORO_THROW(Err, msg) CORO_CHECK(false, Err, msg)

/// Programming-error check, compiled only in Debug builds.
#ifndef NDEBUG
#define CORO_ASSERT(cond)                                                                      \
    do {                                                                                       \
        if (!(cond))                                                                           \
            throw std::logic_error(::coro::detail::with_source_location(                       \
                "assertion failed: " #cond, __FILE__, __LINE__));                              \
    } while (false)
#else
#define CORO_ASSERT(cond) ((void)0)
#endif
