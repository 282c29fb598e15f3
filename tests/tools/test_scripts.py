"""tools/run.sh (what it builds, how it reads its arguments) and tools/scaling.py (its arithmetic,
its check for matplotlib, its table from real runs). CORO_CLI is the built corocontact."""
import importlib.util
import os
import pathlib
import shutil
import stat
import subprocess
import sys

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]
CLI = pathlib.Path(os.environ["CORO_CLI"])

TINY = """[simulation]
dt = 0.01
steps = 2
[[body]]
name = "block"
shape = "box"
cells = [2, 1, 1]
"""


def scaling_module():
    spec = importlib.util.spec_from_file_location("scaling", ROOT / "tools" / "scaling.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def executable(path, text):
    path.write_text(text)
    path.chmod(path.stat().st_mode | stat.S_IXUSR)
    return path


def test_scaling_efficiency_is_relative_to_the_first_thread_count():
    rows = scaling_module().scaling_rows([(2, {"steps_per_s": 10.0}), (4, {"steps_per_s": 18.0}),
                                          (8, {"steps_per_s": 20.0})])
    assert [r[0] for r in rows] == [2, 4, 8]
    assert [r[2] for r in rows] == pytest.approx([1.0, 1.8, 2.0])   # speed-up over 2 threads
    assert [r[3] for r in rows] == pytest.approx([1.0, 0.9, 0.5])   # 1.8 of an ideal 2, 2 of 4


def test_scaling_checks_matplotlib_before_any_run(tmp_path):
    fake = tmp_path / "no_matplotlib" / "matplotlib"
    fake.mkdir(parents=True)
    (fake / "__init__.py").write_text("raise ImportError('No module named matplotlib')\n")
    ran = tmp_path / "ran"
    binary = executable(tmp_path / "corocontact", f"#!/bin/sh\ntouch {ran}\nexit 1\n")
    case = tmp_path / "tiny.toml"
    case.write_text(TINY)
    result = subprocess.run([sys.executable, str(ROOT / "tools" / "scaling.py"), str(case), "--binary", str(binary)],
                            env={**os.environ, "PYTHONPATH": str(fake.parent)}, capture_output=True, text=True)
    assert result.returncode == 2, result.stderr
    assert "matplotlib is missing" in result.stderr and "--no-plot" in result.stderr
    assert not ran.exists(), "scaling.py ran the case before finding matplotlib missing"


def test_scaling_table_from_real_runs(tmp_path):
    case = tmp_path / "tiny.toml"
    case.write_text(TINY)
    result = subprocess.run([sys.executable, str(ROOT / "tools" / "scaling.py"), str(case), "--threads", "2", "1",
                             "--no-plot", "--binary", str(CLI), "--out", str(tmp_path / "runs")],
                            capture_output=True, text=True)
    assert result.returncode == 0, result.stderr
    lines = result.stdout.splitlines()
    assert lines[0].startswith("tiny.toml: 1 body, 12 tets, 2 steps; speed-up and efficiency relative to 2 threads")
    first, second = lines[2].split(), lines[3].split()
    assert first[0] == "2" and first[2:4] == ["1.00", "1.00"]
    assert second[0] == "1"
    assert float(second[3]) == pytest.approx(2.0 * float(second[2]), abs=0.016)  # efficiency = speed-up × 2 / 1


@pytest.fixture
def run_sh_tree(tmp_path):
    """A copy of tools/run.sh in a tree whose setup.sh records its arguments and whose
    build/bin/corocontact is the real one, with the default case."""
    (tmp_path / "tools").mkdir()
    shutil.copy(ROOT / "tools" / "run.sh", tmp_path / "tools" / "run.sh")
    executable(tmp_path / "tools" / "setup.sh", f"#!/bin/sh\necho \"$@\" > {tmp_path / 'setup_args'}\n")
    (tmp_path / "build" / "bin").mkdir(parents=True)
    (tmp_path / "build" / "bin" / "corocontact").symlink_to(CLI)
    (tmp_path / "cases" / "two_spheres").mkdir(parents=True)
    shutil.copy(ROOT / "cases" / "two_spheres" / "two_spheres.toml", tmp_path / "cases" / "two_spheres")
    return tmp_path


def run_sh(tree, *arguments):
    return subprocess.run([str(tree / "tools" / "run.sh"), *arguments], cwd=tree, capture_output=True, text=True)


def test_run_sh_builds_only_the_command_and_options_alone_run_the_default_case(run_sh_tree):
    result = run_sh(run_sh_tree, "--steps", "1", "--quiet", "--out", str(run_sh_tree / "o"))
    assert result.returncode == 0, result.stderr
    assert (run_sh_tree / "setup_args").read_text().split() == ["--target", "corocontact"]
    assert result.stdout.startswith("two_spheres: 1 step in")
    assert "Open the .pvd above in ParaView" in result.stdout
    assert (run_sh_tree / "o" / "two_spheres.pvd").is_file()


def test_run_sh_takes_a_case_then_its_options(run_sh_tree):
    (run_sh_tree / "tiny.toml").write_text(TINY)
    result = run_sh(run_sh_tree, "tiny.toml", "--steps", "1", "--quiet", "--out", str(run_sh_tree / "o"))
    assert result.returncode == 0, result.stderr
    assert result.stdout.startswith("tiny: 1 step in")


def test_run_sh_passes_on_a_failure(run_sh_tree):
    result = run_sh(run_sh_tree, "missing.toml")
    assert result.returncode == 2
    assert "missing.toml" in result.stderr
    assert "Open the .pvd" not in result.stdout
