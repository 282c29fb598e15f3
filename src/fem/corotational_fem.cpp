#include <corocontact/fem/corotational_fem.hpp>

#include "detail/tet_block_kernel.hpp"
#include "detail/tet_pack_kernel.hpp"

#include <corocontact/core/error.hpp>
#include <corocontact/fem/corotation.hpp>
#include <corocontact/partition/element_loop.hpp>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cstdint>
#include <cmath>
#include <numeric>
#include <stdexcept>
#include <string>

namespace coro {

namespace {
constexpr Index TET_GRAIN = 1024;
constexpr Index ROW_GRAIN = 256;
constexpr double POLAR_TOLERANCE = 1e-15; // polar_rotation's default
// Tets per chunk of the fused rotation + assembly pass (a multiple of the pack width, so the
// packs are those of the separate passes): small enough to stay in L1.
constexpr Index FUSED_CHUNK = 32;

using detail::TET_BLOCK_PAIRS;

std::size_t at(Index i) { return static_cast<std::size_t>(i); }

Mat34 gather_nodes(const Tets& tets, Index t, const double* x)
{
    Mat34 nodes;
    for (int a = 0; a < 4; ++a)
        nodes.col(a) = Eigen::Map<const Vec3>(x + 3 * static_cast<std::ptrdiff_t>(tets(t, a)));
    return nodes;
}

// One part holding every tet and node, in the given order.
PartLayout single_part_layout(const TetMesh& mesh)
{
    TetPartition partition;
    partition.num_parts = 1;
    partition.tet_part.assign(at(mesh.num_tets()), 0);
    return make_part_layout(mesh.tets, mesh.num_vertices(), partition);
}

// CSR from (key, value) pairs sorted by key then value; keys in [0, n).
void build_csr(std::vector<std::pair<Index, Index>>& pairs, Index n, std::vector<Index>& offsets,
               std::vector<Index>& values)
{
    std::sort(pairs.begin(), pairs.end());
    offsets.assign(at(n) + 1, 0);
    values.resize(pairs.size());
    for (std::size_t i = 0; i < pairs.size(); ++i) {
        ++offsets[at(pairs[i].first) + 1];
        values[i] = pairs[i].second;
    }
    std::partial_sum(offsets.begin(), offsets.end(), offsets.begin());
}
} // namespace

CorotationalFem::CorotationalFem(const TetMesh& mesh, const Material& material, PartLayout layout)
    : m_tets(mesh.tets), m_layout(layout.tet_offsets.empty() ? single_part_layout(mesh) : std::move(layout)),
      m_lambda(material.lambda()), m_mu(material.mu())
{
    const Index n_vertices = mesh.num_vertices();
    const Index n_tets = mesh.num_tets();
    m_rest = as_dofs(mesh.rest_positions);
    m_masses = VecX::Zero(n_vertices);
    m_volumes.resize(at(n_tets));
    m_gradients.resize(at(n_tets));
    m_rotations.assign(at(n_tets), Mat3::Identity());

    for (Index t = 0; t < n_tets; ++t) {
        const Mat34 x = gather_nodes(m_tets, t, m_rest.data());
        TetRest rest;
        try {
            rest = make_tet_rest(x.col(0), x.col(1), x.col(2), x.col(3));
        } catch (const NumericalError& e) {
            CORO_THROW(NumericalError, "tet " << t << ": " << e.what());
        }
        m_volumes[at(t)] = rest.volume;
        m_gradients[at(t)] = shape_gradients(rest);
        for (int a = 0; a < 4; ++a)
            m_masses[m_tets(t, a)] += material.density * rest.volume / 4.0;
    }

    // Block pattern, upper storage: node r couples with every node c ≥ r sharing a tet (and itself).
    std::vector<std::vector<Index>> neighbours(at(n_vertices));
    for (Index v = 0; v < n_vertices; ++v)
        neighbours[at(v)].push_back(v);
    for (Index t = 0; t < n_tets; ++t)
        for (int a = 0; a < 4; ++a)
            for (int b = 0; b < 4; ++b)
                if (m_tets(t, b) > m_tets(t, a))
                    neighbours[at(m_tets(t, a))].push_back(m_tets(t, b));
    m_row_offsets.assign(at(n_vertices) + 1, 0);
    for (Index r = 0; r < n_vertices; ++r) {
        auto& row = neighbours[at(r)];
        std::sort(row.begin(), row.end());
        row.erase(std::unique(row.begin(), row.end()), row.end());
        m_columns.insert(m_columns.end(), row.begin(), row.end());
        m_row_offsets[at(r) + 1] = static_cast<Index>(m_columns.size());
        std::vector<Index>().swap(row);
    }
    const BsrMatrix pattern = make_matrix();

    // Targets of every tet's blocks and corner forces; interface rows go to part buffers.
    const Index first_interface = m_layout.first_interface_node();
    const Index parts = m_layout.num_parts;
    m_block_targets.resize(at(n_tets));
    m_force_targets.resize(at(n_tets));
    m_part_block_buffer_offsets.assign(at(parts) + 1, 0);
    m_part_force_buffer_offsets.assign(at(parts) + 1, 0);
    std::vector<Index> block_entry(m_columns.size(), -1), node_entry(at(n_vertices), -1);
    std::vector<std::pair<Index, Index>> block_pairs, force_pairs; // (block or node, entry)
    Index n_block_entries = 0, n_force_entries = 0;
    m_block_transposed.assign(at(n_tets), 0);
    for (Index p = 0; p < parts; ++p) {
        std::vector<Index> touched_blocks, touched_nodes;
        for (Index t = m_layout.tet_offsets[at(p)]; t < m_layout.tet_offsets[at(p) + 1]; ++t) {
            for (int i = 0; i < 4; ++i) {
                const Index node = m_tets(t, i);
                if (node < first_interface) {
                    m_force_targets[at(t)][at(i)] = node;
                    continue;
                }
                if (node_entry[at(node)] < 0) {
                    node_entry[at(node)] = n_force_entries++;
                    touched_nodes.push_back(node);
                    force_pairs.emplace_back(node - first_interface, node_entry[at(node)]);
                }
                m_force_targets[at(t)][at(i)] = -1 - node_entry[at(node)];
            }
            // Block (i, j) is stored at (min, max) of the two nodes, transposed if node i > node j;
            // its row is interior (written by this part) or an interface row (buffered).
            for (std::size_t pair = 0; pair < TET_BLOCK_PAIRS.size(); ++pair) {
                const Index ni = m_tets(t, TET_BLOCK_PAIRS[pair][0]), nj = m_tets(t, TET_BLOCK_PAIRS[pair][1]);
                const Index row = std::min(ni, nj), k = pattern.find(row, std::max(ni, nj));
                if (ni > nj)
                    m_block_transposed[at(t)] |= static_cast<std::uint16_t>(1u << pair);
                if (row < first_interface) {
                    m_block_targets[at(t)][pair] = k;
                    continue;
                }
                if (block_entry[at(k)] < 0) {
                    block_entry[at(k)] = n_block_entries++;
                    touched_blocks.push_back(k);
                    block_pairs.emplace_back(k, block_entry[at(k)]);
                }
                m_block_targets[at(t)][pair] = -1 - block_entry[at(k)];
            }
        }
        for (const Index k : touched_blocks)
            block_entry[at(k)] = -1;
        for (const Index v : touched_nodes)
            node_entry[at(v)] = -1;
        m_part_block_buffer_offsets[at(p) + 1] = n_block_entries;
        m_part_force_buffer_offsets[at(p) + 1] = n_force_entries;
    }
    m_block_buffer.assign(9 * at(n_block_entries), 0.0);
    m_single_block_buffer.assign(9 * at(n_block_entries), 0.0f);
    m_force_buffer.assign(3 * at(n_force_entries), 0.0);

    // Interface blocks: every block of an interface row, with its entries in part order.
    std::vector<Index> block_offsets_all, block_entries_all;
    build_csr(block_pairs, static_cast<Index>(m_columns.size()), block_offsets_all, block_entries_all);
    m_interface_block_offsets.push_back(0);
    for (Index k = m_row_offsets[at(first_interface)]; k < static_cast<Index>(m_columns.size()); ++k) {
        for (Index e = block_offsets_all[at(k)]; e < block_offsets_all[at(k) + 1]; ++e)
            m_interface_block_entries.push_back(block_entries_all[at(e)]);
        m_interface_block_offsets.push_back(static_cast<Index>(m_interface_block_entries.size()));
    }
    build_csr(force_pairs, n_vertices - first_interface, m_interface_force_offsets, m_interface_force_entries);
}

void CorotationalFem::element_part(Index part, const Pass& pass)
{
    if (pass.matrix && pass.matrix->precision() == MatrixPrecision::SINGLE)
        element_part_in(part, pass, pass.matrix->single_values().data(), m_single_block_buffer.data());
    else
        element_part_in(part, pass, pass.matrix ? pass.matrix->values().data() : nullptr, m_block_buffer.data());
}

template <class Value>
void CorotationalFem::element_part_in(Index part, const Pass& pass, Value* values, Value* block_buffer)
{
    const Index t_begin = m_layout.tet_offsets[at(part)], t_end = m_layout.tet_offsets[at(part) + 1];
    const Index r_begin = m_layout.node_offsets[at(part)], r_end = m_layout.node_offsets[at(part) + 1];
    double* force_buffer = m_force_buffer.data();

    if (values) {
        std::fill(values + 9 * static_cast<std::ptrdiff_t>(m_row_offsets[at(r_begin)]),
                  values + 9 * static_cast<std::ptrdiff_t>(m_row_offsets[at(r_end)]), Value(0));
        for (Index r = r_begin; r < r_end; ++r) {
            Value* diagonal = values + 9 * static_cast<std::ptrdiff_t>(pass.matrix->diagonal(r));
            for (int i = 0; i < 3; ++i)
                diagonal[4 * i] = static_cast<Value>(pass.mass_scale * m_masses[r]);
        }
        std::fill(block_buffer + 9 * static_cast<std::ptrdiff_t>(m_part_block_buffer_offsets[at(part)]),
                  block_buffer + 9 * static_cast<std::ptrdiff_t>(m_part_block_buffer_offsets[at(part) + 1]), Value(0));
    }
    if (pass.forces) {
        std::fill(pass.forces + 3 * static_cast<std::ptrdiff_t>(r_begin),
                  pass.forces + 3 * static_cast<std::ptrdiff_t>(r_end), 0.0);
        std::fill(force_buffer + 3 * static_cast<std::ptrdiff_t>(m_part_force_buffer_offsets[at(part)]),
                  force_buffer + 3 * static_cast<std::ptrdiff_t>(m_part_force_buffer_offsets[at(part) + 1]), 0.0);
    }
    const Slots<Value> slots{values, block_buffer, pass.forces, force_buffer};
    if (!pass.rotate || (!pass.forces && !values)) {
        tet_range(t_begin, t_end, pass, slots);
        return;
    }
    // Rotations and assembly in one pass: a chunk of tets is rotated, then assembled while its
    // data is still in cache.
    Pass rotate_only;
    rotate_only.x = pass.x;
    rotate_only.rotate = true;
    Pass assemble_only = pass;
    assemble_only.rotate = false;
    const Slots<Value> no_outputs{nullptr, nullptr, nullptr, nullptr};
    for (Index chunk = t_begin; chunk < t_end; chunk += FUSED_CHUNK) {
        const Index chunk_end = std::min(chunk + FUSED_CHUNK, t_end);
        tet_range(chunk, chunk_end, rotate_only, no_outputs);
        tet_range(chunk, chunk_end, assemble_only, slots);
    }
}

template <class Value>
void CorotationalFem::tet_range(Index t_begin, Index t_end, const Pass& pass, const Slots<Value>& slots)
{
    Index t = t_begin;
#if defined(CORO_TET_PACKS)
    for (; t < t_end; t += detail::LANES)
        tet_pack(t, static_cast<int>(std::min<Index>(detail::LANES, t_end - t)), pass, slots);
#endif
    for (; t < t_end; ++t)
        one_tet(t, pass, slots);
}

template <class Value>
void CorotationalFem::one_tet(Index t, const Pass& pass, const Slots<Value>& slots)
{
    const Mat34& g = m_gradients[at(t)];
    const Mat34 nodes = pass.x ? gather_nodes(m_tets, t, pass.x) : Mat34(Mat34::Zero());
    if (pass.rotate) {
        const Mat3 f = nodes * g.transpose();
        CORO_CHECK(f.allFinite(), NumericalError, "tet " << t << ": the deformation gradient is not finite");
        m_rotations[at(t)] = polar_rotation(f, m_rotations[at(t)], POLAR_TOLERANCE);
    }
    if (!pass.forces && !slots.values)
        return; // rotations only: no rotated gradients needed
    const Mat34 rg = m_rotations[at(t)] * g; // rotated gradients G_i
    const double volume = m_volumes[at(t)];

    if (pass.forces) {
        const Mat3 m = nodes * rg.transpose(); // F Rᵀ
        const Mat3 strain = 0.5 * (m + m.transpose()) - Mat3::Identity();
        const Mat34 f = -volume * linear_stress(strain, m_lambda, m_mu) * rg;
        for (int a = 0; a < 4; ++a) {
            double* out = slots.force(m_force_targets[at(t)][at(a)]);
            out[0] += f(0, a);
            out[1] += f(1, a);
            out[2] += f(2, a);
        }
    }
    if (slots.values) {
        // K'_ij = s V (λ G_i G_jᵀ + μ G_j G_iᵀ + μ (G_i·G_j) I); entry (a, b) is
        // λG_i[a]·G_j[b] + μG_j[a]·G_i[b] (+ the diagonal term): two products per entry
        // with the gradients pre-scaled. Only i ≤ j is formed: the matrix keeps its upper
        // blocks, K'_ij at (node i, node j), or K'_ijᵀ when node i is the larger.
        const double s = pass.stiffness_scale * volume;
        const Mat34 lg = (s * m_lambda) * rg, mg = (s * m_mu) * rg;
        const auto& targets = m_block_targets[at(t)];
        const unsigned transposed = m_block_transposed[at(t)];
        const detail::PaddedColumns padded_g(rg), padded_l(lg), padded_m(mg);
        for (std::size_t pair = 0; pair < TET_BLOCK_PAIRS.size(); ++pair)
            detail::add_tet_block(slots.block(targets[pair]), TET_BLOCK_PAIRS[pair][0], TET_BLOCK_PAIRS[pair][1],
                                  ((transposed >> pair) & 1u) != 0, rg, lg, mg, padded_g, padded_l, padded_m);
    }
}

#if defined(CORO_TET_PACKS)
template <class Value>
void CorotationalFem::tet_pack(Index first, int count, const Pass& pass, const Slots<Value>& slots)
{
    using namespace detail;
    // Lanes past `count` repeat the last tet; nothing of theirs is stored.
    Index tet[LANES];
    const double* gradients[LANES];
    double* rotations[LANES];
    for (int l = 0; l < LANES; ++l) {
        tet[l] = first + std::min(l, count - 1);
        gradients[l] = m_gradients[at(tet[l])].data();
        rotations[l] = m_rotations[at(tet[l])].data();
    }
    Pack g[4][3], p[4][3];
    load_mat34(gradients, g);
    if (pass.x)
        gather_nodes(m_tets, tet, pass.x, p);
    else
        for (auto& node : p)
            for (Pack& v : node)
                v = splat(0.0);

    Mat3Pack r;
    bool r_current = false;
    if (pass.rotate) {
        const Mat3Pack f = deformation_gradient(p, g);
        if (const int bad = non_finite_lanes(f) & ((1 << count) - 1))
            CORO_THROW(NumericalError,
                       "tet " << tet[__builtin_ctz(static_cast<unsigned>(bad))] << ": the deformation gradient is not finite");
        const int svd = polar_rotation_lanes(f, load_mat3(rotations), POLAR_TOLERANCE, r) & ((1 << count) - 1);
        store_mat3(r, rotations, count);
        for (int l = 0; l < count; ++l)
            if ((svd >> l) & 1)
                m_rotations[at(tet[l])] = polar_rotation_svd(lane_of(f, l));
        r_current = svd == 0;
    }
    if (!pass.forces && !slots.values)
        return;
    if (!r_current)
        r = load_mat3(rotations);
    Pack rg[4][3];
    rotate_gradients(r, g, rg);
    const Pack volume = _mm256_set_pd(m_volumes[at(tet[3])], m_volumes[at(tet[2])], m_volumes[at(tet[1])],
                                      m_volumes[at(tet[0])]);

    if (pass.forces) {
        Pack f[4][3];
        corner_forces(p, rg, volume, m_lambda, m_mu, f);
        add_corner_forces(f, count, [&](int l, int a) { return slots.force(m_force_targets[at(tet[l])][at(a)]); });
    }
    if (slots.values) {
        std::uint16_t transposed[LANES];
        for (int l = 0; l < LANES; ++l)
            transposed[l] = m_block_transposed[at(tet[l])];
        add_stiffness_blocks(rg, mul(volume, splat(pass.stiffness_scale)), m_lambda, m_mu, transposed, count, [&](int l, int pair) { return slots.block(m_block_targets[at(tet[l])][at(pair)]); });
    }
}
#endif

template <class Value>
Block3 CorotationalFem::interface_block_sum(Index b, const Value* block_buffer) const
{
    Block3 sum = Block3::Zero();
    for (Index e = m_interface_block_offsets[at(b)]; e < m_interface_block_offsets[at(b) + 1]; ++e)
        sum += Eigen::Map<const Eigen::Matrix<Value, 3, 3, Eigen::RowMajor>>(
                   block_buffer + 9 * at(m_interface_block_entries[at(e)]))
                   .template cast<double>();
    return sum;
}

void CorotationalFem::finish_rows(Index row_begin, Index row_end, const Pass& pass)
{
    const Index first_interface = m_layout.first_interface_node();
    const Index begin = std::max(row_begin, first_interface);
    if (pass.matrix) {
        BsrMatrix& matrix = *pass.matrix;
        const bool single = matrix.precision() == MatrixPrecision::SINGLE;
        // Interface block b is block m_row_offsets[first_interface] + b of the matrix.
        const Index first_block = m_row_offsets[at(first_interface)];
        for (Index r = begin; r < row_end; ++r)
            for (Index k = m_row_offsets[at(r)]; k < m_row_offsets[at(r) + 1]; ++k) {
                Block3 sum = single ? interface_block_sum(k - first_block, m_single_block_buffer.data())
                                    : interface_block_sum(k - first_block, m_block_buffer.data());
                if (k == matrix.diagonal(r))
                    sum.diagonal().array() += pass.mass_scale * m_masses[r];
                matrix.set_block(k, sum);
            }
        if (pass.fixed)
            project_fixed_rows(row_begin, row_end, pass.fixed, matrix);
    }
    if (pass.forces) {
        for (Index r = begin; r < row_end; ++r) {
            const Index v = r - first_interface;
            Vec3 sum = Vec3::Zero();
            for (Index e = m_interface_force_offsets[at(v)]; e < m_interface_force_offsets[at(v) + 1]; ++e)
                sum += Eigen::Map<const Vec3>(m_force_buffer.data() + 3 * at(m_interface_force_entries[at(e)]));
            Eigen::Map<Vec3>(pass.forces + 3 * static_cast<std::ptrdiff_t>(r)) = sum;
        }
    }
}

void CorotationalFem::run_pass(const Pass& pass)
{
    for_each_part(m_layout.num_parts, [&](Index part) { element_part(part, pass); });
    if (!pass.matrix && !pass.forces)
        return;
    tbb::parallel_for(tbb::blocked_range<Index>(0, num_vertices(), ROW_GRAIN), [&](const tbb::blocked_range<Index>& rows) {
        finish_rows(rows.begin(), rows.end(), pass);
    });
}

void CorotationalFem::project_fixed_rows(Index row_begin, Index row_end, const char* fixed, BsrMatrix& matrix) const
{
    for (Index r = row_begin; r < row_end; ++r) {
        if (fixed[r]) {
            for (Index k = m_row_offsets[at(r)]; k < m_row_offsets[at(r) + 1]; ++k)
                matrix.set_block(k, Block3::Zero());
            matrix.set_block(matrix.diagonal(r), Block3::Identity());
            continue;
        }
        for (Index k = m_row_offsets[at(r)]; k < m_row_offsets[at(r) + 1]; ++k)
            if (fixed[m_columns[at(k)]])
                matrix.set_block(k, Block3::Zero());
    }
}

void CorotationalFem::set_rotations(std::vector<Mat3> rotations)
{
    if (static_cast<Index>(rotations.size()) != num_tets())
        throw std::invalid_argument("CorotationalFem::set_rotations: " + std::to_string(rotations.size()) +
                                    " rotations for " + std::to_string(num_tets()) + " tets");
    m_rotations = std::move(rotations);
}

void CorotationalFem::update_rotations(CRef<VecX> x)
{
    Pass pass;
    pass.x = x.data();
    pass.rotate = true;
    run_pass(pass);
}

void CorotationalFem::internal_forces(CRef<VecX> x, Eigen::Ref<VecX> f)
{
    Pass pass;
    pass.x = x.data();
    pass.forces = f.data();
    run_pass(pass);
}

void CorotationalFem::assemble(double stiffness_scale, double mass_scale, const std::vector<char>& fixed,
                               BsrMatrix& matrix)
{
    Pass pass;
    pass.matrix = &matrix;
    pass.stiffness_scale = stiffness_scale;
    pass.mass_scale = mass_scale;
    pass.fixed = fixed.empty() ? nullptr : fixed.data();
    run_pass(pass);
}

void CorotationalFem::assemble_with_forces(CRef<VecX> x, double stiffness_scale, double mass_scale,
                                           const std::vector<char>& fixed, BsrMatrix& matrix, Eigen::Ref<VecX> forces)
{
    Pass pass;
    pass.x = x.data();
    pass.forces = forces.data();
    pass.matrix = &matrix;
    pass.stiffness_scale = stiffness_scale;
    pass.mass_scale = mass_scale;
    pass.fixed = fixed.empty() ? nullptr : fixed.data();
    run_pass(pass);
}

void CorotationalFem::rotate_and_assemble_with_forces(CRef<VecX> x, double stiffness_scale, double mass_scale,
                                                      const std::vector<char>& fixed, BsrMatrix& matrix,
                                                      Eigen::Ref<VecX> forces)
{
    Pass pass;
    pass.x = x.data();
    pass.rotate = true;
    pass.forces = forces.data();
    pass.matrix = &matrix;
    pass.stiffness_scale = stiffness_scale;
    pass.mass_scale = mass_scale;
    pass.fixed = fixed.empty() ? nullptr : fixed.data();
    run_pass(pass);
}

double CorotationalFem::strain_energy(CRef<VecX> x) const
{
    double energy = 0.0;
    for (Index t = 0; t < num_tets(); ++t) {
        const Mat3 f = gather_nodes(m_tets, t, x.data()) * m_gradients[at(t)].transpose();
        const Mat3 r = polar_rotation_svd(f);
        const Mat3 s = r.transpose() * f;
        const Mat3 strain = 0.5 * (s + s.transpose()) - Mat3::Identity();
        const double trace = strain.trace();
        energy += m_volumes[at(t)] * (m_mu * strain.squaredNorm() + 0.5 * m_lambda * trace * trace);
    }
    return energy;
}

BsrMatrix CorotationalFem::make_matrix(MatrixPrecision precision) const
{
    // Product chunks: each part's interior rows, then the interface rows cut into pieces of
    // about a part's size (they couple mostly among themselves).
    std::vector<Index> chunks{0};
    const Index parts = m_layout.num_parts, first_interface = m_layout.first_interface_node();
    for (Index p = 0; p < parts; ++p)
        if (m_layout.node_offsets[at(p) + 1] > chunks.back())
            chunks.push_back(m_layout.node_offsets[at(p) + 1]);
    const Index piece = std::max<Index>(1024, first_interface / std::max<Index>(parts, 1));
    for (Index r = first_interface; r < num_vertices(); r = std::min(r + piece, num_vertices()))
        chunks.push_back(std::min(r + piece, num_vertices()));
    if (chunks.size() == 1)
        chunks.push_back(num_vertices());
    return BsrMatrix::symmetric_upper(m_row_offsets, m_columns, chunks, precision);
}

VecX CorotationalFem::von_mises_stress(CRef<VecX> x) const
{
    VecX stress(num_tets());
    tbb::parallel_for(tbb::blocked_range<Index>(0, num_tets(), TET_GRAIN), [&](const tbb::blocked_range<Index>& range) {
        for (Index t = range.begin(); t != range.end(); ++t) {
            const Mat3 f = gather_nodes(m_tets, t, x.data()) * m_gradients[at(t)].transpose();
            const Mat3 s = polar_rotation(f, m_rotations[at(t)]).transpose() * f;
            const Mat3 strain = 0.5 * (s + s.transpose()) - Mat3::Identity();
            stress[t] = von_mises(linear_stress(strain, m_lambda, m_mu));
        }
    });
    return stress;
}

} // namespace coro
