#pragma once
// Private to io/: what the Gmsh MSH readers (ASCII and binary) share: the builder that maps
// node tags to indices in file order and collects tets, and the node count of each element type.

#include <corocontact/core/error.hpp>
#include <corocontact/core/tet_mesh.hpp>

#include <algorithm>
#include <array>
#include <cstdint>
#include <limits>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

namespace coro::detail {

/// Fewest bytes one node or one element takes in any MSH flavour ("1 0 0 0\n", "1 4 0 1 2 3 4\n"
/// minus blanks): a header count is never trusted beyond what the file's size can hold.
constexpr std::size_t MSH_MIN_NODE_BYTES = 8;
constexpr std::size_t MSH_MIN_ELEMENT_BYTES = 10;

/// Gmsh element type of the 4-node tetrahedron; points, lines and surface elements are skipped,
/// other volume elements refused (msh_other_volume_element).
constexpr int MSH_TET4 = 4;

/// The name of a Gmsh volume element type other than the 4-node tetrahedron ("10-node
/// tetrahedron", "hexahedron", ...), or null for the tet and for points, lines and surfaces,
/// which a mesh carries for its physical groups and the reader skips. A volume element of
/// another type is refused: skipped, its volume would be missing from the body.
inline const char* msh_other_volume_element(int type)
{
    switch (type) {
    case 5: return "8-node hexahedron";
    case 6: return "6-node prism";
    case 7: return "5-node pyramid";
    case 11: return "10-node tetrahedron";
    case 12: return "27-node hexahedron";
    case 13: return "18-node prism";
    case 14: return "14-node pyramid";
    case 17: return "20-node hexahedron";
    case 18: return "15-node prism";
    case 19: return "13-node pyramid";
    case 29: return "20-node tetrahedron";
    case 30: return "35-node tetrahedron";
    case 31: return "56-node tetrahedron";
    case 92: return "64-node hexahedron";
    case 93: return "125-node hexahedron";
    default: return nullptr;
    }
}

/// Number of nodes of a Gmsh element type (the table of the MSH format documentation), or 0
/// for a type this table does not know. Binary files need it to skip elements of other types.
inline int msh_nodes_per_element(int type)
{
    static constexpr std::array<int, 32> NODES = {0,  2,  3,  4,  4, 8,  6,  5,  3,  6, 9,
                                                  10, 27, 18, 14, 1, 8,  20, 15, 13, 9, 10,
                                                  12, 15, 15, 21, 4, 5,  6,  20, 35, 56};
    if (type >= 0 && type < static_cast<int>(NODES.size()))
        return NODES[static_cast<std::size_t>(type)];
    if (type == 92)
        return 64; // 3rd-order hexahedron
    if (type == 93)
        return 125; // 4th-order hexahedron
    return 0;
}

/// Refuses an element of `type` when it may be a volume element other than the 4-node
/// tetrahedron: one of msh_other_volume_element's, any element of a 3-D entity (`dimension`
/// 3, as MSH 4.1 says; −1 where the format does not say), or a type msh_nodes_per_element does
/// not know (Gmsh has higher-order prisms, pyramids and hexahedra beyond its table).
/// @param[in] where  the place in the file, for the message ("mesh.msh:12")
inline void refuse_other_volume_element(int type, int dimension, const std::string& where)
{
    if (type == 4)
        return;
    const char* name = msh_other_volume_element(type);
    if (name == nullptr && dimension == 3)
        name = "an element of a volume";
    if (name != nullptr)
        CORO_THROW(InputError, where << ": element type " << type << " (" << name
                                     << ") is a volume element corocontact cannot use; expected 4-node "
                                        "tetrahedra (type 4) only: mesh the body with linear tets (Gmsh: "
                                        "-order 1 and no recombination)");
    CORO_CHECK(msh_nodes_per_element(type) > 0, InputError,
               where << ": unknown element type " << type << " (expected a Gmsh element type such as 4, the tet)");
}

/// Nodes and tets as they are read, with node tags mapped to 0-based indices in file order.
/// Every check takes `where`, a callable returning the input location ("path:line" or
/// "path: byte N") that is called only to build a failure message.
class MshBuilder {
public:
    /// @param[in] unit        what a location number counts ("line", "byte"), for messages
    /// @param[in] file_bytes  size of the file: reservations never exceed what it can hold
    MshBuilder(std::string unit, std::size_t file_bytes)
        : m_unit(std::move(unit)), m_file_bytes(file_bytes)
    {
    }

    /// Registers the tag of the next node; `location` (line or byte offset) is kept for the
    /// message about a later duplicate.
    template <class Where>
    void add_node_tag(const Where& where, long location, std::uint64_t tag)
    {
        const auto index = m_node_locations.size();
        CORO_CHECK(index < static_cast<std::size_t>(std::numeric_limits<Index>::max()), InputError,
                   where() << ": too many nodes for a 32-bit index");
        const auto [it, inserted] = m_index_of_tag.emplace(tag, static_cast<Index>(index));
        CORO_CHECK(inserted, InputError,
                   where() << ": duplicate node tag " << tag << " (first defined at " << m_unit
                           << " " << m_node_locations[static_cast<std::size_t>(it->second)]
                           << ")");
        m_node_locations.push_back(location);
    }

