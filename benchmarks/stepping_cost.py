"""Cost of one doStep, stepping only (start-up excluded), against an empty pythonfmu FMU, in one run.

    python benchmarks/stepping_cost.py [--fmu build/DoublePendulum.fmu] [--steps 2000] [--repeats 7]

Both FMUs are instantiated and initialised once through fmpy's ``FMU2Slave``; then only the loop is
timed: per 1 ms step

* **driven**: ``fmi2SetReal`` of all eight inputs (a vertical shaker motion, consistent position,
  velocity and acceleration, and small joint torques), ``fmi2DoStep``, ``fmi2GetReal`` of two outputs;
* **undriven**: ``fmi2DoStep`` and ``fmi2GetReal`` of two outputs, from the chaotic start
  phi1 = phi2 = 2 rad.

The empty FMU holds the same eight inputs and does nothing. CPU time (``time.process_time``), median
of the repeats, the FMUs interleaved so machine noise hits both alike; the ratios are the figures
(target <= 2). Then a profile of the component alone (in-process, the same loops), by part: setting
the inputs, the right-hand side (its evaluations per step times the cost of one), the rest of the
doStep (integrator and bookkeeping), reading the outputs.
"""

from __future__ import annotations

import argparse
import statistics
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

from coupling_performance import build_empty_fmu, shaker

from double_pendulum.component.cosimulation import DoublePendulumCoSimulation
from double_pendulum.fmu.build.fmi2 import build_fmu
from double_pendulum.model.inputs import INPUT_NAMES

H = 1e-3
START = {"phi1_0": 2.0, "phi2_0": 2.0}
READ = ("phi1", "phi2")


def open_slave(fmu_path: Path, start: dict[str, float]):
    """An initialised FMU2Slave and the value references of its inputs and of two outputs."""
    from fmpy import extract, read_model_description
    from fmpy.fmi2 import FMU2Slave

    md = read_model_description(str(fmu_path))
    refs = {v.name: v.valueReference for v in md.modelVariables}
    slave = FMU2Slave(guid=md.guid, unzipDirectory=extract(str(fmu_path)),
                      modelIdentifier=md.coSimulation.modelIdentifier, instanceName="bench")
    slave.instantiate()
    slave.setupExperiment(startTime=0.0)
    slave.enterInitializationMode()
    for name, value in start.items():
        slave.setReal([refs[name]], [value])
    slave.exitInitializationMode()
    outputs = [refs[n] for n in READ] if READ[0] in refs else [refs["y"]] * len(READ)
    return slave, [refs[n] for n in INPUT_NAMES], outputs


def fmi_loop(fmu_path: Path, start: dict[str, float], steps: int, driven: bool) -> float:
    """CPU seconds per step of ``steps`` doSteps of 1 ms through fmpy (instantiation not timed)."""
    slave, inputs, outputs = open_slave(fmu_path, start)
    values = [shaker(k * H) for k in range(steps)]
    set_real, do_step, get_real = slave.setReal, slave.doStep, slave.getReal
    t0 = time.process_time()
    for k in range(steps):
        if driven:
            set_real(inputs, values[k])
        do_step(k * H, H)
        get_real(outputs)
    elapsed = time.process_time() - t0
    slave.terminate()
    slave.freeInstance()
    return elapsed / steps


def component_profile(steps: int, driven: bool) -> dict[str, float]:
    """Microseconds per step of each part of the component's own loop (in-process)."""
    sim = DoublePendulumCoSimulation()
    for name, value in START.items():
        sim.set(name, value)
    sim.initialise()
    values = [shaker(k * H) for k in range(steps)]
    indices = list(range(len(INPUT_NAMES)))
    parts = dict.fromkeys(("inputs", "doStep", "outputs"), 0.0)
    clock = time.process_time
    for k in range(steps):
        t0 = clock()
        if driven:
            sim.set_inputs_at(indices, values[k])  # as the FMU's fmi2SetReal does
        t1 = clock()
        sim.do_step(k * H, H)
        t2 = clock()
        for name in READ:
            sim.get(name)
        t3 = clock()
        parts["inputs"] += t1 - t0
        parts["doStep"] += t2 - t1
        parts["outputs"] += t3 - t2
    f, t, y = sim.integrator.f, sim.time, list(sim.integrator.y)
    n_calls = 2000
    t0 = clock()
    for _ in range(n_calls):
        f(t, y)
    rhs_cost = (clock() - t0) / n_calls
    evaluations = sim.integrator.nfev / steps
    result = {name: total / steps * 1e6 for name, total in parts.items()}
    result["rhs"] = evaluations * rhs_cost * 1e6
    result["integrator"] = result["doStep"] - result["rhs"]
    result["evaluations"] = evaluations
    return result


def median_of(fn: Callable[[], float], repeats: int) -> float:
    return statistics.median(fn() for _ in range(repeats))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--fmu", type=Path, help="DoublePendulum.fmu to measure (default: build the current one)")
    parser.add_argument("--steps", type=int, default=2000)
    parser.add_argument("--repeats", type=int, default=7)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory(prefix="dp_bench_stepping_") as tmp:
        pendulum = args.fmu or build_fmu(Path(tmp) / "DoublePendulum.fmu")
        empty = build_empty_fmu(Path(tmp))
        times: dict[tuple[str, bool], list[float]] = {}
        for _ in range(args.repeats):
            for driven in (True, False):
                for name, fmu, start in (("fmu", pendulum, START), ("empty", empty, {})):
                    times.setdefault((name, driven), []).append(fmi_loop(fmu, start, args.steps, driven))
    print(f"doStep of 1 ms through fmpy, stepping only ({args.steps} steps, median of {args.repeats}):")
    for driven in (True, False):
        fmu, empty_cost = (statistics.median(times[(n, driven)]) for n in ("fmu", "empty"))
        label = "driven (8 inputs set every step)" if driven else "undriven (no inputs)            "
        print(f"  {label}: FMU {fmu * 1e6:6.1f} us, empty FMU {empty_cost * 1e6:5.1f} us"
              f" -> ratio {fmu / empty_cost:5.2f} (target <= 2)")
    print("The component alone, in-process, us per step by part:")
    for driven in (True, False):
        parts = component_profile(args.steps, driven)
        print(f"  {'driven  ' if driven else 'undriven'}: inputs {parts['inputs']:5.1f}, right-hand side"
              f" {parts['rhs']:5.1f} ({parts['evaluations']:.1f} evaluations), integrator and bookkeeping"
              f" {parts['integrator']:5.1f}, outputs {parts['outputs']:4.1f}; doStep {parts['doStep']:5.1f}")


if __name__ == "__main__":
    main()
