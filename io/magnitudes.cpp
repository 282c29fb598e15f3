#include <corocontact/io/magnitudes.hpp>

#include <corocontact/core/error.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

namespace coro {
namespace {

constexpr double LOG_LOW = -140.0;
constexpr double LOG_HIGH = 140.0;
constexpr double LOG_MAX_COORDINATE_PER_EDGE = 10.0;
/// log10 of the largest dt²·(λ+2μ)/(ρ·h²) the implicit step accepts with double and with single
/// matrix values; see check_stiffness_to_mass_ratio.
constexpr double LOG_MAX_STIFFNESS_TO_MASS = 10.0;
constexpr double LOG_MAX_STIFFNESS_TO_MASS_SINGLE = 4.0;

/// "3.2e-600" for 10^log10, also beyond the range of double.
std::string power_text(double log10)
{
    double exponent = std::floor(log10);
    double mantissa = std::pow(10.0, log10 - exponent);
    if (mantissa >= 9.95) {
        mantissa = 1.0;
        exponent += 1.0;
    }
    std::ostringstream text;
    text.precision(2);
    text << mantissa << "e" << (exponent >= 0 ? "+" : "") << static_cast<long>(exponent);
    return text.str();
}

/// What the mesh gives the scales: edge lengths, tet volumes, coordinate magnitude.
struct Geometry {
    double shortest_edge = std::numeric_limits<double>::infinity();
    double longest_edge = 0.0;
    double smallest_volume = std::numeric_limits<double>::infinity();
    double largest_volume = 0.0;
    double largest_coordinate = 0.0;
};

Geometry measure(const TetMesh& mesh)
{
    Geometry g;
    const auto& x = mesh.rest_positions;
    for (Index t = 0; t < mesh.num_tets(); ++t) {
        for (int a = 0; a < 4; ++a)
            for (int b = a + 1; b < 4; ++b) {
                const double edge = (x.row(mesh.tets(t, a)) - x.row(mesh.tets(t, b))).norm();
                g.shortest_edge = std::min(g.shortest_edge, edge);
                g.longest_edge = std::max(g.longest_edge, edge);
            }
        const double volume = std::abs(signed_volume(mesh, t));
        g.smallest_volume = std::min(g.smallest_volume, volume);
        g.largest_volume = std::max(g.largest_volume, volume);
    }
    g.largest_coordinate = x.size() > 0 ? x.cwiseAbs().maxCoeff() : 0.0;
    return g;
}

/// One scale: a product of positive factors, each named by its key ("simulation.dt") and
/// value, with a power (dt² is dt to the power 2, a mass in a denominator has -1, a factor
/// that does not apply has 0), and for a derived factor the key it is derived from
/// ("poisson = 0.3").
struct Factor {
    Factor(std::string name_, double value_, double power_ = 1.0, std::string derived_from_ = {})
        : name(std::move(name_)), value(value_), power(power_), derived_from(std::move(derived_from_))
    {
    }
    std::string name;
    double value;
    double power;
    std::string derived_from;
};

class ScaleCheck {
public:
    explicit ScaleCheck(const BodySpec& body) : m_body(body) {}

