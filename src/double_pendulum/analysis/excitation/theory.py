r"""Linear theory of the upright double pendulum on a vertically vibrated pivot (Kapitza, Acheson).

Pivot height :math:`y_p = a \sin(\omega t)` [m], so the pivot acceleration is
:math:`\ddot y_p = -a\omega^2 \sin(\omega t)`. Linearised about the upright position
:math:`\varphi_i = \pi + \theta_i`, the pendulum obeys

.. math::

    M_0 \ddot\theta = (g + \ddot y_p(t))\, D\, \theta
    \quad\Longleftrightarrow\quad \ddot\theta = (g + \ddot y_p)\, A\, \theta,\qquad A = M_0^{-1} D,

with the same mass matrix :math:`M_0` and gravity matrix :math:`gD` as the hanging normal modes
(:func:`double_pendulum.model.dynamics.linearised_normal_modes`: :math:`M_0\ddot q = -gDq`). The
eigenvalues of :math:`A` are therefore :math:`\lambda_i = \omega_i^2/g = 1/L_i`, with
:math:`L_i = g/\omega_i^2` [m] the length of the simple pendulum that swings like mode *i*
(:func:`equivalent_lengths`). Because one scalar factor multiplies :math:`A`, the modal coordinates
decouple exactly: each mode is an inverted simple pendulum of length :math:`L_i` on the same
vibrating pivot (Acheson 1993, "A pendulum theorem", Proc. R. Soc. A 443, 239-245; Acheson and
Mullin 1993, Nature 366, 215). With :math:`\tau = \omega t/2` each modal amplitude obeys Mathieu's
equation

.. math::

    \eta'' + (\delta - 2q\cos 2\tau)\,\eta = 0,\qquad \delta = -\frac{4g}{L_i\omega^2},\quad
    q = \frac{2a}{L_i}

(the phase of the forcing does not matter for stability). It is stable in the first stability
region :math:`a_0(q) < \delta < b_1(q)` (Mathieu characteristic values, :mod:`scipy.special`;
the next region starts at :math:`\delta = a_1(q) > 0` for every :math:`q \le 3`). The upright double pendulum is
stable when both modes are.

* Lower bound (Kapitza): :math:`a_0(q) = -q^2/2 + 7q^4/128 + \dots`, so to leading order
  :math:`a^2\omega^2 > 2 g L_i`, binding for the longest length :math:`L_1 = g/\omega_{slow}^2`
  (Acheson: :math:`a\omega > \sqrt{2}\, g/\omega_{slow}`); a single point mass on a massless rod
  has :math:`L = l`: :math:`a^2\omega^2 > 2gl`.
* Upper bound (parametric flutter of the fast mode): :math:`b_1(q) = 0` at :math:`q = 0.908`, so
  at high frequency :math:`a < 0.454\, L_2` with :math:`L_2 = g/\omega_{fast}^2`.

Assumptions: small angles (linearised), frictionless joints, vertical pivot motion only, the
pivot acceleration exactly sinusoidal. The FMU holds the acceleration constant over a communication
step (N steps a period; a zero-order hold scales the fundamental by sinc(pi/N), 0.6 % for N = 16), so
the system as simulated has its own exact Floquet bounds: over step k the modal equation is
:math:`\ddot\eta = c_k\,\eta` with the constant :math:`c_k = (g + \ddot y_p(t_k))/L_i`, solved in closed
form (:func:`upright_step_matrix`); the product over one period is the monodromy matrix
(:func:`held_mode_monodromy`), and a mode is stable while its trace lies in (-2, 2)
(:func:`held_lower_amplitude`, :func:`held_upright_stable`).

Damped forced response (:func:`torque_response`, :func:`damped_peak_frequency`): a pivot torque
:math:`\tau_1 = T_0 e^{i\omega t}` on the hanging pendulum with viscous bearings gives
:math:`(K - \omega^2 M_0 + i\omega C)\,X = (T_0, 0)` with the hanging :math:`M_0`, :math:`K = gD` and
:math:`C = [[b_{v1} + b_{v2}, -b_{v2}], [-b_{v2}, b_{v2}]]` (the torques :math:`b_{v1}\omega_1` and
:math:`b_{v2}(\omega_2 - \omega_1)` of :mod:`double_pendulum.model.forces`); its amplitude peaks lie below
and beside the undamped normal modes, by O(zeta^2) and differently for the two rods.
"""

from __future__ import annotations

import cmath
import math
from collections.abc import Sequence

import numpy as np
from scipy.optimize import brentq, minimize_scalar
from scipy.special import mathieu_a, mathieu_b

from ...model.dynamics import linearised_normal_modes
from ...model.links import link_coefficients
from ...model.parameters import PendulumParameters

Q_FLUTTER = 0.9081  # q where b_1(q) = 0: the flutter bound a < Q_FLUTTER L / 2 at high frequency


