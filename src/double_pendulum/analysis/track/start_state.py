r"""Start state of the FMU estimated from measured bob positions (least squares through the FMU).

A single frame's angles are known to the position noise, but its rates come from a derivative
filter over several frames and carry its truncation error and noise. :func:`fit_start_state`
instead adjusts the state :math:`s = (\varphi_1, \varphi_2, \omega_1, \omega_2)` at ``t0`` until the
FMU, started there, reproduces the measured positions of the next frames:

.. math::

    \chi^2(s) = \sum_i \sum_{q \in \{x_1, y_1, x_2, y_2\}}
        \left(\frac{q^{FMU}_i(s) - q^{meas}_i}{\sigma_q}\right)^2

(positions relative to the pivot rest position [m], ``sigma`` per coordinate [m]; or the angles
phi1, phi2 [rad] with ``outputs=ANGLE_OUTPUTS``), minimised by Levenberg-Marquardt with a
finite-difference Jacobian J (one FMU run per column). Covariance
:math:`C = (J^T J)^{-1}`, multiplied by :math:`\chi^2/(n-4)` unless ``absolute_sigma`` (as
:func:`scipy.optimize.curve_fit`). The other start values (mechanisms, lengths, solver) are
passed through unchanged; the suspension, if on, starts at rest in its equilibrium.

Times are on the frame grid :math:`t_i = t_0 + n_i\,\Delta t`; frames may be missing (``offsets``).

Free geometry. ``geometry`` names further parameters fitted together with the state (one more
Jacobian column each): ``pivot_offset_x``, ``pivot_offset_y`` [m] shift the FMU's positions (its
origin is the pivot at rest) by the pivot's offset from the pivot the positions are measured from
(:data:`PIVOT_SHIFTS`, positions only; not the FMU's ``pivot_x`` input), ``view_rotation`` [rad]
turns them about the pivot (:data:`VIEW_ROTATION`); any other name is an FMU
start value of the model, e.g. the rod lengths ``l1``, ``l2`` [m], started from ``model_values``
(or 0). The covariance then covers state and geometry (``StartStateFit.full_cov``), and chi2_red
divides by n - 4 - len(geometry).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from scipy.optimize import least_squares

from ...fmu.running.runner import FmuRunner
from .measurement import FRAME_INTERVAL, Reconstruction

POSITION_OUTPUTS: tuple[str, ...] = ("x1", "y1", "x2", "y2")
"""The FMU outputs compared with the track's positions [m]."""
ANGLE_OUTPUTS: tuple[str, ...] = ("phi1", "phi2")
"""The FMU outputs compared with the track's angles [rad]."""
STATE_NAMES: tuple[str, ...] = ("phi1_0", "phi2_0", "omega1_0", "omega2_0")
"""FMU start values of the fitted state (rad, rad, rad/s, rad/s)."""
FIT_SETTINGS: dict[str, Any] = {"solver": "dop853", "rtol": 1e-10, "atol": 1e-12}
"""Tight tolerances: the finite-difference Jacobian divides integration error by the step."""
DIFF_STEP = 1e-6
"""Relative finite-difference step of the Jacobian (scipy's ``diff_step``): 1e-6 rad moves a bob by
0.3 um, far above the integration error at :data:`FIT_SETTINGS`, far below the position noise."""
PIVOT_SHIFTS: dict[str, tuple[str, ...]] = {"pivot_offset_x": ("x1", "x2"), "pivot_offset_y": ("y1", "y2")}
"""Free geometry parameters that shift FMU position outputs [m] (the pivot's offset), by the outputs they shift."""
VIEW_ROTATION = "view_rotation"
"""Free geometry parameter [rad]: the FMU's bob positions turned counter-clockwise about the pivot
(before the pivot shift), e.g. a camera whose vertical is not along gravity."""
POSITION_TRANSFORMS: tuple[str, ...] = (*PIVOT_SHIFTS, VIEW_ROTATION)
"""Free geometry that moves the FMU's positions instead of entering the FMU as a start value."""
GEOMETRY_UNITS = {"pivot_offset_x": "m", "pivot_offset_y": "m", VIEW_ROTATION: "rad", "l1": "m", "l2": "m"}
"""Units of the usual free geometry (``StartStateFit.as_dict``)."""


