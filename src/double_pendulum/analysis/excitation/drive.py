r"""Driving the pendulum through the FMU's inputs: input signals, runs and what is measured on them.

* :func:`vertical_vibration`: the pivot at height :math:`y = a\sin(\omega t)` [m] with the
  consistent velocity :math:`a\omega\cos(\omega t)` [m/s] and acceleration
  :math:`-a\omega^2\sin(\omega t)` [m/s2] (the FMU holds them as a second-order hold over a
  communication step, the acceleration constant: docs/coupling.md);
* :func:`pivot_torque`: :math:`\tau_1 = T_0\sin(\omega t)` [N m] on the upper rod.

Every signal carries all eight inputs (the unused ones 0), sampled on the communication grid, so
fmpy sets exactly these values at each communication point. :func:`simulate_signal` runs one case
through the FMU with fmpy (an :class:`~double_pendulum.fmu.running.runner.FmuRunner`, or a path: one runner
per process, for :func:`~double_pendulum.analysis.sweep.parallel_map` workers) or, without an FMU,
in-process with the same component (:func:`double_pendulum.fmu.masters.simulate.simulate`, same numbers).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ...fmu.masters.simulate import simulate
from ...fmu.running.runner import FmuRunner
from ...model.inputs import INPUT_NAMES
from ..sweep import parallel_map, process_runner

RunnerLike = FmuRunner | str | None
"""Where a case runs: an FMU runner, the path of the FMU (one runner per process), or None (in-process)."""


def time_grid(stop_time: float, step: float) -> tuple[np.ndarray, float]:
    """``(t, stop)``: the communication grid ``n * step`` [s] and its end ``stop = N * step >= stop_time``.

    One extra row past ``stop`` keeps fmpy's interpolation inside the signal.
    """
    n = max(1, math.ceil(stop_time / step - 1e-9))
    return np.arange(n + 2) * step, n * step


def input_signal(t: np.ndarray, **columns: np.ndarray) -> np.ndarray:
    """fmpy's input array: ``time`` [s] then every FMU input (:data:`INPUT_NAMES`), 0 unless given."""
    unknown = set(columns) - set(INPUT_NAMES)
    if unknown:
        raise ValueError(f"not FMU inputs: {sorted(unknown)}")
    arrays = [t] + [np.asarray(columns.get(name, np.zeros_like(t)), dtype=float) for name in INPUT_NAMES]
    return np.rec.fromarrays(arrays, names=["time", *INPUT_NAMES]).view(np.ndarray)


def vertical_vibration(a: float, omega: float, t: np.ndarray) -> np.ndarray:
    r"""Pivot at :math:`y = a\sin\omega t` [m], :math:`v_y = a\omega\cos\omega t` [m/s],
    :math:`a_y = -a\omega^2\sin\omega t` [m/s2]; ``a`` [m], ``omega`` [rad/s], ``t`` [s]."""
    s, c = np.sin(omega * t), np.cos(omega * t)
    return input_signal(t, pivot_y=a * s, pivot_vy=a * omega * c, pivot_ay=-a * omega**2 * s)


def pivot_torque(amplitude: float, omega: float, t: np.ndarray) -> np.ndarray:
    r"""Torque :math:`\tau_1 = T_0\sin\omega t` [N m] on the upper rod at the fixed pivot."""
    return input_signal(t, tau1=amplitude * np.sin(omega * t))


def runner_for(path: str) -> FmuRunner:
    """This process's runner for the FMU at ``path`` (extracted once:
    :func:`~double_pendulum.analysis.sweep.process_runner`)."""
    return process_runner(f"path:{path}", lambda: path)[0]


def simulate_signal(
    where: RunnerLike,
    start: Mapping[str, Any],
    signal: np.ndarray,
    stop_time: float,
    step: float,
    outputs: Sequence[str],
) -> np.ndarray:
    """Run one case with the input ``signal``: through fmpy (``where`` a runner or FMU path) or in-process."""
    if where is None:
        return simulate(dict(start), stop_time=stop_time, output_interval=step, input=signal, outputs=outputs)
    runner = runner_for(where) if isinstance(where, str) else where
    return runner.simulate(dict(start), stop_time=stop_time, output_interval=step, input=signal, outputs=outputs)


