#!/usr/bin/env python3
"""What stepping a case from Python costs against the corocontact command: the same run (case,
steps, frames at output_every, threads) done by `corocontact run` and by the Python module in a
Python process of its own, alternately, several times. Prints the median times of both and
their ratio: the time loop (summary.json wall_s: steps and frames, loading excluded), the
whole process (start, loading, run, exit) and its CPU time (user + system, all threads).

    PYTHONPATH=build/python /usr/bin/python3 tools/bench_python.py [CASE] [--steps N]
        [--threads N] [--repeat N] [--cli build/bin/corocontact]
"""
import argparse
import json
import os
import pathlib
import resource
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


def cpu_seconds_of_children():
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def timed_run(command, out, name, env=None):
    """(process wall time, summary wall_s, process CPU time) of one run writing into `out`."""
    cpu = cpu_seconds_of_children()
    start = time.perf_counter()
    subprocess.run(command, check=True, stdout=subprocess.DEVNULL, env=env)
    process = time.perf_counter() - start
    loop = json.loads((out / f"{name}.summary.json").read_text())["wall_s"]
    return process, loop, cpu_seconds_of_children() - cpu


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
    print(f"{'':>10} {'time loop [s]':>14} {'process [s]':>12} {'process CPU [s]':>16}")
    medians = {}
    for side, results in (("command", cli), ("python", python)):
        medians[side] = [statistics.median(r[i] for r in results) for i in (1, 0, 2)]
        print(f"{side:>10} {medians[side][0]:14.3f} {medians[side][1]:12.3f} {medians[side][2]:16.3f}   "
              f"(loop per run: {' '.join(f'{r[1]:.3f}' for r in results)})")
    ratios = [p / c for p, c in zip(medians["python"], medians["command"])]
    print(f"{'ratio':>10} {ratios[0]:14.3f} {ratios[1]:12.3f} {ratios[2]:16.3f}   (python / command, medians)")


if __name__ == "__main__":
    main()
