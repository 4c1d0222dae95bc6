r"""The added-mass stability limit of explicit (Jacobi, zero-order hold) coupling, derived and measured.

Model of the loop: the pendulum hanging (nearly) straight down moves vertically with its pivot as
one rigid mass m = m1 + m2, so its force on the pivot is F = -m (g + a_p) with a_p the pivot
acceleration it is given. The suspension mass M_s on spring k and damper c (omega^2 = k / M_s,
zeta = c / (2 sqrt(k M_s))) feels f = F + m g (the dynamic part). In the Jacobi master
(:func:`double_pendulum.fmu.coupling.run_jacobi`, libcosim, the container FMU) the exchange at
t_n gives the suspension f_n (the pendulum's output of t_n) and the pendulum A_n (the suspension's
output of t_n), both held over [t_n, t_n + h]. The outputs of t_n were computed with the inputs
of the step before, so

    A_n = (f_{n-1} - k y_n - c v_n) / M_s,        f_{n+1} = -m A_n
        = -mu f_{n-1} + mu (k y_n + c v_n),       mu = m / M_s,

and (y, v) advance exactly under the held f_n: (y, v)_{n+1} = Phi(h) (y, v)_n + Gamma(h) f_n.
With X_n = (y_n, v_n, f_n, f_{n-1}) this is X_{n+1} = G(mu, h omega, zeta) X_n: bounded iff the
spectral radius rho(G) <= 1. For h omega -> 0, Phi -> I, Gamma -> 0 and the force recursion
decouples: f_{n+1} = -mu f_{n-1}, eigenvalues z = +-i sqrt(mu): **unstable for mu > 1 at any
macro step** (the classic added-mass instability: the lagged inertial force of a load heavier
than its support over-corrects it every step, growing as sqrt(mu) per step). At finite h omega
the spring and damper shift the limit (:func:`critical_mass_ratio`).
"""

from __future__ import annotations

import math

import numpy as np


def amplification_matrix(mu: float, h_omega: float, zeta: float = 0.0) -> np.ndarray:
    """G of X_{n+1} = G X_n, in units M_s = 1, omega = 1 (so h = h_omega, k = 1, c = 2 zeta)."""
    from scipy.linalg import expm

    a = np.array([[0.0, 1.0], [-1.0, -2.0 * zeta]])
    block = np.zeros((3, 3))
    block[:2, :2], block[1, 2] = a, 1.0  # augmented: force held constant
    e = expm(block * h_omega)
    phi, gamma = e[:2, :2], e[:2, 2]
    g = np.zeros((4, 4))
    g[:2, :2], g[:2, 2] = phi, gamma
    g[2, 0], g[2, 1], g[2, 3] = mu, mu * 2.0 * zeta, -mu
    g[3, 2] = 1.0
    return g


def spectral_radius(mu: float, h_omega: float, zeta: float = 0.0) -> float:
    """Largest |eigenvalue| of :func:`amplification_matrix`: the growth factor per macro step."""
    return float(max(abs(np.linalg.eigvals(amplification_matrix(mu, h_omega, zeta)))))


def critical_mass_ratio(h_omega: float, zeta: float = 0.0, *, lo: float = 1e-3, hi: float = 1e3) -> float:
    """The mass ratio mu = (m1 + m2) / M_s above which Jacobi coupling grows (rho > 1 + 1e-9), by bisection.

    Returns ``nan`` if even ``lo`` is unstable (the suspension's own discretisation is then unstable).
    """

    def unstable(mu: float) -> bool:
        return spectral_radius(mu, h_omega, zeta) > 1.0 + 1e-9

    if unstable(lo):
        return math.nan
    if not unstable(hi):
        return math.inf
    for _ in range(60):
        mid = math.sqrt(lo * hi)
        lo, hi = (lo, mid) if unstable(mid) else (mid, hi)
    return math.sqrt(lo * hi)
