"""Model Exchange against Co-Simulation, measured side by side (issue 22, point 4).

Usage: ``python benchmarks/fmi3_interfaces.py [--repeats 3]``

1. **ME with CVode against our CS at equal error.** The FMI 3 FMU from the chaotic start
   phi1 = phi2 = 2 rad for 2 s, output every 10 ms, both through fmpy: Model Exchange integrated by
   fmpy's CVode (BDF, relative tolerance r, absolute r x the nominal 1) and Co-Simulation (the
   FMU's own dop853, rtol r, atol r / 1000). Error: the larger angle error at t = 2 s against the
   cached reference (``double_pendulum.analysis.solvers.reference``). For each target error the loosest
   tolerance that reaches it, its CPU time, and the cost ratio ME / CS.
2. **The pendulum on its suspension: monolithic ME against split CS.** The default suspension
   (M_s = 2 kg, k = 2e4 N/m, c = 20 N s/m) with phi1 = phi2 = 1 rad for 1 s: the FMI 3 FMU with
   ``suspension`` on, integrated as one system by CVode (ME; the FMU's own dop853 as CS for
   comparison), against DoublePendulum.fmu and Suspension.fmu (FMI 2) coupled by
   ``double_pendulum.fmu.masters.coupling.run_coupled`` (Jacobi as libcosim does it, and iterative with
   rollback) at several macro steps. Error: the largest angle error on the 10 ms grid against the
   monolith's reference; cost: CPU time of the whole run; for each target error the cheapest run of
   each kind and the cost ratio split / monolithic ME.

CPU times (``time.process_time``, median of the repeats, FMUs extracted once). Compare ratios, not
seconds: the machine is shared and noisy.
"""

from __future__ import annotations

import argparse
import statistics
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np
from fmpy import extract, read_model_description, simulate_fmu

from double_pendulum.analysis.solvers.reference import reference_solution
from double_pendulum.fmu.build.fmi2 import build_fmu
from double_pendulum.fmu.build.fmi3 import build_fmu3
from double_pendulum.fmu.masters.coupling import FmuSlave, run_coupled, split_values

CHAOTIC = {"phi1_0": 2.0, "phi2_0": 2.0}
ON_SUSPENSION = {"phi1_0": 1.0, "phi2_0": 1.0, "suspension": True}
ANGLES = ("phi1", "phi2")
TOLERANCES = (1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11, 1e-12, 1e-13)
TARGETS = (1e-4, 1e-6, 1e-8)  # rad
SUSPENSION_TOLERANCES = (1e-6, 1e-8, 1e-10)
SUSPENSION_TARGETS = (1e-3, 1e-5)  # rad
COUPLINGS = (("jacobi", 1e-3), ("jacobi", 2e-4), ("jacobi", 5e-5), ("iterative", 5e-3), ("iterative", 1e-3),
             ("iterative", 2e-4))


def timed(fn: Callable[[], object], repeats: int) -> tuple[float, object]:
    """Median CPU time [s] of ``repeats`` calls and the last result."""
    times, result = [], None
    for _ in range(repeats):
        start = time.process_time()
        result = fn()
        times.append(time.process_time() - start)
    return statistics.median(times), result


def run_me(fmu3: str, start: dict, stop: float, rtol: float) -> np.ndarray:
    return simulate_fmu(fmu3, fmi_type="ModelExchange", start_values=start, stop_time=stop, output_interval=0.01,
                        relative_tolerance=rtol, output=list(ANGLES))


def run_cs(fmu3: str, start: dict, stop: float, rtol: float) -> np.ndarray:
    return simulate_fmu(fmu3, fmi_type="CoSimulation", start_values={**start, "rtol": rtol, "atol": rtol * 1e-3},
                        stop_time=stop, output_interval=0.01, output=list(ANGLES))


def end_error(result: np.ndarray, reference) -> float:
    return max(abs(float(result[n][-1]) - float(reference.states[n][-1])) for n in ANGLES)


def run_error(times: np.ndarray, result: np.ndarray, reference) -> float:
    """The largest angle error on the reference's grid [rad] (each run sampled at the grid's times)."""
    return max(float(np.max(np.abs(np.interp(reference.time, times, result[n]) - reference.states[n])))
               for n in ANGLES)


