r"""The tracking noise of a record carried into its energy: the per-frame variance and the covariance of a fit's score.

The noise model is AR(1) (:mod:`~double_pendulum.analysis.ar1`): each coordinate of a bob carries its own series
:math:`z_i = \rho z_{i-1} + s\,\varepsilon_i`, of standard deviation :math:`\sigma_1` (upper bob) or
:math:`\sigma_2` (lower bob), one :math:`\rho`, the coordinates independent and the noise isotropic
(:func:`position_noise`). It moves the angles by the tangential components,

.. math::

    \delta\varphi_{1,j} = (\cos\varphi_{1,j}\,\delta x_{1,j} + \sin\varphi_{1,j}\,\delta y_{1,j}) / l_1,\qquad
    \delta\varphi_{2,j} = (\cos\varphi_{2,j}\,(\delta x_{2,j} - \delta x_{1,j})
                          + \sin\varphi_{2,j}\,(\delta y_{2,j} - \delta y_{1,j})) / l_2,

the rates through the derivative stencil, :math:`\delta\omega_i = \sum_k c_k\,\delta\varphi_{i+k}`, and the energy
of frame i by :math:`\delta E_i = g_{\varphi,i}\cdot\delta\varphi_i + g_{\omega,i}\cdot\delta\omega_i` with the
gradients of :func:`~.measurement.energy_gradient`.

- :func:`energy_noise_variance`: :math:`\mathrm{var}\,\delta E_i` [J^2] (the rates' variance :math:`c^T R c` times
  the angles', :math:`R_{jk} = \rho^{|j-k|}`, uncorrelated with them in the same frame);
- :func:`score_coefficients`: a fit's score :math:`J^T\delta E` (J its Jacobian, n by k) as
  :math:`\sum_j \sum_q a_{q,j}\,\delta q_j` over the four coordinates q: the coefficients :math:`a_{q,j}` collect
  frame j's angle noise in its own energy and, through the stencil, in its neighbours' rates;
- :func:`noise_covariance`: the covariance of any such sum, :math:`\sum_q \sigma_q^2\,a_q^T R\,a_q` (O(n) by
  :func:`~double_pendulum.analysis.ar1.ar1_correlation_times`). Of the score, it is the meat of a sandwich that
  knows the rate noise is a derivative: little of it lies at the pendulum's own frequencies, where an AR(1) model
  of the residuals (:func:`~double_pendulum.analysis.ar1.ar1_sandwich`) puts as much as its lag-one correlation
  says.

Lengths in m, angles in rad, rates in rad/s, energies in J.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ...model.parameters import PendulumParameters
from ..ar1 import ar1_coefficient, ar1_correlation_times
from .measurement import Geometry, Track, energy_gradient, robust_sigma, sigma_energy_propagated


@dataclass(frozen=True)
class PositionNoise:
    """AR(1) tracking noise of each coordinate: standard deviations [m] of the upper and the lower bob, one lag-one
    coefficient for both."""

    sigma1: float
    sigma2: float
    rho: float


def position_noise(track: Track, geometry: Geometry) -> PositionNoise:
    r"""The track's AR(1) position noise: rho the lag-one correlation of the upper bob's distance from the pivot (a
    rigid rod's length: noise alone), each bob's sigma from the rods' lengths' second differences as in
    :func:`~.measurement.estimate_position_noise`, whose white-noise variance :math:`6 s^2` is
    :math:`(6 - 8\rho + 2\rho^2) s^2` under AR(1) noise; the lower bob's from the distance between the bobs
    (variance :math:`\sigma_1^2 + \sigma_2^2`). The radial noise stands for the tangential (isotropic noise)."""
    p, v = geometry.pivot, track.valid
    r1 = np.where(v, np.hypot(track.x1 - p.xc, track.y1 - p.yc), np.nan)
    r2 = np.where(v, np.hypot(track.x2 - track.x1, track.y2 - track.y1), np.nan)
    rho = ar1_coefficient(r1[v])
    gain = 6.0 - 8.0 * rho + 2.0 * rho * rho

    def sigma(r: np.ndarray) -> float:
        d2 = r[2:] - 2.0 * r[1:-1] + r[:-2]
        return robust_sigma(d2[np.isfinite(d2)]) / math.sqrt(gain)

    s1, s12 = sigma(r1), sigma(r2)
    return PositionNoise(s1, math.sqrt(max(s12 * s12 - s1 * s1, 0.0)), rho)


def energy_noise_variance(p1: np.ndarray, p2: np.ndarray, w1: np.ndarray, w2: np.ndarray, params: PendulumParameters,
                          noise: PositionNoise, coeffs: np.ndarray) -> np.ndarray:  # fmt: skip
    r"""Variance [J^2] per frame of the energy at the states (p1, p2, w1, w2) from the AR(1) position ``noise``
    through the derivative stencil ``coeffs``: :func:`~.measurement.sigma_energy_propagated` (white noise: the
    rates' variance :math:`\sum c_k^2` times the angles') with the stencil scaled so that its :math:`\sum c_k^2` is
    :math:`c^T R c`."""
    scale = math.sqrt(float(coeffs @ ar1_correlation_times(coeffs, noise.rho)) / float(coeffs @ coeffs))
    return sigma_energy_propagated(p1, p2, w1, w2, params, noise.sigma1, noise.sigma2, scale * coeffs) ** 2


def score_coefficients(jac: np.ndarray, frames: np.ndarray, phi1: np.ndarray, phi2: np.ndarray, w1: np.ndarray,
                       w2: np.ndarray, params: PendulumParameters,
                       coeffs: np.ndarray) -> tuple[np.ndarray, ...]:  # fmt: skip
    r"""The coefficients :math:`a_q` (n_frames, k) of :math:`J^T\delta E` (module docstring) on each coordinate's
    noise, q = x1, y1, x2, y2 in the frame the angles are measured in: ``jac`` (n, k) the fit's Jacobian in the
    fitted ``frames`` (n indices into the track), ``phi1``, ``phi2`` the angles of every frame of the track [rad],
    ``w1``, ``w2`` the rates in the fitted frames [rad/s], ``params`` the pendulum, ``coeffs`` the stencil [1/s]."""
    gp1, gp2, gw1, gw2 = energy_gradient(phi1[frames], phi2[frames], w1, w2, params)
    n_all, k = len(phi1), jac.shape[1]

    def spread(g: np.ndarray) -> np.ndarray:
        out = np.zeros((n_all, k))
        out[frames] = jac * g[:, None]
        return out

    def through_stencil(y: np.ndarray) -> np.ndarray:
        """Coefficient of each frame's angle noise in sum_i y_i (sum_m c_m dphi_{i+m}): sum_m c_m y_{j-m}."""
        return np.column_stack([np.convolve(y[:, q], coeffs, mode="same") for q in range(k)])

    a1 = spread(gp1) + through_stencil(spread(gw1))
    a2 = spread(gp2) + through_stencil(spread(gw2))
    c1, s1 = (np.nan_to_num(f(phi1))[:, None] / params.l1 for f in (np.cos, np.sin))
    c2, s2 = (np.nan_to_num(f(phi2))[:, None] / params.l2 for f in (np.cos, np.sin))
    return a1 * c1 - a2 * c2, a1 * s1 - a2 * s2, a2 * c2, a2 * s2


def noise_covariance(coefficients: tuple[np.ndarray, ...], noise: PositionNoise) -> np.ndarray:
    r"""Covariance (k, k) of :math:`\sum_q a_q^T \delta q` for coefficients :math:`a_q` (n_frames, k) on the
    coordinates x1, y1, x2, y2 of every frame: :math:`\sum_q \sigma_q^2 a_q^T R a_q`."""
    sigmas = (noise.sigma1, noise.sigma1, noise.sigma2, noise.sigma2)
    return sum(s * s * (a.T @ ar1_correlation_times(a, noise.rho)) for a, s in zip(coefficients, sigmas))
