"""Cost of coupling, measured side by side and printed as ratios (benchmarks).

Usage: ``python benchmarks/coupling_performance.py [--repeats 3]``

The split system (PendulumOnSuspension.ssp: DoublePendulum + Suspension) on libcosim at a 1 ms
macro step versus the monolithic FMU (``suspension`` on) on libcosim at the same step, both for
1 s (report only). The cost of one driven doStep against an empty FMU, with start-up excluded, is
``benchmarks/stepping_cost.py``; ``shaker`` and ``build_empty_fmu`` here serve it.

CPU times (``time.process_time``, median of the repeats). Compare the ratios, not the seconds:
the machine is shared and noisy.
"""

from __future__ import annotations

import argparse
import math
import statistics
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

from double_pendulum.fmu.build.fmi2 import build_fmu
from double_pendulum.fmu.build.ssp import write_ssp
from double_pendulum.fmu.running.hosts import simulate_ssp_with_libcosim, simulate_with_libcosim
from double_pendulum.model.inputs import INPUT_NAMES

EMPTY_SLAVE = '''
from pythonfmu import Fmi2Causality, Fmi2Slave, Real

INPUTS = {names!r}


class EmptyWithInputs(Fmi2Slave):
    """A pythonfmu FMU that does nothing but hold eight inputs: the cost floor of pythonfmu + fmpy."""

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        for name in INPUTS:
            setattr(self, name, 0.0)
            self.register_variable(Real(name, causality=Fmi2Causality.input))
        self.y = 0.0
        self.register_variable(Real("y", causality=Fmi2Causality.output))

    def do_step(self, current_time, step_size):
        return True
'''


def median_cpu(fn: Callable[[], object], repeats: int) -> float:
    """Median CPU time [s] of ``fn()`` over ``repeats`` calls."""
    times = []
    for _ in range(repeats):
        start = time.process_time()
        fn()
        times.append(time.process_time() - start)
    return statistics.median(times)


def build_empty_fmu(folder: Path) -> Path:
    from pythonfmu.builder import FmuBuilder

    script = folder / "EmptyWithInputs.py"
    script.write_text(EMPTY_SLAVE.format(names=list(INPUT_NAMES)))
    return Path(FmuBuilder.build_FMU(script, dest=folder / "EmptyWithInputs.fmu"))


def shaker(t: float) -> list[float]:
    """The eight inputs at t [s]: pivot_y = a sin(w t) with its velocity and acceleration, small torques."""
    a, w = 0.01, 30.0
    values = dict.fromkeys(INPUT_NAMES, 0.0)
    values.update(pivot_y=a * math.sin(w * t), pivot_vy=a * w * math.cos(w * t),
                  pivot_ay=-a * w * w * math.sin(w * t), tau1=1e-3 * math.sin(5 * t), tau2=-1e-3)
    return [values[n] for n in INPUT_NAMES]


def bench_split_on_libcosim(pendulum: Path, suspension: Path, folder: Path, repeats: int) -> float:
    ssp = write_ssp(folder / "PendulumOnSuspension.ssp", pendulum, suspension, {}, macro_step=1e-3)
    t_split = median_cpu(lambda: simulate_ssp_with_libcosim(ssp, stop_time=1.0, macro_step=1e-3), repeats)
    t_mono = median_cpu(lambda: simulate_with_libcosim(pendulum, {"suspension": True}, ["phi1"], stop_time=1.0,
                                                       step_size=1e-3), repeats)
    print(f"1 s on libcosim at a 1 ms macro step: split system {t_split:.2f} s, monolithic FMU {t_mono:.2f} s "
          f"-> ratio {t_split / t_mono:.2f}")
    return t_split / t_mono


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory(prefix="dp_bench_coupling_") as tmp:
        folder = Path(tmp)
        pendulum = build_fmu(folder / "DoublePendulum.fmu")
        suspension = build_fmu(folder / "Suspension.fmu", "Suspension")
        bench_split_on_libcosim(pendulum, suspension, folder, args.repeats)


if __name__ == "__main__":
    main()
