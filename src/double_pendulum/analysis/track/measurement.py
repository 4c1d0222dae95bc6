r"""The seed pendulum's measured motion: camera track, pivot and rod lengths, angles and energy.

The seed report (section 4.2) filmed the pendulum at 29.97 fps and tracked both bobs with the
"Tracker" software (Table 1, ``data/seed_table1.csv``). This module turns that table into the
quantities the friction analysis needs:

1. :func:`load_track` reads the table, rebuilds the time from the frame number
   (``t = frame / 29.97 s``; the printed time is cut to 3, later 2 decimals) and flags bad frames
   (:func:`flag_bad_frames`).
2. :func:`fit_geometry` finds the pivot and l1 by a least-squares circle fit of the upper bob
   (:func:`fit_circle`) and l2 as the mean distance between the bobs.
3. :func:`reconstruct` shifts the track to the pivot, computes the angles

   .. math::

       \varphi_1 = \operatorname{atan2}(x_1, -y_1),\qquad
       \varphi_2 = \operatorname{atan2}(x_2 - x_1, -(y_2 - y_1))

   (unwrapped; the positions first turned back by the camera's tilt against gravity,
   :attr:`Geometry.tilt`, which :mod:`.tilt` fits), their rates by central differences (the seed's
   method, 4.2.1) and by a Savitzky-Golay derivative filter (:data:`SG_WINDOW`, :data:`SG_POLYORDER`),
   the energy per frame with :func:`double_pendulum.model.energy.total_energy` and two uncertainties of that energy: the
   seed's eq. 25 and the propagated position noise (:func:`sigma_energy_propagated`).

Lengths in m, times in s, angles in rad, energies in J.

Bad frames are flagged in the boolean mask ``Track.valid`` and kept in the arrays; every later
step skips them (the circle fit, l2, the noise estimate) or marks the frames that depend on them
(``Reconstruction.energy_valid`` is false wherever a derivative stencil touches a flagged frame).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import NamedTuple

import numpy as np
from scipy.optimize import least_squares

from ...data import data_path
from ...model.energy import kinetic_energy, potential_energy, total_energy
from ...model.kinematics import velocities
from ...model.parameters import PendulumParameters
from ..ar1 import ar1_coefficient, ar1_sandwich

FPS = 29.97
"""Frame rate of the seed's video [1/s]."""
FRAME_INTERVAL = 1.0 / FPS
"""Time between frames [s]."""
DEFAULT_TRACK_PATH = data_path("seed_table1.csv")
"""The repository's copy of the seed's Table 1 (``src/double_pendulum`` -> ``../../data``)."""
TRACK_COLUMNS = ("frame", "t_s", "x1_m", "y1_m", "x2_m", "y2_m")

SEED_VELOCITY_ERROR = 0.1
"""The seed's assumed error of each bob's speed [m/s] (section 4.2.2, eq. 25)."""
SEED_TOTAL_MASS_KG = 0.7
"""The seed's total moving mass including the acrylic rods (section 4.2.3) [kg]."""
SG_WINDOW = 7
"""Window (frames) of the Savitzky-Golay derivative filter; see :func:`savgol_derivative`."""
SG_POLYORDER = 5
"""Polynomial order of the Savitzky-Golay derivative filter."""
MAD_TO_SIGMA = 1.4826
"""Median absolute deviation to standard deviation for normally distributed data."""


@dataclass(frozen=True, eq=False)
class Track:
    """The measured track: one entry per video frame (positions as printed, origin not the pivot).

    ``valid`` is false for frames flagged by :func:`flag_bad_frames`; they are kept, not dropped.
    ``dt`` [s] is the time between frames (the seed's camera: :data:`FRAME_INTERVAL`; a user's record:
    :mod:`.user_track`); every derivative and every simulation on the frame grid uses it.
    """

    frame: np.ndarray
    t: np.ndarray
    x1: np.ndarray
    y1: np.ndarray
    x2: np.ndarray
    y2: np.ndarray
    valid: np.ndarray
    dt: float = FRAME_INTERVAL

    def __len__(self) -> int:
        return len(self.frame)


