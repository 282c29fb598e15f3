#include "mesh_fixtures.hpp"

#include <corocontact/core/error.hpp>
#include <corocontact/io/case_reader.hpp>
#include <corocontact/io/scene_loader.hpp>
#include <corocontact/sim/checkpoint.hpp>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <limits>
#include <iterator>
#include <string>

using namespace coro;
using ::testing::AllOf;
using ::testing::HasSubstr;
using ::testing::ThrowsMessage;
namespace fs = std::filesystem;

namespace {

// Two partitioned spheres that touch after a few steps, with friction and damping: every kind
// of state a step carries over.
const char* CASE = R"toml([simulation]
dt = 0.005
steps = 16
gravity = [0.0, -9.81, 0.0]
[solver]
max_iterations = 30
parts_per_thread = 4
[contact]
enabled = true
stiffness = 1e6
damping = 10.0
friction = 0.3
[[body]]
name = "left"
shape = "sphere"
radius = 0.5
resolution = 8
translate = [-0.52, 0.05, 0.0]
velocity = [2.0, 0.0, 0.0]
young = 2e5
rayleigh_stiffness = 0.002
[[body]]
name = "right"
shape = "sphere"
radius = 0.5
resolution = 8
translate = [0.52, -0.05, 0.0]
velocity = [-2.0, 0.5, 0.0]
young = 2e5
)toml";

struct Loaded {
    CaseSpec spec;
    LoadedScene loaded;
    Scene& scene() { return loaded.scene; }
};

Loaded load(const fs::path& case_file)
{
    Loaded run{read_case(case_file), {}};
    run.loaded = load_scene(run.spec);
    return run;
}

void expect_same_state(const Scene& a, const Scene& b)
{
    ASSERT_EQ(a.bodies.size(), b.bodies.size());
    for (std::size_t i = 0; i < a.bodies.size(); ++i) {
        EXPECT_EQ(a.bodies[i].positions(), b.bodies[i].positions()) << a.bodies[i].name();
        EXPECT_EQ(a.bodies[i].velocities(), b.bodies[i].velocities()) << a.bodies[i].name();
        EXPECT_EQ(a.bodies[i].fem().rotations(), b.bodies[i].fem().rotations()) << a.bodies[i].name();
    }
}

} // namespace

TEST(Checkpoint, RoundTripRestoresPositionsVelocitiesAndRotations)
{
    const fs::path dir = test::scratch_dir("checkpoint_roundtrip");
    const fs::path case_file = test::write_text(dir / "spheres.toml", CASE);
    Loaded first = load(case_file);
    Simulation simulation(first.scene(), first.spec);
    CheckpointState saved;
    RunControl control;
    control.checkpoint_every = 5;
    control.on_checkpoint = [&](Index step, const RunSummary& so_far) {
        if (step == 5)
            write_checkpoint(dir / "five.checkpoint", first.scene(), {step, so_far, {{0, 0.0}, {5, 0.025}}},
                             case_fingerprint(first.spec));
    };
    simulation.run(5, nullptr, nullptr, control);

    Loaded second = load(case_file);
    std::vector<std::string> warnings;
    const CheckpointState state =
        read_checkpoint(dir / "five.checkpoint", second.scene(), case_fingerprint(second.spec), warnings);
    EXPECT_TRUE(warnings.empty());
    EXPECT_EQ(state.step, 5);
    EXPECT_EQ(state.summary.steps, 5);
    EXPECT_GT(state.summary.solves, 0);
    ASSERT_EQ(state.frames.size(), 2u);
    EXPECT_EQ(state.frames[1].step, 5);
    EXPECT_EQ(state.frames[1].time, 0.025);
    expect_same_state(first.scene(), second.scene());
}

TEST(Checkpoint, ContinuedRunEqualsUninterruptedRunBitwise)
{
    const fs::path dir = test::scratch_dir("checkpoint_continue");
    const fs::path case_file = test::write_text(dir / "spheres.toml", CASE);

    Loaded whole = load(case_file);
    Simulation uninterrupted(whole.scene(), whole.spec);
    const RunSummary whole_summary = uninterrupted.run(16, nullptr, nullptr);
    ASSERT_GT(whole_summary.max_contact_depth, 0.0) << "the spheres must touch";

    Loaded part = load(case_file);
    Simulation first(part.scene(), part.spec);
    RunControl control;
    control.checkpoint_every = 7;
    control.on_checkpoint = [&](Index step, const RunSummary& so_far) {
        write_checkpoint(dir / "run.checkpoint", part.scene(), {step, so_far, {}}, case_fingerprint(part.spec));
    };
    first.run(9, nullptr, nullptr, control); // checkpoints at 7 and at the last step, 9

    Loaded rest = load(case_file);
    std::vector<std::string> warnings;
    const CheckpointState state =
        read_checkpoint(dir / "run.checkpoint", rest.scene(), case_fingerprint(rest.spec), warnings);
    ASSERT_EQ(state.step, 9);
    Simulation second(rest.scene(), rest.spec);
    RunControl resume;
    resume.resume_step = state.step;
    resume.resume_summary = state.summary;
    const RunSummary summary = second.run(16, nullptr, nullptr, resume);
    expect_same_state(whole.scene(), rest.scene());
    EXPECT_EQ(summary.steps, 16);
    EXPECT_EQ(summary.first_step, 9);
    EXPECT_EQ(summary.solves, whole_summary.solves);
    EXPECT_EQ(summary.detections, whole_summary.detections);
    EXPECT_EQ(summary.cg_iterations_mean, whole_summary.cg_iterations_mean);
    EXPECT_EQ(summary.max_contact_depth, whole_summary.max_contact_depth);
    EXPECT_EQ(summary.contacts_mean, whole_summary.contacts_mean);
}

