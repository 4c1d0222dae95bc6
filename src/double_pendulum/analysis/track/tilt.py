r"""The camera's tilt against gravity, read from the energy, and the record's one geometry with its covariance.

A camera turned counter-clockwise by :math:`\theta` against gravity films every position turned by
:math:`\theta` about the pivot (the convention of :data:`~.start_state.VIEW_ROTATION`), so both rod angles come
out :math:`\theta` too large. The kinetic energy does not see it; the potential energy does. With
:math:`V = -g \sum_k m_k y_k` (bobs and rods, y up) and the positions turned back,
:math:`y \to y\cos\theta - x\sin\theta`, the energy of the untilted track is, to first order,

.. math::

    E^{meas}_i = E_i - \theta\, g\, M\, x_{cm,i}

(M the moving mass, :math:`x_{cm}` its centre's horizontal offset from the pivot [m]): a term that swings with
the pendulum on top of the smooth decay. :func:`fit_tilt` finds :math:`\theta` [rad] with the decay, minimising

.. math::

    \sum_i \left(E(\varphi_{1,i} - \theta, \varphi_{2,i} - \theta, \omega_{1,i}, \omega_{2,i}) - a e^{b t_i}\right)^2

(exact in :math:`\theta`: the package's energy function on the turned angles; a [J], b [1/s]; equal weights,
the frames after the hand release). The decay's shape hardly matters: the tilt's term changes sign every swing,
the decay does not. Its standard error is the sandwich of the least-squares fit under AR(1) residuals of the
fit's own lag-one correlation (:func:`~double_pendulum.analysis.ar1.ar1_sandwich`), as the decay fit's
(:mod:`~double_pendulum.analysis.decay.noise`).

**One geometry** (:func:`record_geometry`): the tilt, the pivot (x, y) and l1 from the circle fit of the upper bob,
l2 from the bobs' distance (:func:`~.measurement.fit_geometry`), with one covariance. The circle fit and l2
give their block (:func:`~.measurement.circle_covariance`, ``sigma_l2``; both treat the frames as independent); the
tilt's row adds to its own variance what the other four carry into it,
:math:`\mathrm{var}\,\theta = \sigma^2_{\theta,stat} + g^T C g`, :math:`\mathrm{cov}(\theta, q) = g^T C`, with
:math:`g = \partial\theta/\partial q` by central differences over each one's standard error.

Angles in rad (the summaries in degrees where they say so), lengths in m, energies in J, times in s.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from dataclasses import dataclass
from functools import lru_cache
from typing import Any

import numpy as np
from scipy.optimize import least_squares

from ...model.energy import total_energy
from ...model.parameters import SEED_RIGID_LINKS
from ..ar1 import ar1_coefficient, ar1_sandwich
from .measurement import Geometry, Reconstruction, Track, circle_covariance, fit_geometry, load_track, reconstruct

GEOMETRY_NAMES: tuple[str, ...] = ("tilt", "pivot_x", "pivot_y", "l1", "l2")
"""The record geometry's parameters, in the covariance's order: the camera's tilt [rad], the pivot in the track's
coordinates [m], the rods' lengths [m]."""
GEOMETRY_UNITS = {"tilt": "rad", "pivot_x": "m", "pivot_y": "m", "l1": "m", "l2": "m"}
N_PARTS = 4
"""Consecutive parts of the record in which the tilt is fitted again (its stability over the record)."""


@dataclass(frozen=True)
class TiltFit:
    """The tilt [rad] fitted with the decay E = a exp(b t) (a [J], b [1/s]) to the energy of ``n`` frames: its
    standard error under AR(1) residuals and without correlation, the residuals' rms [J] and lag-one correlation
    with the tilt fitted and with the tilt held at the track's (refitted decay)."""

    tilt: float
    stderr: float
    stderr_independent: float
    a: float
    b: float
    rms: float
    rho: float
    rms_untilted: float
    rho_untilted: float
    n: int

    def as_dict(self) -> dict[str, Any]:
        return {"tilt_deg": math.degrees(self.tilt), "stderr_deg": math.degrees(self.stderr),
                "stderr_independent_deg": math.degrees(self.stderr_independent), "a_J": self.a, "b_per_s": self.b,
                "residual_rms_J": self.rms, "residual_lag_one": self.rho,
                "residual_rms_untilted_J": self.rms_untilted, "residual_lag_one_untilted": self.rho_untilted,
                "n_frames": self.n}  # fmt: skip


