"""Print the figures of the implicit solvers: stiff scenes (rodas4) and long energy behaviour (gauss4).

Usage: ``python benchmarks/implicit_solvers.py [--repeats 3]``

Stiff scenes, each over 2 s from the regular 0.3 rad start at rtol 1e-6, atol 1e-9: this
package's ``rodas4`` and ``dop853`` against ``scipy.integrate.solve_ivp`` with ``LSODA`` and
``Radau`` on the same vector field (the list-based field wrapped for NumPy arrays). Printed: accepted
steps, rejected steps (not reported by SciPy), right-hand side evaluations (SciPy's ``nfev``
excludes the finite-difference Jacobian columns, counted in ``njev`` Jacobians of ``n`` calls each),
the CPU time (``time.process_time``, median of the repeats) and the largest deviation of the final
angles from ``dop853`` at rtol 1e-12.

Energy: the largest ``|E - E0|`` [J] at the steps in the first and in the last 100 s of 1000 s of
the frictionless pendulum, ``gauss4`` with a fixed 0.02 s step against ``dop853`` at rtol 1e-6.
"""

from __future__ import annotations

import argparse
import math
import statistics
import time
from collections.abc import Callable

from scipy.integrate import solve_ivp

from double_pendulum.model.parameters import BearingParameters, SuspensionParameters
from double_pendulum.model.vector_field import ModelConfig, build_model, energies
from double_pendulum.solvers import make_integrator

RTOL, ATOL, T_END = 1e-6, 1e-9, 2.0
Field = Callable[[float, list[float]], list[float]]


def _suspension(k: float, c: float, m_s: float = 0.05) -> ModelConfig:
    return ModelConfig(suspension=SuspensionParameters(suspension=True, M_s=m_s, k_x=k, k_y=k, c_x=c, c_y=c))


def _bearing(omega_reg: float) -> ModelConfig:
    return ModelConfig(bearing=BearingParameters(bearing_friction=True, omega_reg=omega_reg))


def stiff_cases() -> list[tuple[str, Field, list[float]]]:
    """(label, vector field, start) of the stiff scenes."""
    cases = []
    for label, config, angle in (
        ("suspension k=1e7 N/m, c=200 N s/m, M_s=0.05 kg", _suspension(1e7, 200.0), 0.3),
        ("suspension k=1e7 N/m, c=20 N s/m, M_s=0.05 kg", _suspension(1e7, 20.0), 0.3),
        ("suspension k=1e8 N/m, c=200 N s/m, M_s=0.05 kg", _suspension(1e8, 200.0), 0.3),
        ("bearing omega_reg=1e-6 rad/s, at rest (1e-5 rad)", _bearing(1e-6), 1e-5),
        ("bearing omega_reg=1e-6 rad/s, swinging (0.3 rad)", _bearing(1e-6), 0.3),
    ):
        model = build_model(config)
        cases.append((label, model.vector_field, model.initial_state(angle, angle, 0.0, 0.0)))
    omega = 1e4
    cases.append(
        (
            "y'' = -1e8 y - 1e4 y' (damping ratio 0.5), y0 = 1e-3",
            lambda t, y: [y[1], -omega * omega * y[0] - omega * y[1]],
            [1e-3, 0.0],
        )
    )
    return cases


def _timed(run: Callable[[], tuple[list[float], str]], repeats: int) -> tuple[list[float], str, float]:
    samples = []
    for _ in range(repeats):
        t0 = time.process_time()
        y, counts = run()
        samples.append(time.process_time() - t0)
    return y, counts, statistics.median(samples)


def _own(name: str, f: Field, y0: list[float]) -> Callable[[], tuple[list[float], str]]:
    def run() -> tuple[list[float], str]:
        it = make_integrator(name, f, 0.0, y0, rtol=RTOL, atol=ATOL, fixed_step=1.0)
        y = it.advance_to(T_END)
        return y, f"steps {it.n_steps:6d}  rejected {it.n_rejected:5d}  nfev {it.nfev:7d}"

    return run


def _scipy(method: str, f: Field, y0: list[float]) -> Callable[[], tuple[list[float], str]]:
    def run() -> tuple[list[float], str]:
        sol = solve_ivp(lambda t, y: f(t, y.tolist()), (0.0, T_END), y0, method=method, rtol=RTOL, atol=ATOL)
        counts = f"steps {len(sol.t) - 1:6d}  rejected     -  nfev {sol.nfev:7d}  njev {sol.njev}"
        return sol.y[:, -1].tolist(), counts

    return run


def print_stiff_figures(repeats: int) -> None:
    for label, f, y0 in stiff_cases():
        ref = make_integrator("dop853", f, 0.0, y0, rtol=1e-12, atol=1e-15, fixed_step=1.0).advance_to(T_END)
        print(f"\n{label}, {T_END:g} s, rtol {RTOL:g}, atol {ATOL:g}")
        runs = [(n, _own(n, f, y0)) for n in ("rodas4", "dop853")]
        runs += [(f"scipy {m}", _scipy(m, f, y0)) for m in ("LSODA", "Radau")]
        for name, run in runs:
            y, counts, cpu = _timed(run, repeats)
            deviation = max(abs(a - b) for a, b in zip(y[:2], ref[:2]))
            print(f"  {name:12s} {counts:55s} cpu {cpu * 1e3:8.1f} ms  |dy| {deviation:.1e}")


def energy_errors(name: str, window: float = 100.0, t_end: float = 1000.0, **settings) -> tuple[float, ...]:
    """Largest |E - E0| [J] in the first and last ``window`` s, steps and CPU time [s]."""
    config = ModelConfig()
    y0 = [0.3, 0.3, 0.0, 0.0]
    e0 = math.fsum(energies(config, y0))
    it = make_integrator(name, build_model(config).vector_field, 0.0, y0, **settings)
    first = last = 0.0
    t0 = time.process_time()
    while it.t < t_end:
        it.step()
        error = abs(math.fsum(energies(config, it.y)) - e0)
        if it.t <= window:
            first = max(first, error)
        elif it.t >= t_end - window:
            last = max(last, error)
    return first, last, it.n_steps, it.nfev, time.process_time() - t0


def print_energy_figures() -> None:
    print("\nEnergy error, frictionless, 0.3 rad start, 1000 s (E0 = 0.103 J)")
    for label, name, settings in (
        ("gauss4 h=0.02 s", "gauss4", {"rtol": 1.0, "atol": 1.0, "fixed_step": 0.02}),
        ("dop853 rtol 1e-6", "dop853", {"rtol": 1e-6, "atol": 1e-9, "fixed_step": 1.0}),
    ):
        first, last, steps, nfev, cpu = energy_errors(name, **settings)
        print(
            f"  {label:18s} first 100 s {first:.2e} J  last 100 s {last:.2e} J  "
            f"steps {steps}  nfev {nfev}  cpu {cpu:.1f} s"
        )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3, help="timing repeats (median)")
    args = parser.parse_args()
    print_stiff_figures(args.repeats)
    print_energy_figures()


if __name__ == "__main__":
    main()
