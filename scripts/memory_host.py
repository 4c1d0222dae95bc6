"""A Python host for the valgrind part of scripts/check_memory.sh: fmpy runs the FMUs, SciPy does ordinary
work, and the process exits as Python processes do (atexit handlers, interpreter teardown, the C library's
exit handlers) with the FMUs' binaries still loaded.

    python memory_host.py BUILD_FOLDER [simulate|alive]

``simulate``: build/DoublePendulum.fmu (FMI 2, co-simulation) and fmi3/DoublePendulum.fmu (FMI 3, co-simulation
and model exchange) for about 1 s of model time each, then scipy.integrate.solve_ivp with a numpy right-hand
side and LAPACK through scipy.linalg, then a normal exit. ``alive``: one FMI 2 instance instantiated, stepped
and never freed (fmpy's FMU2Slave without terminate/freeInstance), then a normal exit with it alive.
"""

from __future__ import annotations

import sys
from pathlib import Path

KEPT: list[object] = []


def simulate(build: Path) -> None:
    from fmpy import simulate_fmu

    runs = [(build / "DoublePendulum.fmu", "CoSimulation"),
            (build / "fmi3" / "DoublePendulum.fmu", "CoSimulation"),
            (build / "fmi3" / "DoublePendulum.fmu", "ModelExchange")]
    for path, interface in runs:
        result = simulate_fmu(str(path), fmi_type=interface, stop_time=1.0, output_interval=0.02,
                              start_values={"phi1_0": 2.0})
        print(f"{path.relative_to(build)} {interface}: phi1(1 s) = {float(result['phi1'][-1]):.6f}", flush=True)


def scipy_work() -> None:
    import numpy as np
    import scipy.integrate
    import scipy.linalg

    def pendulum(t, y):
        return np.array([y[1], -9.81 * np.sin(y[0])])

    solution = scipy.integrate.solve_ivp(pendulum, (0.0, 5.0), [1.0, 0.0], rtol=1e-8, atol=1e-10)
    matrix = np.random.default_rng(1).standard_normal((40, 40))
    eigenvalues = scipy.linalg.eigvals(matrix)  # LAPACK (dgeev), through scipy's Fortran wrappers
    inverse = scipy.linalg.inv(matrix)
    print(f"scipy: solve_ivp {solution.status} ({solution.t.size} steps), eigvals {eigenvalues.size}, "
          f"inv residual {np.abs(inverse @ matrix - np.eye(40)).max():.1e}", flush=True)


def alive(build: Path):
    from fmpy import extract, read_model_description
    from fmpy.fmi2 import FMU2Slave

    path = build / "DoublePendulum.fmu"
    description = read_model_description(str(path))
    folder = extract(str(path), str(build / "alive"))  # in the build folder, which the caller removes
    fmu = FMU2Slave(guid=description.guid, unzipDirectory=folder, modelIdentifier="DoublePendulum",
                    instanceName="alive")
    fmu.instantiate()
    fmu.setupExperiment(startTime=0.0)
    fmu.enterInitializationMode()
    fmu.exitInitializationMode()
    for k in range(10):
        fmu.doStep(currentCommunicationPoint=k * 0.01, communicationStepSize=0.01)
    print("alive: an instance stepped and left alive at exit (no terminate, no freeInstance)", flush=True)
    return fmu


def main() -> None:
    build, mode = Path(sys.argv[1]), sys.argv[2] if len(sys.argv) > 2 else "simulate"
    if mode == "simulate":
        simulate(build)
        scipy_work()
    elif mode == "alive":
        KEPT.append(alive(build))  # referenced until the interpreter tears down
    else:
        raise SystemExit(f"unknown mode {mode!r}: simulate or alive")


if __name__ == "__main__":
    main()
