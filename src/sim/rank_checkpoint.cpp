#include <corocontact/sim/rank_checkpoint.hpp>

#include "detail/bytes.hpp"

#include <corocontact/core/collective.hpp>

namespace coro {

void write_checkpoint(const std::filesystem::path& path, const Scene& scene, const SceneDistribution& distribution,
                      const CheckpointState& state, std::uint64_t fingerprint)
{
    Communicator& communicator = *distribution.communicator;
    std::vector<char> mine;
    detail::ByteWriter out(mine);
    for (const Body& body : scene.bodies) {
        const CheckpointBody part = checkpoint_body(body);
        out.put_string(part.entry);
        out.put_string(part.state);
    }
    const std::vector<std::vector<char>> all = communicator.gather(mine, 0);
    run_collectively(&communicator, [&] {
        if (communicator.rank() != 0)
            return;
        std::vector<CheckpointBody> bodies(distribution.ownership.owner.size());
        for (std::size_t r = 0; r < all.size(); ++r) {
            detail::ByteReader in(all[r]);
            for (const Index b : distribution.ownership.bodies_of(static_cast<Index>(r))) {
                bodies[static_cast<std::size_t>(b)].entry = in.get_string();
                bodies[static_cast<std::size_t>(b)].state = in.get_string();
            }
        }
        write_checkpoint(path, bodies, state, fingerprint);
    });
}

} // namespace coro