class CircleFit(NamedTuple):
    """Least-squares circle: centre (xc, yc) and radius [m], their standard errors, rms residual [m]."""

    xc: float
    yc: float
    radius: float
    sigma_xc: float
    sigma_yc: float
    sigma_radius: float
    rms_residual: float


@dataclass(frozen=True)
class Geometry:
    """Pivot and rod lengths measured from a track.

    ``pivot`` is the circle fit of the upper bob (centre = pivot in the track's coordinates,
    radius = l1); ``l2`` is the mean distance between the bobs with ``sigma_l2`` = std / sqrt(n).
    ``tilt`` [rad]: the camera's rotation against gravity (counter-clockwise, as
    :data:`~.start_state.VIEW_ROTATION`): :func:`reconstruct` turns the positions back by it about the pivot,
    so every angle is measured from gravity's vertical (:mod:`.tilt` fits it; 0: the untilted track).
    """

    pivot: CircleFit
    l2: float
    sigma_l2: float
    l2_std: float
    n_frames: int
    tilt: float = 0.0

    @property
    def l1(self) -> float:
        """Length of the upper rod [m]."""
        return self.pivot.radius

    @property
    def sigma_l1(self) -> float:
        """Standard error of l1 [m]."""
        return self.pivot.sigma_radius


@dataclass(frozen=True, eq=False)
class Reconstruction:
    """Angles, angular velocities and energies per frame, in pivot coordinates.

    ``omega1_cd``/``omega2_cd`` and ``energy_cd`` use central differences, ``omega1``/``omega2``
    and ``energy`` the Savitzky-Golay derivative; both are NaN where their stencil leaves the track.
    ``sigma_energy_seed`` is the seed's eq. 25 on the central-difference speeds, ``sigma_energy``
    the propagated position noise for ``energy``; ``momentum`` = sqrt(m1^2 v1^2 + m2^2 v2^2)
    [kg m/s] with the Savitzky-Golay speeds (eq. 25 without its dv). ``energy_valid`` marks the
    frames where both energies are defined and no stencil touches a flagged frame;
    ``release_frame`` is the end of the hand release (:func:`find_release_frame`), at the earliest the first
    ``energy_valid`` frame (where the rates are defined).
    """

    track: Track
    geometry: Geometry
    params: PendulumParameters
    sigma_pos1: float
    sigma_pos2: float
    x1: np.ndarray
    y1: np.ndarray
    x2: np.ndarray
    y2: np.ndarray
    phi1: np.ndarray
    phi2: np.ndarray
    omega1_cd: np.ndarray
    omega2_cd: np.ndarray
    omega1: np.ndarray
    omega2: np.ndarray
    energy_cd: np.ndarray
    energy: np.ndarray
    e_kin: np.ndarray
    e_pot: np.ndarray
    sigma_energy_seed: np.ndarray
    sigma_energy: np.ndarray
    momentum: np.ndarray
    energy_valid: np.ndarray
    release_frame: int

    @property
    def t(self) -> np.ndarray:
        """Time of each frame [s]."""
        return self.track.t

    @property
    def free_motion(self) -> np.ndarray:
        """Frames to fit: ``energy_valid`` and at or after ``release_frame``."""
        return self.energy_valid & (np.arange(len(self.t)) >= self.release_frame)


# --- loading and flagging ------------------------------------------------------------------------


