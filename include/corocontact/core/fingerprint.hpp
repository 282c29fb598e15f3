#pragma once
/// @file fingerprint.hpp
/// @brief A 64-bit fingerprint of bytes (FNV-1a): tells a checkpoint's case file from another
/// and the processes of a distributed run that loaded different files. Not cryptographic.

#include <cstddef>
#include <cstdint>

namespace coro {

constexpr std::uint64_t FNV1A_START = 14695981039346656037ull;

/// FNV-1a of `size` bytes at `data`, continuing from `hash` (FNV1A_START for a first piece), so
/// that several pieces fingerprint as their concatenation.
inline std::uint64_t fnv1a(const void* data, std::size_t size, std::uint64_t hash = FNV1A_START)
{
    const auto* bytes = static_cast<const unsigned char*>(data);
    for (std::size_t i = 0; i < size; ++i) {
        hash ^= bytes[i];
        hash *= 1099511628211ull;
    }
    return hash;
}

} // namespace coro
