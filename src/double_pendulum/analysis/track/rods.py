r"""The rods' mass and the camera's tilt, read together from the energy.

The reconstructed energy (:func:`~.measurement.reconstruct`) is that of a pendulum whose rods the analysis is told.
Each link's uniform plate (:mod:`double_pendulum.model.links`) adds to the kinetic energy in proportion to its moment
of inertia and to the potential energy in proportion to its first moment; both are linear in the plates' masses, so
with both members at :math:`m` [kg]

.. math::

    E(\varphi_1, \varphi_2, \omega_1, \omega_2; m) = E_0 + m\,D,\qquad
    D = \tfrac12 J'_1\omega_1^2 + \tfrac12 J'_2\omega_2^2 + K'\omega_1\omega_2\cos\Delta
        + g S'_1 (1-\cos\varphi_1) + g S'_2 (1-\cos\varphi_2)

(:math:`J'_1 = \tfrac54 l_1^2 + L_1^2/12`, :math:`J'_2 = l_2^2/4 + L_2^2/12`, :math:`K' = l_1 l_2/2` [m^2],
:math:`S'_1 = \tfrac32 l_1`, :math:`S'_2 = l_2/2` [m]; :math:`E_0` the bobs'). The rods' share of the kinetic energy
is not their share of the potential energy, so with the wrong :math:`m` the energy is off by :math:`\Delta m\,D`,
which swings at twice the pendulum's frequency on top of the smooth decay (the tilt's term, :mod:`.tilt`, at its
own). :func:`fit_tilt_and_rods` finds both with the decay :math:`a e^{bt + ct^2}` (a [J], b [1/s], c [1/s^2]: the
curvature takes the decay's departure from an exponential, which would otherwise count as slow noise) on rates whose
derivative filter's truncation the model's local motion has taken off (:mod:`.model_rates`; it is computed with
the fitted tilt and rods and the fit repeated, :data:`ROUNDS`).

**Noise in the rates.** The rates come from noisy angles; the energy's noise :math:`\delta E_i = \nabla E\cdot\delta
s_i` grows with the inertia, so plain least squares prefers lighter rods (on 20 synthetic records of 50 g members:
-4 g at 0.5 mm of AR(1) noise with rho 0.5, -15 g at 1 mm). The fit removes that with *corrected* least squares,

.. math::

    \min_{\theta,m,a,b,c}\ \sum_i \left(E(\varphi_{1,i}-\theta, \varphi_{2,i}-\theta, \omega_{1,i}, \omega_{2,i}; m)
        - a e^{b t_i + c t_i^2}\right)^2 - \sum_i v_i(m),

:math:`v_i(m)` [J^2] the energy's variance in frame i from the AR(1) position noise
(:func:`~.energy_noise.energy_noise_variance`; quadratic in m; its dependence on the tilt, a turn of the gradients
by 0.04 rad, left out): the expected squared noise whose m-dependence biased the plain fit (on those records the
corrected fit is off by +0.0 +- 0.4 g and +0.6 +- 0.9 g).

**Errors.** The sandwich :math:`H^{-1} M H^{-1}` with the corrected objective's Hessian
:math:`H = J^TJ - \tfrac12\partial^2_m \sum_i v_i` and the covariance :math:`M` of the score :math:`J^T\delta E`
that the noise model gives (:func:`~.energy_noise.score_coefficients`, :func:`~.energy_noise.noise_covariance`: the
rate noise is a derivative and carries little at the pendulum's frequencies, where the rods' and the tilt's terms
lie), scaled by the residuals' variance over the one the noise model predicts (as errors are scaled by a reduced
chi-square: what the noise model misses counts as more of that noise). The AR(1) sandwich of the residuals
(:func:`~double_pendulum.analysis.ar1.ar1_sandwich`, :mod:`.tilt`'s error) stands beside it (``cov_ar1``); on 100
synthetic records it overstated the rods' error by 30 % (pulls of sd 0.77, against 1.00 with the noise model's).
:func:`record_tilt_and_rods` adds what the pivot's and the lengths' errors carry into both (circle fit and mean
distance under AR(1) noise). The plates' lengths, the bobs' masses and g are taken as known, and the noise model
(AR(1), isotropic, the upper bob's :math:`\rho` for both) as right: the correction for the noise scales with its
variance, and so does the rods' mass with it (:func:`~.energy_noise.position_noise`).

Masses in kg, angles in rad, lengths in m, energies in J, times in s.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from dataclasses import dataclass
from functools import lru_cache
from typing import Any

import numpy as np

from ...model.energy import total_energy
from ...model.parameters import SEED_RIGID_LINKS, PendulumParameters
from ..ar1 import ar1_coefficient, ar1_sandwich
from .energy_noise import PositionNoise, energy_noise_variance, noise_covariance, position_noise, score_coefficients
from .measurement import (
    Geometry,
    Reconstruction,
    Track,
    circle_covariance,
    fit_geometry,
    load_track,
    reconstruct,
    savgol_derivative_coefficients,
)
from .model_rates import model_rates
from .tilt import _shifted, fit_tilt

PARAMETER_NAMES = ("tilt", "member_kg", "a", "b", "c")
"""The fit's parameters: the tilt [rad], each rod member's mass [kg] and the decay's a [J], b [1/s], c [1/s^2]."""
ROUNDS = 2
"""Fits on model rates (:mod:`.model_rates`) computed with the previous fit's tilt and rods (on the seed's record the
second moves the member's mass by 0.3 g, a third by 0.001 g)."""
_UNIT_KG = 0.1
"""Member mass [kg] at which the energy's slope D = dE/dm is taken (E is linear in m)."""


