r"""Summaries, tables and figure inputs of the suspension study (scenario ``suspension_transfer``).

The study fits a pivot suspension (stiffness k = k_x = k_y, damping c = c_x = c_y, mass M_s) to the
measured energy decay (:mod:`~double_pendulum.analysis.suspension.identification`), sweeps the decay
rate b over (k, c, M_s) (:mod:`~double_pendulum.analysis.suspension.decay_map`) and compares both with the
linear response of :mod:`~double_pendulum.analysis.suspension.response`. This module turns those
results into the summary's entries (plain dicts, keys naming their units), the CSV tables and the
arrays the figures show.

Natural frequencies of the suspension: :math:`\omega_{n,x} = \sqrt{k/M_s}` horizontally and
:math:`\omega_{n,y} = \sqrt{k/(M_s + m_1 + m_2)}` vertically (the rods carry the bobs up and down).

Units: k in N/m, c in N s/m, M_s in kg, energies in J, times in s, rates in 1/s, omega in rad/s.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from ..track.measurement import FRAME_INTERVAL
from .decay_map import DecayMap, crossing, linear_response_grid
from .identification import Identification, MeasuredDecay, decay_shape, simulated_decay_rate
from .response import ForceSpectrum

# --- summary entries -----------------------------------------------------------------------------


def measured_summary(md: MeasuredDecay, seed_b: float, total_b_err: float) -> dict[str, Any]:
    """The measured decay E = a exp(b t) after the release: window, a [J], b [1/s] with its plain and
    correlation-inflated errors and its total error ``total_b_err`` [1/s] (statistical and systematic, the
    ``energy_decay`` error budget's), the seed's b ``seed_b`` [1/s] and the decay shape p of dE/dt = -k E^p."""
    return {
        "t0_s": md.frames.t0,
        "release_frame": md.i0,
        "n_frames": int(len(md.frames.t)),
        "window_s": [float(md.frames.t[0]), float(md.frames.t[-1])],
        "a_J": md.fit.value("a"),
        "b_per_s": md.b,
        "b_per_s_stderr": md.fit.error("b"),
        "b_per_s_stderr_autocorr": md.b_err,
        "autocorrelation_factor": md.factor,
        "b_per_s_total_error": total_b_err,
        "seed_b_per_s": seed_b,
        "decay_shape": decay_shape(md.frames.t, md.energy, md.frames.sigma, md.factor),
    }


def run_summary(md: MeasuredDecay, result: np.ndarray, reference_chi2: float, total_b_err: float) -> dict[str, Any]:
    r"""b (of E_pendulum and E_total) [1/s], p and chi2 of one FMU run on the fitted frames.

    With the normalised residuals :math:`r_i = (E^{FMU}_i - E_i)/\sigma_i`:
    :math:`\chi^2 = \sum r_i^2`, ``delta_chi2`` = chi2 - ``reference_chi2``; b is compared with the
    measured b relatively, in units of its statistical error (``difference_in_measured_sigma``) and of its total
    error ``total_b_err`` [1/s] (``difference_in_total_sigma``, statistical and systematic: the one to judge by).
    """
    energy = np.asarray(result["E_pendulum"])[md.frames.offsets]
    r = (energy - md.energy) / md.frames.sigma
    b = simulated_decay_rate(result, md.frames)
    return {
        "b_E_pendulum_per_s": b,
        "b_E_total_per_s": simulated_decay_rate(result, md.frames, "E_total"),
        "relative_difference_to_measured": (b - md.b) / md.b,
        "difference_in_measured_sigma": (b - md.b) / md.b_err,
        "difference_in_total_sigma": (b - md.b) / total_b_err,
        "p": decay_shape(md.frames.t, energy, md.frames.sigma)["p"],
        "chi2": float(r @ r),
        "delta_chi2": float(r @ r) - reference_chi2,
    }


def resonant_point(dmap: DecayMap, level: float) -> tuple[float, float] | None:
    """(k, c) where the lightest-damped column of the map crosses ``level`` [1/s]: the resonant end of
    the iso-b curve (k log-interpolated), or None if that column does not cross it."""
    k = crossing(dmap.k, dmap.b[:, 0], level)
    return None if k is None else (k, float(dmap.c[0]))


def resonant_summary(point: tuple[float, float], m_s: float, spectrum: ForceSpectrum) -> dict[str, float]:
    """The resonant end (k, c) of the iso-b curve at M_s = ``m_s``: its natural frequencies [rad/s], the
    linear-response share of b and its lightly damped limit pi S_F(omega_n) / (2 M) / mean E [1/s]."""
    m_x, m_y = spectrum.masses(m_s)
    k, c = point
    return {
        "k_N_per_m": k,
        "c_N_s_per_m": c,
        "M_s_kg": m_s,
        "omega_n_x_rad_s": math.sqrt(k / m_x),
        "omega_n_y_rad_s": math.sqrt(k / m_y),
        "linear_response_share_per_s": spectrum.linear_response_rate(k, c, m_s),
        "resonant_limit_share_per_s": spectrum.resonant_rate(k, m_s),
    }


def spectrum_summary(spectrum: ForceSpectrum, ident: Identification) -> dict[str, Any]:
    r"""Force statistics, the identified suspension's natural frequencies and the three limits there.

    rms forces :math:`\sqrt{\langle F_x^2\rangle}`, :math:`\sqrt{\langle F_y^2\rangle}` [N], the rms
    frequency :math:`\sqrt{\langle|\dot F|^2\rangle/\langle F^2\rangle}` [rad/s], and at the identified
    (k, c, M_s) the linear-response, lightly damped and stiff-limit shares of b [1/s].
    """
    var_x, var_y = spectrum.force_variances()
    m_x, m_y = spectrum.masses(ident.m_s)
    return {
        "rms_F_x_N": math.sqrt(var_x),
        "rms_F_y_N": math.sqrt(var_y),
        "mean_dF_dt_squared_N2_per_s2": spectrum.fdot_squared,
        "rms_frequency_rad_s": math.sqrt(spectrum.fdot_squared / (var_x + var_y)),
        "mean_E_pendulum_J": spectrum.mean_energy,
        "identified_omega_n_x_rad_s": math.sqrt(ident.k / m_x),
        "identified_omega_n_y_rad_s": math.sqrt(ident.k / m_y),
        "linear_response_share_at_identified_per_s": spectrum.linear_response_rate(ident.k, ident.c, ident.m_s),
        "resonant_limit_share_at_identified_per_s": spectrum.resonant_rate(ident.k, ident.m_s),
        "quasi_static_share_at_identified_per_s": spectrum.quasi_static_rate(ident.k, ident.c),
    }


# --- tables --------------------------------------------------------------------------------------


def records_table(rows: Sequence[Mapping[str, float]]) -> np.ndarray:
    """Rows of equal keys as a structured float array (columns in the first row's key order)."""
    names = list(rows[0])
    return np.rec.fromarrays([np.array([r[n] for r in rows], dtype=float) for n in names], names=names).view(np.ndarray)


def map_table(maps: Sequence[DecayMap], m12: float) -> np.ndarray:
    """All maps' grid points as one table (columns :data:`~double_pendulum.analysis.suspension.decay_map.MAP_UNITS`);
    ``m12`` = m1 + m2 [kg] for the vertical natural frequency."""
    return records_table([row for d in maps for row in d.rows(m12)])


FRAME_UNITS = {
    "frame": "1",
    "E_measured": "J",
    "sigma_E": "J",
    "E_pendulum_identified": "J",
    "E_total_identified": "J",
    "E_pendulum_no_suspension": "J",
    "E_pendulum_resonant": "J",
    "residual_identified": "1",
}
"""Units of the columns of :func:`frames_table` (time in s)."""


def frames_table(md: MeasuredDecay, runs: Mapping[str, np.ndarray], ident_resid: np.ndarray) -> np.ndarray:
    """Per fitted frame: measured energy and errors, simulated energies, normalised residuals.

    ``runs`` are FMU runs on the frames ("identified", "no suspension", optionally "resonant");
    ``ident_resid`` the identification's residuals (E_FMU - E) / sigma.
    """
    off = md.frames.offsets
    columns: dict[str, np.ndarray] = {
        "time": md.frames.t,
        "frame": (md.i0 + off).astype(float),
        "E_measured": md.energy,
        "sigma_E": md.frames.sigma,
        "E_pendulum_identified": runs["identified"]["E_pendulum"][off],
        "E_total_identified": runs["identified"]["E_total"][off],
        "E_pendulum_no_suspension": runs["no suspension"]["E_pendulum"][off],
    }
    if "resonant" in runs:
        columns["E_pendulum_resonant"] = runs["resonant"]["E_pendulum"][off]
    columns["residual_identified"] = ident_resid
    return np.rec.fromarrays([np.asarray(v, dtype=float) for v in columns.values()], names=list(columns)).view(
        np.ndarray
    )


# --- figure inputs -------------------------------------------------------------------------------


def map_panels(maps: Sequence[DecayMap], spectrum: ForceSpectrum, n_fine: int) -> dict[str, dict[str, np.ndarray]]:
    """One panel per map for the decay-rate map figure: the FMU's b [1/s] on (k, c) and the linear
    response's b0 + share on an ``n_fine`` x ``n_fine`` logarithmic grid over the same ranges."""
    panels = {}
    for dmap in maps:
        kf, cf, bf = linear_response_grid(
            spectrum, dmap.b_base, (dmap.k[0], dmap.k[-1]), (dmap.c[0], dmap.c[-1]), dmap.m_s, n_fine
        )
        panel = {"k": dmap.k, "c": dmap.c, "b": dmap.b, "m_s": dmap.m_s, "k_fine": kf, "c_fine": cf, "b_fine": bf}
        panels[f"M_s = {dmap.m_s:g} kg"] = panel
    return panels


def predicted_cuts(
    dmap: DecayMap, spectrum: ForceSpectrum, n_c: int = 80
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``n_c`` values of c over the map's range and, per k of the map, the predicted suspension shares
    [1/s] there: the linear response and the stiff limit -c <|dF/dt|^2> / (k^2 mean E)."""
    c_fine = np.geomspace(dmap.c[0], dmap.c[-1], n_c)
    lr = np.array([[spectrum.linear_response_rate(k, c, dmap.m_s) for c in c_fine] for k in dmap.k])
    qs = np.array([[spectrum.quasi_static_rate(k, c) for c in c_fine] for k in dmap.k])
    return c_fine, lr, qs


def natural_frequency_marks(spectrum: ForceSpectrum, ident: Identification) -> dict[str, float]:
    """The suspension's natural frequencies [rad/s] at the assumed k and M_s of the fit ``ident`` (both assumed, not
    measured), labelled, to mark in the force spectrum."""
    w_x, w_y = math.sqrt(ident.k / ident.m_s), math.sqrt(ident.k / (ident.m_s + spectrum.m12))
    assumed = f"at the assumed k = {ident.k:g} N/m, M_s = {ident.m_s:g} kg"
    return {
        f"horizontal omega_n,x = sqrt(k/M_s) = {w_x:.0f} rad/s {assumed}": w_x,
        f"vertical omega_n,y = sqrt(k/(M_s+m1+m2)) = {w_y:.0f} rad/s {assumed}": w_y,
    }


SPECTRUM_SHOWN_FROM = 1.0
"""Lowest angular frequency [rad/s] shown: below it, the Welch window's leakage of the decaying mean."""


def shown_force_spectra(spectrum: ForceSpectrum) -> tuple[np.ndarray, dict[str, np.ndarray]]:
    """omega [rad/s] from :data:`SPECTRUM_SHOWN_FROM` and the PSDs of F_x, F_y [N^2 s/rad] there."""
    shown = spectrum.omega >= SPECTRUM_SHOWN_FROM
    return spectrum.omega[shown], {"horizontal pivot force F_x": spectrum.s_x[shown],
                                   "vertical pivot force F_y": spectrum.s_y[shown]}


def energy_fit_inputs(md: MeasuredDecay, runs: Mapping[str, np.ndarray]) -> dict[str, Any]:
    """Arguments of :func:`double_pendulum.plots.plot_energy_decay` for the measured energy and the runs.

    The whole record (t [s], E [J]) with errors sigma [J] on the fitted frames (NaN elsewhere) and the
    mask ``used`` of those frames; each run's E_pendulum as the curve "FMU, <label>" on the frame times
    ``t_curve`` = t0 + n / FPS.
    """
    full_t = md.rec.t
    used = np.zeros(len(full_t), dtype=bool)
    used[md.i0 + md.frames.offsets] = True
    sigma = np.full(len(full_t), np.nan)
    sigma[used] = md.frames.sigma
    return {
        "t": full_t,
        "energy": md.rec.energy,
        "sigma": sigma,
        "curves": {f"FMU, {label}": np.asarray(r["E_pendulum"]) for label, r in runs.items()},
        "t_curve": md.frames.t0 + np.arange(md.frames.n_frames) * FRAME_INTERVAL,
        "used": used,
    }
