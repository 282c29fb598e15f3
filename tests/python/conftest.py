"""Shared by the tests of the Python module: the command to compare with, and the source tree.

CTest (tests/python/CMakeLists.txt) sets PYTHONPATH to build/python and CORO_CLI to the built
command."""
import os
import pathlib
import subprocess

import pytest

SOURCE_DIR = pathlib.Path(__file__).resolve().parents[2]
CASES = SOURCE_DIR / "cases"


@pytest.fixture(scope="session")
def cli():
    """Runs the corocontact command: cli("run", case, "--steps", 5) -> CompletedProcess."""
    command = os.environ["CORO_CLI"]

    def run(*arguments, check_exit=None):
        result = subprocess.run([command, *map(str, arguments)], capture_output=True, text=True,
                                stdin=subprocess.DEVNULL)
        if check_exit is not None:
            assert result.returncode == check_exit, result.stderr
        return result

    return run


def error_message(stderr, prefix="error: "):
    """The message of the command's `error: ...` line (it runs to the end of stderr)."""
    start = stderr.index(prefix)
    return stderr[start + len(prefix):].rstrip("\n")