def equivalent_lengths(params: PendulumParameters) -> tuple[float, float]:
    """``(L_slow, L_fast)`` [m]: ``L_i = g / omega_i**2``, the simple pendulum swinging like mode i."""
    (w_slow, w_fast), _ = linearised_normal_modes(params)
    return params.g / w_slow**2, params.g / w_fast**2


def kapitza_amplitude(omega: float, length: float, g: float) -> float:
    """Kapitza's threshold amplitude [m]: ``a = sqrt(2 g L) / omega`` (averaged, leading order in a/L).

    ``omega`` [rad/s] is the vibration's angular frequency, ``length`` [m], ``g`` [m/s2].
    """
    return math.sqrt(2.0 * g * length) / omega


def mathieu_parameters(a: float, omega: float, length: float, g: float) -> tuple[float, float]:
    """Mathieu's ``(delta, q) = (-4 g / (L omega**2), 2 a / L)`` (dimensionless) of one upright mode."""
    return -4.0 * g / (length * omega**2), 2.0 * a / length


def mode_upright_stable(a: float, omega: float, length: float, g: float) -> bool:
    """True if the inverted mode of length ``length`` [m] is stable: ``a_0(q) < delta < b_1(q)``."""
    delta, q = mathieu_parameters(a, omega, length, g)
    if q == 0.0:
        return False
    return bool(mathieu_a(0, q) < delta < mathieu_b(1, q))


def mathieu_lower_amplitude(omega: float, length: float, g: float) -> float:
    """The exact (linear, Floquet) lower stability bound [m]: the ``a`` with ``a_0(2a/L) = delta``."""
    delta = -4.0 * g / (length * omega**2)
    q = brentq(lambda q: mathieu_a(0, q) - delta, 1e-12, 10.0, xtol=1e-14)
    return 0.5 * q * length


def mathieu_upper_amplitude(omega: float, length: float, g: float) -> float:
    """The flutter (upper) stability bound [m]: the ``a`` with ``b_1(2a/L) = delta`` (-> 0.454 L)."""
    delta = -4.0 * g / (length * omega**2)
    if mathieu_b(1, 1e-12) <= delta:
        return 0.0
    q = brentq(lambda q: mathieu_b(1, q) - delta, 1e-12, 10.0, xtol=1e-14)
    return 0.5 * q * length


def upright_stable(a: float, omega: float, params: PendulumParameters) -> bool:
    """True if the linearised upright double pendulum is stable (both modes, :func:`mode_upright_stable`)."""
    return all(mode_upright_stable(a, omega, length, params.g) for length in equivalent_lengths(params))


def stability_band(omega: float, params: PendulumParameters) -> tuple[float, float, float]:
    """``(a_kapitza, a_lower, a_upper)`` [m] at ``omega`` [rad/s] for the double pendulum.

    ``a_kapitza = sqrt(2 g L_slow) / omega`` (averaged), ``a_lower`` the exact lower bound of the
    slow mode, ``a_upper`` the flutter bound of the fast mode; stable for ``a_lower < a < a_upper``.
    """
    l_slow, l_fast = equivalent_lengths(params)
    g = params.g
    return (kapitza_amplitude(omega, l_slow, g), mathieu_lower_amplitude(omega, l_slow, g),
            mathieu_upper_amplitude(omega, l_fast, g))


def averaging_matrix(params: PendulumParameters) -> np.ndarray:
    r""":math:`A = M_0^{-1} D` [1/m] from the normal modes: :math:`A = V\,\mathrm{diag}(\omega_i^2/g)\,V^{-1}`.

    ``V`` has the mode shapes ``(1, phi2/phi1)`` as columns (hanging: :math:`\ddot q = -gAq`).
    """
    omegas, shapes = linearised_normal_modes(params)
    v = np.array(shapes, dtype=float).T
    return v @ np.diag([w * w / params.g for w in omegas]) @ np.linalg.inv(v)


def upright_start(theta0: Sequence[float], a: float, omega: float, params: PendulumParameters) -> dict[str, float]:
    r"""Start values: rods tilted by ``theta0`` [rad] from upright, on the slow motion of the averaged theory.

    The pivot ``a sin(omega t)`` starts at its centre moving at ``a omega``; the fast micro-motion
    :math:`\xi = a\sin(\omega t)\,A\bar\theta` then has the velocity :math:`a\omega A\theta_0` at
    t = 0. Starting the rods with that angular velocity [rad/s] leaves the slow (averaged) motion
    at rest, so a stable case stays within about ``|theta0| (1 + a/L_fast)`` instead of swinging
    out by ``a omega theta0 / (L Omega)`` when the averaged frequency Omega is small.
    """
    th = np.asarray(theta0, dtype=float)
    w0 = a * omega * (averaging_matrix(params) @ th)
    return {"phi1_0": math.pi + float(th[0]), "phi2_0": math.pi + float(th[1]),
            "omega1_0": float(w0[0]), "omega2_0": float(w0[1])}


