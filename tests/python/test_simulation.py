"""corocontact.Simulation: a case stepped from Python writes the command's frames bit for bit,
its arrays are the frames' arrays in the input node order, and inputs changed from Python
act as the same values given in the case file."""
import _thread
import json
import math
import threading

import numpy as np
import pytest
from vtkmodules.util.numpy_support import vtk_to_numpy
from vtkmodules.vtkIOXML import vtkXMLUnstructuredGridReader

import corocontact
from conftest import CASES, SOURCE_DIR

TILTED_PLANE = SOURCE_DIR / "examples" / "python" / "tilted_plane.toml"


def step_like_the_command(sim, steps):
    """What `corocontact run --steps N` does: frame 0, every output_every-th step and the last."""
    sim.write_frame()
    while sim.steps_done < steps:
        sim.step()
        if sim.steps_done % sim.output_every == 0 or sim.steps_done == steps:
            sim.write_frame()


def series_files(folder):
    """Every file of a run but the summary (it holds timings), relative to the folder."""
    return sorted(p.relative_to(folder) for p in folder.rglob("*")
                  if p.is_file() and not p.name.endswith(".summary.json"))


@pytest.mark.parametrize("case, steps", [
    (CASES / "two_spheres" / "two_spheres.toml", 45),   # two bodies colliding
    (CASES / "pile" / "pile.toml", 10),                 # 64 bodies, a floor plane, friction
    (CASES / "coupled" / "coupled.toml", 10),           # an embedded surface, a mesh obstacle
])
def test_frames_stepped_from_python_equal_the_command_bit_for_bit(cli, tmp_path, case, steps):
    cli("run", case, "--steps", steps, "--out", tmp_path / "cli", "--threads", 2, "--quiet", check_exit=0)
    sim = corocontact.Simulation(case, threads=1, output_dir=tmp_path / "python")
    step_like_the_command(sim, steps)
    sim.write_summary()
    keys, name = sim.summary().keys(), sim.name
    assert (tmp_path / "python" / "corocontact.lock").exists()
    del sim  # lets go of the output folder's lock

    cli_files = series_files(tmp_path / "cli")
    assert cli_files == series_files(tmp_path / "python")
    assert len(cli_files) > 3
    for file in cli_files:
        assert (tmp_path / "cli" / file).read_bytes() == (tmp_path / "python" / file).read_bytes(), file
    # The summaries: the same keys, the same counts and means; only timings and threads differ.
    from_cli = json.loads((tmp_path / "cli" / f"{name}.summary.json").read_text())
    from_python = json.loads((tmp_path / "python" / f"{name}.summary.json").read_text())
    assert keys == from_cli.keys() == from_python.keys()
    timings = {"wall_s", "steps_per_s", "setup_s", "phases", "peak_rss_mb", "threads"}
    assert {k: v for k, v in from_python.items() if k not in timings} == \
        {k: v for k, v in from_cli.items() if k not in timings}
    assert from_python["steps"] == steps and from_python["threads"] == 1 and from_cli["threads"] == 2


def test_one_run_per_output_folder_and_an_earlier_run_removed(cli, tmp_path):
    case = CASES / "two_spheres" / "two_spheres.toml"
    cli("run", case, "--steps", 10, "--out", tmp_path, "--quiet", check_exit=0)  # frames 0, 5, 10
    first = corocontact.Simulation(case, output_dir=tmp_path)
    with pytest.warns(corocontact.OutputWarning, match=r"removed \d+ files \(3 frames\) of an earlier run"):
        first.write_frame()
    assert not (tmp_path / "two_spheres_000010.vtm").exists()
    # The folder is taken: by the command's rules, with the command's message.
    refused = cli("run", case, "--steps", 10, "--out", tmp_path, "--quiet", check_exit=4)
    assert "corocontact.Simulation(" in refused.stderr
    second = corocontact.Simulation(case, output_dir=tmp_path)
    with pytest.raises(corocontact.OutputError) as raised:
        second.write_frame()
    assert isinstance(raised.value, OSError) and "corocontact.Simulation(" in str(raised.value)
    del first
    with pytest.warns(corocontact.OutputWarning, match=r"removed \d+ files \(1 frames\)"):
        second.write_frame()  # the first one's frame is an earlier run's now


def read_vtu(path):
    reader = vtkXMLUnstructuredGridReader()
    reader.SetFileName(str(path))
    reader.Update()
    return reader.GetOutput()