TEST(Checkpoint, RejectsTruncatedForeignAndOtherCaseFiles)
{
    const fs::path dir = test::scratch_dir("checkpoint_bad");
    const fs::path case_file = test::write_text(dir / "spheres.toml", CASE);
    Loaded run = load(case_file);
    write_checkpoint(dir / "good.checkpoint", run.scene(), {3, {}, {}}, case_fingerprint(run.spec));
    std::string bytes;
    {
        std::ifstream file(dir / "good.checkpoint", std::ios::binary);
        bytes.assign(std::istreambuf_iterator<char>(file), std::istreambuf_iterator<char>());
    }
    test::write_text(dir / "truncated.checkpoint", bytes.substr(0, bytes.size() / 2));
    std::string flipped = bytes;
    flipped[flipped.size() / 2] ^= 0x10;
    test::write_text(dir / "flipped.checkpoint", flipped);
    test::write_text(dir / "text.checkpoint", "hello\n");

    std::vector<std::string> warnings;
    const auto read = [&](const fs::path& path, std::uint64_t fingerprint) {
        Loaded fresh = load(case_file);
        read_checkpoint(path, fresh.scene(), fingerprint, warnings);
    };
    const std::uint64_t fingerprint = case_fingerprint(run.spec);
    EXPECT_NO_THROW(read(dir / "good.checkpoint", fingerprint));
    EXPECT_THAT([&] { read(dir / "truncated.checkpoint", fingerprint); },
                ThrowsMessage<InputError>(AllOf(HasSubstr("truncated.checkpoint"), HasSubstr("truncated or corrupt"))));
    EXPECT_THAT([&] { read(dir / "flipped.checkpoint", fingerprint); },
                ThrowsMessage<InputError>(HasSubstr("truncated or corrupt")));
    EXPECT_THAT([&] { read(dir / "text.checkpoint", fingerprint); },
                ThrowsMessage<InputError>(HasSubstr("not a corocontact checkpoint")));
    EXPECT_THAT([&] { read(dir / "absent.checkpoint", fingerprint); },
                ThrowsMessage<InputError>(HasSubstr("absent.checkpoint")));
    EXPECT_THAT([&] { read(dir / "good.checkpoint", fingerprint + 1); },
                ThrowsMessage<InputError>(HasSubstr("another case file")));

    // A checksum that fits but a NaN in the state (an edited file): refused, not run into exit 3.
    Loaded with_nan = load(case_file);
    with_nan.scene().bodies[1].velocities().setConstant(std::numeric_limits<double>::quiet_NaN());
    write_checkpoint(dir / "nan.checkpoint", with_nan.scene(), {3, {}, {}}, fingerprint);
    EXPECT_THAT([&] { read(dir / "nan.checkpoint", fingerprint); },
                ThrowsMessage<InputError>(HasSubstr("nan.checkpoint: corrupt checkpoint: body 'right': node 0 (mesh file order) "
                                                    "has the non-finite velocity component nan")));

    // Same case file text but one body fewer: the body table must not match.
    std::string one_body = CASE;
    one_body = one_body.substr(0, one_body.rfind("[[body]]"));
    const fs::path other_file = test::write_text(dir / "one.toml", one_body);
    Loaded other = load(other_file);
    EXPECT_THAT([&] { read_checkpoint(dir / "good.checkpoint", other.scene(), fingerprint, warnings); },
                ThrowsMessage<InputError>(HasSubstr("holds 2 bodies, the case has 1")));
}

TEST(Checkpoint, OneProcessOfADistributedRunRestoresOnlyItsBodies)
{
    // The file of the whole case, written from its bodies' parts as rank 0 gathers them, is the
    // one-process file; a process holding only "right" restores just that body from it.
    const fs::path dir = test::scratch_dir("checkpoint_parts");
    const fs::path case_file = test::write_text(dir / "spheres.toml", CASE);
    Loaded first = load(case_file);
    Simulation simulation(first.scene(), first.spec);
    simulation.run(6, nullptr, nullptr);
    const std::uint64_t fingerprint = case_fingerprint(first.spec);
    write_checkpoint(dir / "whole.checkpoint", first.scene(), {6, simulation.summary(), {}}, fingerprint);
    std::vector<CheckpointBody> parts;
    for (const Body& body : first.scene().bodies)
        parts.push_back(checkpoint_body(body));
    write_checkpoint(dir / "parts.checkpoint", parts, {6, simulation.summary(), {}}, fingerprint);
    std::ifstream whole(dir / "whole.checkpoint", std::ios::binary), from_parts(dir / "parts.checkpoint", std::ios::binary);
    EXPECT_TRUE(std::equal(std::istreambuf_iterator<char>(whole), {}, std::istreambuf_iterator<char>(from_parts), {}));

    Loaded second = load(case_file);
    second.scene().bodies.erase(second.scene().bodies.begin()); // this process holds body 1 only
    std::vector<BodyWarning> warnings;
    const CheckpointState state =
        read_checkpoint(dir / "parts.checkpoint", second.scene(), {1}, 2, fingerprint, warnings);
    EXPECT_EQ(state.step, 6);
    ASSERT_EQ(second.scene().bodies.size(), 1u);
    EXPECT_EQ(second.scene().bodies[0].positions(), first.scene().bodies[1].positions());
    EXPECT_EQ(second.scene().bodies[0].velocities(), first.scene().bodies[1].velocities());
    EXPECT_EQ(second.scene().bodies[0].fem().rotations(), first.scene().bodies[1].fem().rotations());
    EXPECT_THAT([&] { read_checkpoint(dir / "parts.checkpoint", second.scene(), {1}, 3, fingerprint, warnings); },
                ThrowsMessage<InputError>(HasSubstr("holds 2 bodies, the case has 3")));
}
