#include <corocontact/solver/contact_coupling.hpp>

#include <algorithm>

namespace coro {

namespace {
std::size_t at(Index i) { return static_cast<std::size_t>(i); }

// Whether a share's row gets blocks (a fixed node's coefficient is 0: none).
bool has_blocks(const ContactCoupling::Share& share) { return share.row >= 0 && share.coefficient != 0.0; }
} // namespace

void ContactCoupling::set_chunks(const RowChunks& chunks)
{
    m_num_chunks = chunks.num_chunks();
    m_row_chunk.resize(at(chunks.num_rows()));
    for (Index c = 0; c < m_num_chunks; ++c)
        std::fill(m_row_chunk.begin() + chunks.offsets[at(c)], m_row_chunk.begin() + chunks.offsets[at(c) + 1], c);
    m_chunk_offsets.assign(at(m_num_chunks) + 1, 0);
}

void ContactCoupling::reset(const std::vector<Index>& share_offsets)
{
    const std::size_t terms = share_offsets.size() - 1;
    m_stiffness.resize(terms);
    m_share_counts.resize(terms);
    m_share_offsets.resize(terms + 1);
    for (std::size_t i = 0; i < terms; ++i) {
        m_share_counts[i] = share_offsets[i + 1] - share_offsets[i];
        const Index groups = (m_share_counts[i] + SHARE_GROUP - 1) / SHARE_GROUP;
        m_share_offsets[i + 1] = m_share_offsets[i] + SHARE_GROUP * groups;
    }
    m_shares.resize(at(m_share_offsets.back()));
}

void ContactCoupling::finish()
{
    const auto chunk_of = [&](Index row) { return m_row_chunk[at(row)]; };
    // Fill up the last group of every term; count the shares with a row by chunk.
    const Index n_chunks = m_num_chunks;
    m_fill.assign(at(n_chunks) + 1, 0);
    for (Index term = 0; term < num_terms(); ++term) {
        const Index first = m_share_offsets[at(term)], written = first + m_share_counts[at(term)];
        for (Index s = first; s < written; ++s)
            if (m_shares[at(s)].row >= 0)
                ++m_fill[at(chunk_of(m_shares[at(s)].row)) + 1];
        for (Index s = written; s < m_share_offsets[at(term) + 1]; ++s)
            m_shares[at(s)] = {-1, m_shares[at(first)].column, 0.0};
    }
    // A counting sort by chunk keeps the terms of a chunk in term order.
    for (Index c = 0; c < n_chunks; ++c)
        m_fill[at(c) + 1] += m_fill[at(c)];
    m_chunk_offsets.assign(m_fill.begin(), m_fill.end());
    m_row_terms.resize(at(m_fill.back()));
    for (Index term = 0; term < num_terms(); ++term) {
        const Index first = m_share_offsets[at(term)], written = first + m_share_counts[at(term)];
        for (Index s = first; s < written; ++s) {
            const Share& share = m_shares[at(s)];
            if (share.row >= 0)
                m_row_terms[at(m_fill[at(chunk_of(share.row))]++)] = {share.row, term, share.coefficient};
        }
    }
}

void ContactCoupling::multiply_add(Index chunk, const double* x, double* y) const
{
    const Index end = m_chunk_offsets[at(chunk) + 1];
    for (Index k = m_chunk_offsets[at(chunk)]; k < end;) {
        const Index term = m_row_terms[at(k)].term;
        Vec3 u = Vec3::Zero();
        for (Index s = m_share_offsets[at(term)]; s < m_share_offsets[at(term) + 1]; s += SHARE_GROUP)
            for (Index g = 0; g < SHARE_GROUP; ++g) {
                const Share& share = m_shares[at(s + g)];
                u += share.coefficient * Eigen::Map<const Vec3>(x + 3 * static_cast<std::ptrdiff_t>(share.column));
            }
        const Vec3 product = m_stiffness[at(term)] * u;
        for (; k < end && m_row_terms[at(k)].term == term; ++k) {
            const RowTerm& entry = m_row_terms[at(k)];
            Eigen::Map<Vec3>(y + 3 * static_cast<std::ptrdiff_t>(entry.row)) += entry.coefficient * product;
        }
    }
}

void ContactCoupling::add_diagonal(Index chunk, Index first_row, Block3* out) const
{
    for (Index k = m_chunk_offsets[at(chunk)]; k < m_chunk_offsets[at(chunk) + 1]; ++k) {
        const RowTerm& entry = m_row_terms[at(k)];
        double coefficient = 0.0; // Σ c_s over the term's shares of this node
        for (Index s = m_share_offsets[at(entry.term)]; s < m_share_offsets[at(entry.term) + 1]; ++s)
            if (m_shares[at(s)].row == entry.row)
                coefficient += m_shares[at(s)].coefficient;
        out[entry.row - first_row] += (entry.coefficient * coefficient) * m_stiffness[at(entry.term)];
    }
}

void ContactCoupling::blocks(Index num_rows, CouplingBlocks& out) const
{
    Index count = 0;
    for (Index term = 0; term < num_terms(); ++term) {
        const Index first = m_share_offsets[at(term)], end = first + m_share_counts[at(term)];
        Index columns = 0;
        for (Index s = first; s < end; ++s)
            columns += m_shares[at(s)].coefficient != 0.0 ? 1 : 0;
        for (Index s = first; s < end; ++s)
            count += has_blocks(m_shares[at(s)]) ? columns : 0;
    }
    out.reset(count);
    Index k = 0;
    for (Index term = 0; term < num_terms(); ++term) {
        const Index first = m_share_offsets[at(term)], end = first + m_share_counts[at(term)];
        for (Index r = first; r < end; ++r) {
            const Share& row = m_shares[at(r)];
            if (!has_blocks(row))
                continue;
            for (Index c = first; c < end; ++c) {
                const Share& column = m_shares[at(c)];
                if (column.coefficient == 0.0)
                    continue;
                out.entry(k++) = {row.row, column.column,
                                  Block3(row.coefficient * column.coefficient * m_stiffness[at(term)])};
            }
        }
    }
    out.finish(num_rows);
}

} // namespace coro
