#pragma once
// Contact detection for the Python module and its results as rows: the only place here that
// calls the contact module's detection and reads ContactPoint, so a change of either is made
// here alone.

#include <corocontact/contact/contact_surface.hpp>
#include <corocontact/contact/detector.hpp>
#include <corocontact/contact/plane_obstacle.hpp>
#include <corocontact/sim/case_spec.hpp>

#include <filesystem>
#include <string>
#include <vector>

namespace coro::python {

/// Detected contacts, one row per surface vertex inside another body or obstacle, ordered as
/// the rows of `corocontact detect --csv`: by body, then vertex, then other.
struct ContactRows {
    /// What `other` indexes: the contact surfaces' names (bodies in case order, then mesh
    /// obstacles "obstacle<k>"), then the planes "plane<k>"; a body's index is its own.
    std::vector<std::string> names;
    std::vector<Index> body;   ///< index into names (always a body)
    std::vector<Index> vertex; ///< the vertex's index in its body's mesh file (in its surface
                               ///< file, for an embedded surface)
    std::vector<Index> other;  ///< index into names
    std::vector<double> depth; ///< [m], ≥ 0
    Positions normal;          ///< #rows×3 outward unit normal of the other surface (or plane)
};

/// Rows of detected contacts.
/// @param[in] surfaces    as detection used them (ContactSurface::source_id gives `vertex`)
/// @param[in] num_planes  plane obstacles the points may refer to
/// @param[in] points      detection output
ContactRows contact_rows(const std::vector<ContactSurface>& surfaces, Index num_planes,
                         const std::vector<ContactPoint>& points);

/// `corocontact detect CASE --mode MODE --csv`, as rows.
/// @param[in] mode  "exact" or "paper"
/// @param[out] warnings  what `detect` prints as "warning: ..." while loading
/// @throws InputError as `corocontact detect`, or for another mode
ContactRows detect_case(const std::filesystem::path& case_file, const std::string& mode,
                        std::vector<std::string>& warnings);

/// A surface given by the caller: triangles, or tets whose boundary is taken.
struct MeshInput {
    std::string name;
    Positions vertices; ///< #V×3 [m]
    Tris faces;         ///< #F×3, outward (counter-clockwise from outside); or empty
    Tets tets;          ///< #T×4, used when faces is empty
};

/// Detection among the caller's meshes (no obstacles). Vertices are checked finite, indices in
/// range and distinct within a face or tet; tets are oriented (core/tet_mesh.hpp
/// validate_and_orient). A closed surface with inward normals is flipped (with a warning); an
/// open one is tested by the winding number (with a warning).
/// @param[in] mode  "exact" or "paper"
/// @throws InputError naming the mesh ("meshes[2]" or its name) and the element
ContactRows detect_meshes(std::vector<MeshInput> meshes, const std::string& mode, std::vector<std::string>& warnings);

} // namespace coro::python
