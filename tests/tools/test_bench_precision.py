"""tools/bench_precision's own options: a value that is not a whole number in range, or an option
neither it nor Google Benchmark knows, is a usage error (exit 2, the option named) before any beam
is built; good values run. CORO_BENCH_PRECISION is the built bench_precision."""
import os
import pathlib
import subprocess

import pytest

BENCH = pathlib.Path(os.environ["CORO_BENCH_PRECISION"])
# Runs no benchmark, so that a usage error the bench failed to see costs seconds, not minutes.
NO_BENCHMARK = ["--benchmark_filter=NONE"]


def run(arguments):
    return subprocess.run([str(BENCH)] + arguments, capture_output=True, text=True, timeout=100)


@pytest.mark.parametrize("arguments, message", [
    (["--scale", "0"], "--scale expects a whole number from 1 to 4, got '0'"),
    (["--scale", "5"], "--scale expects a whole number from 1 to 4, got '5'"),
    (["--scale", "-1"], "--scale expects a whole number from 1 to 4, got '-1'"),
    (["--scale", "2x"], "--scale expects a whole number from 1 to 4, got '2x'"),
    (["--scale", "99999999999"], "--scale expects a whole number from 1 to 4"),
    (["--threads", "0"], "--threads expects a whole number from 1 to 1024, got '0'"),
    (["--threads", "two"], "--threads expects a whole number from 1 to 1024, got 'two'"),
    (["--scale=2"], "unrecognized command-line flag: --scale=2"),
])
def test_bad_options_are_usage_errors(arguments, message):
    result = run(NO_BENCHMARK + arguments)
    assert result.returncode == 2, result.stdout + result.stderr
    assert message in result.stderr
    assert "nodes" not in result.stdout  # no beam was built


def test_an_option_without_its_value_is_a_usage_error():
    result = run(NO_BENCHMARK + ["--scale"])
    assert result.returncode == 2, result.stdout + result.stderr
    assert "--scale expects a whole number from 1 to 4, got ''" in result.stderr


def test_good_values_build_the_beam():
    result = run(NO_BENCHMARK + ["--scale", "1", "--threads", "1"])
    assert result.returncode == 0, result.stdout + result.stderr
    assert "beam of 16x16x76 nodes (SOFA's), 145111 blocks (upper, 10.4 MB of double values), 1 threads" in result.stdout
