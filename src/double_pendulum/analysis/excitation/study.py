"""The three studies of the ``base_excitation`` scenario: Kapitza, Acheson, resonance.

* **Kapitza** (:func:`kapitza_study`): the double pendulum made a single one by a tiny lower mass
  (``m2 = mass_ratio * m1``: the upper rod then moves as a point mass on a massless rod of length
  l1; the lower bob, a test mass, changes the equivalent length ``g / omega_slow**2`` of the slow
  mode by a relative ``O(m2/m1)``, reported). The upright threshold amplitude at a fixed frequency
  is bisected with :func:`~double_pendulum.analysis.excitation.drive.bisect_threshold` on the Floquet
  multipliers of the system as simulated (:func:`~double_pendulum.analysis.excitation.drive.floquet_outcome`:
  the monodromy matrix of one period through the FMU, the input held over each communication step)
  and compared with the exact bound of the held input, the exact Mathieu bound of the continuous
  sinusoid and ``a = sqrt(2 g l1) / omega``.
* **Acheson** (:func:`acheson_cases`, :func:`acheson_rows`): the default double pendulum started
  0.01 rad from upright on a grid of amplitude and frequency, each point judged upright-stable or
  falling, against the linear theory (:mod:`double_pendulum.analysis.excitation.theory`).
* **Resonance** (:func:`resonance_cases`, :func:`resonance_peaks`): pivot torque ``T0 sin(omega t)``
  with a viscous pivot bearing, steady-state amplitudes against the drive frequency, peaks against
  the small-angle normal modes.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy.optimize import brentq

from ...model.dynamics import linearised_normal_modes
from ...model.parameters import PendulumParameters
from .drive import (
    UPRIGHT_OUTPUTS,
    Bisection,
    FloquetCase,
    RunnerLike,
    TorqueCase,
    VibrationCase,
    bisect_threshold,
    floquet_outcome,
    peak_frequency,
    resonance_frequencies,
    run_vibration,
)
from .theory import (
    damped_peak_frequency,
    equivalent_lengths,
    held_lower_amplitude,
    held_upright_stable,
    kapitza_amplitude,
    mathieu_lower_amplitude,
    mathieu_upper_amplitude,
    stability_band,
    upright_stable,
    upright_start,
)


# ------------------------------------------------------------------------------ Kapitza
@dataclass(frozen=True)
class KapitzaSetup:
    """Kapitza bisection on the Floquet multipliers: frequency [rad/s], communication steps a period,
    bisection steps, bracket; the two example runs' start tilt [rad], length [s] and distance from the
    threshold (relative)."""

    omega: float = 50.0
    theta0: float = 0.01
    stop_time: float = 4.0
    steps_per_period: int = 24
    iterations: int = 16
    bracket: tuple[float, float] = (0.9, 1.15)  # times sqrt(2 g l1) / omega
    mass_ratio: float = 1e-4  # m2 / m1: the single-pendulum limit
    example_offset: float = 0.02  # the example runs at the threshold times (1 -+ example_offset)


@dataclass
class KapitzaResult:
    """The measured threshold (``bisection``) and the theory it is compared with (amplitudes in m)."""

    setup: KapitzaSetup
    params: PendulumParameters
    bisection: Bisection
    theory_point_mass: float  # sqrt(2 g l1) / omega
    effective_length: float  # g / omega_slow**2 [m] of the limit pendulum
    theory_effective: float  # sqrt(2 g L) / omega
    mathieu_exact: float  # exact linear bound for L, continuous sinusoid (a_0(q) = delta)
    held_exact: float  # exact linear bound for L, acceleration held over each step (as simulated)
    examples: dict[str, np.ndarray]  # tilt runs below and above the threshold: label -> result


def kapitza_parameters(setup: KapitzaSetup) -> PendulumParameters:
    """The single-pendulum limit: default rods and upper mass, ``m2 = mass_ratio * m1``."""
    base = PendulumParameters()
    return PendulumParameters(m1=base.m1, m2=setup.mass_ratio * base.m1, l1=base.l1, l2=base.l2, g=base.g)


def kapitza_case(a: float, setup: KapitzaSetup, params: PendulumParameters) -> VibrationCase:
    """Both rods tilted ``theta0`` from upright (on the slow motion): an example run, not judged."""
    start = {"m1": params.m1, "m2": params.m2, **upright_start((setup.theta0, setup.theta0), a, setup.omega, params)}
    return VibrationCase(a, setup.omega, start, setup.stop_time, setup.steps_per_period, setup.theta0)


def kapitza_study(where: RunnerLike, setup: KapitzaSetup) -> KapitzaResult:
    """Bisect the upright threshold amplitude [m] of the single-pendulum limit on the Floquet multipliers
    of the system as simulated (runs through ``where``); run the upper rod just below and above it."""
    params = kapitza_parameters(setup)
    length = equivalent_lengths(params)[0]
    a_point = kapitza_amplitude(setup.omega, params.l1, params.g)
    masses = {"m1": params.m1, "m2": params.m2}

    def probe(a: float) -> dict[str, Any]:
        return floquet_outcome(FloquetCase(a, setup.omega, masses, setup.steps_per_period), where)

    low, high = (f * a_point for f in setup.bracket)
    bisection = bisect_threshold(probe, low, high, setup.iterations)
    examples = {}
    for sign, word in ((-1.0, "below"), (1.0, "above")):
        a = bisection.threshold * (1.0 + sign * setup.example_offset)
        examples[f"a = {a * 1e3:.2f} mm ({100 * setup.example_offset:g} % {word} the threshold)"] = run_vibration(
            kapitza_case(a, setup, params), where)
    return KapitzaResult(setup, params, bisection, a_point, length,
                         kapitza_amplitude(setup.omega, length, params.g),
                         mathieu_lower_amplitude(setup.omega, length, params.g),
                         held_lower_amplitude(setup.omega, length, params.g, setup.steps_per_period), examples)


# ------------------------------------------------------------------------------ Acheson
@dataclass(frozen=True)
class AchesonSetup:
    """The stability map: grid [rad/s] x [m] judged by the Floquet multipliers as simulated, communication
    steps a period; the example runs' start tilt (upper rod) [rad], frequency, amplitudes and length [s]."""

    omegas: tuple[float, ...]
    amplitudes: tuple[float, ...]
    theta0: float = 0.01
    steps_per_period: int = 16
    example_omega: float = 200.0
    example_amplitudes: tuple[float, ...] = (0.008, 0.022, 0.036)
    example_stop_time: float = 3.0


