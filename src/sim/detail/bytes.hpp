#pragma once
// Messages between processes as plain bytes: values appended in order and read back in the same
// order, in the native representation (the processes of a run share one build).

#include <corocontact/core/types.hpp>

#include <cstring>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

namespace coro::detail {

class ByteWriter {
public:
    explicit ByteWriter(std::vector<char>& bytes) : m_bytes(bytes) {}
    template <class T> void put(const T& value) { put(&value, 1); }
    template <class T> void put(const T* values, std::size_t count)
    {
        static_assert(std::is_trivially_copyable_v<T>);
        const std::size_t size = count * sizeof(T);
        const std::size_t at = m_bytes.size();
        m_bytes.resize(at + size);
        if (size > 0)
            std::memcpy(m_bytes.data() + at, values, size);
    }
    void put_string(const std::string& s)
    {
        put(static_cast<std::uint64_t>(s.size()));
        put(s.data(), s.size());
    }

private:
    std::vector<char>& m_bytes;
};

class ByteReader {
public:
    explicit ByteReader(const std::vector<char>& bytes) : m_bytes(bytes) {}
    template <class T> T get()
    {
        T value;
        get(&value, 1);
        return value;
    }
    template <class T> void get(T* values, std::size_t count)
    {
        static_assert(std::is_trivially_copyable_v<T>);
        const std::size_t size = count * sizeof(T);
        if (size > m_bytes.size() - m_at) // a programming error: both sides run this build
            throw std::logic_error("ByteReader: message shorter than its reader expects");
        if (size > 0)
            std::memcpy(values, m_bytes.data() + m_at, size);
        m_at += size;
    }
    std::string get_string()
    {
        std::string s(static_cast<std::size_t>(get<std::uint64_t>()), '\0');
        get(s.data(), s.size());
        return s;
    }
    bool done() const { return m_at == m_bytes.size(); }

private:
    const std::vector<char>& m_bytes;
    std::size_t m_at = 0;
};

} // namespace coro::detail
