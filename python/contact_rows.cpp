#include "contact_rows.hpp"

#include <corocontact/core/error.hpp>
#include <corocontact/core/surface_mesh.hpp>
#include <corocontact/core/tet_mesh.hpp>
#include <corocontact/io/case_reader.hpp>
#include <corocontact/io/magnitudes.hpp>
#include <corocontact/io/scene_loader.hpp>
#include <corocontact/sim/scene_contact.hpp>

#include <algorithm>
#include <numeric>
#include <sstream>
#include <tuple>

namespace coro::python {

namespace {

std::size_t at(Index i) { return static_cast<std::size_t>(i); }

ContactMode parse_mode(const std::string& mode)
{
    CORO_CHECK(mode == "exact" || mode == "paper", InputError,
               "mode = '" << mode << "': expected \"exact\" or \"paper\"");
    return mode == "paper" ? ContactMode::PAPER : ContactMode::EXACT;
}

/// Checks a caller's triangles: finite vertices, indices in range, three distinct corners.
void check_triangles(const MeshInput& mesh, const std::string& source)
{
    for (Index v = 0; v < mesh.vertices.rows(); ++v)
        CORO_CHECK(mesh.vertices.row(v).allFinite(), InputError,
                   source << ": vertex " << v << " has a non-finite coordinate, expected finite numbers");
    for (Index f = 0; f < mesh.faces.rows(); ++f) {
        for (int c = 0; c < 3; ++c)
            CORO_CHECK(mesh.faces(f, c) >= 0 && mesh.faces(f, c) < mesh.vertices.rows(), InputError,
                       source << ": face " << f << " refers to vertex " << mesh.faces(f, c)
                              << ", expected an index in [0, " << mesh.vertices.rows() << ")");
        CORO_CHECK(mesh.faces(f, 0) != mesh.faces(f, 1) && mesh.faces(f, 1) != mesh.faces(f, 2) &&
                       mesh.faces(f, 0) != mesh.faces(f, 2),
                   InputError, source << ": face " << f << " repeats a vertex, expected 3 distinct vertices");
    }
    CORO_CHECK(mesh.faces.rows() > 0, InputError, source << ": no faces, expected at least one triangle");
}

/// Detection as `corocontact detect` does it: the first `num_bodies` surfaces against each other
/// and the obstacle surfaces, then against the planes.
std::vector<ContactPoint> detect_all(const std::vector<ContactSurface>& surfaces, Index num_bodies,
                                     const std::vector<PlaneObstacle>& planes, const ContactSettings& contact)
{
    std::vector<ContactPoint> points = detect_contacts(surfaces, detection_settings(contact));
    const std::vector<ContactPoint> on_planes = detect_plane_contacts(surfaces, num_bodies, planes);
    points.insert(points.end(), on_planes.begin(), on_planes.end());
    return points;
}

} // namespace

ContactRows contact_rows(const std::vector<ContactSurface>& surfaces, Index num_planes,
                         const std::vector<ContactPoint>& points)
{
    ContactRows rows;
    for (const ContactSurface& surface : surfaces)
        rows.names.push_back(surface.name);
    for (Index k = 0; k < num_planes; ++k)
        rows.names.push_back("plane" + std::to_string(k));
    // Planes are numbered after every surface: the CSV's order (sim/scene_contact.cpp).
    const auto other_index = [&](const ContactTarget& other) {
        return other.is_surface() ? other.index : static_cast<Index>(surfaces.size()) + other.index;
    };
    std::vector<std::tuple<Index, Index, Index, std::size_t>> order;
    order.reserve(points.size());
    for (std::size_t i = 0; i < points.size(); ++i) {
        const ContactPoint& p = points[i];
        order.emplace_back(p.body, surfaces[at(p.body)].source_id[at(p.vertex)], other_index(p.other), i);
    }
    std::sort(order.begin(), order.end());
    rows.normal.resize(static_cast<Index>(points.size()), 3);
    Index r = 0;
    for (const auto& [body, vertex, other, i] : order) {
        rows.body.push_back(body);
        rows.vertex.push_back(vertex);
        rows.other.push_back(other);
        rows.depth.push_back(points[i].depth);
        rows.normal.row(r++) = points[i].normal.transpose();
    }
    return rows;
}

ContactRows detect_case(const std::filesystem::path& case_file, const std::string& mode,
                        std::vector<std::string>& warnings)
{
    const ContactMode contact_mode = parse_mode(mode);
    CaseSpec spec = read_case(case_file);
    spec.contact.mode = contact_mode;
    LoadedScene loaded = load_scene(spec);
    warnings.insert(warnings.end(), loaded.warnings.begin(), loaded.warnings.end());
    const std::vector<ContactSurface> surfaces = make_scene_surfaces(loaded.scene);
    const std::vector<ContactPoint> points = detect_all(
        surfaces, static_cast<Index>(loaded.scene.bodies.size()), loaded.scene.planes, spec.contact);
    return contact_rows(surfaces, static_cast<Index>(loaded.scene.planes.size()), points);
}

ContactRows detect_meshes(std::vector<MeshInput> meshes, const std::string& mode, std::vector<std::string>& warnings)
{
    ContactSettings contact;
    contact.mode = parse_mode(mode);
    std::vector<ContactSurface> surfaces;
    surfaces.reserve(meshes.size());
    for (std::size_t m = 0; m < meshes.size(); ++m) {
        MeshInput& mesh = meshes[m];
        const std::string source = "meshes[" + std::to_string(m) + "] ('" + mesh.name + "')";
        if (mesh.faces.rows() == 0 && mesh.tets.rows() > 0) {
            TetMesh tets{mesh.vertices, mesh.tets};
            validate_and_orient(tets, source);
            mesh.faces = boundary_faces(tets);
        } else {
            check_triangles(mesh, source);
        }
        check_contact_lengths(mesh.vertices, mesh.faces, source);
        const SurfaceCheck check = check_surface(mesh.faces);
        if (!check.closed_and_oriented()) {
            std::ostringstream message;
            message << source << " is not a closed, consistently oriented surface (" << check.open_edges << " open, "
                    << check.nonmanifold_edges << " non-manifold, " << check.misoriented_edges
                    << " misoriented edges); contact tests points against it by the winding number only";
            warnings.push_back(message.str());
        } else if (enclosed_volume(mesh.vertices, mesh.faces) < 0.0) {
            mesh.faces.col(1).swap(mesh.faces.col(2));
            warnings.push_back(source + " had inward normals; its faces were flipped");
        }
        surfaces.push_back(ContactSurface::from_body(mesh.name, mesh.vertices, mesh.faces));
    }
    const std::vector<ContactPoint> points =
        detect_all(surfaces, static_cast<Index>(surfaces.size()), {}, contact);
    return contact_rows(surfaces, 0, points);
}

} // namespace coro::python