def equal_error(fmu3: str, repeats: int) -> None:
    reference = reference_solution(CHAOTIC, 2.0, 0.01)
    print(f"1. chaotic start (2, 2) rad, 2 s, angle error at t = 2 s "
          f"(reference error floor {reference.error_floor:.0e} rad)")
    rows = {}
    for name, run in (("ME (CVode)", run_me), ("CS (dop853)", run_cs)):
        rows[name] = []
        for rtol in TOLERANCES:
            cpu, result = timed(lambda run=run, rtol=rtol: run(fmu3, CHAOTIC, 2.0, rtol), repeats)
            rows[name].append((f"rtol {rtol:.0e}", end_error(result, reference), cpu))
            print(f"   {name:11s} rtol {rtol:7.0e}: error {rows[name][-1][1]:8.1e} rad, {cpu:6.3f} s CPU")
    report_equal_error(rows, TARGETS, "ME (CVode)", "CS (dop853)")


def report_equal_error(rows: dict[str, list[tuple[str, float, float]]], targets: tuple[float, ...], numerator: str,
                       denominator: str) -> None:
    """For each target error [rad] the cheapest run of each kind that reaches it, and their cost ratio.

    ``rows``: per kind, ``(setting, error [rad], CPU [s])`` of every run.
    """
    for target in targets:
        cheapest = {name: min(((cpu, setting) for setting, error, cpu in runs if error <= target), default=None)
                    for name, runs in rows.items()}
        line = ", ".join(f"{name} {best[1]} {best[0]:.3f} s" if best else f"{name} not reached"
                         for name, best in cheapest.items())
        top, bottom = cheapest[numerator], cheapest[denominator]
        if top and bottom:
            line += f"; cost ratio {numerator} / {denominator} = {top[0] / bottom[0]:.3g}"
        print(f"   error <= {target:.0e} rad: {line}")


def monolith_against_split(fmu3: str, folder: Path, repeats: int) -> None:
    reference = reference_solution(ON_SUSPENSION, 1.0, 0.01)
    print(f"2. pendulum on its suspension, (1, 1) rad, 1 s, largest angle error on the 10 ms grid "
          f"(reference error floor {reference.error_floor:.0e} rad)")
    rows: dict[str, list[tuple[str, float, float]]] = {"monolithic ME": [], "monolithic CS": [], "split CS": []}
    for rtol in SUSPENSION_TOLERANCES:
        for name, run in (("monolithic ME", run_me), ("monolithic CS", run_cs)):
            cpu, result = timed(lambda run=run, rtol=rtol: run(fmu3, ON_SUSPENSION, 1.0, rtol), repeats)
            rows[name].append((f"rtol {rtol:.0e}", run_error(result["time"], result, reference), cpu))
            print(f"   {name} ({'CVode' if 'ME' in name else 'dop853'}) rtol {rtol:.0e}: "
                  f"error {rows[name][-1][1]:8.1e} rad, {cpu:6.3f} s CPU")
    pendulum_values, suspension_values = split_values(ON_SUSPENSION)
    fmus = {name: (extract(str(build_fmu(folder / f"{name}.fmu", name)), str(folder / name)),
                   read_model_description(str(folder / f"{name}.fmu"))) for name in ("DoublePendulum", "Suspension")}

    def coupled(scheme: str, h: float) -> np.ndarray:
        pendulum = FmuSlave(*fmus["DoublePendulum"], pendulum_values, "pendulum")
        suspension = FmuSlave(*fmus["Suspension"], suspension_values, "suspension")
        try:
            return run_coupled(pendulum, suspension, stop_time=1.0, macro_step=h, scheme=scheme,
                               suspension_outputs=("x",))
        finally:
            pendulum.close()
            suspension.close()

    for scheme, h in COUPLINGS:
        cpu, result = timed(lambda scheme=scheme, h=h: coupled(scheme, h), repeats)
        rows["split CS"].append((f"{scheme} h {h * 1e3:g} ms", run_error(result["time"], result, reference), cpu))
        print(f"   split CS (FMI 2), {scheme:9s} h = {h * 1e3:4.2f} ms: error {rows['split CS'][-1][1]:8.1e} rad, "
              f"{cpu:6.3f} s CPU")
    report_equal_error(rows, SUSPENSION_TARGETS, "split CS", "monolithic ME")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory(prefix="fmi3_bench_") as tmp:
        folder = Path(tmp)
        fmu3 = extract(str(build_fmu3(folder / "fmi3" / "DoublePendulum.fmu")), str(folder / "fmi3_x"))
        equal_error(fmu3, args.repeats)
        monolith_against_split(fmu3, folder, args.repeats)


if __name__ == "__main__":
    main()
