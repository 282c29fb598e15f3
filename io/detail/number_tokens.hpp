#pragma once
// Private to io/: whitespace-separated numbers of one text line, for the tet mesh readers.

#include "text_input.hpp"

#include <corocontact/core/error.hpp>

#include <charconv>
#include <cmath>
#include <cstdint>
#include <string_view>
#include <system_error>

namespace coro::detail {

/// Whitespace-separated tokens of one line, parsed with std::from_chars.
class NumberTokens : public LineTokens {
public:
    using LineTokens::LineTokens;

    /// A non-negative integer (tags, counts).
    std::uint64_t next_count(std::string_view what)
    {
        return parse_integer<std::uint64_t>(next(what), what, "a non-negative integer");
    }

    /// An int (possibly negative).
    int next_int(std::string_view what)
    {
        return parse_integer<int>(next(what), what, "an integer");
    }

    /// A finite double; a leading '+' is accepted.
    double next_double(std::string_view what)
    {
        std::string_view token = next(what);
        const std::string_view shown = token;
        if (token.size() > 1 && token.front() == '+' && token[1] != '-')
            token.remove_prefix(1); // from_chars rejects the '+' that printf-style writers emit
        double value = 0.0;
        const auto [end, ec] = std::from_chars(token.data(), token.data() + token.size(), value);
        CORO_CHECK(ec != std::errc::result_out_of_range, InputError,
                   cursor().where() << ": expected " << what << ", found " << in_quotes(shown)
                                    << " (out of the range of double)");
        CORO_CHECK(ec == std::errc() && end == token.data() + token.size() && std::isfinite(value),
                   InputError,
                   cursor().where() << ": expected " << what << " (a finite number), found "
                                    << in_quotes(shown));
        return value;
    }

private:
    template <class T>
    T parse_integer(std::string_view token, std::string_view what, std::string_view kind) const
    {
        T value{};
        const auto [end, ec] = std::from_chars(token.data(), token.data() + token.size(), value);
        CORO_CHECK(ec != std::errc::result_out_of_range, InputError,
                   cursor().where() << ": expected " << what << ", found " << in_quotes(token)
                                    << " (too large)");
        CORO_CHECK(ec == std::errc() && end == token.data() + token.size(), InputError,
                   cursor().where() << ": expected " << what << " (" << kind << "), found "
                                    << in_quotes(token));
        return value;
    }
};

} // namespace coro::detail