# ------------------------------------------------------------------------------ upright stability
UPRIGHT_OUTPUTS = ("phi1", "phi2", "omega1", "omega2", "ys", "vys", "E_total", "W_input", "energy_residual")


@dataclass(frozen=True)
class VibrationCase:
    """The pendulum started near upright on a pivot vibrating at ``a`` [m], ``omega`` [rad/s]: an example run.

    ``start``: FMU start values (parameters, angles, angular velocities); ``stop_time`` [s];
    ``steps_per_period``: communication steps per vibration period; ``theta0``: the start tilt [rad]
    the figures scale by. Stability is not judged on such a run (a run that has not yet fallen over
    may still grow): :func:`floquet_outcome` decides it.
    """

    a: float
    omega: float
    start: Mapping[str, Any]
    stop_time: float
    steps_per_period: int
    theta0: float
    outputs: tuple[str, ...] = field(default=UPRIGHT_OUTPUTS)

    @property
    def step(self) -> float:
        """Communication step [s]: the vibration period over ``steps_per_period``."""
        return 2.0 * math.pi / (self.omega * self.steps_per_period)


def run_vibration(case: VibrationCase, where: RunnerLike) -> np.ndarray:
    """The result array of ``case`` (see :func:`simulate_signal` for ``where``)."""
    t, stop = time_grid(case.stop_time, case.step)
    return simulate_signal(where, case.start, vertical_vibration(case.a, case.omega, t), stop, case.step,
                           case.outputs)


# ------------------------------------------------------------------------------ Floquet multipliers as simulated
FLOQUET_PERTURBATION = 1e-4
"""Perturbation [rad, rad/s] of each state component from upright for the monodromy matrix: the
nonlinearity (cubic about upright) changes it by O(1e-8) relative, the integration at
:data:`FLOQUET_SETTINGS` by at most rtol |phi| / 1e-4 = 3e-7 (measured: 2e-10 on the unit circle)."""
FLOQUET_SETTINGS = {"solver": "dop853", "rtol": 1e-11, "atol": 1e-13}
"""Integration of the one-period runs of :func:`simulated_monodromy`."""
FLOQUET_TOLERANCE = 1e-6
"""Unstable: the largest |Floquet multiplier| exceeds 1 by more than this (a growth of 1e-4 % a period;
a stable frictionless upright pendulum has every multiplier on the unit circle, and the simulated
monodromy puts them there to about 2e-10)."""
STATE_OUTPUTS = ("phi1", "phi2", "omega1", "omega2")


@dataclass(frozen=True)
class FloquetCase:
    """The upright pendulum on a pivot vibrating at ``a`` [m], ``omega`` [rad/s], ``steps_per_period``
    communication steps a period; ``parameters``: FMU start values other than the state (masses...)."""

    a: float
    omega: float
    parameters: Mapping[str, Any]
    steps_per_period: int

    @property
    def period(self) -> float:
        """The vibration period [s]."""
        return 2.0 * math.pi / self.omega


def simulated_monodromy(case: FloquetCase, where: RunnerLike = None) -> np.ndarray:
    r"""The monodromy matrix (4x4) of the upright state as simulated, by finite differences.

    Five runs of one period through ``where`` (the FMU, or in-process), with the vibration's inputs
    held over each communication step as in every other run: from upright
    :math:`(\pi, \pi, 0, 0)` and from upright plus :data:`FLOQUET_PERTURBATION` in each state component
    j; column j is the difference of the end states over the perturbation. Its eigenvalues are the
    Floquet multipliers of the upright periodic orbit (upright is a fixed point of a vertical vibration).
    """
    step = case.period / case.steps_per_period
    t, stop = time_grid(case.period, step)
    signal = vertical_vibration(case.a, case.omega, t)
    upright = np.array([math.pi, math.pi, 0.0, 0.0])

    def end_state(x0: np.ndarray) -> np.ndarray:
        start = {**case.parameters, **FLOQUET_SETTINGS,
                 **dict(zip(("phi1_0", "phi2_0", "omega1_0", "omega2_0"), x0.tolist()))}
        result = simulate_signal(where, start, signal, stop, step, STATE_OUTPUTS)
        end = np.flatnonzero(np.isclose(result["time"], stop, rtol=0.0, atol=1e-9 * stop))[0]
        return np.array([result[n][end] for n in STATE_OUTPUTS])

    base = end_state(upright)
    columns = [(end_state(upright + FLOQUET_PERTURBATION * e) - base) / FLOQUET_PERTURBATION for e in np.eye(4)]
    return np.column_stack(columns)


