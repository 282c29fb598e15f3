// Loading a case into bodies: warnings for surfaces contact cannot trust as closed; values,
// sizes and embedded surfaces refused before they make a run meaningless.

#include <corocontact/io/scene_loader.hpp>

#include <corocontact/core/error.hpp>
#include <corocontact/core/primitives.hpp>
#include <corocontact/core/surface_mesh.hpp>
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
using ::testing::StartsWith;
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

const std::string BLOCK = "[[body]]\nname = \"block\"\nshape = \"box\"\nmin = [0.0, 0.0, 0.0]\nmax = [1.0, 1.0, 1.0]\n";

TEST(LoadScene, RefusesValuesWhoseProductsOverflowDouble)
{
    EXPECT_THAT([] { load("young.toml", BLOCK + "young = 1e300\n"); },
                ThrowsMessage<InputError>(
                    AllOf(StartsWith(scratch().string() + "/young.toml:1: body 'block': the element stiffness (λ + 2μ) "
                                                           "× edge is about 1.3e+300, expected between 1e-140 and 1e+140"),
                          HasSubstr("young = 1e+300"))));
    EXPECT_THAT([] { load("gravity.toml", "[simulation]\ngravity = [0.0, -1e300, 0.0]\n" + BLOCK); },
                ThrowsMessage<InputError>(AllOf(HasSubstr("dt × the weight of a node (mass × gravity) is about 4.2e+299"),
                                                HasSubstr("|simulation.gravity| = 1e+300"))));
    EXPECT_THAT([] { load("stiff.toml", "[contact]\nenabled = true\nstiffness = 1e200\n" + BLOCK); },
                ThrowsMessage<InputError>(HasSubstr("the contact force at a depth of one edge (stiffness × edge) is "
                                                    "about 1e+200")));
    EXPECT_THAT([] { load("load.toml", BLOCK + "[[body.load]]\nforce = [1e150, 0.0, 0.0]\n"); },
                ThrowsMessage<InputError>(HasSubstr("dt × a load's total force is about 1e+148")));
    // Large but representable: accepted where no mass is added to it (a static analysis).
    EXPECT_EQ(load("young_ok.toml", "[simulation]\nanalysis = \"static\"\n" + BLOCK +
                                        "young = 1e120\n[[body.fixed]]\nmax = [0.0, 1e9, 1e9]\n")
                  .scene.bodies.size(),
              1u);
}

TEST(LoadScene, RefusesAStiffnessToMassRatioWhoseMassDoubleLoses)
{
    // dt²(λ+2μ)/(ρh²) = 1e-4 × 1.346e5 / (1e-20 × 1²) = 1.3e21: the mass vanishes in the sum.
    EXPECT_THAT([] { load("light.toml", "[simulation]\ngravity = [0.0, -9.81, 0.0]\n" + BLOCK + "density = 1e-20\n"); },
                ThrowsMessage<InputError>(AllOf(
                    StartsWith(scratch().string() + "/light.toml:3: body 'block': the stiffness-to-mass ratio of the "
                                                    "implicit step, dt²(λ+2μ)/(ρh²), is about 1.3e+21"),
                    HasSubstr("density = 1e-20"), HasSubstr("expected at most 1e+10"),
                    HasSubstr("simulation.dt at most 2.73e-08, young at most 7.43e-07, or density at least 1.35e-09"))));
    // Just inside the bound (9.6e9), and the same body in a static analysis, which has no mass term.
    EXPECT_EQ(load("light_ok.toml", BLOCK + "density = 1.4e-9\n").scene.bodies.size(), 1u);
    EXPECT_EQ(load("light_static.toml", "[simulation]\nanalysis = \"static\"\n" + BLOCK +
                                            "density = 1e-20\n[[body.fixed]]\nmax = [0.0, 1e9, 1e9]\n")
                  .scene.bodies.size(),
              1u);
}