def acheson_case(a: float, omega: float, setup: AchesonSetup) -> FloquetCase:
    """One map point: the default pendulum's upright Floquet multipliers at ``a`` [m], ``omega`` [rad/s]."""
    return FloquetCase(a, omega, {}, setup.steps_per_period)


def acheson_cases(setup: AchesonSetup) -> list[FloquetCase]:
    """One case per grid point, frequency-major (``omegas`` outer, ``amplitudes`` inner)."""
    return [acheson_case(a, w, setup) for w in setup.omegas for a in setup.amplitudes]


def acheson_examples(where: RunnerLike, setup: AchesonSetup) -> dict[float, np.ndarray]:
    """Runs with every output at ``example_omega``, upper rod ``theta0`` from upright and lower rod upright
    (on the slow motion), for each example amplitude [m]."""
    out = {}
    for a in setup.example_amplitudes:
        start = upright_start((setup.theta0, 0.0), a, setup.example_omega, PendulumParameters())
        case = VibrationCase(a, setup.example_omega, start, setup.example_stop_time, setup.steps_per_period,
                             setup.theta0, outputs=UPRIGHT_OUTPUTS)
        out[a] = run_vibration(case, where)
    return out


def example_label(a: float, setup: AchesonSetup) -> str:
    """``omega = .. rad/s, a = .. mm: stable`` (or ``unstable``) by the Floquet multipliers, as the map's points
    (computed in-process: the same component as the FMU)."""
    verdict = floquet_outcome(acheson_case(a, setup.example_omega, setup))
    outcome = "stable" if verdict["stable"] else "unstable"
    return (f"omega = {setup.example_omega:g} rad/s, a = {a * 1e3:g} mm: upright {outcome}"
            f" (largest Floquet multiplier {verdict['spectral_radius']:.4f} a period)")


def acheson_rows(outcomes: Sequence[dict[str, Any]], steps_per_period: int) -> list[dict[str, Any]]:
    """The map's table: each outcome with the linear theory's verdicts, for the acceleration held over each of
    ``steps_per_period`` steps as simulated (``theory_stable``) and for the continuous sinusoid
    (``theory_continuous_stable``)."""
    params = PendulumParameters()
    return [{**o, "theory_stable": held_upright_stable(o["amplitude_m"], o["omega_rad_per_s"], params,
                                                       steps_per_period),
             "theory_continuous_stable": upright_stable(o["amplitude_m"], o["omega_rad_per_s"], params)}
            for o in outcomes]


