"""Speed of the FMU, measured side by side in one run and printed as ratios (issue: performance).

Usage: ``python benchmarks/fmu_performance.py [--fmu PATH] [--repeats 5]``

1. The FMU through fmpy versus SciPy ``solve_ivp(method="DOP853")`` called directly on the same
   vector field, each at the loosest tolerance that reaches an error <= 1e-8 at t = 3 s (chaotic
   start phi1 = phi2 = 2 rad, against the cached reference), output every 10 ms. Target <= 0.5.
2. The FMU's cost per doStep at a 1 ms communication step versus an empty pythonfmu FMU doing the
   same number of steps (both through fmpy, one output recorded). Target <= 2.
3. FMU start-up (loading the binary, instantiate + initialise + the first 1 ms doStep, first
   instance in a fresh process, so including the import of the bundled package) versus the empty
   FMU. Target <= 2.
4. The stiff suspension (k = 1e7 N/m, M_s = 0.05 kg, 2 s) with the FMU's stiff solver (rodas4)
   versus SciPy's LSODA called directly, each at the loosest tolerance whose largest error over
   the run is <= 1e-5. Target <= 1.

CPU times (``time.process_time``, median of the repeats, spread in brackets). Compare the ratios,
not the absolute seconds: the machine is shared and noisy.
"""

from __future__ import annotations

import argparse
import statistics
import subprocess
import sys
import tempfile
import textwrap
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np

from double_pendulum.analysis.solvers.reference import STATE_OUTPUTS, reference_solution
from double_pendulum.component.cosimulation import DoublePendulumCoSimulation
from double_pendulum.fmu.running.choice import fmu_to_run
from double_pendulum.fmu.running.runner import FmuRunner

CHAOTIC = {"phi1_0": 2.0, "phi2_0": 2.0}
STIFF = {"phi1_0": 1.0, "phi2_0": 1.0, "suspension": True, "M_s": 0.05, "k_x": 1e7, "k_y": 1e7,
         "c_x": 200.0, "c_y": 200.0}
RTOLS = (1e-4, 3e-5, 1e-5, 3e-6, 1e-6, 3e-7, 1e-7, 3e-8, 1e-8, 3e-9, 1e-9, 3e-10, 1e-10, 3e-11, 1e-11, 3e-12, 1e-12)

EMPTY_SLAVE = '''
from pythonfmu import Fmi2Causality, Fmi2Slave, Real


class Empty(Fmi2Slave):
    """A pythonfmu FMU that does nothing: the cost floor of pythonfmu + fmpy."""

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self.x = 0.0
        self.register_variable(Real("x", causality=Fmi2Causality.output))

    def do_step(self, current_time, step_size):
        return True
'''


def timed(fn: Callable[[], object], repeats: int) -> tuple[float, float, object]:
    """Median CPU time [s], relative spread and the last result of ``repeats`` calls."""
    times, result = [], None
    for _ in range(repeats):
        t0 = time.process_time()
        result = fn()
        times.append(time.process_time() - t0)
    med = statistics.median(times)
    return med, (max(times) - min(times)) / med if med else 0.0, result


def vector_field(start: dict) -> tuple[Callable, np.ndarray]:
    """The model's vector field and start vector for ``start`` (the same equations as the FMU)."""
    sim = DoublePendulumCoSimulation()
    for k, v in start.items():
        sim.set(k, v)
    sim.initialise()
    return sim.model.vector_field, np.array(sim.integrator.y)


def fmu_error(runner: FmuRunner, start: dict, ref, stop: float) -> float:
    r = runner.simulate(start, stop_time=stop, output_interval=0.01, outputs=list(STATE_OUTPUTS))
    return max(abs(float(r[n][-1]) - float(ref.states[n][-1])) for n in STATE_OUTPUTS)


def scipy_run(start: dict, stop: float, method: str, rtol: float, atol: float):
    from scipy.integrate import solve_ivp

    f, y0 = vector_field(start)
    t_eval = np.round(np.arange(0.0, stop + 1e-9, 0.01), 10)
    return solve_ivp(lambda t, y: f(t, y.tolist()), (0.0, stop), y0, method=method, rtol=rtol, atol=atol,
                     t_eval=t_eval)