TEST(LoadScene, RefusesAStiffnessToMassRatioWhoseMassSingleValuesLose)
{
    // r = 13.46 / density: 1.3e4 with density 1e-3, beyond single values' 1e4 (a falling box's
    // motion was wrong by 1% at 1e5 and 27% at 1e6), well within double's 1e10.
    const std::string single = "[solver]\nmatrix_precision = \"single\"\n";
    EXPECT_THAT([&] { load("light_single.toml", single + BLOCK + "density = 1e-3\n"); },
                ThrowsMessage<InputError>(AllOf(
                    HasSubstr("light_single.toml:3: body 'block': the stiffness-to-mass ratio of the implicit step, "
                              "dt²(λ+2μ)/(ρh²), is about 1.3e+4"),
                    HasSubstr("expected at most 1e+4 with solver.matrix_precision = \"single\""),
                    HasSubstr("use matrix_precision = \"double\" (up to 1e+10), or simulation.dt at most"))));
    EXPECT_EQ(load("light_double.toml", BLOCK + "density = 1e-3\n").scene.bodies.size(), 1u);
    EXPECT_EQ(load("light_single_ok.toml", single + BLOCK + "density = 2e-3\n").scene.bodies.size(), 1u);
}

TEST(LoadScene, RefusesLengthsWhoseFourthPowersContactCannotForm)
{
    // Scaled so that every product of the solver fits, only contact's squared lengths do not:
    // refused with contact on, accepted without.
    EXPECT_NO_THROW(load("giant_alone.toml", "[[body]]\nname = \"giant\"\nshape = \"box\"\nmin = [0.0, 0.0, 0.0]\n"
                                             "max = [1e71, 1e71, 1e71]\ndensity = 1e-80\nyoung = 1e-60\n"));
    const std::string giant = "[contact]\nenabled = true\n[[body]]\nname = \"giant\"\nshape = \"box\"\nmin = [0.0, 0.0, 0.0]\n"
                              "max = [1e71, 1e71, 1e71]\ndensity = 1e-80\nyoung = 1e-60\n";
    EXPECT_THAT([&] { load("giant.toml", giant); },
                ThrowsMessage<InputError>(HasSubstr("body 'giant': a squared coordinate in contact detection is about 1e+142")));
    const std::string dwarf = "[contact]\nenabled = true\n[[body]]\nname = \"dwarf\"\nshape = \"box\"\nmin = [0.0, 0.0, 0.0]\n"
                              "max = [1e-71, 1e-71, 1e-71]\ndensity = 1e80\nyoung = 1e60\n";
    EXPECT_THAT([&] { load("dwarf.toml", dwarf); },
                ThrowsMessage<InputError>(HasSubstr("body 'dwarf': a squared coordinate in contact detection is about")));
}

TEST(LoadScene, RefusesValuesWhoseProductsVanishInDouble)
{
    EXPECT_THAT([] { load("density.toml", BLOCK + "density = 1e-300\n"); },
                ThrowsMessage<InputError>(HasSubstr("body 'block': the node mass (density × volume / 4) is about 4.2e-302")));
    EXPECT_THAT([] { load("dt.toml", "[simulation]\ndt = 1e-300\n" + BLOCK); },
                ThrowsMessage<InputError>(
                    AllOf(HasSubstr("dt² × the element stiffness is about 1.3e-595"), HasSubstr("simulation.dt = 1e-300"))));
    EXPECT_THAT([] { load("velocity.toml", BLOCK + "velocity = [1e-200, 0.0, 0.0]\n"); },
                ThrowsMessage<InputError>(HasSubstr("the initial momentum of a node (mass × velocity) is about 4.2e-199")));
    // A static analysis has no dt: a tiny dt there is unused, not refused.
    EXPECT_EQ(load("static.toml", "[simulation]\nanalysis = \"static\"\ndt = 1e-300\n" + BLOCK +
                                      "[[body.fixed]]\nmax = [0.0, 1e9, 1e9]\n")
                  .scene.bodies.size(),
              1u);
}

TEST(LoadScene, RefusesABodySoFarFromTheOriginThatStrainsAreRoundingNoise)
{
    EXPECT_THAT([] { load("far.toml", BLOCK + "translate = [0.0, 2e10, 0.0]\n"); },
                ThrowsMessage<InputError>(HasSubstr("body 'block': node coordinates reach 2e+10 while the shortest edge is 1")));
    EXPECT_EQ(load("near.toml", BLOCK + "translate = [0.0, 5e9, 0.0]\n").scene.bodies.size(), 1u);
}