def with_members(params: PendulumParameters, member_kg: float) -> PendulumParameters:
    """``params`` with both rod members at ``member_kg`` [kg] (plate lengths as they are)."""
    return dataclasses.replace(params, m_rod1=member_kg, m_rod2=member_kg)


@dataclass(frozen=True)
class TiltRodsFit:
    """The tilt [rad] and each rod member's mass [kg] fitted with the decay (module docstring): values ``x`` and
    covariance ``cov`` of :data:`PARAMETER_NAMES` (the noise model's sandwich scaled by ``scale``; where the noise
    model has no noise, a noise-free track, the AR(1) sandwich), the AR(1) sandwich's ``cov_ar1`` beside it; the
    member's mass that plain least squares on the filter's rates gives (the noise's and the truncation's biases left
    in); the residuals' rms [J] and lag-one correlation, the rms [J] the noise model predicts, the noise used and the
    number of frames."""

    x: np.ndarray
    cov: np.ndarray
    cov_ar1: np.ndarray
    scale: float
    member_kg_plain: float
    rms: float
    rho: float
    rms_noise: float
    noise: PositionNoise
    n: int

    @property
    def tilt(self) -> float:
        """The tilt [rad]."""
        return float(self.x[0])

    @property
    def member_kg(self) -> float:
        """Each rod member's mass [kg]."""
        return float(self.x[1])

    def as_dict(self) -> dict[str, Any]:
        """JSON-ready, the tilt in degrees and the masses in g."""
        err, err_ar1 = np.sqrt(np.diag(self.cov)), np.sqrt(np.diag(self.cov_ar1))
        return {"tilt_deg": math.degrees(self.tilt), "tilt_stderr_deg": math.degrees(err[0]),
                "rod_member_g": 1e3 * self.member_kg, "rod_member_stderr_g": 1e3 * err[1],
                "correlation_tilt_rods": float(self.cov[0, 1] / (err[0] * err[1])),
                "tilt_stderr_ar1_deg": math.degrees(err_ar1[0]), "rod_member_stderr_ar1_g": 1e3 * err_ar1[1],
                "scale": self.scale, "residual_rms_noise_model_J": self.rms_noise,
                "rod_member_plain_g": 1e3 * self.member_kg_plain, "a_J": float(self.x[2]),
                "b_per_s": float(self.x[3]), "c_per_s2": float(self.x[4]), "residual_rms_J": self.rms,
                "residual_lag_one": self.rho,
                "noise_sigma1_mm": 1e3 * self.noise.sigma1, "noise_sigma2_mm": 1e3 * self.noise.sigma2,
                "noise_rho": self.noise.rho, "n_frames": self.n}  # fmt: skip


