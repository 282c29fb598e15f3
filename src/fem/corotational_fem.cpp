#include <corocontact/fem/corotational_fem.hpp>

#include <corocontact/core/error.hpp>
#include <corocontact/fem/corotation.hpp>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

namespace coro {

namespace {
constexpr Index TET_GRAIN = 1024;
constexpr Index ROW_GRAIN = 256;

std::size_t at(Index i) { return static_cast<std::size_t>(i); }

Mat34 gather_nodes(const Tets& tets, Index t, CRef<VecX> x)
{
    Mat34 nodes;
    for (int a = 0; a < 4; ++a)
        nodes.col(a) = x.segment<3>(3 * tets(t, a));
    return nodes;
}

// Exclusive prefix sum of counts, in place; returns the total.
Index prefix_sum(std::vector<Index>& counts)
{
    Index total = 0;
    for (auto& c : counts) {
        const Index n = c;
        c = total;
        total += n;
    }
    return total;
}
} // namespace

CorotationalFem::CorotationalFem(const TetMesh& mesh, const Material& material)
    : m_tets(mesh.tets), m_lambda(material.lambda()), m_mu(material.mu())
{
    const Index n_vertices = mesh.num_vertices();
    const Index n_tets = mesh.num_tets();
    m_rest = as_dofs(mesh.rest_positions);
    m_masses = VecX::Zero(n_vertices);
    m_volumes.resize(at(n_tets));
    m_gradients.resize(at(n_tets));
    m_rotations.assign(at(n_tets), Mat3::Identity());
    m_rotated_gradients.resize(at(n_tets));
    m_force_slots.resize(at(n_tets));

    for (Index t = 0; t < n_tets; ++t) {
        const Mat34 x = gather_nodes(m_tets, t, m_rest);
        TetRest rest;
        try {
            rest = make_tet_rest(x.col(0), x.col(1), x.col(2), x.col(3));
        } catch (const NumericalError& e) {
            CORO_THROW(NumericalError, "tet " << t << ": " << e.what());
        }
        m_volumes[at(t)] = rest.volume;
        m_gradients[at(t)] = shape_gradients(rest);
        m_rotated_gradients[at(t)] = m_gradients[at(t)];
        for (int a = 0; a < 4; ++a)
            m_masses[m_tets(t, a)] += material.density * rest.volume / 4.0;
    }

    // Node → corners, in ascending tet order.
    m_node_offsets.assign(at(n_vertices) + 1, 0);
    for (Index t = 0; t < n_tets; ++t)
        for (int a = 0; a < 4; ++a)
            ++m_node_offsets[at(m_tets(t, a))];
    m_node_corners.resize(at(prefix_sum(m_node_offsets)));
    {
        std::vector<Index> cursor(m_node_offsets.begin(), m_node_offsets.end() - 1);
        for (Index t = 0; t < n_tets; ++t)
            for (int a = 0; a < 4; ++a)
                m_node_corners[at(cursor[at(m_tets(t, a))]++)] = 4 * t + a;
    }

    // Block pattern: node r couples with every node sharing a tet (and itself).
    m_row_offsets.assign(at(n_vertices) + 1, 0);
    std::vector<Index> neighbours;
    for (Index r = 0; r < n_vertices; ++r) {
        neighbours.clear();
        neighbours.push_back(r);
        for (Index k = m_node_offsets[at(r)]; k < m_node_offsets[at(r) + 1]; ++k) {
            const Index t = m_node_corners[at(k)] / 4;
            for (int b = 0; b < 4; ++b)
                neighbours.push_back(m_tets(t, b));
        }
        std::sort(neighbours.begin(), neighbours.end());
        neighbours.erase(std::unique(neighbours.begin(), neighbours.end()), neighbours.end());
        m_columns.insert(m_columns.end(), neighbours.begin(), neighbours.end());
        m_row_offsets[at(r) + 1] = static_cast<Index>(m_columns.size());
    }

    // Contributions of each tet's 16 blocks, bucketed by stored block in tet order.
    const BsrMatrix pattern = make_matrix();
    std::vector<Index> block_of(at(16 * n_tets));
    m_block_offsets.assign(m_columns.size() + 1, 0);
    for (Index t = 0; t < n_tets; ++t)
        for (int i = 0; i < 4; ++i)
            for (int j = 0; j < 4; ++j) {
                const Index k = pattern.find(m_tets(t, i), m_tets(t, j));
                block_of[at(16 * t + 4 * i + j)] = k;
                ++m_block_offsets[at(k)];
            }
    m_block_contributions.resize(at(prefix_sum(m_block_offsets)));
    std::vector<Index> cursor(m_block_offsets.begin(), m_block_offsets.end() - 1);
    for (Index c = 0; c < 16 * n_tets; ++c)
        m_block_contributions[at(cursor[at(block_of[at(c)])]++)] = c;
}

void CorotationalFem::update_rotations(CRef<VecX> x)
{
    tbb::parallel_for(tbb::blocked_range<Index>(0, num_tets(), TET_GRAIN),
                      [&](const tbb::blocked_range<Index>& range) {
                          for (Index t = range.begin(); t != range.end(); ++t) {
                              const Mat34 nodes = gather_nodes(m_tets, t, x);
                              const Mat3 f = nodes * m_gradients[at(t)].transpose();
                              CORO_CHECK(f.allFinite(), NumericalError,
                                         "tet " << t << ": the deformation gradient is not finite");
                              m_rotations[at(t)] = polar_rotation(f, m_rotations[at(t)]);
                              m_rotated_gradients[at(t)] = m_rotations[at(t)] * m_gradients[at(t)];
                          }
                      });
}

void CorotationalFem::internal_forces(CRef<VecX> x, Eigen::Ref<VecX> f)
{
    tbb::parallel_for(tbb::blocked_range<Index>(0, num_tets(), TET_GRAIN),
                      [&](const tbb::blocked_range<Index>& range) {
                          for (Index t = range.begin(); t != range.end(); ++t) {
                              const Mat34& g = m_rotated_gradients[at(t)];
                              const Mat3 m = gather_nodes(m_tets, t, x) * g.transpose(); // F Rᵀ
                              const Mat3 strain = 0.5 * (m + m.transpose()) - Mat3::Identity();
                              m_force_slots[at(t)] =
                                  -m_volumes[at(t)] * linear_stress(strain, m_lambda, m_mu) * g;
                          }
                      });
    tbb::parallel_for(tbb::blocked_range<Index>(0, num_vertices(), ROW_GRAIN),
                      [&](const tbb::blocked_range<Index>& range) {
                          for (Index v = range.begin(); v != range.end(); ++v) {
                              Vec3 sum = Vec3::Zero();
                              for (Index k = m_node_offsets[at(v)]; k < m_node_offsets[at(v) + 1]; ++k) {
                                  const Index corner = m_node_corners[at(k)];
                                  sum += m_force_slots[at(corner / 4)].col(corner % 4);
                              }
                              f.segment<3>(3 * v) = sum;
                          }
                      });
}

double CorotationalFem::strain_energy(CRef<VecX> x) const
{
    double energy = 0.0;
    for (Index t = 0; t < num_tets(); ++t) {
        const Mat3 f = gather_nodes(m_tets, t, x) * m_gradients[at(t)].transpose();
        const Mat3 r = polar_rotation_svd(f);
        const Mat3 s = r.transpose() * f;
        const Mat3 strain = 0.5 * (s + s.transpose()) - Mat3::Identity();
        const double trace = strain.trace();
        energy += m_volumes[at(t)] * (m_mu * strain.squaredNorm() + 0.5 * m_lambda * trace * trace);
    }
    return energy;
}

BsrMatrix CorotationalFem::make_matrix() const { return BsrMatrix(m_row_offsets, m_columns); }

void CorotationalFem::assemble(double stiffness_scale, double mass_scale,
                               const std::vector<char>& fixed, BsrMatrix& matrix) const
{
    const auto is_fixed = [&](Index v) { return !fixed.empty() && fixed[at(v)] != 0; };
    tbb::parallel_for(
        tbb::blocked_range<Index>(0, num_vertices(), ROW_GRAIN), [&](const tbb::blocked_range<Index>& range) {
            for (Index r = range.begin(); r != range.end(); ++r) {
                for (Index k = m_row_offsets[at(r)]; k < m_row_offsets[at(r) + 1]; ++k) {
                    const Index c = m_columns[at(k)];
                    auto block = matrix.block(k);
                    if (is_fixed(r) || is_fixed(c)) {
                        block = (r == c) ? Block3(Block3::Identity()) : Block3(Block3::Zero());
                        continue;
                    }
                    Mat3 sum = Mat3::Zero();
                    for (Index n = m_block_offsets[at(k)]; n < m_block_offsets[at(k) + 1]; ++n) {
                        const Index contribution = m_block_contributions[at(n)];
                        const Index t = contribution / 16;
                        const Mat34& g = m_rotated_gradients[at(t)];
                        sum += stiffness_block(g.col((contribution / 4) % 4), g.col(contribution % 4),
                                               m_lambda, m_mu, m_volumes[at(t)]);
                    }
                    block = stiffness_scale * sum;
                    if (r == c)
                        block.diagonal().array() += mass_scale * m_masses[r];
                }
            }
        });
}

VecX CorotationalFem::von_mises_stress(CRef<VecX> x) const
{
    VecX stress(num_tets());
    tbb::parallel_for(tbb::blocked_range<Index>(0, num_tets(), TET_GRAIN),
                      [&](const tbb::blocked_range<Index>& range) {
                          for (Index t = range.begin(); t != range.end(); ++t) {
                              const Mat3 f = gather_nodes(m_tets, t, x) * m_gradients[at(t)].transpose();
                              const Mat3 s = polar_rotation(f, m_rotations[at(t)]).transpose() * f;
                              const Mat3 strain = 0.5 * (s + s.transpose()) - Mat3::Identity();
                              stress[t] = von_mises(linear_stress(strain, m_lambda, m_mu));
                          }
                      });
    return stress;
}

} // namespace coro