TEST(LoadScene, RefusesASceneThatCannotFitInMemoryBeforeMakingIt)
{
    // 1.8e9 tets: about 1 TB at the estimate's 600 bytes per tet. Refused at once, before a
    // single node is generated (this test would otherwise run out of memory).
    EXPECT_THAT([] { load("huge.toml", BLOCK + "cells = [1000, 1000, 300]\n"); },
                ThrowsMessage<InputError>(AllOf(HasSubstr("body 'block': cells = [1000, 1000, 300]: the scene would have "
                                                          "1800000000 tets, which need about 1080.0 GB of memory"),
                                                HasSubstr("more than the"))));
}

TEST(LoadScene, RefusesAnEmbeddedSurfaceFarOutsideItsTets)
{
    test::write_text(scratch() / "far.obj", "v 5 5 5\nv 6 5 5\nv 5 6 5\nv 5 5 6\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n");
    EXPECT_THAT([] { load("far_surface.toml", BLOCK + "surface = \"far.obj\"\n"); },
                ThrowsMessage<InputError>(AllOf(HasSubstr("body 'block': surface"),
                                                HasSubstr("far.obj: vertex 0 (counted from 0 in file order) lies 6.9282 "
                                                          "outside the bounding box of the body's tets"))));
    // Inside the bounding box of a body of two boxes 10 apart, but 4 away from either.
    TetMesh two = make_box(Vec3::Zero(), Vec3::Ones(), {1, 1, 1});
    const TetMesh right = make_box(Vec3(10, 0, 0), Vec3(11, 1, 1), {1, 1, 1});
    const Index n = two.num_vertices();
    two.rest_positions.conservativeResize(2 * n, 3);
    two.rest_positions.bottomRows(n) = right.rest_positions;
    two.tets.conservativeResize(2 * two.num_tets(), 4);
    two.tets.bottomRows(right.num_tets()) = right.tets.array() + n;
    write_msh22(scratch() / "two_boxes.msh", two);
    test::write_text(scratch() / "gap.obj", "v 0.2 0.2 0.2\nv 0.8 0.2 0.2\nv 0.2 0.8 0.2\nv 5 0.5 0.5\n"
                                            "f 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n");
    EXPECT_THAT([] { load("gap.toml", "[[body]]\nname = \"two\"\nmesh = \"two_boxes.msh\"\nsurface = \"gap.obj\"\n"); },
                ThrowsMessage<InputError>(AllOf(HasSubstr("gap.obj: vertex 3 (counted from 0 in file order) lies 4 "
                                                          "outside the body's tets, 231% of the longest edge"),
                                                HasSubstr("expected the surface on or inside the body"))));
}

/// A tet as an OBJ surface: three corners at z = 0.2 in the unit box and a top at (0.3, 0.3,
/// top_z); faces with outward normals, or all reversed.
std::string tet_obj(const std::string& top_z, bool inward = false)
{
    return "v 0.2 0.2 0.2\nv 0.8 0.2 0.2\nv 0.2 0.8 0.2\nv 0.3 0.3 " + top_z + "\n" +
           (inward ? "f 1 2 3\nf 1 4 2\nf 1 3 4\nf 2 4 3\n" : "f 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n");
}

TEST(LoadScene, WarnsAboutAnEmbeddedSurfaceALittleOutsideItsTets)
{
    // The top vertex is 0.5 above the unit box, 29% of the longest edge (the cell diagonal, √3)
    // of the tet it is bound to: more than a fine surface over coarse tets shows (≤ 15%).
    test::write_text(scratch() / "near.obj", tet_obj("1.5"));
    const LoadedScene loaded = load("near_surface.toml", BLOCK + "surface = \"near.obj\"\n");
    EXPECT_THAT(loaded.warnings, Contains(AllOf(HasSubstr("near.obj: vertex 3"), HasSubstr("lies 0.5 outside"),
                                                HasSubstr("(1 of 4 vertices lie outside)"))));
    test::write_text(scratch() / "inside.obj", tet_obj("0.9"));
    EXPECT_THAT(load("inside_surface.toml", BLOCK + "surface = \"inside.obj\"\n").warnings, IsEmpty());
}

TEST(LoadScene, TurnsAnInsideOutEmbeddedSurfaceOutward)
{
    // inside.obj of the test above with every face reversed: contact would take the tet's inside
    // for its outside and never find another body's vertex in it.
    test::write_text(scratch() / "inward.obj", tet_obj("0.9", true));
    const LoadedScene loaded = load("inward_surface.toml", BLOCK + "surface = \"inward.obj\"\n");
    EXPECT_THAT(loaded.warnings, Contains(AllOf(HasSubstr("body 'block': surface"), HasSubstr("inward.obj"),
                                                HasSubstr("had inward normals; its faces were flipped"))));
    const SurfaceMesh& surface = loaded.scene.bodies.at(0).embedded_surface();
    EXPECT_GT(enclosed_volume(surface.vertices, surface.faces), 0.0);
}

