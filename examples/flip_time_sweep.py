"""How long until the lower rod first turns over, for every pair of start angles: a parameter sweep.

    python examples/flip_time_sweep.py [--grid 24] [--stop 10] [--workers N] [--fmu PATH] [--out DIR]

``run_sweep`` runs the FMU once per case (a dict of start values) on worker processes, one per core, and gives
the results back in the order of the cases. ``reduce`` is applied on the worker, so only one number per run
travels back. The workers are started afresh ("spawn"): a script that sweeps must guard its top level with
``if __name__ == "__main__":``, as here. Writes flip_times.png into the folder ``--out`` (default:
``examples_output/`` under the current folder, made if missing), nothing anywhere else, and prints the share of
starts that flip.
"""

import argparse
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from double_pendulum.analysis.sweep import grid_cases, run_sweep  # noqa: E402
from double_pendulum.fmu.running.choice import FmuPathError, fmu_to_run  # noqa: E402


def first_flip_s(result: np.ndarray) -> float:
    """Time [s] at which the lower rod first passes its upright position (|phi2| > pi); NaN if it never does."""
    flipped = np.flatnonzero(np.abs(result["phi2"]) > np.pi)
    return float(result["time"][flipped[0]]) if len(flipped) else float("nan")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--grid", type=int, default=24, help="start angles per axis (default: 24)")
    parser.add_argument("--stop", type=float, default=10.0, help="length of each run [s] (default: 10)")
    parser.add_argument("--workers", type=int, default=None, help="worker processes (default: one per core)")
    parser.add_argument("--fmu", default=None, help="an FMU of the double pendulum to run, read and never built "
                        "over (default: build/DoublePendulum.fmu, built there if missing or older than the sources)")
    parser.add_argument("--out", default="examples_output", metavar="DIR",
                        help="the folder the figure flip_times.png goes into, made if missing "
                        "(default: examples_output)")
    args = parser.parse_args()
    try:  # a path given is only read; the default is built first if missing or older than the sources
        fmu = str(fmu_to_run(args.fmu))
    except FmuPathError as error:
        parser.exit(2, f"{parser.prog}: error: --fmu {error}\n")

    angles = np.linspace(-3.0, 3.0, args.grid)  # rad, both rods released from rest
    cases = grid_cases({"solver": "dop853", "rtol": 1e-8}, phi1_0=angles, phi2_0=angles)
    times = run_sweep(fmu, cases, stop_time=args.stop, output_interval=0.01,
                      outputs=("phi1", "phi2"), reduce=first_flip_s, max_workers=args.workers)
    grid = np.array(times).reshape(len(angles), len(angles))  # rows: phi1_0, columns: phi2_0

    fig, ax = plt.subplots(figsize=(6.5, 5.5), layout="constrained")
    image = ax.pcolormesh(angles, angles, grid.T, shading="nearest", cmap="viridis")
    fig.colorbar(image, ax=ax, label="time until the lower rod first turns over [s]")
    ax.set(xlabel="upper rod's start angle phi1_0 [rad]", ylabel="lower rod's start angle phi2_0 [rad]",
           title=f"first flip of the lower rod (white: none within {args.stop:g} s)", aspect="equal")
    out = Path(args.out) / "flip_times.png"
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=100)
    print(f"{np.isfinite(grid).mean():.0%} of {grid.size} starts flip the lower rod within {args.stop:g} s; "
          f"wrote {out}")


if __name__ == "__main__":  # the sweep's worker processes import this file: they must not run the sweep again
    main()