def load_track(path: str | Path | None = None, *, z_max: float = 5.0, min_deviation: float = 0.005) -> Track:
    """Read the seed's Table 1 (CSV with columns :data:`TRACK_COLUMNS`) into a :class:`Track`.

    The time is rebuilt as ``frame / FPS`` [s] (the printed ``t_s`` is truncated and ignored).
    ``z_max`` and ``min_deviation`` [m] are passed to :func:`flag_bad_frames`.
    Raises FileNotFoundError if the file is missing, ValueError if its columns or frame numbers
    are not as expected.
    """
    path = DEFAULT_TRACK_PATH if path is None else Path(path)
    if not path.is_file():
        raise FileNotFoundError(
            f"track table not found: {path} (expected the seed's Table 1 as CSV with columns "
            f"{', '.join(TRACK_COLUMNS)}; see data/README.md)"
        )
    with open(path) as fh:
        header = tuple(h.strip() for h in fh.readline().strip().split(","))
    if header != TRACK_COLUMNS:
        raise ValueError(f"{path}: columns {header}, expected {TRACK_COLUMNS}")
    data = np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)
    frame = data[:, 0].astype(int)
    if not np.array_equal(frame, np.arange(frame[0], frame[0] + len(frame))):
        raise ValueError(f"{path}: frame numbers are not consecutive")
    x1, y1, x2, y2 = (data[:, k].copy() for k in range(2, 6))
    valid = flag_bad_frames(x1, y1, x2, y2, z_max=z_max, min_deviation=min_deviation)
    return Track(frame=frame, t=frame / FPS, x1=x1, y1=y1, x2=x2, y2=y2, valid=valid)


def robust_sigma(values: np.ndarray) -> float:
    """Standard deviation estimated as 1.4826 * median absolute deviation (NaN ignored)."""
    values = np.asarray(values, dtype=float)
    return float(MAD_TO_SIGMA * np.nanmedian(np.abs(values - np.nanmedian(values))))


def _within(r: np.ndarray, reference: np.ndarray, z_max: float, min_deviation: float) -> np.ndarray:
    """True where ``|r - median| <= max(z_max * robust sigma, min_deviation)`` (stats over ``reference``)."""
    median = float(np.median(r[reference]))
    threshold = max(z_max * robust_sigma(r[reference]), min_deviation)
    with np.errstate(invalid="ignore"):
        return np.abs(r - median) <= threshold


def flag_bad_frames(
    x1: np.ndarray,
    y1: np.ndarray,
    x2: np.ndarray,
    y2: np.ndarray,
    *,
    z_max: float = 5.0,
    min_deviation: float = 0.005,
    max_iterations: int = 5,
) -> np.ndarray:
    """Return the mask of good frames (True = keep) of a two-bob track [m].

    The rods are rigid, so a tracker jump shows as a rod length far from its median. A frame is
    flagged if a coordinate is not finite, or if the distance of the upper bob from the pivot
    (algebraic circle fit, :func:`kasa_circle`) or the distance between the bobs deviates from its
    median by more than ``max(z_max * sigma, min_deviation)``, where sigma = 1.4826 MAD is a
    robust scatter that a few bad frames cannot inflate; ``min_deviation`` (default 5 mm, five
    times the printed resolution) keeps the rule from flagging rounding noise. The pivot and the
    statistics are recomputed from the kept frames until the mask no longer changes.
    """
    finite = np.isfinite(x1) & np.isfinite(y1) & np.isfinite(x2) & np.isfinite(y2)
    valid = finite.copy()
    r2 = np.hypot(x2 - x1, y2 - y1)
    for _ in range(max_iterations):
        xc, yc, _ = kasa_circle(x1[valid], y1[valid])
        r1 = np.hypot(x1 - xc, y1 - yc)
        new = finite & _within(r1, valid, z_max, min_deviation) & _within(r2, valid, z_max, min_deviation)
        if np.array_equal(new, valid):
            break
        valid = new
    return valid


# --- circle fit and rod lengths -----------------------------------------------------------------


def kasa_circle(x: np.ndarray, y: np.ndarray) -> tuple[float, float, float]:
    """Algebraic (Kasa) circle fit: solve ``x^2 + y^2 = 2 xc x + 2 yc y + c`` by linear least squares.

    Returns ``(xc, yc, R)`` with ``R = sqrt(c + xc^2 + yc^2)``. Slightly biased for noisy arcs,
    used as the start of :func:`fit_circle`.
    """
    a = np.c_[2.0 * x, 2.0 * y, np.ones_like(x)]
    (xc, yc, c), *_ = np.linalg.lstsq(a, x * x + y * y, rcond=None)
    return float(xc), float(yc), math.sqrt(c + xc * xc + yc * yc)


