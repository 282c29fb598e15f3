#pragma once
/// @file tet_mesh.hpp
/// @brief A tetrahedral mesh: rest positions and tets, plus load-time validation.

#include <corocontact/core/types.hpp>

#include <array>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace coro {

/// A linear tetrahedral mesh in its rest configuration.
struct TetMesh {
    Positions rest_positions; ///< #V×3 node coordinates (length unit of the case).
    Tets tets;                ///< #T×4 node indices, positive orientation after orient_tets().

    Index num_vertices() const { return static_cast<Index>(rest_positions.rows()); }
    Index num_tets() const { return static_cast<Index>(tets.rows()); }
};

/// Local faces of a positively oriented tet (nodes 0..3), each ordered so that its normal
/// points away from the opposite node.
inline constexpr std::array<std::array<int, 3>, 4> TET_FACES{{{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}}};

/// Largest node coordinate magnitude validate_and_orient accepts: tets of larger size have
/// volumes (edge³) beyond the range of double.
constexpr double MAX_COORDINATE = 1e100;

/// Signed volume det([x1−x0, x2−x0, x3−x0])/6 of one tet.
double signed_volume(const Vec3& x0, const Vec3& x1, const Vec3& x2, const Vec3& x3);

/// Signed volume of tet `t` of `mesh`.
double signed_volume(const TetMesh& mesh, Index t);

/// Sum of the tets' volumes.
double total_volume(const TetMesh& mesh);

/// The first tet (in file order) whose four nodes another, earlier tet already has, in any
/// order: {earlier, later}; nothing if every tet is listed once.
std::optional<std::pair<Index, Index>> find_duplicate_tet(const Tets& tets);

/// Two tets that overlap across a face they share.
struct TetOverlap {
    Index first = 0;               ///< the earlier of the two tets (file order)
    Index second = 0;              ///< the later one
    std::array<Index, 3> face{};   ///< the shared face's nodes, ascending
    bool shared_by_more = false;   ///< more than two tets share the face
};

/// The first face (in file order of its later tet) shared by two tets lying on the same side
/// of it, or by more than two tets: in a valid mesh an interior face has exactly one tet on
/// each side. Nothing if there is none.
/// @param[in] mesh  positively oriented tets (after validate_and_orient's reorientation)
std::optional<TetOverlap> find_overlapping_tets(const TetMesh& mesh);

/// Validates a freshly read mesh and makes every tet positively oriented.
///
/// Checks: at least one tet, finite coordinates of magnitude at most MAX_COORDINATE, indices
/// in range, no node repeated within a tet, volume above a relative threshold (1e-12 × the mean
/// edge length cubed, which must not underflow), and no two tets overlapping across a shared
/// face, a tet listed twice named as such. Negative-volume tets are reoriented (swap of nodes 2
/// and 3).
/// @param[in,out] mesh  the mesh, reoriented in place
/// @param[in] source    name of the input (file or body) used in messages
/// @return the number of tets that were reoriented (callers warn when it is > 0)
/// @throws InputError naming `source` and the element when a check fails
Index validate_and_orient(TetMesh& mesh, const std::string& source);

/// Mean-ratio quality of tet `t`: 12 (3V)^(2/3) / Σ edge², 1 for a regular tet, → 0 for a
/// degenerate one, negative for an inverted one.
double mean_ratio_quality(const TetMesh& mesh, Index t);

/// Nodes referenced by no tet (they carry no stiffness and no mass).
std::vector<Index> unreferenced_vertices(const TetMesh& mesh);

/// Nodes of tets that lie exactly where a node of a smaller index lies, each as {that first
/// node, this one}, ordered by position. Such nodes are not joined: the tets on either side of
/// them are separate pieces (unmerged duplicates of a mesher, or a mesh written twice).
std::vector<std::array<Index, 2>> coincident_vertices(const TetMesh& mesh);

} // namespace coro