def test_arrays_equal_the_frames_in_input_node_order(tmp_path):
    sim = corocontact.Simulation(CASES / "two_spheres" / "two_spheres.toml", output_dir=tmp_path)
    sim.step(40)  # the spheres are in contact by now
    sim.write_frame()
    assert len(sim.contacts["depth"]) > 0
    for body in sim.bodies:
        grid = read_vtu(tmp_path / f"{sim.name}_000040" / f"{body.name}.vtu")
        points = vtk_to_numpy(grid.GetPoints().GetData())
        data = grid.GetPointData()
        assert np.array_equal(body.positions, points)
        assert np.array_equal(body.velocities, vtk_to_numpy(data.GetArray("velocity")))
        assert np.array_equal(body.positions - body.rest_positions, vtk_to_numpy(data.GetArray("displacement")))
        assert np.array_equal(body.contact_forces, vtk_to_numpy(data.GetArray("contact_force")))
        cells = vtk_to_numpy(grid.GetCells().GetConnectivityArray()).reshape(-1, 4)
        assert np.array_equal(body.tets, cells)
        assert np.array_equal(body.von_mises, vtk_to_numpy(grid.GetCellData().GetArray("von_mises")))
        inside = vtk_to_numpy(data.GetArray("contact_inside"))
        rows = sim.contacts["body"] == body.name
        assert sorted(np.flatnonzero(inside)) == sorted(set(sim.contacts["vertex"][rows]))
        assert body.positions.shape == (body.num_vertices, 3) and body.positions.dtype == np.float64


def test_constant_arrays_are_read_only_and_state_arrays_are_copies():
    sim = corocontact.Simulation(CASES / "two_spheres" / "two_spheres.toml")
    body = sim.bodies[0]
    for constant in (body.rest_positions, body.tets, body.surface_faces, body.masses):
        assert not constant.flags.writeable
    positions = body.positions
    positions[:] = 0.0
    assert not np.array_equal(body.positions, positions)
    # The boundary of a sphere: closed, every edge in two faces, and Euler characteristic 2.
    faces = body.surface_faces
    edges = {tuple(sorted(e)) for f in faces for e in ((f[0], f[1]), (f[1], f[2]), (f[2], f[0]))}
    assert len(np.unique(faces)) - len(edges) + len(faces) == 2
    assert math.isclose(body.masses.sum(), 1000.0 * 4.0 / 3.0 * math.pi * 0.5**3, rel_tol=0.05)


SUNK = {"rotate_degrees = 35.0": "rotate_degrees = 35.0\ntranslate = [0.0, -0.004, 0.0]"}


def tilted_plane_case(tmp_path, replace):
    """The example's case with some lines of it replaced: {old line: new line}. With SUNK, the box
    starts 3.3 mm deep in the plane, so that the first step's contact response has every input."""
    text = TILTED_PLANE.read_text()
    for old, new in replace.items():
        assert old in text
        text = text.replace(old, new)
    path = tmp_path / f"case_{len(list(tmp_path.glob('case_*')))}.toml"
    path.write_text(text)
    return path


def positions_after(sim, steps):
    sim.step(steps)
    return np.concatenate([b.positions for b in sim.bodies])


@pytest.mark.parametrize("key, value", [("friction", 0.3), ("stiffness", 2e5), ("damping", 5.0)])
def test_contact_settings_set_from_python_act_as_in_the_case_file(tmp_path, key, value):
    line = {"friction": "friction = 0.5", "stiffness": "stiffness = 1e5", "damping": "damping = 20.0"}[key]
    in_file = corocontact.Simulation(tilted_plane_case(tmp_path, {**SUNK, line: f"{key} = {value!r}"}))
    from_python = corocontact.Simulation(tilted_plane_case(tmp_path, SUNK))
    assert len(from_python.contacts["depth"]) > 0
    setattr(from_python, f"contact_{key}", value)
    assert getattr(from_python, f"contact_{key}") == value
    assert np.array_equal(positions_after(in_file, 40), positions_after(from_python, 40))


def test_velocities_gravity_loads_and_fixed_nodes_set_from_python_act_as_in_the_case_file(tmp_path):
    case = tilted_plane_case(tmp_path, {
        **SUNK, "density = 1000.0": "density = 1000.0\nvelocity = [0.5, 0.2, -0.1]\n"
                            "[[body.fixed]]\nmin = [-1.0, -1.0, -1.0]\nmax = [1.0, 1.0, -0.05]\n"
                            "[[body.load]]\nmin = [-1.0, 0.09, -1.0]\nmax = [1.0, 1.0, 1.0]\nforce = [3.0, -2.0, 1.0]",
        "gravity = [0.0, -9.81, 0.0]": "gravity = [1.0, -5.0, 0.5]"})
    with pytest.warns(corocontact.InputWarning, match=r"N of its \[\[body.load\]\] forces fall on fixed nodes"):
        in_file = corocontact.Simulation(case)
    from_python = corocontact.Simulation(tilted_plane_case(tmp_path, SUNK))
    assert len(from_python.contacts["depth"]) > 0
    box = from_python.body("box")
    rest = box.rest_positions
    fixed = rest[:, 2] <= -0.05
    loaded = ((rest >= [-1.0, 0.09, -1.0]) & (rest <= [1.0, 1.0, 1.0])).all(axis=1)
    assert 0 < fixed.sum() < box.num_vertices and 0 < loaded.sum() < box.num_vertices
    from_python.gravity = [1.0, -5.0, 0.5]
    box.fixed = fixed
    velocities = np.tile([0.5, 0.2, -0.1], (box.num_vertices, 1))
    velocities[fixed] = 0.0
    box.velocities = velocities
    loads = np.zeros((box.num_vertices, 3))
    loads[loaded] = np.array([3.0, -2.0, 1.0]) / loaded.sum()
    with pytest.warns(corocontact.InputWarning, match=r"body 'box': [\d.]+ of the [\d.]+ N of its loads fall on fixed"):
        box.loads = loads
    assert np.array_equal(box.fixed, in_file.body("box").fixed)
    assert np.array_equal(box.loads, in_file.body("box").loads)
    assert np.array_equal(positions_after(in_file, 40), positions_after(from_python, 40))
    assert np.array_equal(box.positions[fixed], rest[fixed])