@dataclass(frozen=True, eq=False)
class StartStateFit:
    """A fitted start state at ``t0`` [s]: values, standard errors, covariance, goodness of fit."""

    t0: float
    state: np.ndarray
    stderr: np.ndarray
    cov: np.ndarray
    chi2: float
    n_residuals: int
    n_frames: int
    rms_residual: float
    n_fmu_runs: int
    geometry: Mapping[str, float] = field(default_factory=dict)
    geometry_stderr: Mapping[str, float] = field(default_factory=dict)
    full_cov: np.ndarray | None = None

    @property
    def names(self) -> tuple[str, ...]:
        """Names of all fitted parameters: the state's start values, then the free geometry."""
        return (*STATE_NAMES, *self.geometry)

    @property
    def values(self) -> np.ndarray:
        """All fitted parameters in :attr:`names` order."""
        return np.concatenate([self.state, np.fromiter(self.geometry.values(), float, len(self.geometry))])

    @property
    def covariance(self) -> np.ndarray:
        """Covariance of all fitted parameters (:attr:`names` order); the state's ``cov`` without geometry."""
        return self.cov if self.full_cov is None else self.full_cov

    @property
    def chi2_red(self) -> float:
        """chi2 / (n - number of fitted parameters)."""
        return self.chi2 / max(self.n_residuals - len(self.names), 1)

    def start_values(self) -> dict[str, float]:
        """The state as FMU start values ``phi1_0 .. omega2_0``."""
        return state_start_values(self.state)

    def as_dict(self) -> dict[str, Any]:
        """Plain dictionary (for JSON); the geometry entries only if geometry was fitted."""
        geometry = {}
        if self.geometry:
            geometry = {
                "geometry": {k: float(v) for k, v in self.geometry.items()},
                "geometry_stderr": {k: float(v) for k, v in self.geometry_stderr.items()},
                "geometry_units": {k: GEOMETRY_UNITS.get(k, "as the FMU start value") for k in self.geometry},
                "parameters": list(self.names),
            }
        return {
            "t0_s": self.t0,
            "state": dict(zip(STATE_NAMES, map(float, self.state))),
            "stderr": dict(zip(STATE_NAMES, map(float, self.stderr))),
            **geometry,
            "correlation": _correlation(self.covariance).tolist(),
            "chi2": self.chi2,
            "chi2_red": self.chi2_red,
            "n_frames": self.n_frames,
            "rms_residual": self.rms_residual,
            "n_fmu_runs": self.n_fmu_runs,
        }


def _correlation(cov: np.ndarray) -> np.ndarray:
    d = np.sqrt(np.diag(cov))
    return cov / np.outer(d, d)


def state_start_values(state: Sequence[float]) -> dict[str, float]:
    """Map ``(phi1, phi2, omega1, omega2)`` [rad, rad/s] to the FMU's start values."""
    return {name: float(v) for name, v in zip(STATE_NAMES, state)}


def split_geometry(geometry: Mapping[str, float]) -> tuple[dict[str, float], dict[str, float]]:
    """Free geometry values split into FMU start values and position transforms (:data:`POSITION_TRANSFORMS`)."""
    start = {k: float(v) for k, v in geometry.items() if k not in POSITION_TRANSFORMS}
    shifts = {k: float(v) for k, v in geometry.items() if k in POSITION_TRANSFORMS}
    return start, shifts


