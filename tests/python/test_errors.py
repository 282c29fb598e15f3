"""Errors come through as exceptions with the command's messages: InputError where the command
exits with 2, NumericalError where it exits with 3; values set from Python are checked like the
case file's."""
import os
import warnings

import numpy as np
import pytest

import corocontact
from conftest import CASES, SOURCE_DIR, error_message

BAD = SOURCE_DIR / "tests" / "data" / "bad"


def corpus(command):
    """The case files of the bad-input corpus that `corocontact COMMAND` must refuse with exit 2."""
    rows = [line.split("\t") for line in (BAD / "expected.tsv").read_text().splitlines()
            if line and not line.startswith("#")]
    return [name for name, cmd, code, _ in rows if cmd == command and code == "2"]


@pytest.mark.parametrize("name", corpus("run"))
def test_simulation_raises_input_error_with_the_message_of_run(cli, tmp_path, name):
    result = cli("run", BAD / name, "--out", tmp_path / "cli", check_exit=2)
    with pytest.raises(corocontact.InputError) as raised:
        corocontact.Simulation(BAD / name, output_dir=tmp_path / "python")
    assert str(raised.value) == error_message(result.stderr)
    assert isinstance(raised.value, ValueError)


@pytest.mark.parametrize("name", corpus("detect"))
def test_detect_raises_input_error_with_the_message_of_detect(cli, tmp_path, name):
    result = cli("detect", BAD / name, "--csv", tmp_path / "x.csv", check_exit=2)
    with pytest.raises(corocontact.InputError) as raised:
        corocontact.detect(BAD / name)
    assert str(raised.value) == error_message(result.stderr)


def test_corpus_is_not_empty():
    assert len(corpus("run")) >= 10


def test_missing_case_file(cli, tmp_path):
    result = cli("run", tmp_path / "nothing.toml", "--out", tmp_path / "cli", check_exit=2)
    with pytest.raises(corocontact.InputError) as raised:
        corocontact.Simulation(tmp_path / "nothing.toml")
    assert str(raised.value) == error_message(result.stderr)
    assert "nothing.toml" in str(raised.value)


def test_divergence_raises_numerical_error_with_the_message_of_run(cli, tmp_path):
    case = SOURCE_DIR / "tests" / "cli" / "data" / "soft_block_hit_hard.toml"
    result = cli("run", case, "--out", tmp_path / "cli", check_exit=3)
    sim = corocontact.Simulation(case, output_dir=tmp_path / "python")
    with pytest.raises(corocontact.NumericalError) as raised:
        sim.step(sim.last_step)
    assert str(raised.value) == error_message(result.stderr, prefix="error: the simulation diverged: ")
    assert str(raised.value).startswith("step 2 ")
    assert isinstance(raised.value, RuntimeError)
    # The failed step left no state to go on from or to write.
    steps_done = sim.steps_done
    for call in (sim.step, sim.write_frame):
        with pytest.raises(corocontact.NumericalError, match=r"^step 2 .*load the case again|^step 2 .*meaningless"):
            call()
    assert sim.steps_done == steps_done


@pytest.fixture()
def spheres():
    return corocontact.Simulation(CASES / "two_spheres" / "two_spheres.toml")


