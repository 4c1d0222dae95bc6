r"""Linear response of a damped pivot suspension to the force of the swinging pendulum.

The pendulum pushes its pivot with the force F(t) (the FMU's ``F_pivot_x``, ``F_pivot_y`` minus
the static weight). If the suspension hardly changes the pendulum's motion, each axis is a driven
oscillator, :math:`x(\omega) = F(\omega)/(k - M\omega^2 + i c\omega)`, and its damper dissipates
the mean power

.. math::

    P = \int_0^\infty \frac{c\,\omega^2\,S_F(\omega)}{(k - M\omega^2)^2 + c^2\omega^2}\,d\omega

with :math:`S_F` the one-sided power spectral density of the force [N^2 s/rad] (so that
:math:`\int S_F\,d\omega = \langle F^2\rangle`). The pendulum's energy then decays at the extra rate
:math:`b - b_0 \approx -(P_x + P_y)/\bar E`. The mass M is what the pivot moves: above the
pendulum's own frequencies the hinged rods let the bobs stay behind sideways (M_x = M_s), while the
rods carry them up and down (M_y = M_s + m1 + m2). Limits:

- stiff (:math:`k \gg M\omega^2` and :math:`k \gg c\omega` over the spectrum): x = F/k,
  :math:`P = c\,\langle|\dot F|^2\rangle / k^2`, the rate goes as c/k^2;
- lightly damped resonance (:math:`\omega_n = \sqrt{k/M}` inside the spectrum, c small): the
  Lorentzian integrates to :math:`P = \pi S_F(\omega_n)/(2M)`, independent of c;
- overdamped (:math:`c\omega \gg k`): the damper clamps the pivot, :math:`P = \langle F^2\rangle/c`.

Units: k in N/m, c in N s/m, masses in kg, omega in rad/s, power in W, rates in 1/s.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ...fmu.running.runner import FmuRunner

FORCE_SAMPLE_RATE = 200.0
"""Sampling rate [1/s] of the fixed-pivot force for its spectrum (Nyquist 628 rad/s)."""
WELCH_SEGMENT = 1024
"""Welch segment length [samples] (5.1 s, resolution 1.2 rad/s)."""
SPECTRUM_POINTS = 20000
"""Points of the frequency grid the response integral is evaluated on (spacing 0.03 rad/s)."""
SPECTRUM_SETTINGS: dict[str, Any] = {"solver": "dop853", "rtol": 1e-8, "atol": 1e-10}


@dataclass(frozen=True, eq=False)
class ForceSpectrum:
    """Pivot force of the pendulum on a fixed pivot.

    ``s_x``, ``s_y``: one-sided PSDs [N^2 s/rad] on ``omega`` [rad/s]; ``mean_energy``: mean
    pendulum energy [J] over the run; ``fdot_squared``: mean |dF/dt|^2 [N^2/s^2]; ``m12``: m1 + m2
    [kg]; ``result``: the FMU run it came from.
    """

    omega: np.ndarray
    s_x: np.ndarray
    s_y: np.ndarray
    mean_energy: float
    fdot_squared: float
    m12: float
    result: np.ndarray = field(repr=False)

    def masses(self, m_s: float) -> tuple[float, float]:
        """Masses [kg] the pivot moves horizontally and vertically: M_s and M_s + m1 + m2."""
        return m_s, m_s + self.m12

    def response_power(self, k: float, c: float, m_s: float) -> float:
        """Mean power [W] dissipated in both dampers (the module's integral, one term per axis)."""
        w = self.omega
        total = 0.0
        for s, mass in zip((self.s_x, self.s_y), self.masses(m_s)):
            total += float(np.trapezoid(c * w * w * s / ((k - mass * w * w) ** 2 + (c * w) ** 2), w))
        return total

    def linear_response_rate(self, k: float, c: float, m_s: float) -> float:
        """Predicted suspension share of the decay rate [1/s]: -P / mean E."""
        return -self.response_power(k, c, m_s) / self.mean_energy

    def quasi_static_rate(self, k: float, c: float) -> float:
        """Stiff limit of the suspension share [1/s]: -c <|dF/dt|^2> / (k^2 mean E)."""
        return -c * self.fdot_squared / (k * k * self.mean_energy)

    def resonant_rate(self, k: float, m_s: float) -> float:
        """Lightly damped limit of the share [1/s]: -sum over axes pi S(omega_n) / (2 M) / mean E."""
        total = 0.0
        for s, mass in zip((self.s_x, self.s_y), self.masses(m_s)):
            total += math.pi * float(np.interp(math.sqrt(k / mass), self.omega, s)) / (2.0 * mass)
        return -total / self.mean_energy

    def force_variances(self) -> tuple[float, float]:
        """<F_x^2>, <F_y^2> [N^2] (integrals of the spectra)."""
        return float(np.trapezoid(self.s_x, self.omega)), float(np.trapezoid(self.s_y, self.omega))


def psd(signal: np.ndarray, omega: np.ndarray, sample_rate: float = FORCE_SAMPLE_RATE) -> np.ndarray:
    """Welch one-sided PSD [unit^2 s/rad] of ``signal`` (mean removed), interpolated onto ``omega`` [rad/s]."""
    from scipy.signal import welch  # noqa: PLC0415 - scipy.signal takes a second to import; only the spectrum needs it

    f, s = welch(signal - np.mean(signal), fs=sample_rate, nperseg=min(WELCH_SEGMENT, len(signal)))
    return np.interp(omega, 2.0 * math.pi * f, s / (2.0 * math.pi), right=0.0)


def pivot_force_spectrum(
    runner: FmuRunner,
    values: Mapping[str, Any],
    start_time: float,
    duration: float,
    m12: float,
    g: float,
) -> ForceSpectrum:
    """Run the pendulum on a fixed pivot (suspension off, the rest as ``values``) for ``duration`` [s]
    and return its force spectrum. F_y gets the static weight (m1 + m2) g added back."""
    result = runner.simulate(
        {**SPECTRUM_SETTINGS, **values, "suspension": False},
        start_time=start_time,
        stop_time=start_time + duration,
        output_interval=1.0 / FORCE_SAMPLE_RATE,
        outputs=("F_pivot_x", "F_pivot_y", "E_pendulum"),
    )
    fx = np.asarray(result["F_pivot_x"])
    fy = np.asarray(result["F_pivot_y"]) + m12 * g
    omega = np.linspace(0.01, math.pi * FORCE_SAMPLE_RATE, SPECTRUM_POINTS)
    dt = 1.0 / FORCE_SAMPLE_RATE
    fdot2 = float(np.mean(np.gradient(fx, dt) ** 2 + np.gradient(fy, dt) ** 2))
    return ForceSpectrum(
        omega, psd(fx, omega), psd(fy, omega), float(np.mean(result["E_pendulum"])), fdot2, m12, result
    )
