#include <corocontact/partition/partition.hpp>

#include <corocontact/core/error.hpp>

#include <metis.h>
#include <unistd.h>

#include <algorithm>
#include <numeric>

namespace coro {

namespace {
constexpr idx_t METIS_SEED = 20101025; // fixed: the same mesh always gets the same parts

const char* metis_status(int status)
{
    switch (status) {
    case METIS_ERROR_INPUT: return "METIS_ERROR_INPUT";
    case METIS_ERROR_MEMORY: return "METIS_ERROR_MEMORY";
    case METIS_ERROR: return "METIS_ERROR";
    default: return "unknown METIS status";
    }
}
} // namespace

std::vector<Index> TetPartition::part_sizes() const
{
    std::vector<Index> sizes(static_cast<std::size_t>(num_parts), 0);
    for (const Index p : tet_part)
        ++sizes[static_cast<std::size_t>(p)];
    return sizes;
}

double TetPartition::imbalance() const
{
    const std::vector<Index> sizes = part_sizes();
    if (tet_part.empty())
        return 1.0;
    const double mean = static_cast<double>(tet_part.size()) / num_parts;
    return *std::max_element(sizes.begin(), sizes.end()) / mean;
}

Index default_num_parts(Index num_tets, Index parts_per_thread)
{
    // The machine's online cores, not the process's CPU set (TBB's default concurrency follows
    // that): `mpirun` binds each rank to a core and `taskset` narrows it, and the partition, and
    // with it the bits of every result, would change with them.
    const Index cores = std::max<Index>(1, static_cast<Index>(sysconf(_SC_NPROCESSORS_ONLN)));
    return std::max<Index>(1, std::min<Index>(parts_per_thread * cores, num_tets / MIN_TETS_PER_PART));
}

TetPartition partition_tets(const Tets& tets, Index num_vertices, Index num_parts)
{
    CORO_CHECK(num_parts >= 1, InputError, "partition: " << num_parts << " parts requested, expected >= 1");
    TetPartition partition;
    const Index n_tets = static_cast<Index>(tets.rows());
    partition.num_parts = std::max<Index>(1, std::min(num_parts, n_tets));
    partition.tet_part.assign(static_cast<std::size_t>(n_tets), 0);
    if (partition.num_parts == 1)
        return partition;

    idx_t ne = n_tets, nn = num_vertices, ncommon = 3, nparts = partition.num_parts, objval = 0;
    std::vector<idx_t> eptr(static_cast<std::size_t>(n_tets) + 1), eind(4 * static_cast<std::size_t>(n_tets));
    for (Index t = 0; t <= n_tets; ++t)
        eptr[static_cast<std::size_t>(t)] = 4 * t;
    for (Index t = 0; t < n_tets; ++t)
        for (int a = 0; a < 4; ++a)
            eind[4 * static_cast<std::size_t>(t) + static_cast<std::size_t>(a)] = tets(t, a);
    std::vector<idx_t> epart(static_cast<std::size_t>(n_tets)), npart(static_cast<std::size_t>(num_vertices));
    idx_t options[METIS_NOPTIONS];
    METIS_SetDefaultOptions(options);
    options[METIS_OPTION_SEED] = METIS_SEED;
    options[METIS_OPTION_NUMBERING] = 0;
    const int status = METIS_PartMeshDual(&ne, &nn, eptr.data(), eind.data(), nullptr, nullptr, &ncommon, &nparts,
                                          nullptr, options, &objval, epart.data(), npart.data());
    CORO_CHECK(status == METIS_OK, NumericalError,
               "METIS_PartMeshDual failed with " << metis_status(status) << " for " << n_tets << " tets into "
                                                 << nparts << " parts");
    for (Index t = 0; t < n_tets; ++t)
        partition.tet_part[static_cast<std::size_t>(t)] = static_cast<Index>(epart[static_cast<std::size_t>(t)]);
    partition.edge_cut = static_cast<Index>(objval);
    return partition;
}

} // namespace coro