    /// Appends the coordinates of the next node; `add_node_tag` must have been called first.
    void add_node_coordinates(const std::array<double, 3>& x)
    {
        m_positions.insert(m_positions.end(), x.begin(), x.end());
    }

    /// Reserves for `count` more nodes, at most as many as the file's bytes can hold.
    void reserve_nodes(std::uint64_t count)
    {
        const auto n = static_cast<std::size_t>(
            std::min<std::uint64_t>(count, m_file_bytes / MSH_MIN_NODE_BYTES + 1));
        m_node_locations.reserve(m_node_locations.size() + n);
        m_positions.reserve(m_positions.size() + 3 * n);
        m_index_of_tag.reserve(m_index_of_tag.size() + n);
    }

    /// Reserves for `count` more tets, at most as many as the file's bytes can hold.
    void reserve_elements(std::uint64_t count)
    {
        const auto n = static_cast<std::size_t>(
            std::min<std::uint64_t>(count, m_file_bytes / MSH_MIN_ELEMENT_BYTES + 1));
        m_tets.reserve(m_tets.size() + 4 * n);
        m_tet_tags.reserve(m_tet_tags.size() + n);
        m_tet_locations.reserve(m_tet_locations.size() + n);
    }

    /// Appends a tet given by node tags, mapping them to indices; the tags must be distinct and
    /// known. `location` (line or byte offset) is kept for the message about a later duplicate.
    template <class Where>
    void add_tet(const Where& where, long location, std::uint64_t element_tag,
                 const std::array<std::uint64_t, 4>& node_tags)
    {
        CORO_CHECK(m_tets.size() / 4 < static_cast<std::size_t>(std::numeric_limits<Index>::max()),
                   InputError, where() << ": too many tets for a 32-bit index");
        for (std::size_t k = 0; k < node_tags.size(); ++k) {
            const std::uint64_t tag = node_tags[k];
            for (std::size_t j = 0; j < k; ++j)
                CORO_CHECK(node_tags[j] != tag, InputError,
                           where() << ": tet element " << element_tag << " repeats node tag " << tag
                                   << " (expected 4 distinct nodes)");
            const auto it = m_index_of_tag.find(tag);
            CORO_CHECK(it != m_index_of_tag.end(), InputError,
                       where() << ": tet element " << element_tag << " references unknown node tag "
                               << tag);
            m_tets.push_back(it->second);
        }
        m_tet_tags.push_back(element_tag);
        m_tet_locations.push_back(location);
    }

    /// Number of nodes read so far.
    std::size_t num_nodes() const { return m_node_locations.size(); }

    /// The mesh as read (not validated, not oriented). A tet listed twice (the same 4 nodes in
    /// any order) is refused here, where its element tags and locations are known;
    /// `where_at(location)` gives "path:line" or "path: byte N" for a location of add_tet.
    template <class WhereAt>
    TetMesh finish(const WhereAt& where_at) const
    {
        TetMesh mesh;
        const auto n_nodes = static_cast<Eigen::Index>(m_node_locations.size());
        const auto n_tets = static_cast<Eigen::Index>(m_tets.size() / 4);
        mesh.rest_positions = Eigen::Map<const Positions>(m_positions.data(), n_nodes, 3);
        mesh.tets = Eigen::Map<const Tets>(m_tets.data(), n_tets, 4);
        if (const auto duplicate = find_duplicate_tet(mesh.tets)) {
            const auto first = static_cast<std::size_t>(duplicate->first);
            const auto second = static_cast<std::size_t>(duplicate->second);
            CORO_THROW(InputError, where_at(m_tet_locations[second])
                                       << ": tet element " << m_tet_tags[second]
                                       << " has the same 4 nodes as tet element " << m_tet_tags[first] << " ("
                                       << m_unit << " " << m_tet_locations[first]
                                       << "); expected every tet once (Gmsh's MSH 2 format repeats a volume's "
                                          "elements for each physical group the volume belongs to: give the "
                                          "volume one physical group, or save as MSH 4.1)");
        }
        return mesh;
    }

private:
    std::string m_unit;
    std::size_t m_file_bytes = 0;
    std::vector<double> m_positions;     // 3 per node, in file order
    std::vector<long> m_node_locations;  // line or byte of each node's tag
    std::unordered_map<std::uint64_t, Index> m_index_of_tag;
    std::vector<Index> m_tets; // 4 per tet
    std::vector<std::uint64_t> m_tet_tags; // element tag of each tet
    std::vector<long> m_tet_locations;     // line or byte of each tet
};

} // namespace coro::detail