def floquet_outcome(case: FloquetCase, where: RunnerLike = None) -> dict[str, Any]:
    """The verdict from the Floquet multipliers of :func:`simulated_monodromy`.

    ``spectral_radius``: the largest |multiplier| (the growth factor per period of the fastest-growing
    perturbation); ``floquet_exponent_per_s`` = ln(spectral radius) / period [1/s]; ``stable`` if the
    spectral radius is at most 1 + :data:`FLOQUET_TOLERANCE`.
    """
    rho = float(max(abs(np.linalg.eigvals(simulated_monodromy(case, where)))))
    return {"amplitude_m": case.a, "omega_rad_per_s": case.omega, "spectral_radius": rho,
            "floquet_exponent_per_s": math.log(rho) / case.period, "stable": bool(rho <= 1.0 + FLOQUET_TOLERANCE)}


@dataclass
class Bisection:
    """Result of :func:`bisect_threshold`: the threshold [m], the final bracket and every probe."""

    threshold: float
    unstable_at: float
    stable_at: float
    probes: list[dict[str, Any]]


def bisect_threshold(probe: Callable[[float], dict[str, Any]], low: float, high: float, iterations: int) -> Bisection:
    """Bisect on the amplitude [m] between ``low`` (must be unstable) and ``high`` (must be stable).

    ``probe(a) -> verdict`` with ``verdict["stable"]``. Raises ``ValueError`` if the bracket's ends are
    not unstable / stable. The threshold is the bracket's midpoint after ``iterations`` halvings
    (uncertainty +-(high - low) / 2**(iterations + 1)).
    """
    probes = []
    for a, want in ((low, False), (high, True)):
        verdict = probe(a)
        probes.append(verdict)
        if verdict["stable"] != want:
            raise ValueError(f"bad bracket: a = {a:.6g} m is {'stable' if verdict['stable'] else 'unstable'}")
    for _ in range(iterations):
        mid = 0.5 * (low + high)
        verdict = probe(mid)
        probes.append(verdict)
        if verdict["stable"]:
            high = mid
        else:
            low = mid
    return Bisection(0.5 * (low + high), low, high, probes)


# ------------------------------------------------------------------------------ forced response
TORQUE_OUTPUTS = ("phi1", "phi2", "omega1", "omega2", "E_total", "W_input", "W_bearing", "energy_residual")


@dataclass(frozen=True)
class TorqueCase:
    """Pivot torque ``torque`` [N m] at ``omega`` [rad/s], run ``settle_time + window`` [s] at ``step`` [s]."""

    torque: float
    omega: float
    start: Mapping[str, Any]
    settle_time: float
    window: float
    step: float


def run_torque(case: TorqueCase, where: RunnerLike, outputs: Sequence[str] = TORQUE_OUTPUTS) -> np.ndarray:
    """The result array of ``case`` (see :func:`simulate_signal` for ``where``)."""
    t, stop = time_grid(case.settle_time + case.window, case.step)
    return simulate_signal(where, case.start, pivot_torque(case.torque, case.omega, t), stop, case.step, outputs)


def drive_amplitude(t: np.ndarray, x: np.ndarray, omega: float) -> float:
    r"""Amplitude of ``x`` at the drive frequency: least squares :math:`x \approx c + A\cos\omega t + B\sin\omega t`.

    Returns :math:`\sqrt{A^2 + B^2}` (unit of ``x``); leftover free oscillations at other
    frequencies average out over the window.
    """
    basis = np.column_stack([np.ones_like(t), np.cos(omega * t), np.sin(omega * t)])
    coef, *_ = np.linalg.lstsq(basis, x, rcond=None)
    return float(math.hypot(coef[1], coef[2]))


