#pragma once
/// @file block_names.hpp
/// @brief The names of a frame's blocks besides the bodies' own (each body's block is named
/// after the body): they name the .vtu files too, so the case reader refuses a body name that
/// one of them already takes.

#include <corocontact/core/types.hpp>

#include <string>

namespace coro {

/// The block of a body's embedded contact surface: "<body>_surface".
inline std::string surface_block_name(const std::string& body_name) { return body_name + "_surface"; }

/// The block of the k-th mesh obstacle (0-based, counting mesh obstacles only): "obstacle<k>".
inline std::string obstacle_block_name(Index k) { return "obstacle" + std::to_string(k); }

/// The block of the k-th plane obstacle (0-based, counting planes only): "plane<k>".
inline std::string plane_block_name(Index k) { return "plane" + std::to_string(k); }

} // namespace coro