def shift_outputs(matrix: np.ndarray, outputs: Sequence[str], shifts: Mapping[str, float]) -> np.ndarray:
    """Output ``matrix`` (columns ``outputs``) with the position transforms applied: the bob positions
    turned by :data:`VIEW_ROTATION` [rad] about the pivot, then the pivot ``shifts`` [m] added."""
    out = np.array(matrix, dtype=float)
    shifts = dict(shifts)
    angle = shifts.pop(VIEW_ROTATION, 0.0)
    if angle:
        c, s = np.cos(angle), np.sin(angle)
        for x, y in (("x1", "y1"), ("x2", "y2")):
            if x not in outputs or y not in outputs:
                raise ValueError(f"{VIEW_ROTATION} turns {x}, {y}, which are not among the outputs {tuple(outputs)}")
            i, j = list(outputs).index(x), list(outputs).index(y)
            out[:, i], out[:, j] = c * matrix[:, i] - s * matrix[:, j], s * matrix[:, i] + c * matrix[:, j]
    for name, value in shifts.items():
        for col in PIVOT_SHIFTS[name]:
            if col not in outputs:
                raise ValueError(f"{name} shifts {col}, which is not among the fitted outputs {tuple(outputs)}")
            out[:, list(outputs).index(col)] += value
    return out


def simulate_frames(
    runner: FmuRunner,
    start_values: Mapping[str, Any],
    t0: float,
    n_frames: int,
    *,
    dt: float = FRAME_INTERVAL,
    outputs: Sequence[str] = POSITION_OUTPUTS,
) -> np.ndarray:
    """Run the FMU from ``t0`` [s] and return ``n_frames`` rows on the grid ``t0 + n dt`` (n = 0..)."""
    result = runner.simulate(
        dict(start_values), start_time=t0, stop_time=t0 + (n_frames - 1) * dt, output_interval=dt, outputs=outputs
    )
    if len(result) != n_frames:
        raise RuntimeError(f"expected {n_frames} output rows from t0 = {t0} s, got {len(result)}")
    return result


def output_matrix(result: np.ndarray, outputs: Sequence[str] = POSITION_OUTPUTS) -> np.ndarray:
    """Columns ``outputs`` of an FMU result as an (n, len(outputs)) array."""
    return np.column_stack([result[name] for name in outputs])


def fit_start_state(
    runner: FmuRunner,
    t0: float,
    offsets: Sequence[int] | np.ndarray,
    data: np.ndarray,
    sigma: Sequence[float] | np.ndarray,
    guess: Sequence[float],
    model_values: Mapping[str, Any] | None = None,
    *,
    outputs: Sequence[str] = POSITION_OUTPUTS,
    dt: float = FRAME_INTERVAL,
    absolute_sigma: bool = False,
    geometry: Sequence[str] = (),
    geometry_guess: Mapping[str, float] | None = None,
    tolerance: float = 1e-8,
) -> StartStateFit:
    """Fit ``(phi1, phi2, omega1, omega2)`` at ``t0`` [s] to measured frames (see the module docstring).

    ``offsets``: frame numbers after ``t0`` (0 = the frame at t0) of the rows of ``data``, whose
    columns are the FMU ``outputs`` (default x1, y1, x2, y2 relative to the pivot rest position [m]);
    ``sigma``: their errors per column (shape (len(outputs),)) or per entry (shape of ``data``);
    ``guess``: start of the iteration (e.g. the reconstruction's angles and rates at t0);
    ``model_values``: every other FMU start value (mechanisms, lengths); the solver defaults to
    :data:`FIT_SETTINGS`. ``absolute_sigma``: take ``sigma`` as the true errors (else scale the
    covariance by chi2 / (n - p)). ``geometry``: names of free geometry parameters fitted with the
    state (module docstring), started from ``geometry_guess``, else ``model_values``, else 0.
    ``tolerance``: relative change of chi2 and of the parameters at which the iteration stops (scipy's
    ``ftol`` and ``xtol``; 1e-8 is scipy's default).
    """
    offsets = np.asarray(offsets, dtype=int)
    data = np.asarray(data, dtype=float)
    sigma = np.broadcast_to(np.asarray(sigma, dtype=float), data.shape)
    base = {**FIT_SETTINGS, **dict(model_values or {})}
    n_frames = int(offsets.max()) + 1
    names = tuple(geometry)
    known = {**base, **dict(geometry_guess or {})}
    x0 = np.concatenate([np.asarray(guess, dtype=float), [float(known.get(n, 0.0)) for n in names]])
    runs = [0]

    def residuals(x: np.ndarray) -> np.ndarray:
        runs[0] += 1
        start, shifts = split_geometry(dict(zip(names, x[4:])))
        values = {**base, **start, **state_start_values(x[:4])}
        sim = simulate_frames(runner, values, t0, n_frames, dt=dt, outputs=outputs)
        return ((shift_outputs(output_matrix(sim, outputs)[offsets], outputs, shifts) - data) / sigma).ravel()

    res = least_squares(residuals, x0, method="lm", diff_step=DIFF_STEP, x_scale="jac", ftol=tolerance,
                        xtol=tolerance)
    chi2 = float(res.fun @ res.fun)
    m = res.fun.size
    cov = np.linalg.inv(res.jac.T @ res.jac)
    if not absolute_sigma:
        cov = cov * chi2 / max(m - len(res.x), 1)
    resid = res.fun.reshape(data.shape) * sigma
    err = np.sqrt(np.diag(cov))
    return StartStateFit(
        t0=float(t0),
        state=res.x[:4].copy(),
        stderr=err[:4],
        cov=cov[:4, :4],
        chi2=chi2,
        n_residuals=m,
        n_frames=len(offsets),
        rms_residual=float(np.sqrt(np.mean(resid**2))),
        n_fmu_runs=runs[0],
        geometry=dict(zip(names, map(float, res.x[4:]))),
        geometry_stderr=dict(zip(names, map(float, err[4:]))),
        full_cov=cov if names else None,
    )


