"""corocontact.detect and detect_meshes: the rows of `corocontact detect --csv`, and inside
answers and depths checked against a case whose answer is known."""
import csv

import numpy as np
import pytest

import corocontact
from conftest import CASES

OVERLAP = CASES / "overlap" / "overlap.toml"


def cli_rows(cli, tmp_path, case, *options):
    path = tmp_path / "detect.csv"
    cli("detect", case, "--csv", path, *options, check_exit=0)
    with open(path, newline="") as f:
        reader = csv.reader(f)
        assert next(reader) == ["body", "vertex", "other", "depth"]
        return [(body, int(vertex), other, float(depth)) for body, vertex, other, depth in reader]


def python_rows(found):
    assert set(found) >= {"body", "vertex", "other", "depth", "normal"}
    return list(zip(found["body"].tolist(), found["vertex"].tolist(), found["other"].tolist(),
                    found["depth"].tolist()))


COUPLED = CASES / "coupled"
SUNK_CASES = {
    # The ball's embedded surface sunk into the mesh obstacle (a ramp).
    "coupled": (COUPLED / "coupled.toml", {
        "translate = [0.0, 0.9, 0.0]": "translate = [0.0, 0.3, 0.0]",
        '"ball_fine.obj"': f'"{COUPLED / "ball_fine.obj"}"', '"ramp.obj"': f'"{COUPLED / "ramp.obj"}"'}),
    # 64 bodies, the floor plane raised into the lowest layer.
    "pile": (CASES / "pile" / "pile.toml", {
        "point = [0.0000, 0.0000, 0.0000]\nnormal = [0.0000, 1.0000, 0.0000]":
        "point = [0.0000, 0.3000, 0.0000]\nnormal = [0.0000, 1.0000, 0.0000]"}),
}


def sunk_case(tmp_path, name):
    """A case of cases/ changed so that its bodies start inside their obstacles."""
    case, replace = SUNK_CASES[name]
    text = case.read_text()
    for old, new in replace.items():
        assert old in text
        text = text.replace(old, new)
    path = tmp_path / case.name
    path.write_text(text)
    return path


@pytest.mark.parametrize("case, mode", [
    (OVERLAP, "exact"),  # three bodies deep in each other
    (OVERLAP, "paper"),
    ("coupled", "exact"),
    ("pile", "exact"),
])
def test_detect_gives_the_rows_of_the_command(cli, tmp_path, case, mode):
    if case in SUNK_CASES:
        case = sunk_case(tmp_path, case)
    expected = cli_rows(cli, tmp_path, case, "--mode", mode)
    found = corocontact.detect(case, mode=mode)
    assert len(expected) > 0
    assert python_rows(found) == expected  # depths compared exactly (the CSV has 17 digits)
    names = found["names"]
    assert (names[found["body_index"]] == found["body"]).all()
    assert (names[found["other_index"]] == found["other"]).all()
    assert np.allclose(np.linalg.norm(found["normal"], axis=1), 1.0)


def test_detect_meshes_on_a_cases_bodies_gives_the_rows_of_the_command(cli, tmp_path):
    expected = cli_rows(cli, tmp_path, OVERLAP)
    bodies = corocontact.Simulation(OVERLAP).bodies
    names = [b.name for b in bodies]
    from_tets = corocontact.detect_meshes([(b.rest_positions, b.tets) for b in bodies], names=names)
    from_faces = corocontact.detect_meshes([(b.rest_positions, b.surface_faces) for b in bodies], names=names)
    assert python_rows(from_tets) == expected
    assert python_rows(from_faces) == expected


def cube(lo, hi):
    """A closed, outward triangulated box: 8 vertices, 12 faces."""
    lo, hi = np.asarray(lo, float), np.asarray(hi, float)
    vertices = np.array([[hi[0] if i & 1 else lo[0], hi[1] if i & 2 else lo[1], hi[2] if i & 4 else lo[2]]
                         for i in range(8)])
    quads = [(0, 2, 3, 1), (4, 5, 7, 6), (0, 1, 5, 4), (2, 6, 7, 3), (0, 4, 6, 2), (1, 3, 7, 5)]
    faces = [f for a, b, c, d in quads for f in ((a, b, c), (a, c, d))]
    return vertices, np.array(faces)


def test_detect_meshes_finds_the_vertices_inside_a_box_at_their_depth():
    # The second box's four corners at x = 0.5 are inside the unit box, 0.25 from its nearest
    # faces (y or z); no corner of the unit box is inside the second one.
    found = corocontact.detect_meshes([cube([0, 0, 0], [1, 1, 1]), cube([0.5, 0.25, 0.25], [1.5, 0.75, 0.75])],
                                      names=["unit", "bar"])
    assert found["body"].tolist() == ["bar"] * 4 and found["other"].tolist() == ["unit"] * 4
    assert found["vertex"].tolist() == [0, 2, 4, 6]
    assert np.allclose(found["depth"], 0.25, rtol=0, atol=1e-15)
    assert np.allclose(np.abs(found["normal"]).sum(axis=1), 1.0)  # ±y or ±z


def test_detect_meshes_flips_an_inward_surface_and_warns():
    vertices, faces = cube([0, 0, 0], [1, 1, 1])
    with pytest.warns(corocontact.InputWarning, match=r"meshes\[0\] \('mesh0'\) had inward normals"):
        found = corocontact.detect_meshes([(vertices, faces[:, ::-1]), cube([0.5, 0.25, 0.25], [1.5, 0.75, 0.75])])
    assert found["vertex"].tolist() == [0, 2, 4, 6]


def test_no_contact_gives_empty_arrays():
    found = corocontact.detect_meshes([cube([0, 0, 0], [1, 1, 1]), cube([2, 0, 0], [3, 1, 1])])
    assert all(len(found[key]) == 0 for key in ("body", "vertex", "other", "depth"))
    assert found["normal"].shape == (0, 3)
    assert corocontact.Simulation(CASES / "two_spheres" / "two_spheres.toml").contacts["depth"].shape == (0,)
