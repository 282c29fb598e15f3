#!/usr/bin/env python3
"""Friction against sliding distance: a box on a plane tilted 35° (tilted_plane.toml).

For each friction coefficient μ the case is loaded, [contact] friction is set from Python, the
box is let go for `duration` seconds and the distance its centre travelled is measured. Coulomb
friction predicts s = g (sin θ − μ cos θ) t² / 2 for μ < tan θ and no sliding above; the plot
shows both.

    PYTHONPATH=build/python /usr/bin/python3 examples/python/friction_sweep.py [--out DIR]

writes DIR/friction_sweep.png (default out/friction_sweep/) and prints the table.
"""
import argparse
import math
import pathlib

import numpy as np

import corocontact

CASE = pathlib.Path(__file__).resolve().with_name("tilted_plane.toml")
TILT_DEGREES = 35.0  # the plane's tilt in tilted_plane.toml


def sliding_distance(friction, duration, threads=None):
    """How far [m] the box's centre moves in `duration` seconds with friction coefficient μ."""
    sim = corocontact.Simulation(CASE, threads=threads)
    sim.contact_friction = friction
    box = sim.body("box")
    start = box.positions.mean(axis=0)
    sim.step(round(duration / sim.dt))
    return float(np.linalg.norm(box.positions.mean(axis=0) - start))


def coulomb_distance(friction, duration, gravity=9.81, tilt_degrees=TILT_DEGREES):
    """Coulomb's answer for a rigid block: s = max(0, g (sin θ − μ cos θ)) t² / 2 [m]."""
    theta = math.radians(tilt_degrees)
    acceleration = gravity * (math.sin(theta) - friction * math.cos(theta))
    return 0.5 * max(0.0, acceleration) * duration**2


def sweep(frictions, duration, threads=None):
    """Simulated and Coulomb distances [m] for each friction coefficient."""
    simulated = np.array([sliding_distance(mu, duration, threads) for mu in frictions])
    predicted = np.array([coulomb_distance(mu, duration) for mu in frictions])
    return simulated, predicted


def plot(frictions, simulated, duration, path):
    import matplotlib

    matplotlib.use("Agg")  # files only, no display needed
    import matplotlib.pyplot as plt

    fine = np.linspace(0.0, max(frictions), 200)
    fig, ax = plt.subplots(figsize=(6.0, 4.0), dpi=120)
    ax.plot(fine, [coulomb_distance(mu, duration) for mu in fine], "-", color="0.4",
            label=r"Coulomb, rigid block: $g(\sin\theta-\mu\cos\theta)\,t^2/2$")
    ax.plot(frictions, simulated, "o", color="C3", label="corocontact")
    ax.axvline(math.tan(math.radians(TILT_DEGREES)), color="0.7", linestyle=":",
               label=r"$\mu = \tan 35°$")
    ax.set_xlabel(r"friction coefficient $\mu$")
    ax.set_ylabel(f"sliding distance after {duration:g} s [m]")
    ax.set_title("Box on a plane tilted 35°")
    ax.legend(frameon=False, fontsize=8)
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=pathlib.Path, default=pathlib.Path("out/friction_sweep"),
                        help="folder for friction_sweep.png (default: out/friction_sweep)")
    parser.add_argument("--duration", type=float, default=0.5, help="simulated seconds per run")
    parser.add_argument("--frictions", type=float, nargs="+",
                        default=[0.0, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.8, 1.0])
    parser.add_argument("--threads", type=int, default=None)
    args = parser.parse_args(argv)

    simulated, predicted = sweep(args.frictions, args.duration, args.threads)
    print(f"{'mu':>5} {'simulated [m]':>14} {'Coulomb [m]':>12}")
    for mu, s, p in zip(args.frictions, simulated, predicted):
        print(f"{mu:5.2f} {s:14.5f} {p:12.5f}")
    args.out.mkdir(parents=True, exist_ok=True)
    png = args.out / "friction_sweep.png"
    plot(args.frictions, simulated, args.duration, png)
    print(f"plot: {png}")
    return args.frictions, simulated, predicted, png


if __name__ == "__main__":
    main()