def scipy_error(sol, ref) -> float:
    return max(abs(float(sol.y[i][-1]) - float(ref.states[n][-1])) for i, n in enumerate(STATE_OUTPUTS))


def loosest(errors: Callable[[float], float], target: float) -> tuple[float, float]:
    """The loosest rtol in RTOLS whose error <= target, and that error."""
    for rtol in RTOLS:
        err = errors(rtol)
        if err <= target:
            return rtol, err
    raise RuntimeError(f"no tolerance in {RTOLS} reaches an error of {target}")


def bench_vs_scipy(runner: FmuRunner, repeats: int) -> float:
    ref = reference_solution(CHAOTIC, 3.0, 0.01)
    fmu_rtol, fmu_err = loosest(lambda r: fmu_error(runner, {**CHAOTIC, "rtol": r, "atol": r * 1e-3}, ref, 3.0), 1e-8)
    sp_rtol, sp_err = loosest(lambda r: scipy_error(scipy_run(CHAOTIC, 3.0, "DOP853", r, r * 1e-3), ref), 1e-8)
    start = {**CHAOTIC, "rtol": fmu_rtol, "atol": fmu_rtol * 1e-3}
    t_fmu, s_fmu, _ = timed(lambda: runner.simulate(start, stop_time=3.0, output_interval=0.01), repeats)
    t_sp, s_sp, _ = timed(lambda: scipy_run(CHAOTIC, 3.0, "DOP853", sp_rtol, sp_rtol * 1e-3), repeats)
    print("1. chaotic 3 s, error <= 1e-8 at t = 3 s, output 10 ms")
    print(f"   FMU dop853 via fmpy: rtol {fmu_rtol:g}, error {fmu_err:.1e}, {t_fmu:.3f} s CPU ({s_fmu:.0%})")
    print(f"   scipy DOP853 direct: rtol {sp_rtol:g}, error {sp_err:.1e}, {t_sp:.3f} s CPU ({s_sp:.0%})")
    ratio = t_fmu / t_sp
    print(f"   ratio FMU / scipy = {ratio:.2f}  (target <= 0.5: {'met' if ratio <= 0.5 else 'NOT met'})")
    return ratio


def build_empty_fmu(folder: Path) -> Path:
    from pythonfmu.builder import FmuBuilder

    script = folder / "Empty.py"
    script.write_text(EMPTY_SLAVE)
    return Path(FmuBuilder.build_FMU(script, dest=folder / "Empty.fmu"))


def bench_do_step(runner: FmuRunner, empty: FmuRunner, repeats: int) -> float:
    n = 2000
    t_fmu, s_fmu, _ = timed(lambda: runner.simulate(CHAOTIC, stop_time=2.0, output_interval=1e-3, outputs=["phi1"]),
                            repeats)
    t_empty, s_empty, _ = timed(lambda: empty.simulate({}, stop_time=2.0, output_interval=1e-3, outputs=["x"]),
                                repeats)
    ratio = t_fmu / t_empty
    print(f"2. doStep at 1 ms, {n} steps through fmpy (chaotic start, dop853 rtol 1e-9)")
    print(f"   FMU {t_fmu / n * 1e6:.1f} us/step ({s_fmu:.0%}), empty pythonfmu FMU {t_empty / n * 1e6:.1f} us/step "
          f"({s_empty:.0%})")
    print(f"   ratio = {ratio:.2f}  (target <= 2: {'met' if ratio <= 2 else 'NOT met'})")
    return ratio


STARTUP_SCRIPT = textwrap.dedent('''
    import os, sys, time
    from fmpy import extract, read_model_description
    from fmpy.fmi2 import FMU2Slave
    md = read_model_description(sys.argv[1])
    t0 = time.process_time()
    fmu = FMU2Slave(guid=md.guid, unzipDirectory=sys.argv[2], modelIdentifier=md.coSimulation.modelIdentifier,
                    instanceName="startup")
    fmu.instantiate()
    fmu.setupExperiment(startTime=0.0)
    fmu.enterInitializationMode()
    fmu.exitInitializationMode()
    fmu.doStep(currentCommunicationPoint=0.0, communicationStepSize=1e-3)
    print(time.process_time() - t0, flush=True)
    os._exit(0)
''')


