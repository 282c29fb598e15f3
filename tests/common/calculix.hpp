#pragma once
/// @file calculix.hpp
/// @brief An independent reference for the static tests: the same tet mesh, material, fixed
/// nodes and nodal forces solved by CalculiX (`ccx`, Debian package calculix-ccx).
///
/// The model is written as C3D4 elements (our positive orientation is CalculiX's), one
/// *STATIC step, optionally with NLGEOM (total Lagrangian, St.Venant–Kirchhoff with *ELASTIC:
/// large rotations, small strains), and *NODE PRINT of U, read back from the .dat file.
/// Errors (ccx missing, a non-zero exit code, an unfinished step, an unreadable .dat) throw
/// std::runtime_error with the reason, so a test that calls these fails with a clear message;
/// nothing here skips.

#include <corocontact/core/material.hpp>
#include <corocontact/core/tet_mesh.hpp>
#include <corocontact/core/types.hpp>

#include <filesystem>
#include <string>
#include <vector>

namespace coro::test {

/// The *STEP of a CalculiX static analysis; step time runs from 0 to 1.
struct CalculixStep {
    bool nlgeom = false;             ///< geometric nonlinearity (`*STEP, NLGEOM`)
    double initial_increment = 0.05; ///< first time increment, in (0, 1]
    double min_increment = 1e-5;     ///< smallest increment after cutbacks
    double max_increment = 0.1;      ///< largest increment, in (0, 1]
    Index max_increments = 1000;     ///< `INC=`: increments allowed in the step
};

/// The text of a CalculiX input deck for a body.
/// @param[in] mesh          positively oriented tets; node v becomes CalculiX node v+1
/// @param[in] material      E and ν (*ELASTIC); ρ is not written
/// @param[in] fixed         #V flags, non-zero: all three DOFs held at zero (*BOUNDARY)
/// @param[in] nodal_forces  #3V dead loads [N] (*CLOAD, non-zero components only)
/// @param[in] step          analysis settings
/// @return the deck, with *NODE PRINT of U for every node at every increment
std::string calculix_input(const TetMesh& mesh, const Material& material,
                           const std::vector<char>& fixed, CRef<VecX> nodal_forces,
                           const CalculixStep& step);

/// Displacements of the last `displacements (vx,vy,vz) for set ... and time ...` block of a
/// CalculiX .dat file.
/// @param[in] dat           the .dat file
/// @param[in] num_vertices  #V; every node 1..#V must appear in the last block
/// @param[out] time         step time of that block (1 when the step finished), if not null
/// @return #V×3 displacements, row v = CalculiX node v+1
/// @throws std::runtime_error naming the file and line when it cannot be read or is incomplete
Positions read_calculix_displacements(const std::filesystem::path& dat, Index num_vertices,
                                      double* time = nullptr);

/// Writes `<dir>/<job>.inp`, runs `ccx -i <job>` in `dir` (output in `<dir>/<job>.log`),
/// checks the exit code and that the step reached time 1, and reads the displacements.
/// @param[in] dir  scratch directory, created if missing
/// @param[in] job  job name: letters, digits, '_' and '-'
/// @return #V×3 displacements at the end of the step
/// @throws std::runtime_error if ccx is not on PATH (install calculix-ccx, see
///         tools/setup.sh), exits non-zero, stops before time 1, or writes no readable .dat
Positions run_calculix(const TetMesh& mesh, const Material& material,
                       const std::vector<char>& fixed, CRef<VecX> nodal_forces,
                       const CalculixStep& step, const std::filesystem::path& dir,
                       const std::string& job);

} // namespace coro::test