def fit_tilt_and_rods(rec: Reconstruction, frames: np.ndarray | None = None, *, noise: PositionNoise | None = None,
                      corrected: bool = True, truncation: bool = True) -> TiltRodsFit:  # fmt: skip
    """The tilt [rad] (on top of ``rec.geometry.tilt``) and each rod member's mass [kg] from the energy of ``rec``
    (module docstring) over ``frames`` (default ``rec.free_motion``); ``rec``'s plate lengths are kept, its
    members' mass is the start. ``noise`` defaults to :func:`position_noise` of the track; ``corrected=False``:
    plain least squares (the noise's bias left in); ``truncation=False``: the filter's rates as they are."""
    idx = np.flatnonzero(rec.free_motion) if frames is None else np.arange(len(rec.t))[frames]
    t = rec.t[idx] - rec.t[idx[0]]
    p1, p2, sg1, sg2 = (a[idx] for a in (rec.phi1, rec.phi2, rec.omega1, rec.omega2))
    noise = position_noise(rec.track, rec.geometry) if noise is None else noise
    coeffs = savgol_derivative_coefficients(dt=rec.track.dt)
    bobs = with_members(rec.params, 0.0)

    def residuals(x: np.ndarray, w1: np.ndarray, w2: np.ndarray) -> np.ndarray:
        e0 = total_energy(p1 - x[0], p2 - x[0], w1, w2, bobs, np.cos)
        e1 = total_energy(p1 - x[0], p2 - x[0], w1, w2, with_members(bobs, _UNIT_KG), np.cos)
        return e0 + x[1] / _UNIT_KG * (e1 - e0) - x[2] * np.exp((x[3] + x[4] * t) * t)

    def jacobian(x: np.ndarray, w1: np.ndarray, w2: np.ndarray) -> np.ndarray:
        steps = np.diag([1e-6, 1e-6, 1e-6 * max(abs(x[2]), 1e-3), 1e-6, 1e-8])
        return np.column_stack([(residuals(x + h, w1, w2) - residuals(x - h, w1, w2)) / (2.0 * h[k])
                                for k, h in enumerate(steps)])  # fmt: skip

    def noise_terms(x: np.ndarray, w1: np.ndarray, w2: np.ndarray) -> tuple[float, float]:
        """B, C of sum_i v_i(m) = A + 2 B m + C m^2 (the gradients are linear in m), from three masses."""
        if not corrected:
            return 0.0, 0.0
        v0, v1, v2 = (
            float(np.sum(energy_noise_variance(p1 - x[0], p2 - x[0], w1, w2, with_members(bobs, m), noise, coeffs)))
            for m in (0.0, _UNIT_KG, 2.0 * _UNIT_KG)
        )
        c = (v2 - 2.0 * v1 + v0) / (2.0 * _UNIT_KG**2)
        return (v1 - v0 - c * _UNIT_KG**2) / (2.0 * _UNIT_KG), c

    def solve(x: np.ndarray, w1: np.ndarray, w2: np.ndarray, b: float, c: float) -> np.ndarray:
        """Gauss-Newton on the (corrected) objective: the residuals are nearly linear in the parameters."""
        for _ in range(30):
            jac = jacobian(x, w1, w2)
            hess, grad = jac.T @ jac, jac.T @ residuals(x, w1, w2)
            hess[1, 1] -= c
            grad[1] -= b + c * x[1]
            step = np.linalg.solve(hess, grad)
            x = x - step
            if abs(step[0]) < 1e-10 and abs(step[1]) < 1e-8:
                break
        return x

    start = fit_tilt(rec, idx)
    x = solve(np.array([start.tilt - rec.geometry.tilt, rec.params.m_rod1, start.a, start.b, 0.0]), sg1, sg2, 0.0, 0.0)
    plain = float(x[1])
    w1, w2 = sg1, sg2
    for _ in range(ROUNDS if truncation else 1):
        if truncation:
            w1, w2 = model_rates(p1 - x[0], p2 - x[0], sg1, sg2, with_members(bobs, max(x[1], 0.0)), rec.track.dt,
                                 coeffs)  # fmt: skip
        b, c = noise_terms(x, w1, w2)
        x = solve(x, w1, w2, b, c)
    r, jac = residuals(x, w1, w2), jacobian(x, w1, w2)
    hess = jac.T @ jac
    hess[1, 1] -= c
    rho = ar1_coefficient(r)
    params = with_members(bobs, max(x[1], 0.0))
    bread = np.linalg.inv(hess)
    score = score_coefficients(jac, idx, rec.phi1 - x[0], rec.phi2 - x[0], w1, w2, params, coeffs)
    meat = noise_covariance(score, noise)
    v_noise = float(np.mean(energy_noise_variance(p1 - x[0], p2 - x[0], w1, w2, params, noise, coeffs)))
    cov_ar1 = ar1_sandwich(jac, r, rho, hessian=hess)
    scale = float(r @ r) / (len(t) - len(x)) / v_noise if v_noise > 0.0 else math.nan
    x[0] += rec.geometry.tilt
    return TiltRodsFit(x, scale * bread @ meat @ bread if v_noise > 0.0 else cov_ar1, cov_ar1, scale, plain,
                       float(np.sqrt(np.mean(r * r))), rho, math.sqrt(v_noise), noise, len(t))  # fmt: skip


