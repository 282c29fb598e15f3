#include <corocontact/sim/contact_step.hpp>

#include <corocontact/core/error.hpp>
#include <corocontact/sim/integrator.hpp>

#include <algorithm>
#include <numeric>
#include <utility>

namespace coro {

namespace {

std::size_t at(Index i) { return static_cast<std::size_t>(i); }

Index find_root(std::vector<Index>& parent, Index i)
{
    while (parent[at(i)] != i)
        i = parent[at(i)] = parent[at(parent[at(i)])];
    return i;
}

bool is_fixed(const Body& body, Index node) { return body.fixed()[at(node)] != 0; }

// One system for several bodies: their matrices side by side plus the coupling blocks.
BsrMatrix merged_matrix(const std::vector<Body>& bodies, const std::vector<Index>& group,
                        const std::vector<Index>& offsets_of_body, const std::vector<const ContactResponse::Block*>& blocks)
{
    Index n_rows = 0;
    for (const Index b : group)
        n_rows += bodies[at(b)].num_vertices();
    // Per merged row: (column, value) from the body's own row, then from coupling blocks.
    std::vector<std::vector<std::pair<Index, Block3>>> rows(at(n_rows));
    for (const Index b : group) {
        const BsrMatrix own = bodies[at(b)].system_matrix().to_general();
        const Index offset = offsets_of_body[at(b)];
        for (Index r = 0; r < own.num_block_rows(); ++r)
            for (Index k = own.row_offsets()[at(r)]; k < own.row_offsets()[at(r) + 1]; ++k)
                rows[at(offset + r)].emplace_back(offset + own.columns()[at(k)], own.block(k));
    }
    for (const ContactResponse::Block* block : blocks)
        rows[at(offsets_of_body[at(block->body_row)] + block->row)].emplace_back(
            offsets_of_body[at(block->body_col)] + block->col, Block3(block->value));

    std::vector<Index> row_offsets{0}, columns;
    std::vector<Block3> values;
    for (auto& row : rows) {
        std::stable_sort(row.begin(), row.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
        for (std::size_t i = 0; i < row.size(); ++i) {
            if (!columns.empty() && static_cast<Index>(columns.size()) > row_offsets.back() && columns.back() == row[i].first)
                values.back() += row[i].second;
            else {
                columns.push_back(row[i].first);
                values.push_back(row[i].second);
            }
        }
        row_offsets.push_back(static_cast<Index>(columns.size()));
    }
    BsrMatrix matrix(row_offsets, columns);
    for (std::size_t k = 0; k < values.size(); ++k)
        matrix.block(static_cast<Index>(k)) = values[k];
    return matrix;
}

void check_finite(const Body& body)
{
    const VecX& v = body.velocities();
    if (v.allFinite())
        return;
    Eigen::Index first = 0;
    while (std::isfinite(v[first]))
        ++first;
    CORO_THROW(NumericalError, "body '" << body.name() << "': velocity of node " << body.input_node(static_cast<Index>(first / 3))
                                        << " is " << v[first]);
}

} // namespace

std::vector<PcgResult> implicit_euler_step_with_contact(std::vector<Body>& bodies, const ContactResponse& response,
                                                        double dt, const Vec3& gravity, const PcgSettings& settings,
                                                        PhaseTimes& times)
{
    const auto n_bodies = static_cast<Index>(bodies.size());
    std::vector<VecX> rhs(bodies.size());
    for (Index b = 0; b < n_bodies; ++b)
        rhs[at(b)] = assemble_implicit_euler(bodies[at(b)], dt, gravity, response.forces[at(b)], times);

    // Contact terms that touch fixed nodes are dropped: those rows and columns are identity.
    std::vector<const ContactResponse::Block*> active;
    std::vector<Index> parent(at(n_bodies));
    std::iota(parent.begin(), parent.end(), 0);
    for (const ContactResponse::Block& block : response.blocks) {
        if (is_fixed(bodies[at(block.body_row)], block.row) || is_fixed(bodies[at(block.body_col)], block.col))
            continue;
        active.push_back(&block);
        const Index a = find_root(parent, block.body_row), c = find_root(parent, block.body_col);
        if (a != c)
            parent[at(std::max(a, c))] = std::min(a, c);
    }
    std::vector<std::vector<Index>> groups(at(n_bodies));
    for (Index b = 0; b < n_bodies; ++b)
        groups[at(find_root(parent, b))].push_back(b);
    std::vector<std::vector<const ContactResponse::Block*>> blocks_of_group(at(n_bodies));
    for (const ContactResponse::Block* block : active)
        blocks_of_group[at(find_root(parent, block->body_row))].push_back(block);

    std::vector<PcgResult> results;
    for (Index root = 0; root < n_bodies; ++root) {
        const std::vector<Index>& group = groups[at(root)];
        if (group.empty())
            continue;
        const auto& blocks = blocks_of_group[at(root)];
        if (group.size() == 1) {
            Body& body = bodies[at(root)];
            BsrMatrix& matrix = body.system_matrix();
            {
                ScopedTimer timer(times.contact);
                for (const ContactResponse::Block* block : blocks) // the blocks come in mirrored pairs
                    matrix.add_symmetric_part(block->row, block->col, block->value);
            }
            ScopedTimer timer(times.solve);
            body.project_fixed(body.velocities());
            results.push_back(body.pcg().solve(matrix, rhs[at(root)], body.velocities(), settings));
            continue;
        }
        std::vector<Index> offsets(at(n_bodies), 0);
        Index n_rows = 0;
        for (const Index b : group) {
            offsets[at(b)] = n_rows;
            n_rows += bodies[at(b)].num_vertices();
        }
        BsrMatrix matrix;
        {
            ScopedTimer timer(times.contact);
            matrix = merged_matrix(bodies, group, offsets, blocks);
        }
        ScopedTimer timer(times.solve);
        VecX b_merged(3 * n_rows), v_merged(3 * n_rows);
        for (const Index b : group) {
            bodies[at(b)].project_fixed(bodies[at(b)].velocities());
            b_merged.segment(3 * offsets[at(b)], rhs[at(b)].size()) = rhs[at(b)];
            v_merged.segment(3 * offsets[at(b)], rhs[at(b)].size()) = bodies[at(b)].velocities();
        }
        PcgSolver solver;
        results.push_back(solver.solve(matrix, b_merged, v_merged, settings));
        for (const Index b : group)
            bodies[at(b)].velocities() = v_merged.segment(3 * offsets[at(b)], rhs[at(b)].size());
    }
    for (Body& body : bodies) {
        check_finite(body);
        body.positions() += dt * body.velocities();
    }
    return results;
}

} // namespace coro