TEST(LoadScene, WarnsAboutNodesThatLieWhereAnotherNodeLies)
{
    // Two tets sharing a face by position only: nodes 5, 6, 7 repeat nodes 1, 2, 3 (the first
    // pair by position: 3 and 7, at (0, 0, 1)).
    test::write_text(scratch() / "unmerged.msh", "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n8\n1 0 0 0\n2 1 0 0\n"
                                                 "3 0 1 0\n4 0 0 1\n5 1 1 1\n6 1 0 0\n7 0 1 0\n8 0 0 1\n$EndNodes\n"
                                                 "$Elements\n2\n1 4 2 0 1 1 2 3 4\n2 4 2 0 1 6 7 8 5\n$EndElements\n");
    const LoadedScene loaded = load("unmerged.toml", "[[body]]\nname = \"b\"\nmesh = \"unmerged.msh\"\n");
    EXPECT_THAT(loaded.warnings, Contains(AllOf(HasSubstr("body 'b': mesh"), HasSubstr("unmerged.msh"),
                                                HasSubstr("3 nodes lie exactly where another node lies (e.g. nodes "
                                                          "3 and 7, counted from 0 in file order)"))));
    EXPECT_THAT(load("merged.toml", BLOCK).warnings, IsEmpty());
}

TEST(LoadScene, WarnsAboutABodyThatLiesExactlyWhereAnotherLies)
{
    const std::string ball = "[[body]]\nname = \"a\"\nshape = \"sphere\"\nresolution = 3\n"
                             "[[body]]\nname = \"b\"\nshape = \"sphere\"\nresolution = 3\n";
    const std::string contact = "[contact]\nenabled = true\n";
    EXPECT_THAT(load("coincident.toml", contact + ball).warnings,
                Contains(AllOf(HasSubstr("coincident.toml:7: body 'b' lies exactly where body 'a' lies"),
                               HasSubstr("give one a translate"))));
    EXPECT_THAT(load("apart.toml", contact + ball + "translate = [3.0, 0.0, 0.0]\n").warnings, IsEmpty());
}

TEST(LoadScene, WarnsWhenALoadFallsOnFixedNodes)
{
    // The load box x >= 1 holds the 4 nodes of the box's right face; the fixed box x >= 1, y <= 0
    // two of them: half of the 8 N is lost.
    const std::string right_face = "[[body.load]]\nmin = [1.0, -1.0, -1.0]\nmax = [2.0, 2.0, 2.0]\nforce = [0.0, -8.0, 0.0]\n";
    const LoadedScene loaded =
        load("lost.toml", BLOCK + "[[body.fixed]]\nmin = [1.0, -1.0, -1.0]\nmax = [2.0, 0.0, 2.0]\n" + right_face);
    EXPECT_THAT(loaded.warnings,
                Contains(HasSubstr("body 'block': 4 of the 8 N of its [[body.load]] forces fall on fixed nodes")));
    EXPECT_THAT(load("kept.toml", BLOCK + "[[body.fixed]]\nmax = [0.0, 2.0, 2.0]\n" + right_face).warnings, IsEmpty());
}

TEST(LoadScene, RefusesABodyThatStartsBehindAPlane)
{
    const std::string plane = "[[obstacle]]\ntype = \"plane\"\npoint = [0.0, 3.0, 0.0]\n";
    EXPECT_THAT([&] { load("behind.toml", "[contact]\nenabled = true\n" + BLOCK + plane); },
                ThrowsMessage<InputError>(AllOf(HasSubstr("behind.toml:8: plane obstacle: body 'block'"),
                                                HasSubstr("lies entirely behind the plane, 2 to 3 behind it"))));
    // Touching the plane (the top face on it) is a start, not a mistake.
    EXPECT_EQ(load("touching.toml", "[contact]\nenabled = true\n" + BLOCK +
                                        "[[obstacle]]\ntype = \"plane\"\npoint = [0.0, 1.0, 0.0]\n")
                  .scene.planes.size(),
              1u);
}

} // namespace
} // namespace coro
