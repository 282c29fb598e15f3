#include "fuzz_input.hpp"

#include <corocontact/core/error.hpp>
#include <corocontact/io/case_reader.hpp>
#include <corocontact/io/mesh_readers.hpp>
#include <corocontact/io/scene_loader.hpp>
#include <corocontact/io/surface_readers.hpp>

#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <stdexcept>
#include <string_view>
#include <system_error>
#include <vector>

namespace coro::fuzz {
namespace {

void write_bytes(const std::filesystem::path& path, const void* data, std::size_t size)
{
    std::FILE* file = std::fopen(path.c_str(), "wb");
    if (file == nullptr)
        throw std::runtime_error("fuzz harness: cannot create " + path.string());
    const bool ok = (size == 0 || std::fwrite(data, 1, size, file) == size);
    if (std::fclose(file) != 0 || !ok)
        throw std::runtime_error("fuzz harness: cannot write " + path.string());
}

void write_text(const std::filesystem::path& path, std::string_view text)
{
    write_bytes(path, text.data(), text.size());
}

/// A unit cube of 5 tets and its closed surface, next to every SCENE case file so that
/// `mesh = "cube.msh"`, `surface = "cube.obj"` and mesh obstacles have something to read.
constexpr std::string_view CUBE_MSH = R"($MeshFormat
2.2 0 8
$EndMeshFormat
$Nodes
8
1 0 0 0
2 1 0 0
3 1 1 0
4 0 1 0
5 0 0 1
6 1 0 1
7 1 1 1
8 0 1 1
$EndNodes
$Elements
5
1 4 2 0 1 1 2 4 5
2 4 2 0 1 2 3 4 7
3 4 2 0 1 2 5 6 7
4 4 2 0 1 4 5 7 8
5 4 2 0 1 2 4 5 7
$EndElements
)";

constexpr std::string_view CUBE_OBJ = R"(v 0 0 0
v 1 0 0
v 1 1 0
v 0 1 0
v 0 0 1
v 1 0 1
v 1 1 1
v 0 1 1
f 1 4 3 2
f 5 6 7 8
f 1 2 6 5
f 2 3 7 6
f 3 4 8 7
f 4 1 5 8
)";

/// Largest generated mesh a SCENE iteration builds: 6 tets per box cell, and a sphere of
/// resolution r has on the order of r^3 tets.
constexpr long long MAX_BOX_CELLS = 2000;
constexpr long long MAX_SPHERE_RESOLUTION = 16;

bool too_big(const CaseSpec& spec)
{
    for (const BodySpec& body : spec.bodies) {
        if (body.shape == BodyShape::BOX) {
            long long cells = 1;
            for (const Index n : body.cells) {
                cells *= std::max<long long>(n, 1);
                if (cells > MAX_BOX_CELLS)
                    return true;
            }
        }
        if (body.shape == BodyShape::SPHERE && body.resolution > MAX_SPHERE_RESOLUTION)
            return true;
    }
    return false;
}

void remove_scratch_dir()
{
    std::error_code ec;
    std::filesystem::remove_all(scratch_dir(), ec);
}

} // namespace

Target target_from_name(const std::string& name)
{
    if (name == "msh")
        return Target::MSH;
    if (name == "tetgen")
        return Target::TETGEN;
    if (name == "obj")
        return Target::OBJ;
    if (name == "stl")
        return Target::STL;
    if (name == "off")
        return Target::OFF;
    if (name == "case")
        return Target::CASE;
    if (name == "scene")
        return Target::SCENE;
    throw std::invalid_argument("unknown fuzz target '" + name + "'");
}

const std::filesystem::path& scratch_dir()
{
    static const std::filesystem::path dir = [] {
        std::string base = "/tmp";
        if (const char* tmp = std::getenv("TMPDIR"); tmp != nullptr && *tmp != '\0')
            base = tmp;
        else if (std::filesystem::is_directory("/dev/shm"))
            base = "/dev/shm";
        std::string pattern = base + "/corocontact-fuzz-XXXXXX";
        std::vector<char> buffer(pattern.begin(), pattern.end());
        buffer.push_back('\0');
        if (::mkdtemp(buffer.data()) == nullptr)
            throw std::runtime_error("fuzz harness: cannot create a folder like " + pattern);
        std::filesystem::path made(buffer.data());
        write_text(made / "cube.msh", CUBE_MSH);
        write_text(made / "cube.obj", CUBE_OBJ);
        return made;
    }();
    static const bool cleanup_registered = (std::atexit(remove_scratch_dir) == 0);
    (void)cleanup_registered;
    return dir;
}

Outcome feed(Target target, const std::uint8_t* data, std::size_t size, std::string* message)
{
    const std::filesystem::path& dir = scratch_dir();
    try {
        switch (target) {
        case Target::MSH:
            write_bytes(dir / "input.msh", data, size);
            (void)read_tet_mesh(dir / "input.msh");
            break;
        case Target::TETGEN: {
            const std::string_view bytes(reinterpret_cast<const char*>(data), size);
            // The separator must be a whole line: at the start or after a '\n'.
            std::size_t split = std::string_view::npos;
            const std::string_view separator = TETGEN_SEPARATOR;
            for (std::size_t at = bytes.find(separator); at != std::string_view::npos;
                 at = bytes.find(separator, at + 1)) {
                const std::size_t end = at + separator.size();
                const bool line_start = (at == 0 || bytes[at - 1] == '\n');
                const bool line_end = (end == bytes.size() || bytes[end] == '\n' ||
                                       bytes[end] == '\r');
                if (line_start && line_end) {
                    split = at;
                    break;
                }
            }
            std::string_view node = bytes;
            std::string_view ele;
            if (split != std::string_view::npos) {
                node = bytes.substr(0, split);
                const std::size_t line_end = bytes.find('\n', split);
                ele = (line_end == std::string_view::npos) ? std::string_view{}
                                                           : bytes.substr(line_end + 1);
            }
            write_text(dir / "input.node", node);
            write_text(dir / "input.ele", ele);
            (void)read_tet_mesh(dir / "input.ele");
            break;
        }
        case Target::OBJ:
            write_bytes(dir / "input.obj", data, size);
            (void)read_surface(dir / "input.obj");
            break;
        case Target::STL:
            write_bytes(dir / "input.stl", data, size);
            (void)read_surface(dir / "input.stl");
            break;
        case Target::OFF:
            write_bytes(dir / "input.off", data, size);
            (void)read_surface(dir / "input.off");
            break;
        case Target::CASE:
            write_bytes(dir / "input.toml", data, size);
            (void)read_case(dir / "input.toml");
            break;
        case Target::SCENE: {
            write_bytes(dir / "scene.toml", data, size);
            const CaseSpec spec = read_case(dir / "scene.toml");
            if (too_big(spec))
                return Outcome::SKIPPED;
            (void)load_scene(spec);
            break;
        }
        }
    } catch (const InputError& e) {
        if (message != nullptr)
            *message = e.what();
        return Outcome::INPUT_ERROR;
    } catch (const NumericalError& e) {
        if (message != nullptr)
            *message = e.what();
        return Outcome::NUMERICAL_ERROR;
    }
    return Outcome::READ;
}

} // namespace coro::fuzz