def theory_boundaries(omegas: np.ndarray, params: PendulumParameters | None = None) -> dict[str, np.ndarray]:
    """Boundaries [m] over ``omegas`` [rad/s]: averaged Kapitza ``sqrt(2 g L_slow)/omega``, exact lower, flutter."""
    params = params or PendulumParameters()
    l_slow, l_fast = equivalent_lengths(params)
    g = params.g
    return {"kapitza_m": np.array([kapitza_amplitude(w, l_slow, g) for w in omegas]),
            "lower_m": np.array([mathieu_lower_amplitude(w, l_slow, g) for w in omegas]),
            "upper_m": np.array([mathieu_upper_amplitude(w, l_fast, g) for w in omegas])}


def wedge_tip_frequency(params: PendulumParameters | None = None) -> float:
    """The lowest frequency [rad/s] with an upright-stable band: exact lower bound = flutter bound."""
    params = params or PendulumParameters()
    l_slow, l_fast = equivalent_lengths(params)
    g = params.g
    return brentq(lambda w: mathieu_lower_amplitude(w, l_slow, g) - mathieu_upper_amplitude(w, l_fast, g),
                  20.0, 2000.0)


def distance_to_bound(a: float, omega: float, params: PendulumParameters | None = None) -> float:
    """Relative distance of amplitude ``a`` [m] from the nearer theoretical bound at ``omega`` [rad/s]."""
    _, lower, upper = stability_band(omega, params or PendulumParameters())
    return min(abs(a / lower - 1.0), abs(a / upper - 1.0) if upper > 0 else math.inf)


def measured_bands(rows: Sequence[dict[str, Any]]) -> list[dict[str, Any]]:
    """Per frequency: the smallest and largest amplitude [m] of the grid that stayed upright (NaN: none)."""
    out = []
    for w in sorted({r["omega_rad_per_s"] for r in rows}):
        stable = [r["amplitude_m"] for r in rows if r["omega_rad_per_s"] == w and r["stable"]]
        out.append({"omega_rad_per_s": w, "lowest_stable_m": min(stable, default=math.nan),
                    "highest_stable_m": max(stable, default=math.nan)})
    return out


# ------------------------------------------------------------------------------ resonance
@dataclass(frozen=True)
class ResonanceSetup:
    """Pivot torque amplitude [N m], viscous pivot bearing [N m s/rad], settling and window [s], step [s]."""

    torque: float = 0.005
    b_v1: float = 0.05
    settle_time: float = 16.0
    window: float = 8.0
    step: float = 0.02
    n_broad: int = 8
    offsets: tuple[float, ...] = tuple(round(0.012 * k, 3) for k in range(-4, 5))


def resonance_start(setup: ResonanceSetup) -> dict[str, Any]:
    """Hanging at rest; bearings: viscous pivot friction ``b_v1`` only (rolling friction off)."""
    return {"phi1_0": 0.0, "phi2_0": 0.0, "omega1_0": 0.0, "omega2_0": 0.0, "bearing_friction": True,
            "c_R1": 0.0, "c_R2": 0.0, "b_v1": setup.b_v1}


def normal_modes() -> tuple[float, float]:
    """The default pendulum's small-angle normal-mode frequencies [rad/s] (slow, fast)."""
    return linearised_normal_modes(PendulumParameters())[0]


def resonance_cases(setup: ResonanceSetup) -> list[TorqueCase]:
    """One case per drive frequency (:func:`resonance_frequencies` around both normal modes)."""
    start = resonance_start(setup)
    return [TorqueCase(setup.torque, float(w), start, setup.settle_time, setup.window, setup.step)
            for w in resonance_frequencies(normal_modes(), setup.n_broad, setup.offsets)]


def resonance_peaks(rows: Sequence[dict[str, Any]], setup: ResonanceSetup) -> list[dict[str, Any]]:
    """Per mode and angle: the fitted peak frequency [rad/s] against the peak of the damped linear response
    (:func:`~double_pendulum.analysis.excitation.theory.damped_peak_frequency`, with the run's viscous pivot
    bearing), its relative error, and the undamped normal mode with the shift damping causes."""
    omegas = np.array([r["omega_rad_per_s"] for r in rows])
    params = PendulumParameters()
    out = []
    for mode_name, mode in zip(("slow", "fast"), normal_modes()):
        for i, angle in enumerate(("phi1", "phi2")):
            peak = peak_frequency(omegas, np.array([r[f"{angle}_amplitude_rad"] for r in rows]), mode)
            damped = damped_peak_frequency(mode, i, params, setup.b_v1)
            out.append({"mode": mode_name, "angle": angle, "normal_mode_rad_per_s": mode,
                        "damped_linear_peak_rad_per_s": damped, "peak_rad_per_s": peak,
                        "relative_error": peak / damped - 1.0, "damping_shift": damped / mode - 1.0})
    return out
