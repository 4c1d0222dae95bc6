r"""Where the pendulum's energy goes when its pivot sits on a damped suspension.

An FMU run with the energy-flow outputs (:data:`ENERGY_FLOW_OUTPUTS`, at
:data:`ENERGY_FLOW_INTERVAL`) carries the pendulum's energy E_pendulum, the energy stored in the
suspension E_suspension (springs and moving mass), the works dissipated by air drag (W_air), the
bearings (W_bearing) and the suspension's dampers (W_suspension), and the power the pivot force
passes into the suspension, P_to_suspension. Without input the budget reads

.. math::

    E_p(t_0) - E_p(t) = W_{air} + W_{bearing} + W_{suspension} + E_s(t) - E_s(t_0),
    \qquad \int_{t_0}^{t} P_{to\ suspension}\,dt' = E_s(t) - E_s(t_0) + W_{suspension}.

:func:`energy_flow_summary` splits the pendulum's loss into these shares and checks the second
balance (trapezoid rule); :func:`peak_frequency` tells at which frequency the pivot moves.

Units: energies and works in J, powers in W, times in s, angular frequencies in rad/s, lengths in m.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np

from ...fmu.running.runner import FmuRunner
from .identification import FitFrames, simulate_frames_from

ENERGY_FLOW_INTERVAL = 0.005
"""Output interval [s] of the energy-flow runs (P_to_suspension oscillates at omega_n)."""
ENERGY_FLOW_OUTPUTS: tuple[str, ...] = (
    "E_pendulum",
    "E_suspension",
    "E_total",
    "W_air",
    "W_bearing",
    "W_suspension",
    "P_to_suspension",
    "xs",
    "ys",
    "energy_residual",
)
"""FMU outputs of an energy-flow run: energies and works [J], power [W], pivot position [m]."""


def energy_flow_run(runner: FmuRunner, values: Mapping[str, Any], frames: FitFrames) -> np.ndarray:
    """The run over the fit window at :data:`ENERGY_FLOW_INTERVAL` with the energy-flow outputs."""
    return simulate_frames_from(runner, values, frames, outputs=ENERGY_FLOW_OUTPUTS, interval=ENERGY_FLOW_INTERVAL)


def peak_frequency(signal: np.ndarray, dt: float) -> float:
    """Angular frequency [rad/s] of the largest peak of the signal's amplitude spectrum (mean removed).

    ``dt`` [s] is the sampling interval; the zero-frequency bin is skipped, so the resolution is
    2 pi / (n dt) for n samples.
    """
    spec = np.abs(np.fft.rfft(signal - np.mean(signal)))
    freq = np.fft.rfftfreq(len(signal), dt)
    return float(2.0 * math.pi * freq[1:][np.argmax(spec[1:])])


def energy_flow_summary(result: np.ndarray) -> dict[str, float]:
    r"""Where the pendulum's lost energy went, and the power balance of the suspension.

    Shares of the pendulum's loss E_p(t0) - E_p(end) [J]: W_suspension, W_air, W_bearing and what the
    suspension still holds, E_s(end) (they add up to 1 when E_s(t0) = 0). Balance:
    :math:`\int P_{to\ suspension}\,dt` (trapezoid) against E_s(end) - E_s(t0) + W_suspension(end); the
    difference is the trapezoid error of sampling a power that oscillates at the suspension frequency.
    Also the largest and mean E_s [J], mean and rms P_to_suspension [W], the spectral peaks of the pivot
    position xs, ys [rad/s] and their rms [m], and the largest |energy_residual| [J] of the FMU.
    """
    t = np.asarray(result["time"])
    e_p = np.asarray(result["E_pendulum"])
    lost = float(e_p[0] - e_p[-1])
    w_s = float(result["W_suspension"][-1])
    e_s = np.asarray(result["E_suspension"])
    p_int = float(np.trapezoid(result["P_to_suspension"], t))
    dt = float(t[1] - t[0])
    return {
        "pendulum_energy_lost_J": lost,
        "share_W_suspension": w_s / lost,
        "share_W_air": float(result["W_air"][-1]) / lost,
        "share_W_bearing": float(result["W_bearing"][-1]) / lost,
        "share_still_in_suspension": float(e_s[-1]) / lost,
        "max_E_suspension_J": float(np.max(e_s)),
        "mean_E_suspension_J": float(np.mean(e_s)),
        "mean_P_to_suspension_W": float(np.mean(result["P_to_suspension"])),
        "rms_P_to_suspension_W": float(np.sqrt(np.mean(np.asarray(result["P_to_suspension"]) ** 2))),
        "integral_P_dt_J": p_int,
        "E_suspension_gain_plus_W_suspension_J": float(e_s[-1] - e_s[0]) + w_s,
        "peak_frequency_xs_rad_s": peak_frequency(np.asarray(result["xs"]), dt),
        "peak_frequency_ys_rad_s": peak_frequency(np.asarray(result["ys"]), dt),
        "rms_xs_m": float(np.std(result["xs"])),
        "rms_ys_m": float(np.std(result["ys"])),
        "max_abs_energy_residual_J": float(np.max(np.abs(result["energy_residual"]))),
    }
