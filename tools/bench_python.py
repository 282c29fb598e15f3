#!/usr/bin/env python3
"""What stepping a case from Python costs against the corocontact command: the same run (case,
steps, frames at output_every, threads) done by `corocontact run` and by the Python module in a
Python process of its own, alternately, several times. Prints the median times of both and
their ratio: the time loop (summary.json wall_s: steps and frames, loading excluded) and the
whole process (start, loading, run, exit).

    PYTHONPATH=build/python /usr/bin/python3 tools/bench_python.py [CASE] [--steps N]
        [--threads N] [--repeat N] [--cli build/bin/corocontact]
"""
import argparse
import json
import os
import pathlib
import statistics
import subprocess
import sys
import tempfile
import time

ROOT = pathlib.Path(__file__).resolve().parents[1]

# The Python side of one run, in a fresh interpreter: what examples and tests/python do.
PYTHON_RUN = """
import sys, corocontact
case, steps, threads, out = sys.argv[1], int(sys.argv[2]), int(sys.argv[3]), sys.argv[4]
sim = corocontact.Simulation(case, threads=threads, output_dir=out)
sim.write_frame()
while sim.steps_done < steps:
    sim.step()
    if sim.steps_done % sim.output_every == 0 or sim.steps_done == steps:
        sim.write_frame()
sim.write_summary()
"""


def cpu_name():
    for line in subprocess.run(["lscpu"], capture_output=True, text=True).stdout.splitlines():
        if line.startswith("Model name:"):
            return line.split(":", 1)[1].strip()
    return "unknown CPU"


def timed_run(command, out, name, env=None):
    """(process wall time, summary wall_s) of one run writing into `out`."""
    start = time.perf_counter()
    subprocess.run(command, check=True, stdout=subprocess.DEVNULL, env=env)
    process = time.perf_counter() - start
    loop = json.loads((out / f"{name}.summary.json").read_text())["wall_s"]
    return process, loop


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("case", nargs="?", type=pathlib.Path, default=ROOT / "cases/two_spheres/two_spheres.toml")
    parser.add_argument("--steps", type=int, default=200)
    parser.add_argument("--threads", type=int, default=2)
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument("--cli", type=pathlib.Path, default=ROOT / "build/bin/corocontact")
    args = parser.parse_args(argv)

    name = args.case.stem  # simulation.name defaults to the case file's stem
    env = dict(os.environ, PYTHONPATH=os.environ.get("PYTHONPATH", str(ROOT / "build/python")))
    cli, python = [], []
    with tempfile.TemporaryDirectory() as scratch:
        for r in range(args.repeat):
            for side, results in (("cli", cli), ("python", python)):
                out = pathlib.Path(scratch) / f"{side}{r}"
                if side == "cli":
                    command = [str(args.cli), "run", str(args.case), "--steps", str(args.steps), "--threads",
                               str(args.threads), "--out", str(out), "--quiet"]
                else:
                    command = [sys.executable, "-c", PYTHON_RUN, str(args.case), str(args.steps), str(args.threads),
                               str(out)]
                results.append(timed_run(command, out, name, env))

    print(f"{name}: {args.steps} steps, {args.threads} threads, {args.repeat} runs each, alternating; {cpu_name()}")
    print(f"{'':>10} {'time loop [s]':>14} {'process [s]':>12}")
    medians = {}
    for side, results in (("command", cli), ("python", python)):
        medians[side] = (statistics.median(r[1] for r in results), statistics.median(r[0] for r in results))
        print(f"{side:>10} {medians[side][0]:14.3f} {medians[side][1]:12.3f}   "
              f"(loop per run: {' '.join(f'{r[1]:.3f}' for r in results)})")
    loop = medians["python"][0] / medians["command"][0]
    process = medians["python"][1] / medians["command"][1]
    print(f"{'ratio':>10} {loop:14.3f} {process:12.3f}   (python / command, medians)")


if __name__ == "__main__":
    main()
