#pragma once
// Private to io/: reading a text input whole and walking its lines with their numbers, for
// readers whose messages say "path:line: expected ..., found ...".

#include <corocontact/core/error.hpp>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <memory>
#include <new>
#include <string>
#include <string_view>
#include <system_error>

namespace coro::detail {

/// Bytes of the well-formed UTF-8 sequence of two to four bytes at the start of `text`, or 0
/// (an ASCII byte, a stray continuation byte, an overlong or surrogate form, a cut sequence).
inline std::size_t utf8_sequence_length(std::string_view text)
{
    const auto byte = [&](std::size_t i) { return static_cast<unsigned char>(text[i]); };
    const unsigned char lead = byte(0);
    std::size_t length = 0;
    unsigned char low = 0x80, high = 0xbf; // the range of the second byte
    if (lead >= 0xc2 && lead <= 0xdf) {
        length = 2;
    } else if (lead >= 0xe0 && lead <= 0xef) {
        length = 3;
        low = lead == 0xe0 ? 0xa0 : 0x80;
        high = lead == 0xed ? 0x9f : 0xbf;
    } else if (lead >= 0xf0 && lead <= 0xf4) {
        length = 4;
        low = lead == 0xf0 ? 0x90 : 0x80;
        high = lead == 0xf4 ? 0x8f : 0xbf;
    }
    if (length == 0 || text.size() < length || byte(1) < low || byte(1) > high)
        return 0;
    for (std::size_t i = 2; i < length; ++i)
        if (byte(i) < 0x80 || byte(i) > 0xbf)
            return 0;
    return length;
}

/// A token or line as it appears in a message: quoted, cut after a few dozen bytes, control
/// bytes and bytes that are not well-formed UTF-8 shown as '?', so binary garbage does not end
/// up in a terminal (UTF-8 text, a name in another script, is shown as it is).
inline std::string in_quotes(std::string_view text)
{
    constexpr std::size_t MAX_SHOWN = 40;
    std::string shown = "'";
    std::size_t i = 0;
    for (; i < std::min(text.size(), MAX_SHOWN); ++i) {
        const auto c = static_cast<unsigned char>(text[i]);
        if (c >= 0x80) {
            const std::size_t length = utf8_sequence_length(text.substr(i));
            if (length == 0) {
                shown += '?';
            } else {
                shown.append(text.substr(i, length));
                i += length - 1;
            }
            continue;
        }
        shown += (c < 0x20 || c == 0x7f) ? '?' : text[i];
    }
    if (i < text.size())
        shown += "...";
    return shown + "'";
}

inline bool is_blank(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f'; }

inline std::string_view trimmed(std::string_view s)
{
    while (!s.empty() && is_blank(s.front()))
        s.remove_prefix(1);
    while (!s.empty() && is_blank(s.back()))
        s.remove_suffix(1);
    return s;
}

/// Reads the whole file; the checks name the file and say what is wrong with it.
/// @param[in] kind  what the file should be, for messages ("mesh file", "surface file")
inline std::string read_file(const std::filesystem::path& path, const char* kind)
{
    std::error_code ec;
    const auto status = std::filesystem::status(path, ec);
    CORO_CHECK(!ec || ec == std::errc::no_such_file_or_directory, InputError,
               path.string() << ": cannot access the " << kind << ": " << ec.message());
    CORO_CHECK(std::filesystem::exists(status), InputError, path.string() << ": " << kind << " does not exist");
    CORO_CHECK(!std::filesystem::is_directory(status), InputError,
               path.string() << ": is a directory, expected a " << kind);
    // A device (/dev/zero, /dev/urandom) would be read without end, and a pipe cannot be read
    // twice, as VTK's readers open the file again.
    CORO_CHECK(std::filesystem::is_regular_file(status), InputError,
               path.string() << ": is not a regular file (a device, pipe or socket), expected a " << kind);
    const std::unique_ptr<std::FILE, int (*)(std::FILE*)> file(std::fopen(path.c_str(), "rb"), &std::fclose);
    CORO_CHECK(file != nullptr, InputError, path.string() << ": cannot open the " << kind << ": " << std::strerror(errno));
    std::string text;
    std::array<char, 1 << 16> buffer{};
    std::size_t n = 0;
    bool out_of_memory = false;
    try {
        while ((n = std::fread(buffer.data(), 1, buffer.size(), file.get())) > 0)
            text.append(buffer.data(), n);
    } catch (const std::bad_alloc&) {
        out_of_memory = true;
    }
    if (out_of_memory) {
        const std::size_t read = text.size();
        std::string().swap(text); // the memory back before the message is made
        CORO_THROW(InputError, path.string() << ": the " << kind << " does not fit in memory (" << read
                                             << " bytes read when an allocation failed)");
    }
    CORO_CHECK(!std::ferror(file.get()), InputError,
               path.string() << ": read error in the " << kind << ": " << std::strerror(errno));
    return text;
}

/// The non-blank lines of a text, trimmed, with their 1-based line numbers; optionally with
/// `#` comments removed. A UTF-8 byte order mark at the start is skipped.
class LineCursor {
public:
    LineCursor(std::string path, std::string_view text, bool hash_comments = false)
        : m_path(std::move(path)), m_text(text), m_hash_comments(hash_comments)
    {
        if (m_text.substr(0, 3) == "\xEF\xBB\xBF")
            m_text.remove_prefix(3);
    }

    /// Advances to the next line with data; false at the end of the text.
    bool next(std::string_view& line)
    {
        while (m_pos < m_text.size()) {
            const std::size_t end = std::min(m_text.find('\n', m_pos), m_text.size());
            line = m_text.substr(m_pos, end - m_pos);
            m_pos = end + 1;
            ++m_line;
            if (m_hash_comments)
                line = line.substr(0, line.find('#'));
            line = trimmed(line);
            if (!line.empty())
                return true;
        }
        return false;
    }

    /// "path:line" of the line last returned (at the end of the text: of the last line).
    std::string where() const { return m_path + ":" + std::to_string(std::max(m_line, 1L)); }
    /// Number of the line last returned.
    long line() const { return m_line; }
    const std::string& path() const { return m_path; }

private:
    std::string m_path;
    std::string_view m_text;
    bool m_hash_comments = false;
    std::size_t m_pos = 0;
    long m_line = 0;
};

/// Whitespace-separated tokens of one line; messages name the cursor's "path:line".
/// Readers derive from it and add their own number parsing.
class LineTokens {
public:
    LineTokens(std::string_view line, const LineCursor& cursor) : m_rest(line), m_cursor(cursor) {}

    /// Number of tokens not yet consumed.
    std::size_t remaining() const
    {
        std::size_t count = 0;
        bool in_token = false;
        for (const char c : m_rest) {
            const bool blank = is_blank(c);
            if (!blank && !in_token)
                ++count;
            in_token = !blank;
        }
        return count;
    }

    /// True when every token was consumed.
    bool empty()
    {
        skip_blanks();
        return m_rest.empty();
    }

    /// The next token; `what` names the expected item in the message at the end of the line.
    std::string_view next(std::string_view what)
    {
        skip_blanks();
        CORO_CHECK(!m_rest.empty(), InputError, m_cursor.where() << ": expected " << what << ", found end of line");
        std::size_t n = 0;
        while (n < m_rest.size() && !is_blank(m_rest[n]))
            ++n;
        const std::string_view token = m_rest.substr(0, n);
        m_rest.remove_prefix(n);
        return token;
    }

    /// Requires that every token was consumed.
    void expect_end(std::string_view what)
    {
        skip_blanks();
        CORO_CHECK(m_rest.empty(), InputError,
                   m_cursor.where() << ": expected end of line after " << what << ", found " << in_quotes(m_rest));
    }

protected:
    const LineCursor& cursor() const { return m_cursor; }

private:
    void skip_blanks()
    {
        while (!m_rest.empty() && is_blank(m_rest.front()))
            m_rest.remove_prefix(1);
    }

    std::string_view m_rest;
    const LineCursor& m_cursor;
};

} // namespace coro::detail