def test_friction_changed_between_steps_stops_a_sliding_box():
    sim = corocontact.Simulation(TILTED_PLANE)
    sim.contact_friction = 0.0
    box = sim.body("box")
    sim.step(100)
    sliding = np.linalg.norm(box.velocities.mean(axis=0))
    assert sliding > 1.0  # g sin 35° × 0.2 s = 1.13 m/s
    sim.contact_friction = 1.0  # above tan 35°: decelerates at g (μ cos 35° − sin 35°) = 2.4 m/s²
    sim.step(300)
    assert np.linalg.norm(box.velocities.mean(axis=0)) < 0.02 * sliding


def test_released_nodes_move_and_fixed_ones_stay():
    sim = corocontact.Simulation(SOURCE_DIR / "cases" / "cantilever" / "cantilever_dynamic.toml")
    beam = sim.bodies[0]
    clamped = beam.fixed
    assert clamped.any()
    sim.step(5)
    assert np.array_equal(beam.positions[clamped], beam.rest_positions[clamped])
    beam.fixed = np.zeros(beam.num_vertices, dtype=bool)
    sim.step(5)
    assert not np.array_equal(beam.positions[clamped], beam.rest_positions[clamped])
    beam.fixed = np.ones(beam.num_vertices, dtype=bool)
    held = beam.positions
    assert not beam.velocities.any()
    sim.step(3)
    assert np.array_equal(beam.positions, held)


def test_the_gil_is_released_while_stepping():
    sim = corocontact.Simulation(CASES / "two_spheres" / "two_spheres.toml", threads=1)
    worker = threading.Thread(target=sim.step, args=(60,))
    refused = 0
    worker.start()
    while worker.is_alive():
        try:
            sim.steps_done
        except RuntimeError as error:
            assert "stepping in another thread" in str(error)
            refused += 1
    worker.join()
    # This thread ran while a step was in progress: the step did not hold the GIL.
    assert refused > 0
    assert sim.steps_done == 60


def test_ctrl_c_stops_between_steps():
    sim = corocontact.Simulation(CASES / "two_spheres" / "two_spheres.toml", threads=1)
    timer = threading.Timer(0.3, _thread.interrupt_main)
    timer.start()
    with pytest.raises(KeyboardInterrupt):
        sim.step(100000)
    timer.join()
    assert 0 < sim.steps_done < 100000
    sim.step()  # the simulation is still usable


def test_time_and_steps():
    sim = corocontact.Simulation(CASES / "two_spheres" / "two_spheres.toml")
    assert (sim.steps_done, sim.time, sim.dt, sim.last_step, sim.analysis) == (0, 0.0, 0.005, 200, "dynamic")
    sim.step(3)
    sim.step()
    assert sim.steps_done == 4 and sim.time == 4 * 0.005
    assert [b.name for b in sim.bodies] == ["left", "right"] and sim.body("right") is sim.bodies[1]
    with pytest.raises(KeyError):
        sim.body("middle")


def test_static_analysis_steps_its_load_steps_only(cli, tmp_path):
    # The cantilever case in 3 load steps instead of 40 (fast; the frames need not be accurate).
    text = (SOURCE_DIR / "cases" / "cantilever" / "cantilever.toml").read_text()
    assert "load_steps = 40" in text
    case = tmp_path / "cantilever.toml"
    case.write_text(text.replace("load_steps = 40", "load_steps = 3"))
    cli("run", case, "--out", tmp_path / "cli", "--quiet", check_exit=0)
    sim = corocontact.Simulation(case, output_dir=tmp_path / "python")
    assert sim.analysis == "static" and sim.output_every == 1
    with pytest.raises(corocontact.InputError, match=r"step\(n = 4\): 3 of the 3 load steps .* are left"):
        sim.step(4)  # refused before any step
    assert sim.steps_done == 0
    step_like_the_command(sim, sim.last_step)
    assert sim.time == 1.0
    for file in series_files(tmp_path / "cli"):  # every load step's frame, the same bytes
        assert (tmp_path / "cli" / file).read_bytes() == (tmp_path / "python" / file).read_bytes(), file
    with pytest.raises(corocontact.InputError, match=r"step\(n = 1\): 0 of the 3 load steps of this static analysis are left"):
        sim.step()