def fit_tilt(rec: Reconstruction, frames: np.ndarray | None = None) -> TiltFit:
    """The camera's tilt [rad] from the energy of ``rec`` (module docstring) over ``frames`` (a mask or indices;
    default ``rec.free_motion``), on top of the tilt ``rec`` already has (``rec.geometry.tilt``)."""
    idx = np.flatnonzero(rec.free_motion) if frames is None else np.arange(len(rec.t))[frames]
    t = rec.t[idx] - rec.t[idx[0]]
    p1, p2, w1, w2 = (a[idx] for a in (rec.phi1, rec.phi2, rec.omega1, rec.omega2))

    def energy(dtheta: float) -> np.ndarray:
        return total_energy(p1 - dtheta, p2 - dtheta, w1, w2, rec.params, np.cos)

    e0 = energy(0.0)
    pos = e0 > 0
    b0, ln_a = np.polyfit(t[pos], np.log(e0[pos]), 1)
    start = np.array([math.exp(ln_a), b0])
    held = least_squares(lambda x: e0 - x[0] * np.exp(x[1] * t), start, method="lm")
    free = least_squares(lambda x: energy(x[2]) - x[0] * np.exp(x[1] * t), [*held.x, 0.0], method="lm",
                         x_scale=[1.0, 0.01, 0.01])  # fmt: skip
    cov = ar1_sandwich(free.jac, free.fun, ar1_coefficient(free.fun))
    independent = float(free.fun @ free.fun) / (len(t) - 3) * np.linalg.inv(free.jac.T @ free.jac)
    return TiltFit(tilt=rec.geometry.tilt + float(free.x[2]), stderr=math.sqrt(cov[2, 2]),
                   stderr_independent=math.sqrt(independent[2, 2]), a=float(free.x[0]), b=float(free.x[1]),
                   rms=float(np.sqrt(np.mean(free.fun**2))), rho=ar1_coefficient(free.fun),
                   rms_untilted=float(np.sqrt(np.mean(held.fun**2))), rho_untilted=ar1_coefficient(held.fun),
                   n=len(t))  # fmt: skip


def _shifted(geometry: Geometry, name: str, step: float) -> Geometry:
    """``geometry`` with one of pivot_x, pivot_y, l1, l2 moved by ``step`` [m]."""
    p = geometry.pivot
    if name == "l2":
        return dataclasses.replace(geometry, l2=geometry.l2 + step)
    field = {"pivot_x": "xc", "pivot_y": "yc", "l1": "radius"}[name]
    return dataclasses.replace(geometry, pivot=p._replace(**{field: getattr(p, field) + step}))