def _circle_residuals(p: np.ndarray, x: np.ndarray, y: np.ndarray) -> np.ndarray:
    return np.hypot(x - p[0], y - p[1]) - p[2]


def _circle_jacobian(p: np.ndarray, x: np.ndarray, y: np.ndarray) -> np.ndarray:
    d = np.hypot(x - p[0], y - p[1])
    return np.c_[-(x - p[0]) / d, -(y - p[1]) / d, -np.ones_like(x)]


def fit_circle(x: np.ndarray, y: np.ndarray) -> CircleFit:
    r"""Geometric least-squares circle through points (x, y) [m].

    Minimises :math:`\sum_i (d_i - R)^2` with :math:`d_i = \sqrt{(x_i-x_c)^2 + (y_i-y_c)^2}`
    (Levenberg-Marquardt, analytic Jacobian, started from :func:`kasa_circle`). Standard errors
    from the Jacobian J at the optimum: :math:`C = s^2 (J^T J)^{-1}` with the residual variance
    :math:`s^2 = \sum_i r_i^2 / (n - 3)`; valid for independent residuals of equal variance.
    """
    x = np.asarray(x, dtype=float)
    y = np.asarray(y, dtype=float)
    if len(x) < 4:
        raise ValueError(f"fit_circle needs at least 4 points, got {len(x)}")
    res = least_squares(_circle_residuals, kasa_circle(x, y), jac=_circle_jacobian, args=(x, y), method="lm")
    xc, yc, radius = res.x
    resid = res.fun
    s2 = float(resid @ resid) / (len(x) - 3)
    cov = s2 * np.linalg.inv(res.jac.T @ res.jac)
    sxc, syc, sr = np.sqrt(np.diag(cov))
    rms = math.sqrt(float(np.mean(resid * resid)))
    return CircleFit(float(xc), float(yc), abs(float(radius)), float(sxc), float(syc), float(sr), rms)


def circle_covariance(x: np.ndarray, y: np.ndarray, fit: CircleFit, *, ar1: bool = False) -> np.ndarray:
    """Covariance of (xc, yc, radius) [m^2] of :func:`fit_circle`'s result ``fit`` through (x, y) [m]:
    s^2 (J^T J)^-1 at the optimum (independent residuals of equal variance, as its standard errors); ``ar1``: the
    sandwich under AR(1) residuals of their own lag-one correlation, the points in the order of the frames
    (:func:`~double_pendulum.analysis.ar1.ar1_sandwich`)."""
    p = np.array([fit.xc, fit.yc, fit.radius])
    jac = _circle_jacobian(p, np.asarray(x, dtype=float), np.asarray(y, dtype=float))
    resid = _circle_residuals(p, np.asarray(x, dtype=float), np.asarray(y, dtype=float))
    if ar1:
        return ar1_sandwich(jac, resid, ar1_coefficient(resid))
    return float(resid @ resid) / (len(resid) - 3) * np.linalg.inv(jac.T @ jac)


def fit_geometry(track: Track) -> Geometry:
    """Pivot and l1 from the circle fit of the upper bob, l2 = mean |r2 - r1| [m] (valid frames only).

    ``sigma_l2`` = std(|r2 - r1|) / sqrt(n) treats the frames as independent; the distance varies
    slowly over neighbouring frames, so this understates the uncertainty of l2 (see the report).
    """
    v = track.valid
    pivot = fit_circle(track.x1[v], track.y1[v])
    d = np.hypot(track.x2[v] - track.x1[v], track.y2[v] - track.y1[v])
    std = float(np.std(d, ddof=1))
    return Geometry(pivot, float(np.mean(d)), std / math.sqrt(len(d)), std, int(v.sum()))