def startup_time(fmu: Path, unzipdir: str, repeats: int) -> tuple[float, float]:
    times = []
    for _ in range(repeats):
        out = subprocess.run([sys.executable, "-c", STARTUP_SCRIPT, str(fmu), unzipdir], capture_output=True,
                             text=True, check=True)
        times.append(float(out.stdout.strip().splitlines()[-1]))
    med = statistics.median(times)
    return med, (max(times) - min(times)) / med


def bench_startup(runner: FmuRunner, empty: FmuRunner, repeats: int) -> float:
    t_fmu, s_fmu = startup_time(runner.fmu_path, runner.unzipdir, repeats)
    t_empty, s_empty = startup_time(empty.fmu_path, empty.unzipdir, repeats)
    ratio = t_fmu / t_empty
    print("3. start-up in a fresh process (loading the binary, instantiate .. the first 1 ms doStep)")
    print(f"   FMU {t_fmu * 1e3:.1f} ms ({s_fmu:.0%}), empty pythonfmu FMU {t_empty * 1e3:.1f} ms ({s_empty:.0%})")
    print(f"   ratio = {ratio:.2f}  (target <= 2: {'met' if ratio <= 2 else 'NOT met'})")
    return ratio


def bench_stiff(runner: FmuRunner, repeats: int) -> float:
    ref = reference_solution(STIFF, 2.0, 0.01)

    def fmu_max_error(rtol: float) -> float:
        r = runner.simulate({**STIFF, "solver": "rodas4", "rtol": rtol, "atol": rtol * 1e-3}, stop_time=2.0,
                            output_interval=0.01, outputs=list(STATE_OUTPUTS))
        return max(float(np.max(np.abs(r[n] - ref.states[n]))) for n in STATE_OUTPUTS)

    def lsoda_max_error(rtol: float) -> float:
        sol = scipy_run(STIFF, 2.0, "LSODA", rtol, rtol * 1e-3)
        return max(float(np.max(np.abs(sol.y[i] - ref.states[n]))) for i, n in enumerate(STATE_OUTPUTS))

    target = 1e-5
    fmu_rtol, err_fmu = loosest(fmu_max_error, target)
    sp_rtol, err_sp = loosest(lsoda_max_error, target)
    start = {**STIFF, "solver": "rodas4", "rtol": fmu_rtol, "atol": fmu_rtol * 1e-3}
    t_fmu, s_fmu, _ = timed(lambda: runner.simulate(start, stop_time=2.0, output_interval=0.01), repeats)
    t_sp, s_sp, _ = timed(lambda: scipy_run(STIFF, 2.0, "LSODA", sp_rtol, sp_rtol * 1e-3), repeats)
    ratio = t_fmu / t_sp
    print(f"4. stiff suspension k = 1e7 N/m, M_s = 0.05 kg, 2 s, max error over the run <= {target:g}")
    print(f"   FMU rodas4 via fmpy: rtol {fmu_rtol:g}, error {err_fmu:.1e}, {t_fmu:.3f} s CPU ({s_fmu:.0%})")
    print(f"   scipy LSODA direct:  rtol {sp_rtol:g}, error {err_sp:.1e}, {t_sp:.3f} s CPU ({s_sp:.0%})")
    print(f"   ratio FMU / LSODA = {ratio:.2f}  (target <= 1: {'met' if ratio <= 1 else 'NOT met'})")
    return ratio


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--fmu", default=None, help="the FMU to measure, read and never built over (default: "
                        "build/DoublePendulum.fmu, built there if missing or older than the sources)")
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp, FmuRunner(fmu_to_run(args.fmu)) as runner, \
            FmuRunner(build_empty_fmu(Path(tmp))) as empty:
        bench_vs_scipy(runner, args.repeats)
        bench_do_step(runner, empty, args.repeats)
        bench_startup(runner, empty, args.repeats)
        bench_stiff(runner, args.repeats)
    sys.stdout.flush()


if __name__ == "__main__":
    main()
    import os

    os._exit(0)  # pythonfmu teardown, see docs/fmu.md