@dataclass(frozen=True, eq=False)
class RecordRods:
    """The tilt [rad] and each rod member's mass [kg] of a record (``values``) with their covariance ``cov``: the
    fit's (``fit``) plus what the pivot's and the lengths' errors carry into them (``sensitivity``: d(tilt, member)
    / d(pivot_x, pivot_y, l1, l2) [rad/m, kg/m]); ``geometry`` the pivot and lengths used."""

    values: np.ndarray
    cov: np.ndarray
    fit: TiltRodsFit
    sensitivity: Mapping[str, tuple[float, float]]
    geometry: Geometry

    @property
    def stderr(self) -> np.ndarray:
        """Standard errors of the tilt [rad] and the member's mass [kg]."""
        return np.sqrt(np.diag(self.cov))

    def as_dict(self) -> dict[str, Any]:
        """JSON-ready: the tilt in degrees, the member's mass in g, their errors and correlation, the fit's own."""
        err = self.stderr
        return {"tilt_deg": math.degrees(self.values[0]), "tilt_stderr_deg": math.degrees(err[0]),
                "rod_member_g": 1e3 * self.values[1], "rod_member_stderr_g": 1e3 * err[1],
                "correlation": float(self.cov[0, 1] / (err[0] * err[1])),
                "sensitivity_deg_and_g_per_mm": {k: [math.degrees(a) * 1e-3, b] for k, (a, b) in
                                                 self.sensitivity.items()},
                "energy_fit": self.fit.as_dict(),
                "how": "tilt and each rod member's mass fitted with E = a exp(b t + c t^2) to the energy on model "
                       "rates (the derivative filter's truncation taken off), by least squares corrected for the "
                       "AR(1) position noise's energy variance; errors from the noise model scaled by the residuals, "
                       "plus what the pivot's and the lengths' errors carry in; plates' lengths, bobs' masses and g "
                       "as given"}  # fmt: skip


