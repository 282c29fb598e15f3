#include "calculix.hpp"

#include <sys/wait.h>

#include <cctype>
#include <cmath>
#include <cstdlib>
#include <deque>
#include <fstream>
#include <iomanip>
#include <sstream>
#include <stdexcept>

namespace coro::test {

namespace {

namespace fs = std::filesystem;

const std::string DISPLACEMENT_HEADER = "displacements (vx,vy,vz) for set";

/// Parses one number as CalculiX prints it; also the Fortran form without 'E' for three-digit
/// exponents ("1.234567-100").
bool parse_number(const std::string& token, double& value)
{
    char* end = nullptr;
    value = std::strtod(token.c_str(), &end);
    if (end == token.c_str())
        return false;
    if (*end == '\0')
        return true;
    if (*end != '+' && *end != '-')
        return false;
    char* exponent_end = nullptr;
    const long exponent = std::strtol(end, &exponent_end, 10);
    if (*exponent_end != '\0')
        return false;
    value *= std::pow(10.0, static_cast<double>(exponent));
    return true;
}

/// "*ERROR" lines and the last lines of a ccx log, for failure messages.
std::string log_excerpt(const fs::path& log)
{
    std::ifstream in(log);
    if (!in)
        return "(no log " + log.string() + ")";
    std::string line, errors;
    std::deque<std::string> tail;
    while (std::getline(in, line)) {
        if (line.find("*ERROR") != std::string::npos)
            errors += "  " + line + "\n";
        tail.push_back(line);
        if (tail.size() > 15)
            tail.pop_front();
    }
    std::string text = "--- " + log.string() + " ---\n" + errors;
    if (!errors.empty())
        text += "  ...\n";
    for (const std::string& l : tail)
        text += "  " + l + "\n";
    return text;
}

bool valid_job_name(const std::string& job)
{
    if (job.empty())
        return false;
    for (const char c : job)
        if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-'))
            return false;
    return true;
}

} // namespace

std::string calculix_input(const TetMesh& mesh, const Material& material,
                           const std::vector<char>& fixed, CRef<VecX> nodal_forces,
                           const CalculixStep& step)
{
    const Index n = mesh.num_vertices();
    if (static_cast<Index>(fixed.size()) != n || nodal_forces.size() != 3 * n)
        throw std::invalid_argument("calculix_input: expected " + std::to_string(n) +
                                    " fixed flags and " + std::to_string(3 * n) + " forces, got " +
                                    std::to_string(fixed.size()) + " and " +
                                    std::to_string(nodal_forces.size()));
    std::ostringstream out;
    // CalculiX reads at most 20 characters per field: 13 significant digits fit with sign,
    // point and exponent ("-1.234567890123e-05"), and are far below the tests' tolerances.
    out << std::setprecision(13);
    out << "** corocontact test model: " << n << " nodes, " << mesh.num_tets() << " C3D4\n";
    out << "*NODE, NSET=NALL\n";
    for (Index v = 0; v < n; ++v)
        out << v + 1 << ", " << mesh.rest_positions(v, 0) << ", " << mesh.rest_positions(v, 1)
            << ", " << mesh.rest_positions(v, 2) << "\n";
    out << "*ELEMENT, TYPE=C3D4, ELSET=EALL\n";
    for (Index t = 0; t < mesh.num_tets(); ++t)
        out << t + 1 << ", " << mesh.tets(t, 0) + 1 << ", " << mesh.tets(t, 1) + 1 << ", "
            << mesh.tets(t, 2) + 1 << ", " << mesh.tets(t, 3) + 1 << "\n";
    bool any_fixed = false;
    for (Index v = 0; v < n; ++v)
        if (fixed[static_cast<std::size_t>(v)]) {
            if (!any_fixed)
                out << "*NSET, NSET=NFIXED\n";
            any_fixed = true;
            out << v + 1 << "\n";
        }
    out << "*MATERIAL, NAME=MAT\n*ELASTIC\n" << material.young << ", " << material.poisson << "\n";
    out << "*SOLID SECTION, ELSET=EALL, MATERIAL=MAT\n";
    if (any_fixed)
        out << "*BOUNDARY\nNFIXED, 1, 3\n";
    out << "*STEP" << (step.nlgeom ? ", NLGEOM" : "") << ", INC=" << step.max_increments << "\n";
    out << "*STATIC\n"
        << step.initial_increment << ", 1.0, " << step.min_increment << ", " << step.max_increment
        << "\n";
    out << "*CLOAD\n";
    for (Index v = 0; v < n; ++v)
        for (int d = 0; d < 3; ++d)
            if (nodal_forces[3 * v + d] != 0.0)
                out << v + 1 << ", " << d + 1 << ", " << nodal_forces[3 * v + d] << "\n";
    out << "*NODE PRINT, NSET=NALL\nU\n*END STEP\n";
    return out.str();
}

Positions read_calculix_displacements(const fs::path& dat, Index num_vertices, double* time)
{
    std::ifstream in(dat);
    if (!in)
        throw std::runtime_error(dat.string() + ": cannot open the CalculiX .dat file");
    Positions last, block;
    std::vector<char> seen, last_seen;
    double block_time = 0.0, last_time = 0.0;
    bool in_block = false, found = false;
    const auto close_block = [&] {
        if (in_block) {
            last = block;
            last_seen = seen;
            last_time = block_time;
        }
        in_block = false;
    };
    std::string line;
    for (int line_no = 1; std::getline(in, line); ++line_no) {
        const auto where = [&] { return dat.string() + ":" + std::to_string(line_no) + ": "; };
        std::istringstream fields(line);
        std::vector<std::string> tokens;
        for (std::string token; fields >> token;)
            tokens.push_back(token);
        if (tokens.empty())
            continue;
        if (line.find(DISPLACEMENT_HEADER) != std::string::npos) {
            close_block();
            if (tokens.size() < 2 || tokens[tokens.size() - 2] != "time" ||
                !parse_number(tokens.back(), block_time))
                throw std::runtime_error(where() + "no time at the end of the header '" + line +
                                         "'");
            block = Positions::Zero(num_vertices, 3);
            seen.assign(static_cast<std::size_t>(num_vertices), 0);
            in_block = found = true;
            continue;
        }
        if (!in_block)
            continue;
        char* end = nullptr;
        const long node = std::strtol(tokens[0].c_str(), &end, 10);
        if (tokens.size() != 4 || *end != '\0') { // the start of another kind of block
            close_block();
            continue;
        }
        if (node < 1 || node > num_vertices)
            throw std::runtime_error(where() + "node " + std::to_string(node) +
                                     " out of range 1.." + std::to_string(num_vertices));
        for (std::size_t d = 0; d < 3; ++d) {
            double value = 0.0;
            if (!parse_number(tokens[d + 1], value))
                throw std::runtime_error(where() + "cannot read displacement '" + tokens[d + 1] +
                                         "'");
            block(node - 1, static_cast<Eigen::Index>(d)) = value;
        }
        seen[static_cast<std::size_t>(node - 1)] = 1;
    }
    close_block();
    if (!found)
        throw std::runtime_error(dat.string() + ": no '" + DISPLACEMENT_HEADER +
                                 " ...' block (did the analysis run, with *NODE PRINT of U?)");
    for (Index v = 0; v < num_vertices; ++v)
        if (!last_seen[static_cast<std::size_t>(v)])
            throw std::runtime_error(dat.string() + ": node " + std::to_string(v + 1) +
                                     " is missing from the last displacement block (time " +
                                     std::to_string(last_time) + ")");
    if (time)
        *time = last_time;
    return last;
}

Positions run_calculix(const TetMesh& mesh, const Material& material,
                       const std::vector<char>& fixed, CRef<VecX> nodal_forces,
                       const CalculixStep& step, const fs::path& dir, const std::string& job)
{
    if (!valid_job_name(job))
        throw std::invalid_argument("run_calculix: job name '" + job +
                                    "' must be letters, digits, '_' or '-'");
    if (std::system("command -v ccx > /dev/null 2>&1") != 0)
        throw std::runtime_error(
            "CalculiX 'ccx' is not on PATH: this test needs it as the reference solver. "
            "Install the Debian package calculix-ccx (tools/setup.sh does).");

    fs::create_directories(dir);
    const fs::path absolute = fs::absolute(dir);
    if (absolute.string().find('\'') != std::string::npos)
        throw std::invalid_argument("run_calculix: directory '" + absolute.string() +
                                    "' contains a single quote");
    for (const char* ext : {".dat", ".frd", ".sta", ".cvg", ".log"})
        fs::remove(absolute / (job + ext));
    {
        std::ofstream inp(absolute / (job + ".inp"), std::ios::binary);
        inp << calculix_input(mesh, material, fixed, nodal_forces, step);
        if (!inp)
            throw std::runtime_error((absolute / (job + ".inp")).string() + ": cannot write");
    }

    const fs::path log = absolute / (job + ".log");
    const std::string command = "cd '" + absolute.string() + "' && ccx -i " + job + " > " + job +
                                ".log 2>&1";
    const int status = std::system(command.c_str());
    if (status == -1 || !WIFEXITED(status) || WEXITSTATUS(status) != 0) {
        const std::string how = status == -1         ? std::string("could not be started")
                                : !WIFEXITED(status) ? std::string("was killed by a signal")
                                                     : "exited with code " +
                                                           std::to_string(WEXITSTATUS(status));
        throw std::runtime_error("'" + command + "' " + how + "\n" + log_excerpt(log));
    }
    double time = 0.0;
    Positions u;
    try {
        u = read_calculix_displacements(absolute / (job + ".dat"), mesh.num_vertices(), &time);
    } catch (const std::runtime_error& e) {
        throw std::runtime_error(std::string(e.what()) + "\n" + log_excerpt(log));
    }
    if (std::abs(time - 1.0) > 1e-6)
        throw std::runtime_error("CalculiX job '" + job + "' stopped at step time " +
                                 std::to_string(time) +
                                 " of 1 (increments too small or too many)\n" + log_excerpt(log));
    return u;
}

} // namespace coro::test
