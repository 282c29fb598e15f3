#include <corocontact/solver/diagonal_preconditioner.hpp>

#include <corocontact/solver/scene_matrix.hpp>

#include <Eigen/LU>

namespace coro {

namespace {
std::size_t at(Index i) { return static_cast<std::size_t>(i); }
} // namespace

void DiagonalPreconditioner::prepare(const SceneMatrix& a)
{
    m_inverse_blocks.resize(at(a.num_block_rows()));
    if (!m_blocks)
        m_inverse_diagonal.resize(at(a.num_dofs()));
    for_each_chunk(a.chunks(), [&](Index c, Index begin, Index end) {
        a.diagonal_blocks(c, m_inverse_blocks.data() + begin);
        for (Index r = begin; r < end; ++r) {
            Block3& d = m_inverse_blocks[at(r)];
            if (m_blocks)
                d = d.inverse().eval();
            else
                for (int i = 0; i < 3; ++i)
                    m_inverse_diagonal[at(3 * r + i)] = 1.0 / d(i, i);
        }
    });
}

void DiagonalPreconditioner::apply_rows(Index begin, Index end, const double* r, double* z) const
{
    if (m_blocks) {
        for (Index v = begin; v != end; ++v)
            Eigen::Map<Vec3>(z + 3 * static_cast<std::ptrdiff_t>(v)) =
                m_inverse_blocks[at(v)] * Eigen::Map<const Vec3>(r + 3 * static_cast<std::ptrdiff_t>(v));
        return;
    }
    for (std::ptrdiff_t i = 3 * static_cast<std::ptrdiff_t>(begin); i < 3 * static_cast<std::ptrdiff_t>(end); ++i)
        z[i] = m_inverse_diagonal[static_cast<std::size_t>(i)] * r[i];
}

} // namespace coro