def estimate_position_noise(track: Track, geometry: Geometry) -> tuple[float, float]:
    r"""Frame-to-frame position noise (sigma1, sigma2) [m] of the upper and lower bob.

    Rigid rods keep r1 = |bob1 - pivot| and r2 = |bob2 - bob1| constant, so their fast
    fluctuations are measurement noise. For white noise of standard deviation s on r, the second
    difference :math:`r_{i+1} - 2 r_i + r_{i-1}` has variance 6 s^2 (slow real changes of r are
    suppressed by the differencing), hence :math:`s = \sigma_{MAD}(\Delta^2 r) / \sqrt 6`.
    r1 carries the upper bob's noise: sigma1 = s(r1); r2 carries both: sigma2 = sqrt(s(r2)^2 - sigma1^2).
    Assumes isotropic noise (the radial scatter stands for the tangential one too).
    """
    p = geometry.pivot
    r1 = np.where(track.valid, np.hypot(track.x1 - p.xc, track.y1 - p.yc), np.nan)
    r2 = np.where(track.valid, np.hypot(track.x2 - track.x1, track.y2 - track.y1), np.nan)

    def second_difference_sigma(r: np.ndarray) -> float:
        d2 = r[2:] - 2.0 * r[1:-1] + r[:-2]
        return robust_sigma(d2[np.isfinite(d2)]) / math.sqrt(6.0)

    s1 = second_difference_sigma(r1)
    s12 = second_difference_sigma(r2)
    return s1, math.sqrt(max(s12 * s12 - s1 * s1, 0.0))


# --- angles and derivatives ---------------------------------------------------------------------


