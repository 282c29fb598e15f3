#pragma once
/// @file scene_loader.hpp
/// @brief Turns a case into bodies: reads or generates meshes, transforms, validates.

#include <corocontact/sim/case_spec.hpp>
#include <corocontact/sim/simulation.hpp>

#include <string>
#include <vector>

namespace coro {

/// A scene ready to run, with what the user should be warned about.
struct LoadedScene {
    Scene scene;
    std::vector<std::string> warnings; ///< e.g. reoriented tets, nodes used by no tet
};

/// Builds the mesh of one body: read from its file or generated (box, sphere), then
/// transformed, validated and oriented. Messages name the body's case location.
/// @param[out] warnings  appended to
/// @throws InputError naming the case file line and the mesh file for any bad input
TetMesh load_body_mesh(const BodySpec& spec, std::vector<std::string>& warnings);

/// Builds every body of the case. Nodes used by no tet are held fixed (with a warning).
/// @throws InputError as load_body_mesh, or for a fixed/load box that holds no node
LoadedScene load_scene(const CaseSpec& spec);

} // namespace coro