# ------------------------------------------------------------------------------ the held input (as simulated)
def upright_step_matrix(c: float, h: float) -> np.ndarray:
    r"""Exact transfer matrix of :math:`\ddot\eta = c\,\eta` over ``h`` [s], ``c`` [1/s2] constant.

    :math:`(\eta, \dot\eta)(h) = [[\cosh sh, \sinh(sh)/s], [s \sinh sh, \cosh sh]]\,(\eta, \dot\eta)(0)`
    with :math:`s = \sqrt{c}` (imaginary for c < 0, where it turns into cos and sin).
    """
    s = cmath.sqrt(c)
    if abs(s * h) < 1e-12:
        return np.array([[1.0, h], [c * h, 1.0]])
    ch, sh = cmath.cosh(s * h), cmath.sinh(s * h)
    return np.array([[ch, sh / s], [s * sh, ch]]).real


def held_mode_monodromy(a: float, omega: float, length: float, g: float, steps_per_period: int) -> np.ndarray:
    r"""Monodromy matrix (2x2) of one upright mode of length ``length`` [m] under the held pivot acceleration.

    The pivot acceleration :math:`\ddot y_p = -a\omega^2\sin(\omega t_k)` [m/s2] is held over step k of
    ``steps_per_period`` (as the FMU holds its inputs): the product of :func:`upright_step_matrix` with
    :math:`c_k = (g + \ddot y_p(t_k))/L` over one period :math:`2\pi/\omega` [s].
    """
    h = 2.0 * math.pi / (omega * steps_per_period)
    monodromy = np.eye(2)
    for k in range(steps_per_period):
        c = (g - a * omega**2 * math.sin(omega * k * h)) / length
        monodromy = upright_step_matrix(c, h) @ monodromy
    return monodromy


def held_floquet_exponent(a: float, omega: float, length: float, g: float, steps_per_period: int) -> float:
    """Floquet exponent [1/s] of one mode under the held input: ln(largest |multiplier|) / period (0: stable)."""
    multipliers = np.linalg.eigvals(held_mode_monodromy(a, omega, length, g, steps_per_period))
    return math.log(max(abs(multipliers))) * omega / (2.0 * math.pi)


def held_lower_amplitude(omega: float, length: float, g: float, steps_per_period: int) -> float:
    """The exact lower (Kapitza) bound [m] of one mode under the held input: trace of the monodromy = 2.

    Below it the mode has a real Floquet multiplier > 1 (trace > 2); bracketed between 0.5 and 1.5 times
    the averaged :func:`kapitza_amplitude` (unstable there and stable, for ``a/L`` below the flutter bound).
    """
    a_kapitza = kapitza_amplitude(omega, length, g)
    return brentq(lambda a: np.trace(held_mode_monodromy(a, omega, length, g, steps_per_period)) - 2.0,
                  0.5 * a_kapitza, 1.5 * a_kapitza, xtol=1e-13)


def held_upright_stable(a: float, omega: float, params: PendulumParameters, steps_per_period: int) -> bool:
    """True if both upright modes are stable under the held input: |trace of each monodromy| < 2."""
    return all(abs(np.trace(held_mode_monodromy(a, omega, length, params.g, steps_per_period))) < 2.0
               for length in equivalent_lengths(params))


# ------------------------------------------------------------------------------ damped forced response
def torque_response(omega: float, params: PendulumParameters, b_v1: float, b_v2: float = 0.0) -> np.ndarray:
    r"""Complex amplitudes ``(X1, X2)`` [rad/(N m)] of phi1, phi2 per unit pivot torque at ``omega`` [rad/s].

    Solves :math:`(K - \omega^2 M_0 + i\omega C) X = (1, 0)` (module docstring) with the viscous pivot and
    elbow bearings ``b_v1``, ``b_v2`` [N m s/rad].
    """
    co = link_coefficients(params)
    m0 = np.array([[co.j1, co.k], [co.k, co.j2]])
    stiffness = np.diag([co.gs1, co.gs2])
    damping = np.array([[b_v1 + b_v2, -b_v2], [-b_v2, b_v2]])
    return np.linalg.solve(stiffness - omega**2 * m0 + 1j * omega * damping, np.array([1.0, 0.0]))


def damped_peak_frequency(near: float, angle: int, params: PendulumParameters, b_v1: float, b_v2: float = 0.0,
                          rel_window: float = 0.15) -> float:
    """Frequency [rad/s] of the largest ``|X_angle|`` (0: phi1, 1: phi2) within ``near * (1 +- rel_window)``."""
    found = minimize_scalar(lambda w: -abs(torque_response(w, params, b_v1, b_v2)[angle]),
                            bounds=(near * (1.0 - rel_window), near * (1.0 + rel_window)), method="bounded",
                            options={"xatol": 1e-9 * near})
    return float(found.x)
