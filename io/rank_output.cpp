#include <corocontact/io/rank_output.hpp>

#include <corocontact/core/collective.hpp>
#include <corocontact/io/scene_output.hpp>

#include <cstring>

namespace coro {

RankFrames::RankFrames(Communicator& communicator, VtkSeriesWriter& writer, const Scene& scene,
                       const std::vector<Index>& body_ids)
    : m_communicator(communicator), m_writer(writer)
{
    // Each process's (case body, block names), gathered and put in case body order.
    std::vector<char> mine;
    const auto put = [&](const void* data, std::size_t size) {
        mine.insert(mine.end(), static_cast<const char*>(data), static_cast<const char*>(data) + size);
    };
    for (std::size_t l = 0; l < scene.bodies.size(); ++l)
        for (const std::string& name : body_block_names(scene.bodies[l])) {
            put(&body_ids[l], sizeof(Index));
            const auto size = static_cast<std::uint32_t>(name.size());
            put(&size, sizeof size);
            put(name.data(), name.size());
        }
    std::vector<std::pair<Index, std::string>> blocks;
    for (const std::vector<char>& bytes : communicator.all_gather(mine))
        for (std::size_t at = 0; at < bytes.size();) {
            Index body = 0;
            std::uint32_t size = 0;
            std::memcpy(&body, bytes.data() + at, sizeof body);
            std::memcpy(&size, bytes.data() + at + sizeof body, sizeof size);
            at += sizeof body + sizeof size;
            blocks.emplace_back(body, std::string(bytes.data() + at, size));
            at += size;
        }
    std::stable_sort(blocks.begin(), blocks.end(),
                     [](const auto& x, const auto& y) { return x.first < y.first; });
    for (const auto& block : blocks)
        m_names.push_back(block.second);

    m_bounds = rest_bounds(scene);
    communicator.all_reduce(m_bounds.first.data(), 3, Reduction::MIN);
    communicator.all_reduce(m_bounds.second.data(), 3, Reduction::MAX);
    for (const FrameBlock& obstacle : obstacle_blocks(scene, m_bounds))
        m_names.push_back(obstacle.name);
}

void RankFrames::write(Index step, double time, const Scene& scene)
{
    const bool root = m_communicator.rank() == 0;
    std::vector<std::filesystem::path> written;
    try {
        run_collectively(&m_communicator, [&] {
            std::vector<FrameBlock> blocks = body_blocks(scene);
            if (root)
                for (FrameBlock& obstacle : obstacle_blocks(scene, m_bounds))
                    blocks.push_back(std::move(obstacle));
            written = m_writer.write_blocks(step, m_names, blocks);
        });
        run_collectively(&m_communicator, [&] {
            if (root)
                m_writer.list_frame(step, time, m_names);
        });
    } catch (...) {
        // The frame is not listed; none of its blocks stays (a rewritten step keeps the new ones).
        std::error_code ignored;
        for (const std::filesystem::path& file : written)
            std::filesystem::remove(file, ignored);
        throw;
    }
}

std::vector<RankLoad> gather_rank_loads(Communicator& communicator, const Scene& scene, const RankStats& stats)
{
    RankLoad mine;
    mine.bodies = static_cast<Index>(scene.bodies.size());
    mine.tets = scene.num_tets();
    mine.mpi_bytes_per_step = stats.mpi_bytes_per_step;
    mine.solve_bytes_per_step = stats.solve_bytes_per_step;
    std::vector<char> bytes(sizeof mine);
    std::memcpy(bytes.data(), &mine, sizeof mine);
    std::vector<RankLoad> loads;
    for (const std::vector<char>& rank : communicator.gather(bytes, 0)) {
        RankLoad load;
        std::memcpy(&load, rank.data(), sizeof load);
        loads.push_back(load);
    }
    return loads;
}

} // namespace coro