@dataclass(frozen=True, eq=False)
class RecordGeometry:
    """The record's one geometry (module docstring): ``geometry`` (with the tilt, for
    :func:`~.measurement.reconstruct`), the values and covariance of :data:`GEOMETRY_NAMES`, the tilt's fit to the
    whole record and to :data:`N_PARTS` parts of it, and the tilt's sensitivity to the other four [rad/m]."""

    geometry: Geometry
    values: np.ndarray
    cov: np.ndarray
    fit: TiltFit
    parts: tuple[TiltFit, ...]
    sensitivity: Mapping[str, float]
    pendulum: Mapping[str, float]

    @property
    def untilted(self) -> Geometry:
        """The same geometry without the tilt: the track as the camera saw it (the named variant)."""
        return dataclasses.replace(self.geometry, tilt=0.0)

    @property
    def tilt(self) -> float:
        """The tilt [rad]."""
        return float(self.values[0])

    @property
    def tilt_stderr(self) -> float:
        """The tilt's standard error [rad] with what the pivot and the lengths carry into it."""
        return float(math.sqrt(self.cov[0, 0]))

    def as_dict(self) -> dict[str, Any]:
        """JSON-ready: values, errors, correlation, the tilt in degrees, its parts and the energy's scatter."""
        err = np.sqrt(np.diag(self.cov))
        parts = [math.degrees(f.tilt) for f in self.parts]
        return {
            "tilt_deg": math.degrees(self.tilt),
            "tilt_stderr_deg": math.degrees(self.tilt_stderr),
            "tilt_stderr_statistical_deg": math.degrees(self.fit.stderr),
            "values": dict(zip(GEOMETRY_NAMES, map(float, self.values))),
            "stderr": dict(zip(GEOMETRY_NAMES, map(float, err))),
            "units": GEOMETRY_UNITS,
            "correlation": (self.cov / np.outer(err, err)).tolist(),
            "tilt_sensitivity_rad_per_m": dict(self.sensitivity),
            "energy_fit": self.fit.as_dict(),
            "parts_tilt_deg": parts,
            "parts_tilt_stderr_deg": [math.degrees(f.stderr) for f in self.parts],
            "parts_range_deg": [min(parts), max(parts)],
            "pendulum": dict(self.pendulum),
            "how": "tilt from the energy's dependence on height (its residuals about E = a exp(b t) swing with "
                   "g M x_cm; AR(1) sandwich error) with what the pivot and lengths carry into it; pivot and l1 "
                   "from the circle fit of the upper bob, l2 from the bobs' distance (frames taken as independent)",
            "convention": "counter-clockwise against gravity, as measured_vs_sim's view_rotation; every angle of "
                          "the untilted track is this much too large",
        }


def record_geometry(track: Track, geometry: Geometry | None = None, *, m1: float | None = None,
                    m2: float | None = None, rods: Mapping[str, float] | None = None,
                    g: float | None = None) -> RecordGeometry:  # fmt: skip
    """The record's one geometry (module docstring) of ``track``: pivot and lengths ``geometry`` (default
    :func:`~.measurement.fit_geometry`), the tilt fitted to the energy of the pendulum given by the masses, rods and
    g (as :func:`~.measurement.reconstruct` takes them)."""
    base = dataclasses.replace(fit_geometry(track) if geometry is None else geometry, tilt=0.0)
    pendulum = {"m1": m1, "m2": m2, "rods": rods, "g": g}
    rec = reconstruct(track, base, **pendulum)
    whole = fit_tilt(rec)
    free = np.flatnonzero(rec.free_motion)
    parts = tuple(fit_tilt(rec, part) for part in np.array_split(free, N_PARTS))
    v = track.valid
    c_circle = circle_covariance(track.x1[v], track.y1[v], base.pivot)
    c_other = np.zeros((4, 4))
    c_other[:3, :3] = c_circle
    c_other[3, 3] = base.sigma_l2**2
    sens = {}
    for k, name in enumerate(GEOMETRY_NAMES[1:]):
        step = math.sqrt(c_other[k, k])
        up, down = (fit_tilt(reconstruct(track, _shifted(base, name, s * step), **pendulum)).tilt for s in (1, -1))
        sens[name] = (up - down) / (2.0 * step)
    grad = np.array(list(sens.values()))
    cov = np.zeros((5, 5))
    cov[1:, 1:] = c_other
    cov[0, 1:] = cov[1:, 0] = grad @ c_other
    cov[0, 0] = whole.stderr**2 + grad @ c_other @ grad
    values = np.array([whole.tilt, base.pivot.xc, base.pivot.yc, base.l1, base.l2])
    return RecordGeometry(dataclasses.replace(base, tilt=whole.tilt), values, cov, whole, parts, sens,
                          {"m1": rec.params.m1, "m2": rec.params.m2,
                           **{k: getattr(rec.params, k) for k in SEED_RIGID_LINKS}})  # fmt: skip


@lru_cache(maxsize=1)
def seed_record_geometry() -> RecordGeometry:
    """The seed's record geometry: the tilt fitted to the energy of the seed's pendulum with its acrylic rods
    (:data:`~double_pendulum.model.parameters.SEED_RIGID_LINKS`), the fuller of the two energies the analyses use
    (point masses give a tilt 0.03 deg smaller, a quarter of its error)."""
    return record_geometry(load_track(), rods=SEED_RIGID_LINKS)
