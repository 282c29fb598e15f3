"""tools/bench_precision's own options: a value that is not a whole number in range is a usage error
(exit 2, the option named) before any beam is built. CORO_BENCH_PRECISION is the built
bench_precision."""
import os
import pathlib
import subprocess

import pytest

BENCH = pathlib.Path(os.environ["CORO_BENCH_PRECISION"])


@pytest.mark.parametrize("arguments, option", [
    (["--scale", "0"], "--scale"),
    (["--scale", "5"], "--scale"),
    (["--scale", "2x"], "--scale"),
    (["--scale"], "--scale"),
    (["--threads", "0"], "--threads"),
    (["--threads", "two"], "--threads"),
])
def test_bad_option_values_are_usage_errors(arguments, option):
    result = subprocess.run([str(BENCH)] + arguments, capture_output=True, text=True, timeout=60)
    assert result.returncode == 2, result.stdout + result.stderr
    assert f"{option} expects a whole number" in result.stderr
    assert "nodes" not in result.stdout  # nothing was built or run
