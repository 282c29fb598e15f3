#!/usr/bin/python3
"""Strong scaling of one case: run it with each thread count, print a table and plot it.

    tools/scaling.py CASE.toml [--threads 1 2] [--steps N] [--plot scaling.png | --no-plot] [--out DIR]

Runs `build/bin/corocontact run CASE --threads T --quiet` for every T, reads each
OUT/NAME.summary.json and prints steps/s, speed-up, parallel efficiency and the time per
phase (ms per step). Speed-up and efficiency are relative to the first thread count T0 given:
speed-up = (steps/s at T) / (steps/s at T0), efficiency = speed-up × T0 / T (1 = perfect
scaling from T0). The PNG (python3-matplotlib from Debian; checked before any run) shows
steps/s and the phase split per thread count. Exit code 2 for bad arguments or a missing
matplotlib, 1 when a run fails.
"""
import argparse
import json
import pathlib
import subprocess
import sys
import tempfile

ROOT = pathlib.Path(__file__).resolve().parent.parent
PHASES = ["rotation", "assembly", "solve", "contact", "output"]


def run_case(binary, case, threads, steps, out_root):
    out = out_root / f"threads_{threads}"
    command = [str(binary), "run", str(case), "--threads", str(threads), "--quiet", "--out", str(out)]
    if steps:
        command += ["--steps", str(steps)]
    result = subprocess.run(command, capture_output=True, text=True)
    if result.returncode != 0:
        sys.stderr.write(result.stderr)
        raise SystemExit(f"scaling.py: {' '.join(command)} exited with {result.returncode}")
    summaries = list(out.glob("*.summary.json"))
    if len(summaries) != 1:
        raise SystemExit(f"scaling.py: expected one summary in {out}, found {len(summaries)}")
    return json.loads(summaries[0].read_text())


def plural(n, one, many):
    return f"{n} {one if n == 1 else many}"


def scaling_rows(runs):
    """(threads, summary, speed-up, efficiency) per run, relative to the first run."""
    t0, s0 = runs[0]
    rate0 = s0["steps_per_s"]
    rows = []
    for threads, s in runs:
        speedup = s["steps_per_s"] / rate0 if rate0 > 0 else 0.0
        rows.append((threads, s, speedup, speedup * t0 / threads))
    return rows


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("case", type=pathlib.Path)
    parser.add_argument("--threads", type=int, nargs="+", default=[1, 2])
    parser.add_argument("--steps", type=int, default=0, help="override simulation.steps")
    parser.add_argument("--plot", type=pathlib.Path, default=None, help="PNG to write (default: CASE_scaling.png in the output dir)")
    parser.add_argument("--no-plot", action="store_true", help="print the table only (no matplotlib needed)")
    parser.add_argument("--out", type=pathlib.Path, default=None, help="directory for the runs (default: a temporary one)")
    parser.add_argument("--binary", type=pathlib.Path, default=ROOT / "build" / "bin" / "corocontact")
    args = parser.parse_args()
    if not args.case.is_file():
        parser.error(f"{args.case}: no such case file")
    if not args.binary.is_file():
        parser.error(f"{args.binary}: not built (run tools/setup.sh)")
    if any(t < 1 for t in args.threads):
        parser.error("--threads: every count must be >= 1")
    if args.plot and args.no_plot:
        parser.error("--plot and --no-plot exclude each other")
    plt = None
    if not args.no_plot:
        try:  # before the runs, which can take long
            import matplotlib
            matplotlib.use("Agg")
            import matplotlib.pyplot as plt
        except ImportError:
            sys.stderr.write("scaling.py: matplotlib is missing: install python3-matplotlib (tools/setup.sh does) "
                             "and run under /usr/bin/python3, or pass --no-plot\n")
            raise SystemExit(2)

    out_root = args.out or pathlib.Path(tempfile.mkdtemp(prefix="coro_scaling_"))
    out_root.mkdir(parents=True, exist_ok=True)
    runs = [(t, run_case(args.binary, args.case, t, args.steps, out_root)) for t in args.threads]
    rows = scaling_rows(runs)

    t0, s0 = runs[0]
    header = f"{'threads':>7} {'steps/s':>9} {'speed-up':>9} {'effic.':>7}  " + " ".join(f"{p + ' ms':>12}" for p in PHASES)
    print(f"{args.case.name}: {plural(s0['bodies'], 'body', 'bodies')}, {plural(s0['tets'], 'tet', 'tets')}, "
          f"{plural(s0['steps'], 'step', 'steps')}; speed-up and efficiency relative to {plural(t0, 'thread', 'threads')}")
    print(header)
    for threads, s, speedup, efficiency in rows:
        per_step = " ".join(f"{1e3 * s['phases'][p] / max(s['steps'], 1):12.3f}" for p in PHASES)
        print(f"{threads:7d} {s['steps_per_s']:9.2f} {speedup:9.2f} {efficiency:7.2f}  {per_step}")
    if plt is None:
        return

    plot = args.plot or out_root / f"{args.case.stem}_scaling.png"
    fig, (left, right) = plt.subplots(1, 2, figsize=(10, 4))
    threads = [t for t, _ in runs]
    left.plot(threads, [s["steps_per_s"] for _, s in runs], "o-", label="measured")
    left.plot(threads, [s0["steps_per_s"] * t / t0 for t in threads], "--", label=f"ideal from {t0}")
    left.set_xlabel("threads")
    left.set_ylabel("steps/s")
    left.set_xticks(threads)
    left.legend()
    left.set_title(args.case.stem)
    bottom = [0.0] * len(runs)
    for phase in PHASES:
        values = [1e3 * s["phases"][phase] / max(s["steps"], 1) for _, s in runs]
        right.bar([str(t) for t in threads], values, bottom=bottom, label=phase)
        bottom = [b + v for b, v in zip(bottom, values)]
    right.set_xlabel("threads")
    right.set_ylabel("ms per step")
    right.legend()
    fig.tight_layout()
    fig.savefig(plot, dpi=100)
    print(f"plot: {plot}")


if __name__ == "__main__":
    main()
