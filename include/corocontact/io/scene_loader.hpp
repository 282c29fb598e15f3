#pragma once
/// @file scene_loader.hpp
/// @brief Turns a case into bodies: reads or generates meshes, transforms, validates.

#include <corocontact/sim/case_spec.hpp>
#include <corocontact/sim/simulation.hpp>

#include <functional>
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

/// Told what load_scene() does next, e.g. "body 'ball' (2 of 64): reading ball.msh".
using LoadProgress = std::function<void(const std::string& stage)>;

/// Builds every body of the case. Nodes used by no tet are held fixed (with a warning).
/// @param[in] progress  called before each stage (may be empty)
/// @throws InputError as load_body_mesh, for a fixed/load box that holds no node, or, in a
///         static analysis, for a body whose fixed nodes leave a rigid-body motion free (none
///         fixed, or all on one line)
LoadedScene load_scene(const CaseSpec& spec, const LoadProgress& progress = {});

} // namespace coro
