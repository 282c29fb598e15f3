#pragma once
/// @file case_spec.hpp
/// @brief Everything a case file says, as plain data (io/case_reader.hpp fills it).
///
/// Defaults here are the documented defaults of docs/case_file.md; units are those of the
/// case (the examples use SI: m, kg, s, N, Pa).

#include <corocontact/core/material.hpp>
#include <corocontact/core/primitives.hpp>
#include <corocontact/core/types.hpp>
#include <corocontact/solver/bsr_matrix.hpp>
#include <corocontact/solver/preconditioner.hpp>

#include <array>
#include <filesystem>
#include <string>
#include <vector>

namespace coro {

enum class Analysis { DYNAMIC, STATIC };
enum class ContactMode { EXACT, PAPER };
enum class CrossCheck { NONE, EMBREE };

/// `[simulation]`
struct SimulationSettings {
    std::string name;                  ///< default: the case file's stem
    Analysis analysis = Analysis::DYNAMIC;
    double dt = 0.01;                  ///< time step [s], > 0 (dynamic)
    Index steps = 100;                 ///< time steps (dynamic), ≥ 1
    Index load_steps = 10;             ///< load increments (static), ≥ 1
    Vec3 gravity = Vec3::Zero();       ///< [m/s²]
    Index output_every = 1;            ///< write every k-th step (dynamic), ≥ 1
    std::filesystem::path output_dir;  ///< default: out/<name> relative to the working directory
};

/// `[solver]`
struct SolverSettings {
    Index max_iterations = 100;        ///< PCG iteration cap per solve, ≥ 1
    double tolerance = 1e-6;           ///< PCG relative residual, ≥ 0 (0: every solve runs the cap)
    PcgPreconditioner preconditioner = PcgPreconditioner::BLOCK_JACOBI;
    MatrixPrecision matrix_precision = MatrixPrecision::DOUBLE; ///< how the system matrices store values
    double static_tolerance = 1e-8;    ///< static: residual relative to the load, > 0
    Index static_max_iterations = 50;  ///< static: Newton iterations per load step, ≥ 1
    Index parts_per_thread = 4;        ///< METIS parts per thread (partitioned loops), ≥ 1
};

/// Largest Coulomb coefficient a case may give: measured coefficients of material pairs lie
/// below about 2, and the implicit friction term grows with μ until it swamps the step's matrix
/// (two spheres in an impact: PCG at its cap of 100 iterations ended at a relative residual of
/// 0.04 with μ = 10, 4 with μ = 1000, 6e4 with μ = 1e12).
constexpr double MAX_FRICTION = 10.0;

/// `[contact]`
struct ContactSettings {
    bool enabled = false;
    ContactMode mode = ContactMode::EXACT;
    double stiffness = 1e5;            ///< penalty [N/m], > 0
    double damping = 0.0;              ///< contact damping [N·s/m], ≥ 0
    double friction = 0.0;             ///< Coulomb coefficient μ, in [0, MAX_FRICTION]
    CrossCheck cross_check = CrossCheck::NONE;
};

/// `[[body.fixed]]`: nodes inside the box (after the body transform) do not move.
struct FixedRegion {
    Vec3 min = Vec3::Constant(-1e300);
    Vec3 max = Vec3::Constant(1e300);
};

/// `[[body.load]]`: the total force is split equally over the nodes inside the box.
struct BoxLoad {
    Vec3 min = Vec3::Constant(-1e300);
    Vec3 max = Vec3::Constant(1e300);
    Vec3 force = Vec3::Zero();         ///< total force [N]
};

enum class BodyShape { MESH, BOX, SPHERE };

/// One `[[body]]`.
struct BodySpec {
    std::string name;
    std::string location;              ///< "case.toml:12" of the [[body]] header, for messages
    BodyShape shape = BodyShape::MESH;
    std::filesystem::path mesh;        ///< absolute after reading (shape = MESH)
    std::filesystem::path surface;     ///< optional embedded surface, absolute; empty if none
    Vec3 box_min = Vec3::Zero();       ///< shape = BOX
    Vec3 box_max = Vec3::Ones();
    std::array<Index, 3> cells{1, 1, 1};
    Vec3 center = Vec3::Zero();        ///< shape = SPHERE
    double radius = 1.0;
    Index resolution = 8;
    BodyTransform transform;
    Vec3 velocity = Vec3::Zero();      ///< initial velocity [m/s]
    Material material;
    double rayleigh_mass = 0.0;        ///< α of C = αM + βK' [1/s]
    double rayleigh_stiffness = 0.0;   ///< β of C = αM + βK' [s]
    std::vector<FixedRegion> fixed;
    std::vector<BoxLoad> loads;
};

enum class ObstacleType { PLANE, MESH };

/// One `[[obstacle]]`: rigid and static.
struct ObstacleSpec {
    ObstacleType type = ObstacleType::PLANE;
    std::string location;              ///< "case.toml:40", for messages
    Vec3 point = Vec3::Zero();         ///< plane
    Vec3 normal = Vec3::UnitY();       ///< plane, normalised after reading
    std::filesystem::path mesh;        ///< mesh obstacle surface, absolute
};

/// A whole case file.
struct CaseSpec {
    std::filesystem::path file;        ///< the case file as given
    SimulationSettings simulation;
    SolverSettings solver;
    ContactSettings contact;
    std::vector<BodySpec> bodies;
    std::vector<ObstacleSpec> obstacles;
};

} // namespace coro