    /// Refuses the product of `factors` outside [1e-140, 1e140]; factors of value 0 make the
    /// term absent (no gravity, no damping), so nothing is checked.
    void operator()(const std::string& what, const std::vector<Factor>& factors) const
    {
        double log10 = 0.0;
        for (const Factor& f : factors) {
            if (f.power == 0.0)
                continue;
            if (f.value == 0.0)
                return;
            log10 += f.power * std::log10(f.value);
        }
        if (log10 >= LOG_LOW && log10 <= LOG_HIGH)
            return;
        std::ostringstream from;
        for (const Factor& f : factors)
            if (f.power != 0.0)
            {
                from << (from.tellp() == 0 ? "" : ", ") << f.name << " = " << f.value;
                if (!f.derived_from.empty())
                    from << " (from " << f.derived_from << ")";
            }
        CORO_THROW(InputError, m_body.location
                                   << ": body '" << m_body.name << "': " << what << " is about " << power_text(log10)
                                   << ", expected between 1e-140 and 1e+140 (the solver multiplies and squares such "
                                      "values; beyond that range they overflow or vanish in double arithmetic); it "
                                      "comes from "
                                   << from.str() << ": check these values and their units");
    }

private:
    const BodySpec& m_body;
};

/// The implicit step solves (M + dt²K)Δv = …, whose diagonal adds a node's mass, about ρh³, to
/// its stiffness times dt², about dt²(λ+2μ)h (h: the shortest edge). Their ratio
/// r = dt²(λ+2μ)/(ρh²) is the square of the number of shortest edges a pressure wave crosses in
/// one step. Double keeps about 16 digits of the sum, so the mass, the only term that carries a
/// free body's motion (rigid-body modes have no stiffness), keeps 16 − log10(r) of them: the
/// error of the motion grows as r × 1e-16 (measured on a free falling box: 1e-4 of the fall at
/// r = 5e11, half of it at r = 5e13, none at r = 5e15, where PCG also meets pᵀAp = 0). Up to
/// r = 1e10 it stays below the default PCG tolerance, 1e-6. Single-precision matrix values keep
/// about 7 digits, so the same loss starts at far smaller r: on that box (2×2×2 cells, dt 0.01,
/// 10 steps) the fall was wrong by 3e-4 of itself at r = 1e3, 9e-4 at 1e4, 9e-3 at 1e5 and 0.27
/// at 1e6, with a spurious spread of the nodes of 3.6e-3, 2.7e-2 and 0.09 of the fall from 1e4
/// on; single values are refused beyond r = 1e4.
void check_stiffness_to_mass_ratio(const SimulationSettings& sim, const SolverSettings& solver, const BodySpec& body,
                                   double shortest_edge)
{
    if (sim.analysis != Analysis::DYNAMIC)
        return; // a static step has no mass term
    const Material& m = body.material;
    const double nu = m.poisson;
    const double p_modulus_factor = (1.0 - nu) / ((1.0 + nu) * (1.0 - 2.0 * nu));
    // In log space: the factors may each be near the end of double's range.
    const double log_ratio = 2.0 * std::log10(sim.dt) + std::log10(m.young) + std::log10(p_modulus_factor) -
                             std::log10(m.density) - 2.0 * std::log10(shortest_edge);
    const bool single = solver.matrix_precision == MatrixPrecision::SINGLE;
    const double log_max = single ? LOG_MAX_STIFFNESS_TO_MASS_SINGLE : LOG_MAX_STIFFNESS_TO_MASS;
    if (log_ratio <= log_max)
        return;
    const double headroom = std::pow(10.0, log_max - log_ratio); // < 1
    std::ostringstream bound;
    bound.precision(3);
    bound << "simulation.dt at most " << sim.dt * std::sqrt(headroom) << ", young at most "
          << m.young * headroom << ", or density at least " << m.density / headroom;
    CORO_THROW(InputError, body.location
                               << ": body '" << body.name << "': the stiffness-to-mass ratio of the implicit step, "
                               << "dt²(λ+2μ)/(ρh²), is about " << power_text(log_ratio)
                               << " (from simulation.dt = " << sim.dt << ", young = " << m.young
                               << ", poisson = " << nu << ", density = " << m.density
                               << " and the shortest edge h = " << shortest_edge
                               << "), expected at most " << power_text(log_max)
                               << (single ? " with solver.matrix_precision = \"single\": beyond that, float values lose "
                                            "the mass in the step's matrix and with it the body's free motion; use "
                                            "matrix_precision = \"double\" (up to 1e+10), or "
                                          : ": beyond that, double precision loses the mass in the step's matrix and "
                                            "with it the body's free motion; use ")
                               << bound.str() << " (other values unchanged)");
}

} // namespace

void check_magnitudes(const CaseSpec& spec, const BodySpec& body, const TetMesh& mesh)
{
    const Geometry g = measure(mesh);
    const Material& material = body.material;
    const double nu = material.poisson;
    // λ + 2μ = E(1−ν)/((1+ν)(1−2ν)): the largest modulus of an element's stiffness.
    const double modulus_factor = (1.0 - nu) / ((1.0 + nu) * (1.0 - 2.0 * nu));
    const ScaleCheck check(body);

    const Factor young{"young", material.young};
    std::ostringstream poisson_value;
    poisson_value << "poisson = " << nu;
    const Factor poisson_term{"the factor (1-ν)/((1+ν)(1-2ν))", modulus_factor, 1.0, poisson_value.str()};
    const Factor density{"density", material.density};
    const Factor quarter{"1/4 (a tet's share per node)", 0.25};
    const Factor short_edge{"the shortest edge", g.shortest_edge}, long_edge{"the longest edge", g.longest_edge};
    const Factor small_volume{"the smallest tet volume", g.smallest_volume},
        large_volume{"the largest tet volume", g.largest_volume};
    const Factor coordinate{"the largest node coordinate", g.largest_coordinate};

    for (const Factor& edge : {short_edge, long_edge})
        check("the element stiffness (λ + 2μ) × edge", {young, poisson_term, edge});
    for (const Factor& volume : {small_volume, large_volume})
        check("the node mass (density × volume / 4)", {density, volume, quarter});
    const double gravity = spec.simulation.gravity.stableNorm();
    const double speed = body.velocity.stableNorm();

    const SimulationSettings& sim = spec.simulation;
    const bool dynamic = sim.analysis == Analysis::DYNAMIC;
    const Factor dt{"simulation.dt", dynamic ? sim.dt : 1.0, dynamic ? 1.0 : 0.0};
    const Factor dt2{"simulation.dt", dynamic ? sim.dt : 1.0, dynamic ? 2.0 : 0.0};
    if (dynamic) {
        for (const Factor& edge : {short_edge, long_edge})
            check("dt² × the element stiffness", {dt2, young, poisson_term, edge});
        check("dt² × the element stiffness / the node mass (largest)",
              {dt2, young, poisson_term, long_edge, {density.name, density.value, -1.0},
               {small_volume.name, small_volume.value, -1.0}, {quarter.name, quarter.value, -1.0}});
        check("dt² × the element stiffness / the node mass (smallest)",
              {dt2, young, poisson_term, short_edge, {density.name, density.value, -1.0},
               {large_volume.name, large_volume.value, -1.0}, {quarter.name, quarter.value, -1.0}});
        check("the initial momentum of a node (mass × velocity)",
              {{"|velocity|", speed}, density, large_volume, quarter});
        check("the initial momentum of a node (mass × velocity)",
              {{"|velocity|", speed}, density, small_volume, quarter});
        if (body.rayleigh_mass > 0.0)
            check("dt × rayleigh_mass × the node mass", {dt, {"rayleigh_mass", body.rayleigh_mass}, density, large_volume, quarter});
        if (body.rayleigh_stiffness > 0.0)
            check("dt × rayleigh_stiffness × the element stiffness",
                  {dt, {"rayleigh_stiffness", body.rayleigh_stiffness}, young, poisson_term, long_edge});
    }
    // Right-hand side: dt (dynamic) times the forces.
    check(std::string(dynamic ? "dt × " : "") + "the elastic force of a rest position (stiffness × coordinate)",
          {dt, young, poisson_term, long_edge, coordinate});
    for (const Factor& volume : {small_volume, large_volume})
        check(std::string(dynamic ? "dt × " : "") + "the weight of a node (mass × gravity)",
              {dt, {"|simulation.gravity|", gravity}, density, volume, quarter});
    for (std::size_t k = 0; k < body.loads.size(); ++k) {
        const Factor force{"|body.load[" + std::to_string(k) + "].force|", body.loads[k].force.stableNorm()};
        check(std::string(dynamic ? "dt × " : "") + "a load's total force", {dt, force});
        check(std::string(dynamic ? "dt × " : "") + "a load's force per node",
              {dt, force, {"1/#nodes", 1.0 / mesh.num_vertices()}});
    }

    const ContactSettings& contact = spec.contact;
    if (contact.enabled) {
        const Factor stiffness{"contact.stiffness", contact.stiffness};
        for (const Factor& edge : {short_edge, long_edge})
            check("the contact force at a depth of one edge (stiffness × edge)", {stiffness, edge});
        if (dynamic)
            check("dt² × contact.stiffness", {dt2, stiffness});
        check(std::string(dynamic ? "dt × " : "") + "contact.damping", {dt, {"contact.damping", contact.damping}});
        check("the friction force at a depth of one edge (friction × stiffness × edge)",
              {{"contact.friction", contact.friction}, stiffness, long_edge});
        // The nearest-point test and the normals multiply four lengths (two squared ones).
        check("a squared coordinate in contact detection", {{coordinate.name, coordinate.value, 2.0}});
        check("a squared edge in contact detection", {{short_edge.name, short_edge.value, 2.0}});
    }

    if (g.largest_coordinate > 0.0 &&
        std::log10(g.largest_coordinate) - std::log10(g.shortest_edge) > LOG_MAX_COORDINATE_PER_EDGE)
        CORO_THROW(InputError, body.location
                                   << ": body '" << body.name << "': node coordinates reach " << g.largest_coordinate
                                   << " while the shortest edge is " << g.shortest_edge
                                   << ", expected at most 1e10 edges away from the origin (positions in double would "
                                      "keep fewer than six significant digits of an edge, and strains would be "
                                      "rounding noise); move the body nearer the origin (translate) or use another "
                                      "length unit");
    check_stiffness_to_mass_ratio(sim, spec.solver, body, g.shortest_edge);
}

void check_contact_lengths(CRef<Positions> vertices, const Tris& faces, const std::string& source)
{
    const double largest = std::pow(10.0, LOG_HIGH / 2.0), smallest = std::pow(10.0, LOG_LOW / 2.0);
    for (Index v = 0; v < vertices.rows(); ++v)
        for (int d = 0; d < 3; ++d)
            CORO_CHECK(std::abs(vertices(v, d)) <= largest, InputError,
                       source << ": vertex " << v << " has the coordinate " << vertices(v, d)
                              << ", expected a magnitude of at most " << largest
                              << " (contact detection multiplies four lengths, which would overflow double)");
    for (Index f = 0; f < faces.rows(); ++f)
        for (int c = 0; c < 3; ++c) {
            const double edge = (vertices.row(faces(f, c)) - vertices.row(faces(f, (c + 1) % 3))).stableNorm();
            CORO_CHECK(edge == 0.0 || edge >= smallest, InputError,
                       source << ": face " << f << " has an edge of length " << edge << ", expected at least "
                              << smallest << " (contact detection multiplies four lengths, which would vanish "
                              << "in double)");
        }
}

} // namespace coro
