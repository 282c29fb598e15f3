#include <corocontact/solver/scene_matrix.hpp>

#include "detail/lane_sums.hpp"

#include <stdexcept>
#include <string>

namespace coro {

namespace {
std::size_t at(Index i) { return static_cast<std::size_t>(i); }
} // namespace

SceneMatrix::SceneMatrix(std::vector<const BsrMatrix*> bodies) : m_bodies(std::move(bodies))
{
    m_offsets.assign(1, 0);
    for (std::size_t b = 0; b < m_bodies.size(); ++b) {
        const BsrMatrix& matrix = *m_bodies[b];
        if (!matrix.is_symmetric_upper())
            throw std::invalid_argument("SceneMatrix: the matrix of body " + std::to_string(b) +
                                        " is not in upper storage");
        const std::vector<Index>& chunks = matrix.chunk_offsets();
        for (std::size_t c = 0; c + 1 < chunks.size(); ++c) {
            if (chunks[c + 1] == chunks[c])
                continue; // the one empty chunk of a matrix without rows
            m_chunks.append(chunks[c + 1] - chunks[c]);
            m_chunk_body.push_back(static_cast<Index>(b));
            m_chunk_local.push_back(static_cast<Index>(c));
        }
        m_any_gathers = m_any_gathers || matrix.has_gathers();
        m_offsets.push_back(m_offsets.back() + matrix.num_block_rows());
    }
    m_chunks.group_tasks(SCENE_TASK_ROWS);
    m_coupling.set_chunks(m_chunks);
    m_coupling.finish();
    m_chunk_component = m_chunk_body;
    m_num_components = num_bodies();
}

void SceneMatrix::set_node_positions(std::vector<const VecX*> positions)
{
    if (positions.size() != m_bodies.size())
        throw std::invalid_argument("SceneMatrix::set_node_positions: " + std::to_string(positions.size()) +
                                    " position vectors for " + std::to_string(m_bodies.size()) + " bodies");
    for (std::size_t b = 0; b < positions.size(); ++b)
        if (!positions[b] || positions[b]->size() != m_bodies[b]->num_dofs())
            throw std::invalid_argument("SceneMatrix::set_node_positions: body " + std::to_string(b) +
                                        " has " + std::to_string(m_bodies[b]->num_dofs()) +
                                        " DOFs, and its positions do not match");
    m_positions = std::move(positions);
}

void SceneMatrix::set_components(const std::vector<Index>& component_of_body)
{
    if (static_cast<Index>(component_of_body.size()) != num_bodies())
        throw std::invalid_argument("SceneMatrix::set_components: " + std::to_string(component_of_body.size()) +
                                    " components for " + std::to_string(num_bodies()) + " bodies");
    Index count = 0;
    for (const Index k : component_of_body) {
        if (k < 0 || k > count)
            throw std::invalid_argument("SceneMatrix::set_components: components must be numbered in the order "
                                        "of their first body");
        count += k == count ? 1 : 0;
    }
    set_components(component_of_body, count);
}

void SceneMatrix::set_components(const std::vector<Index>& component_of_body, Index num_components)
{
    if (static_cast<Index>(component_of_body.size()) != num_bodies())
        throw std::invalid_argument("SceneMatrix::set_components: " + std::to_string(component_of_body.size()) +
                                    " components for " + std::to_string(num_bodies()) + " bodies");
    for (const Index k : component_of_body)
        if (k < 0 || k >= num_components)
            throw std::invalid_argument("SceneMatrix::set_components: component " + std::to_string(k) +
                                        " not in [0, " + std::to_string(num_components) + ")");
    m_num_components = num_components;
    for (std::size_t c = 0; c < m_chunk_component.size(); ++c)
        m_chunk_component[c] = component_of_body[at(m_chunk_body[c])];
}

void SceneMatrix::multiply(const double* x, double* y, double* chunk_dots, const char* active) const
{
    // Rows, coupling and dot of a chunk whose rows are complete after its own first pass.
    const auto finish_chunk = [&](Index c, Index begin, Index end) {
        m_coupling.multiply_add(c, x, y);
        if (!chunk_dots)
            return;
        const std::ptrdiff_t first = 3 * static_cast<std::ptrdiff_t>(begin);
        chunk_dots[c] = detail::lane_dot(x + first, y + first, 3 * static_cast<std::ptrdiff_t>(end - begin));
    };
    for_each_chunk(m_chunks, [&](Index c, Index begin, Index end) {
        if (active && !active[c])
            return;
        const Index body = m_chunk_body[at(c)];
        const std::ptrdiff_t shift = 3 * static_cast<std::ptrdiff_t>(m_offsets[at(body)]);
        const BsrMatrix& matrix = *m_bodies[at(body)];
        matrix.multiply_chunk(m_chunk_local[at(c)], x + shift, y + shift);
        if (!matrix.has_gathers())
            finish_chunk(c, begin, end);
    });
    if (!m_any_gathers)
        return;
    for_each_chunk(m_chunks, [&](Index c, Index begin, Index end) {
        const Index body = m_chunk_body[at(c)];
        const BsrMatrix& matrix = *m_bodies[at(body)];
        if (!matrix.has_gathers() || (active && !active[c]))
            return;
        const std::ptrdiff_t shift = 3 * static_cast<std::ptrdiff_t>(m_offsets[at(body)]);
        matrix.gather_chunk(m_chunk_local[at(c)], x + shift, y + shift);
        finish_chunk(c, begin, end);
    });
}

void SceneMatrix::diagonal_blocks(Index chunk, Block3* out) const
{
    const Index body = m_chunk_body[at(chunk)];
    const BsrMatrix& matrix = *m_bodies[at(body)];
    const Index begin = m_chunks.offsets[at(chunk)], end = m_chunks.offsets[at(chunk) + 1];
    const Index offset = m_offsets[at(body)];
    for (Index r = begin; r < end; ++r)
        out[r - begin] = matrix.block(matrix.diagonal(r - offset));
    m_coupling.add_diagonal(chunk, begin, out);
}

} // namespace coro