def test_values_set_from_python_are_checked_like_the_case_files(spheres):
    body = spheres.bodies[0]
    n = body.num_vertices
    bad = {
        "velocities": (np.full((n, 3), np.nan), rf"body 'left': velocities\[0\] = \(nan, nan, nan\): expected finite"),
        "loads": (np.full((n, 3), np.inf), r"body 'left': loads\[0\] = \(inf, inf, inf\): expected finite"),
    }
    for attribute, (value, message) in bad.items():
        with pytest.raises(corocontact.InputError, match=message):
            setattr(body, attribute, value)
    with pytest.raises(corocontact.InputError, match=rf"velocities: expected an array of shape \({n}, 3\)"):
        body.velocities = np.zeros((n, 2))
    with pytest.raises(corocontact.InputError, match=rf"fixed: expected an array of shape \({n},\), found \(3,\)"):
        body.fixed = [True, False, True]
    with pytest.raises(corocontact.InputError, match="expected an array of numbers"):
        body.loads = "heavy"
    with pytest.raises(corocontact.InputError, match=r"contact.friction: expected a number in \[0, 10\], found -0.1"):
        spheres.contact_friction = -0.1
    with pytest.raises(corocontact.InputError, match=r"contact.friction: expected a number in \[0, 10\], found 1e\+12"):
        spheres.contact_friction = 1e12
    with pytest.raises(corocontact.InputError, match=r"contact.stiffness: expected a number > 0, found 0"):
        spheres.contact_stiffness = 0.0
    with pytest.raises(corocontact.InputError, match=r"contact.damping: expected a finite number >= 0, found inf"):
        spheres.contact_damping = float("inf")
    with pytest.raises(corocontact.InputError, match=r"gravity = \(0, nan, 0\): expected finite numbers"):
        spheres.gravity = [0.0, float("nan"), 0.0]
    with pytest.raises(corocontact.InputError, match=r"step\(n = -1\): expected n >= 0"):
        spheres.step(-1)
    # Nothing was changed by the refused values.
    assert spheres.contact_friction == 0.0 and spheres.contact_stiffness == 1e6
    assert np.all(np.isfinite(body.velocities)) and not body.loads.any()


def test_fixed_nodes_keep_velocity_zero():
    sim = corocontact.Simulation(SOURCE_DIR / "cases" / "cantilever" / "cantilever_dynamic.toml")
    beam = sim.bodies[0]
    node = int(np.flatnonzero(beam.fixed)[0])
    with pytest.raises(corocontact.InputError,
                       match=rf"velocities\[{node}\] = \(1, 0, 0\): node {node} is fixed, expected velocity 0 there"):
        beam.velocities = [1.0, 0.0, 0.0]


def test_contact_settings_need_contact():
    sim = corocontact.Simulation(SOURCE_DIR / "cases" / "cantilever" / "cantilever_dynamic.toml")
    with pytest.raises(corocontact.InputError, match=r"contact.friction: the case has no contact"):
        sim.contact_friction = 0.3


def test_threads_must_be_positive():
    with pytest.raises(corocontact.InputError, match=r"threads = 0: expected an integer >= 1, or None for all cores"):
        corocontact.Simulation(CASES / "two_spheres" / "two_spheres.toml", threads=0)


def test_frames_once_per_step(tmp_path):
    sim = corocontact.Simulation(CASES / "two_spheres" / "two_spheres.toml", output_dir=tmp_path)
    assert sim.write_frame() == tmp_path / "two_spheres.pvd"
    with pytest.raises(corocontact.InputError, match="the frame of step 0 is already written"):
        sim.write_frame()


def test_bad_meshes_name_the_mesh_and_element():
    vertices = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]])
    with pytest.raises(corocontact.InputError, match=r"meshes\[1\] \('mesh1'\): face 0 refers to vertex 4"):
        corocontact.detect_meshes([(vertices, [[0, 2, 1]]), (vertices, [[0, 1, 4]])])
    with pytest.raises(corocontact.InputError, match=r"meshes\[0\]: faces: expected an array of integers"):
        corocontact.detect_meshes([(vertices, [[0.0, 2.0, 1.0]])])
    with pytest.raises(corocontact.InputError, match=r"meshes\[0\] \('a'\): tet 0 .*zero volume|meshes\[0\] \('a'\).*tet"):
        corocontact.detect_meshes([(np.zeros((4, 3)), [[0, 1, 2, 3]])], names=["a"])
    with pytest.raises(corocontact.InputError, match=r"mode = 'fast': expected \"exact\" or \"paper\""):
        corocontact.detect_meshes([], mode="fast")
    with pytest.raises(corocontact.InputError, match=r"mode = 'fast'"):
        corocontact.detect(CASES / "overlap" / "overlap.toml", mode="fast")