def torque_outcome(case: TorqueCase, where: RunnerLike = None) -> dict[str, Any]:
    """Steady-state amplitudes [rad] of phi1, phi2 at the drive frequency over the last ``window`` [s].

    ``drift``: the largest relative change of an amplitude between the window's two halves
    (how far from steady the response still is).
    """
    result = run_torque(case, where, ("phi1", "phi2"))
    t = result["time"]
    row: dict[str, Any] = {"omega_rad_per_s": case.omega}
    drift = 0.0
    for name in ("phi1", "phi2"):
        windows = [(t >= case.settle_time), (t >= case.settle_time) & (t < case.settle_time + case.window / 2),
                   (t >= case.settle_time + case.window / 2)]
        amps = [drive_amplitude(t[w], result[name][w], case.omega) for w in windows]
        row[f"{name}_amplitude_rad"] = amps[0]
        drift = max(drift, abs(amps[2] - amps[1]) / max(amps[0], 1e-300))
    row["drift"] = drift
    return row


Case = TorqueCase | FloquetCase


def case_outcome(case: Case, where: RunnerLike = None) -> dict[str, Any]:
    """The outcome of either kind of case (:func:`floquet_outcome`, :func:`torque_outcome`)."""
    return floquet_outcome(case, where) if isinstance(case, FloquetCase) else torque_outcome(case, where)


def case_cost(case: Case) -> float:
    """Communication steps of a case (its cost, for ordering parallel work)."""
    if isinstance(case, FloquetCase):
        return 5.0 * case.steps_per_period + 50.0  # five one-period runs, each with its start-up
    return (case.settle_time + case.window) / case.step


def run_cases(cases: Sequence[Case], fmu_path: str | None, *,
              max_workers: int | None = None, progress: bool | None = None) -> list[dict[str, Any]]:
    """Outcomes of all ``cases`` (in their order), in parallel worker processes (:func:`parallel_map`).

    Each worker runs the FMU at ``fmu_path`` through fmpy (extracted once per worker), or the
    component in-process if ``fmu_path`` is None. The costliest cases start first.
    """
    order = sorted(range(len(cases)), key=lambda i: -case_cost(cases[i]))
    results, _ = parallel_map(case_outcome, [cases[i] for i in order], shared=fmu_path, max_workers=max_workers,
                              progress=progress, label="base_excitation")
    out: list[dict[str, Any]] = [{}] * len(cases)
    for i, r in zip(order, results):
        out[i] = r
    return out


def peak_frequency(omegas: np.ndarray, amplitudes: np.ndarray, near: float, rel_window: float = 0.15) -> float:
    """The peak [rad/s] of a sampled resonance curve near ``near``: a parabola through log amplitude.

    Takes the largest sample within ``near * (1 +- rel_window)`` and fits a parabola in
    ``log(amplitude)`` through it and its two neighbours (sorted by frequency); if the largest
    sample is at the window's edge (the peak not bracketed), that sample's frequency.
    """
    order = np.argsort(omegas)
    w, amp = np.asarray(omegas)[order], np.asarray(amplitudes)[order]
    inside = np.flatnonzero(np.abs(w / near - 1.0) <= rel_window)
    if inside.size == 0:
        raise ValueError(f"no drive frequency within {rel_window:.0%} of {near:g} rad/s")
    k = inside[np.argmax(amp[inside])]
    if inside.size < 3 or k in (inside[0], inside[-1]):
        return float(w[k])
    c2, c1, _ = np.polyfit(w[k - 1:k + 2], np.log(amp[k - 1:k + 2]), 2)
    return float(-c1 / (2.0 * c2)) if c2 < 0 else float(w[k])


def resonance_frequencies(modes: Sequence[float], n_broad: int, offsets: Sequence[float],
                          span: tuple[float, float] = (0.5, 1.6)) -> np.ndarray:
    """Drive frequencies [rad/s]: ``n_broad`` log-spaced from ``span[0]*min(modes)`` to ``span[1]*max(modes)``,
    plus ``mode * (1 + offset)`` around each mode; sorted, duplicates removed."""
    broad = np.geomspace(span[0] * min(modes), span[1] * max(modes), n_broad)
    dense = [m * (1.0 + o) for m in modes for o in offsets]
    return np.unique(np.round(np.concatenate([broad, dense]), 10))
