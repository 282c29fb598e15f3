#pragma once
/// @file contact_coupling.hpp
/// @brief What contact adds to a scene matrix, kept as one small term per contact instead of
/// its blocks: a 3×3 matrix K and the nodes that share the contact, refilled every step.
///
/// A contact whose shares (nodes) have coefficients c_1…c_m adds c_r c_s K to block (r, s) of
/// the matrix for every pair of its shares: m² blocks (16 for a vertex against a face), all
/// multiples of one K. So row r of its product is c_r K (Σ_s c_s x_s): the m² blocks never
/// exist, a product forms K (Σ_s c_s x_s) once for all of a term's rows in a chunk, and
/// refilling the terms costs O(#shares) instead of O(#blocks) plus a sort of them.

#include <corocontact/solver/coupling_blocks.hpp>
#include <corocontact/solver/row_chunks.hpp>

#include <vector>

namespace coro {

class ContactCoupling {
public:
    /// The row chunks the terms will be indexed by (those of the scene matrix, fixed with it);
    /// before any reset().
    void set_chunks(const RowChunks& chunks);

    /// One node of a term.
    struct Share {
        Index row = -1;           ///< its row of the scene matrix, −1 if it has none here (another
                                  ///< process's node, or a fixed node)
        Index column = 0;         ///< its entry of the product's x (a row here, or a ghost row
                                  ///< after them in a distributed scene)
        double coefficient = 0.0; ///< c (0 for a fixed node: its rows and columns are identity)
    };

    /// Empties the coupling and makes room for terms i = 0, 1, … of
    /// share_offsets[i + 1] − share_offsets[i] shares each (#terms+1 offsets from 0), to be
    /// written with stiffness() and share() (in parallel, each term by one writer). Keeps its
    /// capacity: refilling it allocates nothing once it has held as many terms and shares.
    void reset(const std::vector<Index>& share_offsets);
    Mat3& stiffness(Index term) { return m_stiffness[static_cast<std::size_t>(term)]; }
    /// Share k of term `term`.
    Share& share(Index term, Index k)
    {
        return m_shares[static_cast<std::size_t>(m_share_offsets[static_cast<std::size_t>(term)] + k)];
    }

    /// Indexes the written terms by the chunks' rows: a chunk's terms in term order, so a row
    /// sums its terms in term order (which one process and many processes share). Must be
    /// called after the terms are written and before any other query; O(#chunks + #shares).
    void finish();

    Index num_terms() const { return static_cast<Index>(m_stiffness.size()); }

    /// y_r += Σ_terms c_r K (Σ_s c_s x_s) for the rows r of chunk `chunk`.
    /// @param[in] x      #3 × columns (see Share::column)
    /// @param[in,out] y  #3N scene rows
    void multiply_add(Index chunk, const double* x, double* y) const;

    /// Adds the coupling's diagonal blocks of the rows of chunk `chunk`, whose first row is
    /// `first_row`: out[r − first_row] += Σ c_r c_s K over the share pairs of a term that are
    /// both node r.
    void add_diagonal(Index chunk, Index first_row, Block3* out) const;

    /// The coupling as explicit blocks (c_r c_s K for every pair of shares whose row is here),
    /// sorted and summed as CouplingBlocks::finish does; for whoever needs the matrix entries
    /// themselves (the AMG preconditioner's copy). Shares of coefficient 0 (fixed nodes) have
    /// no blocks.
    void blocks(Index num_rows, CouplingBlocks& out) const;

private:
    /// A term's shares are stored in groups of this many, the last one filled up with shares
    /// of coefficient 0 (of the term's first column), so that a term's sum runs without a
    /// branch on its length (a vertex against a plane has 1 share, against a face 4).
    static constexpr Index SHARE_GROUP = 4;

    struct RowTerm {
        Index row = 0, term = 0;
        double coefficient = 0.0;
    };

    std::vector<Mat3> m_stiffness;         // #terms: K
    std::vector<Index> m_share_offsets{0}; // #terms+1, multiples of SHARE_GROUP
    std::vector<Index> m_share_counts;     // #terms: shares written, before the filling
    std::vector<Share> m_shares;
    std::vector<Index> m_row_chunk;           // #rows: the chunk of every row
    std::vector<RowTerm> m_row_terms;         // finish(): every share with a row, by (chunk, term)
    std::vector<Index> m_chunk_offsets{0, 0}; // finish(): chunk c's row terms [c], [c+1)
    std::vector<Index> m_fill;                // finish(): scratch, #chunks+1
    Index m_num_chunks = 0;
};

} // namespace coro
