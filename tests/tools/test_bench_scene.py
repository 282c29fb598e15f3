"""tools/bench_scene on a tiny generated pile: its table, and ratios and speed-ups that follow from
the table's own times. CORO_BENCH_SCENE is the built bench_scene."""
import os
import pathlib
import re
import subprocess
import sys

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]
BENCH = pathlib.Path(os.environ["CORO_BENCH_SCENE"])

ROW = re.compile(r"^(pile|box)\s+(on|off)\s+(\d+)\s+(\d+)\s+(\d+)\s+([\d.]+)")
RATIO = re.compile(r"contact (on|off)\s+threads (\d+): pile/box ([\d.]+) \(turns ([\d.]+), ([\d.]+)-([\d.]+)\).*"
                   r"speed-up pile ([\d.]+) box ([\d.]+)")


@pytest.fixture(scope="module")
def tiny_pile(tmp_path_factory):
    case = tmp_path_factory.mktemp("bench_scene") / "pile8.toml"
    subprocess.run([sys.executable, str(ROOT / "cases" / "pile_large" / "make_pile_large.py"), "--bodies", "8",
                    "--tets", "50", "--out", str(case)], check=True, capture_output=True)
    return case


def rounding_bound(a, b):
    """How far a / b may lie from the ratio of the unrounded values, a and b printed with 3 decimals,
    the ratio with 2."""
    return (a / b) * (0.0005 / a + 0.0005 / b) + 0.005 + 1e-9


def test_table_and_ratios_of_a_tiny_pile(tiny_pile):
    # 3 steps in turns of 2: two turns, the last a single step. With two turns the printed middle
    # half is their lowest and highest ratio, and the ratio of all steps (a mean of the two,
    # weighted by the box's times) lies between them.
    result = subprocess.run([str(BENCH), str(tiny_pile), "--warmup", "2", "--steps", "3", "--turn", "2",
                             "--threads", "1,2"], capture_output=True, text=True, timeout=120)
    assert result.returncode == 0, result.stderr
    rows = {}
    for line in result.stdout.splitlines():
        if m := ROW.match(line):
            rows[(m[1], m[2], int(m[3]))] = (int(m[4]), int(m[5]), float(m[6]))
    assert len(rows) == 8, result.stdout  # pile and box, contact on and off, 1 and 2 threads
    for contact in ("on", "off"):
        for threads in (1, 2):
            pile_bodies, pile_tets, _ = rows[("pile", contact, threads)]
            box_bodies, box_tets, _ = rows[("box", contact, threads)]
            assert (pile_bodies, box_bodies) == (8, 1)
            assert abs(box_tets - pile_tets) <= 0.25 * pile_tets  # one box of about the pile's tets

    ratios = [m for m in map(RATIO.search, result.stdout.splitlines()) if m]
    assert len(ratios) == 4, result.stdout
    for m in ratios:
        contact, threads = m[1], int(m[2])
        ratio, median, low, high = float(m[3]), float(m[4]), float(m[5]), float(m[6])
        pile_ms, box_ms = rows[("pile", contact, threads)][2], rows[("box", contact, threads)][2]
        assert abs(ratio - pile_ms / box_ms) <= rounding_bound(pile_ms, box_ms)
        assert low <= median <= high
        assert low - 0.01 <= ratio <= high + 0.01
        pile_ref, box_ref = rows[("pile", contact, 1)][2], rows[("box", contact, 1)][2]
        assert abs(float(m[7]) - pile_ref / pile_ms) <= rounding_bound(pile_ref, pile_ms)
        assert abs(float(m[8]) - box_ref / box_ms) <= rounding_bound(box_ref, box_ms)


def test_a_bad_turn_is_refused_with_exit_code_2(tiny_pile):
    result = subprocess.run([str(BENCH), str(tiny_pile), "--turn", "0"], capture_output=True, text=True)
    assert result.returncode == 2
    assert "--turn" in result.stderr and result.stdout == ""
