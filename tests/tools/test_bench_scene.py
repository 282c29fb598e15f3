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
                    "--tets", "50", "--steps", "10", "--out", str(case)], check=True, capture_output=True)
    return case


def test_table_and_ratios_of_a_tiny_pile(tiny_pile):
    # 5 steps in turns of 2: the last turn is a single step.
    result = subprocess.run([str(BENCH), str(tiny_pile), "--warmup", "2", "--steps", "5", "--turn", "2",
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
        pile_ms, box_ms = rows[("pile", contact, threads)][2], rows[("box", contact, threads)][2]
        assert float(m[3]) == pytest.approx(pile_ms / box_ms, abs=0.006, rel=0.01)
        assert float(m[5]) <= float(m[4]) <= float(m[6])  # the turns' median inside their middle half
        pile_speedup = rows[("pile", contact, 1)][2] / pile_ms
        box_speedup = rows[("box", contact, 1)][2] / box_ms
        assert float(m[7]) == pytest.approx(pile_speedup, abs=0.006, rel=0.01)
        assert float(m[8]) == pytest.approx(box_speedup, abs=0.006, rel=0.01)


def test_a_bad_turn_is_refused_with_exit_code_2(tiny_pile):
    result = subprocess.run([str(BENCH), str(tiny_pile), "--turn", "0"], capture_output=True, text=True)
    assert result.returncode == 2
    assert "--turn" in result.stderr and result.stdout == ""
