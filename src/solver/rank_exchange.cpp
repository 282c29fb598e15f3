#include <corocontact/solver/rank_exchange.hpp>

#include <corocontact/core/error.hpp>

#include <algorithm>
#include <cstring>
#include <numeric>
#include <tuple>

namespace coro {

namespace {
std::size_t at(Index i) { return static_cast<std::size_t>(i); }
} // namespace

RankExchange::RankExchange(Communicator& communicator, const std::vector<Index>& chunk_bodies, Index num_rows)
    : m_communicator(communicator), m_rows(num_rows)
{
    std::vector<char> mine(chunk_bodies.size() * sizeof(Index));
    if (!mine.empty())
        std::memcpy(mine.data(), chunk_bodies.data(), mine.size());
    const std::vector<std::vector<char>> all = communicator.all_gather(mine);
    // (body, chunk of the body, gathered position) of every chunk, sorted into the global order.
    std::vector<std::tuple<Index, Index, Index>> chunks;
    m_chunk_counts.resize(all.size());
    m_chunk_offsets.resize(all.size());
    Index position = 0;
    for (std::size_t r = 0; r < all.size(); ++r) {
        const auto count = static_cast<Index>(all[r].size() / sizeof(Index));
        m_chunk_counts[r] = count;
        m_chunk_offsets[r] = position;
        Index previous = -1, within = 0;
        for (Index c = 0; c < count; ++c) {
            Index body = 0;
            std::memcpy(&body, all[r].data() + at(c) * sizeof(Index), sizeof(Index));
            within = body == previous ? within + 1 : 0;
            previous = body;
            chunks.emplace_back(body, within, position++);
        }
    }
    std::sort(chunks.begin(), chunks.end());
    m_order.reserve(chunks.size());
    for (const auto& chunk : chunks) {
        m_order.push_back(std::get<2>(chunk));
        m_order_body.push_back(std::get<0>(chunk));
    }
    const Index num_bodies = m_order_body.empty() ? 0 : m_order_body.back() + 1;
    m_component_of_body.resize(at(num_bodies));
    std::iota(m_component_of_body.begin(), m_component_of_body.end(), Index{0});
    m_num_components = num_bodies;
    m_counts.resize(all.size());
    m_displacements.resize(all.size());
}

void RankExchange::set_components(std::vector<Index> component_of_body)
{
    CORO_ASSERT(component_of_body.size() == m_component_of_body.size());
    m_component_of_body = std::move(component_of_body);
    m_num_components = 0;
    for (const Index k : m_component_of_body)
        m_num_components = std::max(m_num_components, k + 1);
}

void RankExchange::set_halo(Halo halo)
{
    m_halo = std::move(halo);
    m_send.resize(m_halo.ranks.size());
    m_receive.resize(m_halo.ranks.size());
    for (std::size_t i = 0; i < m_halo.ranks.size(); ++i) {
        m_send[i].resize(3 * m_halo.send_rows[i].size());
        m_receive[i].resize(3 * m_halo.ghost_rows[i].size());
    }
}

void RankExchange::update_ghosts(double* x)
{
    if (m_halo.ranks.empty())
        return;
    for (std::size_t i = 0; i < m_halo.ranks.size(); ++i) {
        double* out = m_send[i].data();
        for (const Index row : m_halo.send_rows[i])
            for (int d = 0; d < 3; ++d)
                *out++ = x[3 * static_cast<std::ptrdiff_t>(row) + d];
    }
    m_communicator.exchange(m_halo.ranks, m_send, m_receive);
    for (std::size_t i = 0; i < m_halo.ranks.size(); ++i) {
        const double* in = m_receive[i].data();
        for (const Index ghost : m_halo.ghost_rows[i])
            for (int d = 0; d < 3; ++d)
                x[3 * static_cast<std::ptrdiff_t>(m_rows + ghost) + d] = *in++;
    }
}

void RankExchange::sum_by_component(const double* partials, int width, double* totals)
{
    const std::size_t ranks = m_chunk_counts.size();
    for (std::size_t r = 0; r < ranks; ++r) {
        m_counts[r] = m_chunk_counts[r] * width;
        m_displacements[r] = m_chunk_offsets[r] * width;
    }
    m_gathered.resize(m_order.size() * static_cast<std::size_t>(width));
    const int mine = m_counts[static_cast<std::size_t>(m_communicator.rank())];
    m_communicator.all_gather(partials, mine, m_gathered.data(), m_counts.data(), m_displacements.data());
    const auto w = static_cast<std::size_t>(width);
    std::fill(totals, totals + at(m_num_components) * w, 0.0);
    for (std::size_t i = 0; i < m_order.size(); ++i) {
        double* total = totals + at(m_component_of_body[at(m_order_body[i])]) * w;
        const double* partial = m_gathered.data() + at(m_order[i]) * w;
        for (std::size_t j = 0; j < w; ++j)
            total[j] += partial[j];
    }
}

} // namespace coro