def angles(x1: np.ndarray, y1: np.ndarray, x2: np.ndarray, y2: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Unwrapped rod angles from the downward vertical [rad] (pivot at the origin, y up).

    ``phi1 = atan2(x1, -y1)``, ``phi2 = atan2(x2 - x1, -(y2 - y1))``: the inverse of
    :func:`double_pendulum.model.kinematics.positions`.
    """
    phi1 = np.unwrap(np.arctan2(x1, -y1))
    phi2 = np.unwrap(np.arctan2(x2 - x1, -(y2 - y1)))
    return phi1, phi2


def central_difference_coefficients(dt: float = FRAME_INTERVAL) -> np.ndarray:
    """Stencil ``[-1, 0, 1] / (2 dt)`` [1/s] of the seed's central difference (4.2.1)."""
    return np.array([-1.0, 0.0, 1.0]) / (2.0 * dt)


def savgol_derivative_coefficients(
    window: int = SG_WINDOW, polyorder: int = SG_POLYORDER, dt: float = FRAME_INTERVAL
) -> np.ndarray:
    """First-derivative Savitzky-Golay stencil [1/s], ordered from frame i - window//2 to i + window//2."""
    from scipy.signal import savgol_coeffs  # noqa: PLC0415 - scipy.signal takes a second to import

    return savgol_coeffs(window, polyorder, deriv=1, delta=dt, use="dot")


def apply_stencil(signal: np.ndarray, coeffs: np.ndarray) -> np.ndarray:
    """Return ``sum_k coeffs[k] * signal[i - h + k]`` (h = len(coeffs) // 2); NaN within h of either end."""
    h = len(coeffs) // 2
    out = np.full(len(signal), np.nan)
    if len(signal) > 2 * h:
        out[h : len(signal) - h] = np.correlate(signal, coeffs, mode="valid")
    return out


def derivative_gain(coeffs: np.ndarray, omega: np.ndarray, dt: float = FRAME_INTERVAL) -> np.ndarray:
    r"""Gain of an antisymmetric derivative stencil on a harmonic signal of angular frequency omega [rad/s].

    For :math:`x = e^{i\omega t}` the stencil returns :math:`i\omega\,G(\omega)\,x` with
    :math:`G(\omega) = \sum_k c_k \sin(k\omega\Delta t) / \omega` (k = -h..h); G = 1 is exact.
    G < 1 is the flattening of speed peaks the seed describes in 4.2.2; the kinetic energy of
    that frequency comes out too small by the factor G^2.
    """
    k = np.arange(len(coeffs)) - len(coeffs) // 2
    omega = np.atleast_1d(np.asarray(omega, dtype=float))
    return np.array([np.sum(coeffs * np.sin(k * w * dt)) / w for w in omega])


def savgol_derivative(
    signal: np.ndarray, window: int = SG_WINDOW, polyorder: int = SG_POLYORDER, dt: float = FRAME_INTERVAL
) -> np.ndarray:
    r"""Time derivative by a Savitzky-Golay filter [unit/s]; NaN within window//2 frames of the ends.

    The window and order minimise the error of the energy per frame, which at 29.97 fps comes
    mostly from the truncation error of the derivative while the lower bob whips round, not from
    the position noise. Evidence (rms energy error, mJ, central differences / SG 5,3 / 7,3 / 7,5 /
    9,5 / 9,7 / 11,7): on a simulated frictionless swing of the seed pendulum (start 0.6, -1.0 rad)
    sampled at the camera rate with 0.5 mm noise 24 / 13 / 32 / 12 / 23 / 11 / 19; as the rms
    scatter of the measured energy (Table 1) about its exponential fit 33 / 23 / 41 / 22 / 32 / 21 /
    29. Orders 5 and 7 with short windows are best and equal within the scatter; 7 frames, order 5
    is the shorter of the two. Its gain (:func:`derivative_gain`) is 0.999 / 0.998 / 0.994 at
    20 / 25 / 30 rad/s against 0.927 / 0.888 / 0.841 for central differences, whose flattened
    peaks (seed 4.2.2) take 14 % of the kinetic energy at 20 rad/s. The price is a white-noise
    gain :math:`\sqrt{\sum c_k^2}\,\Delta t` of 1.08 instead of 0.71, which at the measured
    noise of well under 1 mm costs a few mJ.
    """
    return apply_stencil(signal, savgol_derivative_coefficients(window, polyorder, dt))


# --- energy and its uncertainty -----------------------------------------------------------------


def bob_speeds(
    phi1: np.ndarray, phi2: np.ndarray, omega1: np.ndarray, omega2: np.ndarray, params: PendulumParameters
) -> tuple[np.ndarray, np.ndarray]:
    """Speeds |v1|, |v2| [m/s] of the bobs (:func:`double_pendulum.model.kinematics.velocities`)."""
    vx1, vy1, vx2, vy2 = velocities(phi1, phi2, omega1, omega2, params.l1, params.l2, np.sin, np.cos)
    return np.hypot(vx1, vy1), np.hypot(vx2, vy2)


def sigma_energy_seed(v1: np.ndarray, v2: np.ndarray, m1: float, m2: float, dv: float = SEED_VELOCITY_ERROR):
    r"""The seed's eq. 25: :math:`\Delta E = \Delta v \sqrt{m_1^2 v_1^2 + m_2^2 v_2^2}` [J] (v in m/s)."""
    return dv * np.sqrt(m1 * m1 * v1 * v1 + m2 * m2 * v2 * v2)


def energy_gradient(
    phi1: np.ndarray,
    phi2: np.ndarray,
    omega1: np.ndarray,
    omega2: np.ndarray,
    params: PendulumParameters,
    step: float = 1e-6,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Partial derivatives of :func:`~double_pendulum.model.energy.total_energy` by (phi1, phi2, omega1, omega2).

    Central differences of the package's own energy function (no second energy formula); exact
    up to round-off in omega (E is quadratic there), error O(step^2) in phi.
    """
    state = [np.asarray(a, dtype=float) for a in (phi1, phi2, omega1, omega2)]
    grads = []
    for k in range(4):
        up = [a + step if j == k else a for j, a in enumerate(state)]
        down = [a - step if j == k else a for j, a in enumerate(state)]
        grads.append((total_energy(*up, params, np.cos) - total_energy(*down, params, np.cos)) / (2 * step))
    return grads[0], grads[1], grads[2], grads[3]


def sigma_energy_propagated(
    phi1: np.ndarray,
    phi2: np.ndarray,
    omega1: np.ndarray,
    omega2: np.ndarray,
    params: PendulumParameters,
    sigma1: float,
    sigma2: float,
    coeffs: np.ndarray,
) -> np.ndarray:
    r"""Standard deviation [J] of the energy caused by white position noise sigma1, sigma2 [m].

    Noise delta p1, delta p2 of the bobs moves the angles by the tangential components:
    :math:`\delta\varphi_1 = e_1\cdot\delta p_1 / l_1`,
    :math:`\delta\varphi_2 = e_2\cdot(\delta p_2 - \delta p_1) / l_2` with
    :math:`e_j = (\cos\varphi_j, \sin\varphi_j)`, so

    .. math::

        C_\varphi = \begin{pmatrix} \sigma_1^2/l_1^2 & -\sigma_1^2\cos(\varphi_1-\varphi_2)/(l_1 l_2) \\
                    -\sigma_1^2\cos(\varphi_1-\varphi_2)/(l_1 l_2) & (\sigma_1^2+\sigma_2^2)/l_2^2
                    \end{pmatrix}

    The derivative stencil c_k (antisymmetric, c_0 = 0) makes the rate noise
    :math:`C_\omega = \sum_k c_k^2\, C_\varphi`, uncorrelated with the angle noise of the same
    frame. With the gradients :math:`g_\varphi = \partial E/\partial\varphi`,
    :math:`g_\omega = \partial E/\partial\omega` (:func:`energy_gradient`):

    .. math::

        \sigma_E^2 = g_\varphi^T C_\varphi\, g_\varphi + g_\omega^T C_\omega\, g_\omega
    """
    gp1, gp2, gw1, gw2 = energy_gradient(phi1, phi2, omega1, omega2, params)
    l1, l2 = params.l1, params.l2
    v1 = sigma1**2 / l1**2
    v2 = (sigma1**2 + sigma2**2) / l2**2
    c12 = -(sigma1**2) * np.cos(phi1 - phi2) / (l1 * l2)
    var_phi = gp1 * gp1 * v1 + 2.0 * gp1 * gp2 * c12 + gp2 * gp2 * v2
    var_omega = float(np.sum(coeffs * coeffs)) * (gw1 * gw1 * v1 + 2.0 * gw1 * gw2 * c12 + gw2 * gw2 * v2)
    return np.sqrt(var_phi + var_omega)


def find_release_frame(energy: np.ndarray) -> int:
    """Index of the first local maximum of the energy: the frame where the hand release ends.

    While the hand lets go it still does work on the pendulum, so the energy of the first frames
    rises; free motion can only lose energy. The release is taken as over at the first frame i
    (among finite values) with E[i+1] < E[i]. Use an energy that is defined from the first frames
    on (the central-difference one) and check the result on a plot: a single noisy frame early on
    would end the search too soon.
    """
    idx = np.flatnonzero(np.isfinite(energy))
    for i, j in zip(idx[:-1], idx[1:]):
        if energy[j] < energy[i]:
            return int(i)
    return int(idx[0]) if len(idx) else 0


def same_pendulum(rec: Reconstruction) -> dict[str, object]:
    """The keywords of :func:`reconstruct` that give ``rec``'s masses, rods and g (its geometry apart): to
    reconstruct the same pendulum with one choice changed."""
    p = rec.params
    return {"m1": p.m1, "m2": p.m2, "g": p.g,
            "rods": {k: getattr(p, k) for k in ("m_rod1", "m_rod2", "L_rod1", "L_rod2")}}  # fmt: skip


def untilt(x: np.ndarray, y: np.ndarray, tilt: float) -> tuple[np.ndarray, np.ndarray]:
    """Positions (x, y) [m] about the pivot turned clockwise by ``tilt`` [rad]: a camera turned counter-clockwise
    by ``tilt`` against gravity, undone (each angle ``phi`` then falls by ``tilt``). ``tilt = 0``: unchanged."""
    if not tilt:
        return x, y
    c, s = math.cos(tilt), math.sin(tilt)
    return c * x + s * y, -s * x + c * y


def _touches_invalid(valid: np.ndarray, half_width: int) -> np.ndarray:
    """True where a flagged frame lies within ``half_width`` frames."""
    bad = (~valid).astype(float)
    return np.convolve(bad, np.ones(2 * half_width + 1), mode="same") > 0


def reconstruct(
    track: Track,
    geometry: Geometry | None = None,
    *,
    m1: float | None = None,
    m2: float | None = None,
    sigma_pos: tuple[float, float] | None = None,
    window: int = SG_WINDOW,
    polyorder: int = SG_POLYORDER,
    rods: Mapping[str, float] | None = None,
    g: float | None = None,
) -> Reconstruction:
    """Angles, rates and energies per frame of a measured track.

    ``geometry`` defaults to :func:`fit_geometry`; masses default to the seed's
    (:class:`PendulumParameters` defaults); ``sigma_pos`` (upper, lower bob) [m] defaults to
    :func:`estimate_position_noise`. The energy is ``total_energy`` of a ``PendulumParameters``
    with the measured l1, l2 (potential zero with both bobs hanging at rest below the fitted pivot);
    ``rods`` (``m_rod1, m_rod2, L_rod1, L_rod2``, e.g. :data:`~double_pendulum.model.parameters.SEED_RIGID_LINKS`)
    adds the links' rods to it (default: point masses on massless rods); ``g`` [m/s^2] defaults to the model's.
    The derivative stencils use the track's frame interval ``track.dt``.
    """
    geometry = fit_geometry(track) if geometry is None else geometry
    defaults = PendulumParameters()
    params = PendulumParameters(
        m1=defaults.m1 if m1 is None else m1,
        m2=defaults.m2 if m2 is None else m2,
        l1=geometry.l1,
        l2=geometry.l2,
        **dict(rods or {}),
        **({} if g is None else {"g": g}),
    )
    s1, s2 = estimate_position_noise(track, geometry) if sigma_pos is None else sigma_pos
    x1, y1 = untilt(track.x1 - geometry.pivot.xc, track.y1 - geometry.pivot.yc, geometry.tilt)
    x2, y2 = untilt(track.x2 - geometry.pivot.xc, track.y2 - geometry.pivot.yc, geometry.tilt)
    phi1, phi2 = angles(x1, y1, x2, y2)
    cd = central_difference_coefficients(track.dt)
    sg = savgol_derivative_coefficients(window, polyorder, track.dt)
    w1_cd, w2_cd = apply_stencil(phi1, cd), apply_stencil(phi2, cd)
    w1, w2 = apply_stencil(phi1, sg), apply_stencil(phi2, sg)
    energy_cd = total_energy(phi1, phi2, w1_cd, w2_cd, params, np.cos)
    energy = total_energy(phi1, phi2, w1, w2, params, np.cos)
    v1_cd, v2_cd = bob_speeds(phi1, phi2, w1_cd, w2_cd, params)
    v1, v2 = bob_speeds(phi1, phi2, w1, w2, params)
    valid = np.isfinite(energy) & np.isfinite(energy_cd) & ~_touches_invalid(track.valid, window // 2)
    return Reconstruction(
        track=track,
        geometry=geometry,
        params=params,
        sigma_pos1=s1,
        sigma_pos2=s2,
        x1=x1,
        y1=y1,
        x2=x2,
        y2=y2,
        phi1=phi1,
        phi2=phi2,
        omega1_cd=w1_cd,
        omega2_cd=w2_cd,
        omega1=w1,
        omega2=w2,
        energy_cd=energy_cd,
        energy=energy,
        e_kin=kinetic_energy(phi1, phi2, w1, w2, params, np.cos),
        e_pot=potential_energy(phi1, phi2, params, np.cos),
        sigma_energy_seed=sigma_energy_seed(v1_cd, v2_cd, params.m1, params.m2),
        sigma_energy=sigma_energy_propagated(phi1, phi2, w1, w2, params, s1, s2, sg),
        momentum=np.sqrt((params.m1 * v1) ** 2 + (params.m2 * v2) ** 2),
        energy_valid=valid,
        # not before the first frame with both energies and rates (a record that starts in free motion)
        release_frame=max(find_release_frame(energy_cd), int(np.argmax(valid)) if valid.any() else 0),
    )