def record_tilt_and_rods(track: Track, geometry: Geometry | None = None, *, m1: float | None = None,
                         m2: float | None = None, rods: Mapping[str, float] | None = None,
                         g: float | None = None) -> RecordRods:  # fmt: skip
    """The tilt and each rod member's mass of ``track`` (module docstring) with their covariance: pivot and lengths
    ``geometry`` (default :func:`~.measurement.fit_geometry`; its tilt ignored), the bobs, the plates (their
    masses the start) and g as :func:`~.measurement.reconstruct` takes them (default plates: the seed's)."""
    base = dataclasses.replace(fit_geometry(track) if geometry is None else geometry, tilt=0.0)
    pendulum = {"m1": m1, "m2": m2, "rods": SEED_RIGID_LINKS if rods is None else rods, "g": g}
    noise = position_noise(track, base)
    whole = fit_tilt_and_rods(reconstruct(track, base, **pendulum), noise=noise)
    v = track.valid
    c_other = np.zeros((4, 4))
    c_other[:3, :3] = circle_covariance(track.x1[v], track.y1[v], base.pivot, ar1=True)
    d = np.hypot(track.x2[v] - track.x1[v], track.y2[v] - track.y1[v])
    rho_d = ar1_coefficient(d)
    c_other[3, 3] = base.sigma_l2**2 * (1.0 + rho_d) / (1.0 - rho_d)
    sens = {}
    for k, name in enumerate(("pivot_x", "pivot_y", "l1", "l2")):
        step = math.sqrt(c_other[k, k])
        up, down = (fit_tilt_and_rods(reconstruct(track, _shifted(base, name, s * step), **pendulum), noise=noise).x
                    for s in (1, -1))  # fmt: skip
        sens[name] = (float(up[0] - down[0]) / (2.0 * step), float(up[1] - down[1]) / (2.0 * step))
    grad = np.array(list(sens.values())).T
    cov = whole.cov[:2, :2] + grad @ c_other @ grad.T
    return RecordRods(np.array([whole.tilt, whole.member_kg]), cov, whole, sens, base)


@lru_cache(maxsize=1)
def seed_record_rods() -> RecordRods:
    """The seed's record: its tilt and each rod member's mass with their covariance, the seed's bobs, its plates'
    lengths (:data:`~double_pendulum.model.parameters.SEED_RIGID_LINKS`; members started at 70 g)."""
    return record_tilt_and_rods(load_track(), rods=SEED_RIGID_LINKS)


NOISE_SCALES = (0.8, 1.2)
"""Factors on the position noise's standard deviations of :func:`noise_sensitivity`."""
NOISE_RHOS = (0.0, 0.3, 0.7)
"""Lag-one coefficients of :func:`noise_sensitivity`'s position noise (0: white)."""


def noise_sensitivity(track: Track, rods_fit: RecordRods, **pendulum: Any) -> dict[str, Any]:
    """What the noise model, taken as right by the stated error, carries into the member's mass: the fit of
    ``rods_fit`` again with the position noise's standard deviations times :data:`NOISE_SCALES` and with its rho at
    :data:`NOISE_RHOS` (masses in g), the range over them, and the member's mass fitted to each half of the record
    (the frames before and after the middle one) with its fit's own error [g]; ``pendulum``: the bobs, plates and g
    as :func:`~.measurement.reconstruct` takes them."""
    rec = reconstruct(track, rods_fit.geometry, **pendulum)
    noise = rods_fit.fit.noise
    cases = {f"sd x{s:g}": dataclasses.replace(noise, sigma1=s * noise.sigma1, sigma2=s * noise.sigma2)
             for s in NOISE_SCALES}  # fmt: skip
    cases.update({f"rho {r:g}": dataclasses.replace(noise, rho=r) for r in NOISE_RHOS})
    masses = {name: 1e3 * fit_tilt_and_rods(rec, noise=n).member_kg for name, n in cases.items()}
    frames = np.flatnonzero(rec.free_motion)
    halves = {}
    for name, part in zip(("first", "second"), np.array_split(frames, 2)):
        f = fit_tilt_and_rods(rec, part, noise=noise)
        halves[name] = {"rod_member_g": 1e3 * f.member_kg, "rod_member_stderr_g": 1e3 * math.sqrt(f.cov[1, 1])}
    return {"rod_member_g": masses, "range_g": [min(masses.values()), max(masses.values())],
            "noise": {"sigma1_mm": 1e3 * noise.sigma1, "sigma2_mm": 1e3 * noise.sigma2, "rho": noise.rho},
            "halves": halves}  # fmt: skip


def seed_rods_summary() -> dict[str, Any]:
    """The seed's record's tilt and rod members' mass (:func:`seed_record_rods`) with what the noise model carries
    into the mass (:func:`noise_sensitivity`), JSON-ready."""
    r = seed_record_rods()
    return {**r.as_dict(), "noise_sensitivity": noise_sensitivity(load_track(), r, rods=SEED_RIGID_LINKS)}
