"""The FMU driven through its inputs: a motor torque at the pivot, at the slow mode's frequency and away from it.

    python examples/drive_inputs.py [--stop 20] [--fmu PATH] [--out DIR]

An input signal for fmpy is a structured array: a ``time`` column and one column per input, interpolated
between its rows. Every input of the FMU is in it (the unused ones zero), so fmpy has no missing input to warn
about. The energy the motor feeds in is the FMU's output ``W_input``. Writes drive_inputs.png into the folder
``--out`` (default: ``examples_output/`` under the current folder, made if missing) and nothing anywhere else.
"""

import argparse
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from fmpy import simulate_fmu  # noqa: E402

from double_pendulum.fmu.running.choice import FmuPathError, fmu_to_run  # noqa: E402

INPUTS = ("pivot_x", "pivot_y", "pivot_vx", "pivot_vy", "pivot_ax", "pivot_ay", "tau1", "tau2")
TORQUE_N_M = 0.002  # amplitude of the motor torque on the upper rod
SLOW_MODE_RAD_S = 4.81  # the slow normal mode of the seed's pendulum (double-pendulum run base_excitation)


def torque_signal(omega: float, stop: float) -> np.ndarray:
    """tau1 = TORQUE_N_M sin(omega t) [N m] every 10 ms, all other inputs zero."""
    t = np.arange(0.0, stop + 0.005, 0.01)
    columns = {name: np.zeros_like(t) for name in INPUTS}
    columns["tau1"] = TORQUE_N_M * np.sin(omega * t)
    return np.rec.fromarrays([t, *columns.values()], names=["time", *columns])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--stop", type=float, default=20.0, help="length of each run [s] (default: 20)")
    parser.add_argument("--fmu", default=None, help="an FMU of the double pendulum to run, read and never built "
                        "over (default: build/DoublePendulum.fmu, built there if missing or older than the sources)")
    parser.add_argument("--out", default="examples_output", metavar="DIR",
                        help="the folder the figure drive_inputs.png goes into, made if missing "
                        "(default: examples_output)")
    args = parser.parse_args()
    try:  # a path given is only read; the default is built first if missing or older than the sources
        fmu = str(fmu_to_run(args.fmu))
    except FmuPathError as error:
        parser.exit(2, f"{parser.prog}: error: --fmu {error}\n")

    fig, (ax_angle, ax_work) = plt.subplots(2, 1, figsize=(9, 6.5), sharex=True, layout="constrained")
    for omega in (SLOW_MODE_RAD_S, 0.6 * SLOW_MODE_RAD_S):
        result = simulate_fmu(fmu, start_values={"phi1_0": 0.0, "phi2_0": 0.0, "air_drag": True},
                              stop_time=args.stop, output_interval=0.01, input=torque_signal(omega, args.stop),
                              output=["phi1", "W_input"])  # W_input is a local: recorded when asked for
        label = f"torque at {omega:.2f} rad/s"
        ax_angle.plot(result["time"], result["phi1"], lw=0.9, label=label)
        ax_work.plot(result["time"], 1000 * result["W_input"], label=label)
        print(f"{label}: largest swing of the upper rod {np.max(np.abs(result['phi1'])):.3f} rad, "
              f"work fed in {1000 * result['W_input'][-1]:.2f} mJ")
    ax_angle.set(ylabel="upper rod's angle phi1 [rad]",
                 title=f"the pendulum at rest, driven by a motor torque of {1000 * TORQUE_N_M:g} mN m at its pivot")
    ax_work.set(xlabel="time t [s]", ylabel="work fed in by the motor W_input [mJ]")
    for ax in (ax_angle, ax_work):
        ax.grid(alpha=0.3)
        ax.legend(loc="upper left", fontsize=8)
    out = Path(args.out) / "drive_inputs.png"
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=100)
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