def test_objects_made_without_init_are_refused():
    with pytest.raises(TypeError, match=r"Simulation.__new__ without __init__"):
        corocontact.Simulation.__new__(corocontact.Simulation).step()
    with pytest.raises(TypeError, match=r"Simulation.__new__ without __init__"):
        repr(corocontact.Simulation.__new__(corocontact.Simulation))
    with pytest.raises(TypeError, match=r"Body.__new__ without __init__"):
        corocontact.Body.__new__(corocontact.Body).positions


def test_arrays_numpy_would_convert_loosely_are_refused(spheres):
    body = spheres.bodies[0]
    n = body.num_vertices
    with pytest.raises(corocontact.InputError, match=r"fixed\[0\] = nan: expected True or False"):
        body.fixed = np.full(n, np.nan)
    with pytest.raises(corocontact.InputError, match=r"fixed\[0\] = 0.5: expected True or False"):
        body.fixed = np.full(n, 0.5)
    with pytest.raises(corocontact.InputError, match=r"gravity: expected an array of numbers .*found dtype <U5"):
        spheres.gravity = ["0", "-9.81", "0"]
    with pytest.raises(corocontact.InputError, match=r"velocities: expected an array of numbers .*found dtype complex"):
        body.velocities = np.zeros((n, 3), dtype=complex)
    with pytest.raises(corocontact.InputError, match=r"velocities: .*found a masked array"):
        body.velocities = np.ma.masked_all((n, 3))
    with pytest.raises(corocontact.InputError, match=r"vertices: expected an array of numbers .*found dtype object"):
        corocontact.detect_meshes([(np.array([[0, 0, None]] * 4, dtype=object), [[0, 1, 2]])])
    # A view numpy cannot copy (2^40 rows): refused by name, not a crash.
    huge = np.broadcast_to(np.array([0, 1, 2], np.int32), (2**40, 3))
    with pytest.raises(corocontact.InputError, match=r"meshes\[0\]: faces: numpy could not convert"):
        corocontact.detect_meshes([(np.zeros((3, 3)), huge)])
    body.fixed = np.zeros(n, dtype=bool)  # bools, and 0/1 numbers, are what it takes
    body.fixed = np.zeros(n)
    assert not body.fixed.any()


def test_constant_arrays_cannot_be_made_writable(spheres):
    tets = spheres.bodies[0].tets
    for array in (tets, tets.base, tets.view(), np.asarray(tets)):
        with pytest.raises(ValueError, match="cannot set WRITEABLE flag"):
            array.flags.writeable = True


def test_values_set_from_python_are_checked_for_their_scales_like_the_case_files(spheres):
    body = spheres.bodies[0]
    n = body.num_vertices
    before = spheres.contact_stiffness, spheres.gravity, body.velocities, body.loads
    with pytest.raises(corocontact.InputError, match=r"^contact.stiffness: body 'left': the contact force at a depth of one "
                                                     r"edge \(stiffness × edge\)"):
        spheres.contact_stiffness = 5e-324
    with pytest.raises(corocontact.InputError, match=r"^gravity: body 'left': dt × the weight of a node"):
        spheres.gravity = [1e200, 0.0, 0.0]
    with pytest.raises(corocontact.InputError, match=r"^velocities: body 'left': the initial momentum of a node"):
        body.velocities = [1e200, 0.0, 0.0]
    with pytest.raises(corocontact.InputError, match=r"^loads: body 'left': dt × a load's"):
        body.loads = np.full((n, 3), 1e200)
    with pytest.raises(corocontact.InputError, match=r"contact.friction: expected a number in \[0, 10\], "
                                                     r"found 10.0000001"):
        spheres.contact_friction = 10.0000001
    assert spheres.contact_stiffness == before[0] and (spheres.gravity == before[1]).all()
    assert (body.velocities == before[2]).all() and (body.loads == before[3]).all()


