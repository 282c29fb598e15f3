#include <corocontact/solver/coupling_blocks.hpp>

#include <utility>

namespace coro {

namespace {
std::size_t at(Index i) { return static_cast<std::size_t>(i); }
} // namespace

void CouplingBlocks::reset(Index count)
{
    m_entries.resize(at(count));
    m_size = 0;
}

void CouplingBlocks::finish(Index num_rows)
{
    // A counting sort by row keeps each row's contributions in contribution order; a row's few
    // entries are then ordered by column with an insertion sort, which is stable too. So
    // repeated blocks are summed in contribution order, whatever wrote them when.
    const auto key = [&](Index i) { return m_entries[at(i)].column; };
    const auto count = static_cast<Index>(m_entries.size());
    m_row_offsets.assign(at(num_rows) + 1, 0);
    for (const Entry& e : m_entries)
        ++m_row_offsets[at(e.row) + 1];
    for (Index r = 0; r < num_rows; ++r)
        m_row_offsets[at(r) + 1] += m_row_offsets[at(r)];
    m_order.resize(at(count));
    for (Index i = 0; i < count; ++i)
        m_order[at(m_row_offsets[at(m_entries[at(i)].row)]++)] = i;
    // m_row_offsets[r] now holds the end of row r; rows start where the previous one ends.
    m_sorted.resize(at(count));
    Index size = 0, begin = 0;
    for (Index r = 0; r < num_rows; ++r) {
        const Index end = m_row_offsets[at(r)];
        for (Index k = begin + 1; k < end; ++k) { // insertion sort by column, stable
            const Index moving = m_order[at(k)];
            Index j = k;
            for (; j > begin && key(m_order[at(j - 1)]) > key(moving); --j)
                m_order[at(j)] = m_order[at(j - 1)];
            m_order[at(j)] = moving;
        }
        for (Index k = begin; k < end; ++k) {
            const Entry& e = m_entries[at(m_order[at(k)])];
            if (k > begin && e.column == m_sorted[at(size - 1)].column)
                m_sorted[at(size - 1)].value += e.value;
            else
                m_sorted[at(size++)] = e;
        }
        begin = end;
    }
    std::swap(m_entries, m_sorted);
    m_entries.resize(at(size)); // shrinking keeps the capacity
    m_size = size;
}

} // namespace coro
