r"""The AR(1) noise model every analysis of the record shares: residuals :math:`z_i = \rho z_{i-1} + s\,\varepsilon_i`
(independent standard normal :math:`\varepsilon_i`), so :math:`\mathrm{corr}(z_i, z_j) = \rho^{|i-j|}`.

- :func:`ar1_coefficient`: rho as the lag-one autocorrelation of the residuals (Yule-Walker);
- :func:`ar1_correlation_times`: :math:`R x` with :math:`R_{ij} = \rho^{|i-j|}`, in O(n);
- :func:`ar1_sandwich`: the covariance of a least-squares estimate under that noise,
  :math:`(J^T J)^{-1} J^T \Sigma J (J^T J)^{-1}`, :math:`\Sigma_{ij} = \hat v\,\rho^{|i-j|}`,
  :math:`\hat v = |r|^2/(n-k)`.

It sits below the studies that use it (:mod:`.track.tilt` for the camera's tilt, :mod:`.track.rods` and
:mod:`.track.energy_noise` for the rods' mass, :mod:`.decay.noise` for the decay rate), so each reads the same one.
Residuals and Jacobians are normalised by the per-frame errors where there are any; rho is dimensionless.
"""

from __future__ import annotations

import numpy as np
from scipy.signal import lfilter


def ar1_coefficient(residuals: np.ndarray) -> float:
    r"""Lag-one autocorrelation :math:`\hat\rho = \sum_i r_i r_{i-1} / \sum_i r_i^2` of the mean-removed
    ``residuals`` (the Yule-Walker estimate of the AR(1) coefficient, |rho| < 1)."""
    r = np.asarray(residuals, dtype=float)
    r = r - r.mean()
    return float(r[1:] @ r[:-1] / (r @ r))


def ar1_correlation_times(x: np.ndarray, rho: float) -> np.ndarray:
    r"""R x for the AR(1) correlation matrix :math:`R_{ij} = \rho^{|i-j|}` (along axis 0), in O(n):
    :math:`(R x)_i = f_i + g_i - x_i` with the recursions :math:`f_i = x_i + \rho f_{i-1}` (forward) and
    :math:`g_i = x_i + \rho g_{i+1}` (backward)."""
    x = np.asarray(x, dtype=float)
    f = lfilter([1.0], [1.0, -rho], x, axis=0)
    g = lfilter([1.0], [1.0, -rho], x[::-1], axis=0)[::-1]
    return f + g - x


def ar1_sandwich(jac: np.ndarray, resid: np.ndarray, rho: float, hessian: np.ndarray | None = None) -> np.ndarray:
    r"""Covariance of a least-squares estimate with (normalised) Jacobian ``jac`` (n, k) and residuals ``resid``
    (n) under AR(1) residuals of coefficient ``rho``: :math:`(J^TJ)^{-1} J^T \Sigma J (J^TJ)^{-1}`,
    :math:`\Sigma_{ij} = v\rho^{|i-j|}`, :math:`v = |r|^2/(n-k)`. ``hessian``: half the Hessian of the
    objective in place of :math:`J^TJ` in the bread (an objective that is not a plain sum of squares, such as
    the corrected least squares of :mod:`.track.rods`)."""
    n, k = jac.shape
    v = float(resid @ resid) / (n - k)
    bread = np.linalg.inv(jac.T @ jac if hessian is None else hessian)
    return v * bread @ (jac.T @ ar1_correlation_times(jac, rho)) @ bread
