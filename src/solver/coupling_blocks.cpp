#include <corocontact/solver/coupling_blocks.hpp>

#include <algorithm>
#include <cstdint>

namespace coro {

namespace {
std::size_t at(Index i) { return static_cast<std::size_t>(i); }
} // namespace

void CouplingBlocks::reset(Index count)
{
    m_entries.resize(at(count));
    m_size = 0;
}

void CouplingBlocks::finish(const RowChunks& chunks)
{
    // Sort keys (row, column, contribution): unique, so the order is fixed whatever sort runs.
    const auto count = static_cast<Index>(m_entries.size());
    m_keys.resize(at(count));
    for (Index i = 0; i < count; ++i) {
        const Entry& e = m_entries[at(i)];
        m_keys[at(i)] = {(static_cast<std::uint64_t>(static_cast<std::uint32_t>(e.row)) << 32) |
                             static_cast<std::uint32_t>(e.column),
                         i};
    }
    std::sort(m_keys.begin(), m_keys.end());
    m_sorted.resize(at(count));
    Index size = 0;
    for (Index k = 0; k < count; ++k) {
        const Entry& e = m_entries[at(m_keys[at(k)].second)];
        if (size > 0 && k > 0 && m_keys[at(k)].first == m_keys[at(k - 1)].first)
            m_sorted[at(size - 1)].value += e.value;
        else
            m_sorted[at(size++)] = e;
    }
    std::swap(m_entries, m_sorted);
    m_entries.resize(at(size)); // shrinking keeps the capacity
    m_size = size;

    m_chunk_offsets.resize(at(chunks.num_chunks()) + 1);
    Index k = 0;
    for (Index c = 0; c <= chunks.num_chunks(); ++c) {
        const Index row = chunks.offsets[at(c)];
        while (k < size && m_entries[at(k)].row < row)
            ++k;
        m_chunk_offsets[at(c)] = c == chunks.num_chunks() ? size : k;
    }
}

void CouplingBlocks::multiply_add(Index chunk, const double* x, double* y) const
{
    for (Index k = chunk_begin(chunk); k < chunk_begin(chunk + 1); ++k) {
        const Entry& e = m_entries[at(k)];
        Eigen::Map<Vec3>(y + 3 * static_cast<std::ptrdiff_t>(e.row)) +=
            e.value * Eigen::Map<const Vec3>(x + 3 * static_cast<std::ptrdiff_t>(e.column));
    }
}

} // namespace coro
