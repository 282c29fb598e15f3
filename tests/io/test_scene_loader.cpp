// Loading a case into bodies: warnings for surfaces contact cannot trust as closed.

#include <corocontact/io/scene_loader.hpp>

#include <corocontact/core/error.hpp>
#include <corocontact/io/case_reader.hpp>
#include <corocontact/io/mesh_readers.hpp>

#include "mesh_fixtures.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <string>

namespace coro {
namespace {

namespace fs = std::filesystem;
using ::testing::AllOf;
using ::testing::Contains;
using ::testing::HasSubstr;
using ::testing::IsEmpty;
using ::testing::ThrowsMessage;

const fs::path& scratch()
{
    static const fs::path dir = test::scratch_dir("scene_loader");
    return dir;
}

LoadedScene load(const std::string& name, const std::string& case_text)
{
    const fs::path file = test::write_text(scratch() / name, case_text);
    return load_scene(read_case(file));
}

TEST(LoadScene, WarnsWhenAMeshBoundaryIsNotAClosedManifold)
{
    TetMesh bowtie; // two tets sharing only the edge 0-1: that edge has four boundary faces
    bowtie.rest_positions.resize(6, 3);
    bowtie.rest_positions << 0, 0, 0, 1, 0, 0, 0.5, 1, 0, 0.5, 0.5, 1, 0.5, -1, 0, 0.5, -0.5, -1;
    bowtie.tets.resize(2, 4);
    bowtie.tets << 0, 1, 2, 3, 0, 1, 4, 5;
    write_msh22(scratch() / "bowtie.msh", bowtie);
    const LoadedScene loaded =
        load("bowtie.toml", "[[body]]\nname = \"tie\"\nmesh = \"bowtie.msh\"\n");
    EXPECT_THAT(loaded.warnings,
                Contains(AllOf(HasSubstr("body 'tie': the boundary of mesh"),
                               HasSubstr("is not a closed, consistently oriented surface (0 open, "
                                         "1 non-manifold"),
                               HasSubstr("winding number"))));
}

TEST(LoadScene, NoSurfaceWarningForAClosedMesh)
{
    write_msh22(scratch() / "tet.msh", test::unit_tet());
    const LoadedScene loaded = load("tet.toml", "[[body]]\nmesh = \"tet.msh\"\n");
    EXPECT_THAT(loaded.warnings, IsEmpty());
}

TEST(LoadScene, TellsWhatItDoesBeforeEachStage)
{
    write_msh22(scratch() / "stage_tet.msh", test::unit_tet());
    const fs::path file = test::write_text(scratch() / "stages.toml", "[[body]]\nname = \"a\"\nmesh = \"stage_tet.msh\"\n"
                                                                    "[[body]]\nname = \"b\"\nshape = \"box\"\n");
    std::vector<std::string> stages;
    load_scene(read_case(file), [&](const std::string& stage) { stages.push_back(stage); });
    EXPECT_EQ(stages, (std::vector<std::string>{"body 'a' (1 of 2): reading stage_tet.msh",
                                                "body 'a' (1 of 2): METIS parts and element set-up, 1 tet",
                                                "body 'b' (2 of 2): meshing",
                                                "body 'b' (2 of 2): METIS parts and element set-up, 6 tets"}));
}

TEST(LoadScene, StaticBodyMustBeHeldAgainstRigidMotion)
{
    const std::string box = "[simulation]\nanalysis = \"static\"\n[[body]]\nname = \"b\"\nshape = \"box\"\n"
                            "max = [2.0, 1.0, 1.0]\ncells = [2, 1, 1]\n";
    EXPECT_THAT([&] { load("free.toml", box); },
                ThrowsMessage<InputError>(AllOf(HasSubstr("free.toml:3: body 'b': static analysis"),
                                                HasSubstr("no node of the body is fixed"))));
    // One fixed node: it can turn about it.
    EXPECT_THAT([&] { load("point.toml", box + "[[body.fixed]]\nmax = [0.01, 0.01, 0.01]\n"); },
                ThrowsMessage<InputError>(HasSubstr("its 1 fixed node leaves the rotation about it unconstrained")));
    // Three fixed nodes on the line y = z = 0: it can turn about that line.
    EXPECT_THAT([&] { load("line.toml", box + "[[body.fixed]]\nmax = [2.0, 0.01, 0.01]\n"); },
                ThrowsMessage<InputError>(HasSubstr("its 3 fixed nodes lie on one line")));
    // Three fixed nodes not on one line hold it; dynamic analysis needs none.
    EXPECT_NO_THROW(load("corner.toml", box + "[[body.fixed]]\nmax = [1.0, 0.01, 0.01]\n[[body.fixed]]\n"
                                              "max = [0.01, 1.0, 0.01]\n"));
    EXPECT_NO_THROW(load("dynamic.toml", "[[body]]\nshape = \"box\"\n"));
}

TEST(LoadScene, WarnsWhenAnEmbeddedSurfaceIsOpen)
{
    test::write_text(scratch() / "patch.obj", "v 0.2 0.2 0.2\nv 0.8 0.2 0.2\nv 0.2 0.8 0.2\nf 1 2 3\n");
    const LoadedScene loaded = load("patch.toml", "[[body]]\nname = \"b\"\nshape = \"box\"\n"
                                                  "min = [0.0, 0.0, 0.0]\nmax = [1.0, 1.0, 1.0]\n"
                                                  "surface = \"patch.obj\"\n");
    EXPECT_THAT(loaded.warnings,
                Contains(AllOf(HasSubstr("body 'b': surface"), HasSubstr("patch.obj"),
                               HasSubstr("(3 open, 0 non-manifold, 0 misoriented edges)"))));
}

} // namespace
} // namespace coro