def test_detect_meshes_refuses_lengths_contact_cannot_multiply():
    cube_v = np.array([[x, y, z] for x in (-1.0, 1) for y in (-1.0, 1) for z in (-1.0, 1)])
    cube_t = [[0, 1, 3, 7], [0, 1, 5, 7], [0, 2, 3, 7], [0, 2, 6, 7], [0, 4, 5, 7], [0, 4, 6, 7]]
    found = corocontact.detect_meshes([(cube_v * 1e70, cube_t), (cube_v * 0.5e70, cube_t)])
    assert len(found["depth"]) == 8 and np.allclose(np.linalg.norm(found["normal"], axis=1), 1.0)
    with pytest.raises(corocontact.InputError, match=r"meshes\[0\] \('mesh0'\): vertex 0 has the coordinate -1e\+75, "
                                                     r"expected a magnitude of at most 1e\+70"):
        corocontact.detect_meshes([(cube_v * 1e75, cube_t), (cube_v * 0.5e75, cube_t)])
    tet_v = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]]) * 1e-300
    with pytest.raises(corocontact.InputError, match=r"meshes\[0\] \('mesh0'\): face 0 has an edge of length 1e-300, "
                                                     r"expected at least 1e-70"):
        corocontact.detect_meshes([(tet_v, [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])])


def test_a_failed_first_write_lets_the_folder_go(tmp_path):
    sim = corocontact.Simulation(CASES / "two_spheres" / "two_spheres.toml", output_dir=tmp_path)
    (tmp_path / "two_spheres.pvd").mkdir()  # an earlier run's file that cannot be removed
    (tmp_path / "two_spheres.pvd" / "keep").write_text("")
    with pytest.raises(corocontact.OutputError, match="two_spheres.pvd: cannot remove"):
        sim.write_frame()
    assert not (tmp_path / "corocontact.lock").exists()
    (tmp_path / "two_spheres.pvd" / "keep").unlink()
    (tmp_path / "two_spheres.pvd").rmdir()
    assert sim.write_frame() == tmp_path / "two_spheres.pvd"


def test_messages_keep_paths_that_are_not_utf8(tmp_path):
    missing = bytes(tmp_path) + b"/bad\xff/missing.toml"
    with pytest.raises(corocontact.InputError, match="bad\ufffd/missing.toml: cannot read the case file"):
        corocontact.Simulation(missing)


def test_other_arguments_are_refused_as_the_command_refuses_them(tmp_path):
    with pytest.raises(corocontact.InputError, match=r"output_dir = '': expected a path"):
        corocontact.Simulation(CASES / "two_spheres" / "two_spheres.toml", output_dir="")
    sim = corocontact.Simulation(CASES / "two_spheres" / "two_spheres.toml", threads=10000)
    assert 1 <= sim.threads <= len(os.sched_getaffinity(0))


def test_a_value_whose_warning_is_made_an_error_changes_nothing():
    sim = corocontact.Simulation(SOURCE_DIR / "cases" / "cantilever" / "cantilever_dynamic.toml")
    beam = sim.bodies[0]
    loads = np.zeros((beam.num_vertices, 3))
    loads[np.flatnonzero(beam.fixed)[0]] = [0.0, -100.0, 0.0]
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with pytest.raises(corocontact.InputWarning, match="fall on fixed nodes"):
            beam.loads = loads
    assert not beam.loads.any()
    # Fixing a loaded, moving node: refused before its velocity is set to 0.
    free = int(np.flatnonzero(~beam.fixed)[0])
    loads = np.zeros((beam.num_vertices, 3))
    loads[free] = [0.0, -100.0, 0.0]
    beam.loads = loads
    velocities = np.where(beam.fixed[:, None], 0.0, [1.0, 0.0, 0.0])
    beam.velocities = velocities
    fixed = beam.fixed.copy()
    fixed[free] = True
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with pytest.raises(corocontact.InputWarning, match="fall on fixed nodes"):
            beam.fixed = fixed
    assert not beam.fixed[free] and (beam.velocities == velocities).all()
