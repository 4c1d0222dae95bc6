"""Print the core figures of the FMU: energy drift, cost per doStep through fmpy, start-up time.

Usage: ``python benchmarks/core_figures.py [--fmu PATH]``

Timings are CPU times (``time.process_time``) on this machine; the median of several repeats
is printed with the spread. Compare them as ratios within one run, not across machines.
"""

from __future__ import annotations

import argparse
import statistics
import time

import numpy as np

from double_pendulum.fmu.running.choice import fmu_to_run
from double_pendulum.fmu.running.runner import FmuRunner


def _median_spread(samples: list[float]) -> str:
    med = statistics.median(samples)
    lo, hi = min(samples) * 1e6, max(samples) * 1e6
    return f"{med * 1e6:9.1f} us  (min {lo:.1f}, max {hi:.1f}, n={len(samples)})"


def startup_times(runner: FmuRunner, repeats: int) -> list[float]:
    """CPU time of instantiate + setupExperiment + enter/exit initialisation mode."""
    from fmpy.fmi2 import FMU2Slave

    md = runner.model_description
    times = []
    for i in range(repeats):
        fmu = FMU2Slave(
            guid=md.guid,
            unzipDirectory=runner.unzipdir,
            modelIdentifier=md.coSimulation.modelIdentifier,
            instanceName=f"i{i}",
        )
        t0 = time.process_time()
        fmu.instantiate()
        fmu.setupExperiment(startTime=0.0)
        fmu.enterInitializationMode()
        fmu.exitInitializationMode()
        times.append(time.process_time() - t0)
        fmu.terminate()
        fmu.freeInstance()
    return times


def do_step_times(runner: FmuRunner, repeats: int, step: float = 1e-3, stop: float = 2.0) -> list[float]:
    """CPU time per doStep of a whole fmpy run (chaotic start, dop853 rtol 1e-9) at 1 ms steps."""
    n = round(stop / step)
    out = []
    for _ in range(repeats):
        t0 = time.process_time()
        runner.simulate({"phi1_0": 2.0, "phi2_0": 2.0}, stop_time=stop, output_interval=step)
        out.append((time.process_time() - t0) / n)
    return out


def energy_drift(runner: FmuRunner) -> float:
    r = runner.simulate(
        {"phi1_0": 2.0, "phi2_0": 2.0, "rtol": 1e-12, "atol": 1e-14}, stop_time=30.0, output_interval=0.01
    )
    e = r["E_total"]
    return float(np.max(np.abs(e - e[0])) / abs(e[0]))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--fmu", default=None, help="the FMU to measure, read and never built over (default: "
                        "build/DoublePendulum.fmu, built there if missing or older than the sources)")
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args()
    with FmuRunner(fmu_to_run(args.fmu)) as runner:
        print(f"energy drift, chaotic start, 30 s, dop853 rtol 1e-12: {energy_drift(runner):.2e} (relative)")
        steps = _median_spread(do_step_times(runner, args.repeats))
        print(f"doStep through fmpy, 1 ms step, dop853 rtol 1e-9:     {steps}")
        startup = _median_spread(startup_times(runner, args.repeats))
        print(f"FMU start-up (instantiate..exitInitializationMode):   {startup}")


if __name__ == "__main__":
    main()