@dataclass(frozen=True, eq=False)
class TrackWindow:
    """Measured frames after a start frame, ready for :func:`fit_start_state`.

    ``offsets``: frames after ``i0`` (valid frames only); ``positions``: x1, y1, x2, y2 relative to
    the fitted pivot [m] with their noise ``sigma_positions`` [m]; ``angles``: phi1, phi2 [rad] with
    ``sigma_angles`` [rad] (the position noise seen by each rod: s1/l1 and sqrt(s1^2 + s2^2)/l2);
    ``guess``: the reconstruction's angles and Savitzky-Golay rates at ``i0``.
    """

    i0: int
    t0: float
    offsets: np.ndarray
    positions: np.ndarray
    sigma_positions: np.ndarray
    angles: np.ndarray
    sigma_angles: np.ndarray
    guess: np.ndarray

    def data(self, outputs: Sequence[str]) -> tuple[np.ndarray, np.ndarray]:
        """``(data, sigma)`` for :func:`fit_start_state`: positions or angles, chosen by ``outputs``."""
        if tuple(outputs) == POSITION_OUTPUTS:
            return self.positions, self.sigma_positions
        if tuple(outputs) == ANGLE_OUTPUTS:
            return self.angles, self.sigma_angles
        raise ValueError(f"outputs must be {POSITION_OUTPUTS} or {ANGLE_OUTPUTS}, got {tuple(outputs)}")


def track_window(rec: Reconstruction, i0: int, n_frames: int) -> TrackWindow:
    """The ``n_frames`` frames from frame index ``i0`` on (flagged frames left out) of a reconstruction."""
    idx = np.arange(i0, min(i0 + n_frames, len(rec.t)))
    idx = idx[rec.track.valid[idx]]
    s1, s2 = rec.sigma_pos1, rec.sigma_pos2
    l1, l2 = rec.params.l1, rec.params.l2
    return TrackWindow(
        i0=int(i0),
        t0=float(rec.t[i0]),
        offsets=idx - i0,
        positions=np.column_stack([rec.x1[idx], rec.y1[idx], rec.x2[idx], rec.y2[idx]]),
        sigma_positions=np.array([s1, s1, s2, s2]),
        angles=np.column_stack([rec.phi1[idx], rec.phi2[idx]]),
        sigma_angles=np.array([s1 / l1, np.hypot(s1, s2) / l2]),
        guess=np.array([rec.phi1[i0], rec.phi2[i0], rec.omega1[i0], rec.omega2[i0]]),
    )
