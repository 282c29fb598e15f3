#pragma once
// Feeding one fuzz input to one of corocontact's readers. The readers take file paths, so the
// bytes are written to a file in a per-process scratch folder first. Shared by the libFuzzer
// targets (fuzz/fuzz_*.cpp) and the regression test that replays the corpus and every input
// that ever crashed (tests/fuzz_regressions/).

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string>

namespace coro::fuzz {

/// What an input goes through.
enum class Target {
    MSH,    ///< read_tet_mesh("x.msh"): Gmsh 2.2 / 4.1, ASCII or binary
    TETGEN, ///< read_tet_mesh("x.ele") with x.node: the input is split at TETGEN_SEPARATOR
    OBJ,    ///< read_surface("x.obj")
    STL,    ///< read_surface("x.stl")
    OFF,    ///< read_surface("x.off")
    CASE,   ///< read_case("x.toml")
    SCENE,  ///< read_case + load_scene, with a small cube.msh and cube.obj next to the case
};

/// The line that splits a TETGEN input into the .node part (before) and the .ele part (after).
/// A file without it is all .node, with an empty .ele.
inline constexpr const char* TETGEN_SEPARATOR = "#--ele--";

/// How the reader answered. Anything else (a crash, a sanitizer report, another exception,
/// a hang, a huge allocation) is a finding.
enum class Outcome { READ, INPUT_ERROR, NUMERICAL_ERROR, SKIPPED };

/// The target whose corpus folder (fuzz/corpus/<name>/) and executable (fuzz_<name>) have
/// this name: msh, tetgen, obj, stl, off, case, scene. Throws std::invalid_argument otherwise.
Target target_from_name(const std::string& name);

/// Writes the input where the target's reader expects it and calls the reader, catching
/// InputError and NumericalError. The SCENE target skips (SKIPPED) a case whose generated
/// meshes would be larger than a fuzz iteration should build (box cells or sphere resolution
/// beyond a few thousand tets): a legitimate request for a big mesh, not a bug.
/// @param[in] message  if not null, receives the exception message for the error outcomes
Outcome feed(Target target, const std::uint8_t* data, std::size_t size,
             std::string* message = nullptr);

/// The per-process scratch folder (under $TMPDIR, else /dev/shm, else /tmp), created on first
/// use and removed at exit.
const std::filesystem::path& scratch_dir();

} // namespace coro::fuzz
