r"""The added-mass stability limit of explicit (Jacobi, zero-order hold) coupling, derived and measured.

Model of the loop: the pendulum hanging (nearly) straight down moves vertically with its pivot as
one rigid mass m = m1 + m2, so its force on the pivot is F = -m (g + a_p) with a_p the pivot
acceleration it is given. The suspension mass M_s on spring k and damper c (omega^2 = k / M_s,
zeta = c / (2 sqrt(k M_s))) feels f = F + m g (the dynamic part). In the Jacobi master
(:func:`double_pendulum.fmu.masters.coupling.run_jacobi`, libcosim) the exchange at
t_n gives the suspension f_n (the pendulum's output of t_n) and the pendulum A_n (the suspension's
output of t_n), both held over [t_n, t_n + h]. The outputs of t_n were computed with the inputs
of the step before, so

    A_n = (f_{n-1} - k y_n - c v_n) / M_s,        f_{n+1} = -m A_n
        = -mu f_{n-1} + mu (k y_n + c v_n),       mu = m / M_s,

and (y, v) advance exactly under the held f_n: (y, v)_{n+1} = Phi(h) (y, v)_n + Gamma(h) f_n.
With X_n = (y_n, v_n, f_n, f_{n-1}) this is X_{n+1} = G(mu, h omega, zeta) X_n: bounded iff the
spectral radius rho(G) <= 1. For h omega -> 0, Phi -> I, Gamma -> 0 and the force recursion
decouples: f_{n+1} = -mu f_{n-1}, eigenvalues z = +-i sqrt(mu): unstable for mu > 1 in that limit
(the classic added-mass instability: the lagged inertial force of a load heavier than its support
over-corrects it every step, growing as sqrt(mu) per step). At finite h omega the spring and damper
shift the limit (:func:`critical_mass_ratio`): here damping raises it above 1 at small and moderate
h omega (:func:`limit_table`), while large, lightly damped steps lower it.

With the exchange in sequence (``jacobi_sequential``: the force first, then the suspension's
acceleration that follows from it, as fmpy's container FMU and libcosim do), the pendulum gets
A_n = (f_n - k y_n - c v_n) / M_s and

    f_{n+1} = -mu f_n + mu (k y_n + c v_n):

one delay instead of two, X_n = (y_n, v_n, f_n), and for h omega -> 0 the eigenvalue z = -mu:
the same limit mu < 1, but an unstable run grows as mu per step instead of sqrt(mu); here the spring and
damper lower the limit below 1 at every finite h omega, so a load heavier than its support is unstable at
every macro step.
"""

from __future__ import annotations

import math

import numpy as np


def oscillator_step(h_omega: float, zeta: float) -> tuple[np.ndarray, np.ndarray]:
    """Exact step of y'' + 2 zeta y' + y = f (omega = 1, 0 <= zeta < 1) over h_omega with f held.

    (y, v)_{n+1} = Phi (y, v)_n + Gamma f_n with, for w_d = sqrt(1 - zeta^2), s = sin(w_d h),
    c = cos(w_d h), e = exp(-zeta h): Phi = e [[c + zeta s / w_d, s / w_d], [-s / w_d, c - zeta s / w_d]]
    and Gamma = (1 - Phi_00, -Phi_10) (the response to a unit force from rest: (1, 0) - Phi (1, 0)).
    """
    if not 0.0 <= zeta < 1.0:
        raise ValueError(f"zeta = {zeta!r}: the closed form needs an underdamped suspension (0 <= zeta < 1)")
    w_d = math.sqrt(1.0 - zeta * zeta)
    s, c, e = math.sin(w_d * h_omega), math.cos(w_d * h_omega), math.exp(-zeta * h_omega)
    phi = e * np.array([[c + zeta * s / w_d, s / w_d], [-s / w_d, c - zeta * s / w_d]])
    return phi, np.array([1.0 - phi[0, 0], -phi[1, 0]])


def amplification_matrix(mu: float, h_omega: float, zeta: float = 0.0, scheme: str = "jacobi") -> np.ndarray:
    """G of X_{n+1} = G X_n, in units M_s = 1, omega = 1 (so h = h_omega, k = 1, c = 2 zeta).

    ``scheme``: ``"jacobi"`` (both read before either is written: X = (y, v, f_n, f_{n-1})) or
    ``"jacobi_sequential"`` (force first: X = (y, v, f_n)).
    """
    phi, gamma = oscillator_step(h_omega, zeta)
    if scheme == "jacobi_sequential":
        g = np.zeros((3, 3))
        g[:2, :2], g[:2, 2] = phi, gamma
        g[2, :] = [mu, mu * 2.0 * zeta, -mu]  # f_{n+1} = -mu f_n + mu (y_n + 2 zeta v_n)
        return g
    g = np.zeros((4, 4))
    g[:2, :2], g[:2, 2] = phi, gamma
    g[2, 0], g[2, 1], g[2, 3] = mu, mu * 2.0 * zeta, -mu
    g[3, 2] = 1.0
    return g


def spectral_radius(mu: float, h_omega: float, zeta: float = 0.0, scheme: str = "jacobi") -> float:
    """Largest |eigenvalue| of :func:`amplification_matrix`: the growth factor per macro step."""
    return float(max(abs(np.linalg.eigvals(amplification_matrix(mu, h_omega, zeta, scheme)))))


def critical_mass_ratio(
    h_omega: float, zeta: float = 0.0, scheme: str = "jacobi", *, lo: float = 1e-3, hi: float = 1e3
) -> float:
    """The mass ratio mu = (m1 + m2) / M_s above which Jacobi coupling grows (rho > 1 + 1e-9), by bisection.

    Returns ``nan`` if even ``lo`` is unstable (the suspension's own discretisation is then unstable).
    """

    def unstable(mu: float) -> bool:
        return spectral_radius(mu, h_omega, zeta, scheme) > 1.0 + 1e-9

    if unstable(lo):
        return math.nan
    if not unstable(hi):
        return math.inf
    for _ in range(40):
        mid = math.sqrt(lo * hi)
        lo, hi = (lo, mid) if unstable(mid) else (mid, hi)
    return math.sqrt(lo * hi)


DAMPING_RATIOS = (0.0, 0.2, 0.5)
"""Damping ratios zeta of the suspension at which :func:`limit_table` states the derived limit beside the map's."""


def limit_table(h_omegas: tuple[float, ...], scheme: str, zetas: tuple[float, ...] = DAMPING_RATIOS) -> dict:
    """The derived limit mu_c (:func:`critical_mass_ratio`) of ``scheme`` at each damping ratio ``zetas`` and
    ``h_omegas``, keyed ``zeta_<z>`` / ``h_omega_<h omega>``. With the force passed first (``jacobi_sequential``)
    damping lowers mu_c below 1 at every h omega > 0; with both exchanged at once (``jacobi``) it raises it above 1,
    so a load heavier than its support is not unstable at every macro step there."""
    return {f"zeta_{z:g}": {f"h_omega_{hw:g}": critical_mass_ratio(hw, z, scheme) for hw in h_omegas} for z in zetas}
