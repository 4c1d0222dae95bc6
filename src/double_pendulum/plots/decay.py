"""The measured energy decay and the suspension: decay fits, circle fit, decay-rate maps, force
spectrum, energy flow."""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

from .style import running_mean, save


def plot_energy_decay(
    t: np.ndarray,
    energy: np.ndarray,
    sigma: np.ndarray,
    curves: Mapping[str, np.ndarray],
    t_curve: np.ndarray,
    path: str | Path,
    *,
    used: np.ndarray | None = None,
    residual_curve: str | None = None,
) -> Path:
    """Measured energy [J] with error bars over time [s] and fitted decay curves (the seed's fig. 7).

    ``curves`` maps a label to the curve's values on ``t_curve``; frames with ``used`` false are
    drawn grey (not fitted). With ``residual_curve`` a lower panel shows (E - curve) / sigma.
    """
    used = np.isfinite(energy) if used is None else used & np.isfinite(energy)
    rows = 2 if residual_curve else 1
    fig, axes = plt.subplots(rows, 1, figsize=(10, 4 + 2.5 * (rows - 1)), squeeze=False, sharex=True)
    ax = axes[0, 0]
    ax.errorbar(t[used], energy[used], yerr=sigma[used], fmt=".", ms=2, lw=0.5, alpha=0.6, label="measured")
    skip = ~used & np.isfinite(energy)
    if skip.any():
        ax.plot(t[skip], energy[skip], "x", color="0.5", ms=4, label="not fitted")
    for label, values in curves.items():
        ax.plot(t_curve, values, lw=1.5, label=label)
    ax.set(ylabel="E [J]", title="energy of the measured pendulum")
    ax.legend(loc="upper right", fontsize=8)
    ax.grid(alpha=0.3)
    if residual_curve:
        ax_r = axes[1, 0]
        model = np.interp(t[used], t_curve, curves[residual_curve])
        ax_r.plot(t[used], (energy[used] - model) / sigma[used], ".", ms=2)
        ax_r.axhline(0.0, color="k", lw=0.8)
        ax_r.set(ylabel=f"(E - {residual_curve}) / sigma", title="normalised residuals")
        ax_r.grid(alpha=0.3)
    axes[-1, 0].set_xlabel("t [s]")
    return save(fig, path)


def plot_circle_fit(
    x1: np.ndarray,
    y1: np.ndarray,
    x2: np.ndarray,
    y2: np.ndarray,
    t: np.ndarray,
    l1: float,
    l2: float,
    path: str | Path,
    *,
    valid: np.ndarray | None = None,
) -> Path:
    """Track in pivot coordinates [m] with the fitted circle, and the rod-length residuals [mm] over time [s].

    Positions are relative to the fitted pivot; flagged frames (``valid`` false) are marked red.
    """
    valid = np.ones(len(t), dtype=bool) if valid is None else valid
    fig, axes = plt.subplots(1, 3, figsize=(15, 4.5), gridspec_kw={"width_ratios": [1, 1.4, 1.4]})
    ax = axes[0]
    phi = np.arctan2(x1[valid], -y1[valid])
    ang = np.linspace(phi.min() - 0.3, phi.max() + 0.3, 200)
    ax.plot(x2[valid], y2[valid], ".", ms=1.5, alpha=0.5, label="lower bob")
    ax.plot(x1[valid], y1[valid], ".", ms=1.5, label="upper bob")
    ax.plot(l1 * np.sin(ang), -l1 * np.cos(ang), "k-", lw=0.6, label=f"fit, l1 = {1e3 * l1:.1f} mm")
    ax.plot(x1[~valid], y1[~valid], "rx", ms=5, label="flagged")
    ax.plot([0.0], [0.0], "k+", ms=10, label="fitted pivot")
    ax.set(xlabel="x [m]", ylabel="y [m]", aspect="equal", title="track relative to the fitted pivot")
    ax.legend(loc="upper center", fontsize=7, ncols=2)
    ax.grid(alpha=0.3)
    for ax, r, length, name in (
        (axes[1], np.hypot(x1, y1), l1, "r1 - l1 (upper bob to pivot)"),
        (axes[2], np.hypot(x2 - x1, y2 - y1), l2, "|r2 - r1| - l2 (between the bobs)"),
    ):
        ax.plot(t[valid], 1e3 * (r[valid] - length), ".", ms=2)
        ax.plot(t[~valid], 1e3 * (r[~valid] - length), "rx", ms=5)
        ax.axhline(0.0, color="k", lw=0.8)
        ax.set(xlabel="t [s]", ylabel="residual [mm]", title=name)
        ax.grid(alpha=0.3)
    return save(fig, path)


def plot_decay_rate_map(
    panels: Mapping[str, Mapping[str, np.ndarray]],
    levels: Mapping[str, float],
    path: str | Path,
    *,
    points: Mapping[str, tuple[float, float]] | None = None,
    slope_through: tuple[float, float] | None = None,
) -> Path:
    """Decay rate b [1/s] over suspension stiffness k [N/m] and damping c [N s/m], one panel per map.

    Each panel maps ``k``, ``c`` (1-D) and ``b`` (shape (len(k), len(c))), optionally a finer
    prediction ``k_fine``, ``c_fine``, ``b_fine`` drawn as dotted contours. ``levels`` label the
    solid/dashed iso-b contours; ``points`` mark (k, c) pairs and ``slope_through`` draws c ~ k^2
    through a point (the stiff-suspension law), both on the first panel only.
    """
    n = len(panels)
    fig, axes = plt.subplots(1, n, figsize=(6.2 * n, 5.2), squeeze=False)
    styles = ("-", "--", "-.", ":")
    all_b = np.concatenate([np.ravel(p["b"]) for p in panels.values()])
    vmin, vmax = float(np.min(all_b)), float(np.max(all_b))
    for ax, (title, p) in zip(axes[0], panels.items()):
        b = np.asarray(p["b"]).T
        mesh = ax.pcolormesh(p["k"], p["c"], b, shading="nearest", cmap="viridis", vmin=vmin, vmax=vmax)
        for (label, level), ls in zip(levels.items(), styles):
            if np.min(p["b"]) < level < np.max(p["b"]):
                ax.contour(p["k"], p["c"], np.asarray(p["b"]).T, levels=[level], colors="w", linestyles=ls)
                ax.plot([], [], color="k", ls=ls, label=f"{label}: b = {level:.4f} 1/s")
            if "b_fine" in p and np.min(p["b_fine"]) < level < np.max(p["b_fine"]):
                b_fine = np.asarray(p["b_fine"]).T
                ax.contour(p["k_fine"], p["c_fine"], b_fine, levels=[level], colors="r", linestyles=":")
        if "b_fine" in p:
            ax.plot([], [], "r:", label="linear response (fixed-pivot force spectrum)")
        first = ax is axes[0, 0]
        if slope_through is not None and first:
            k0, c0 = slope_through
            ks = np.asarray(p["k"], dtype=float)
            ax.plot(ks, c0 * (ks / k0) ** 2, color="orange", lw=1.0, label="c ~ k^2 (stiff limit)")
        for (label, (k, c)), marker in zip((points or {}).items() if first else (), "o^sDv"):
            ax.plot([k], [c], marker, color="r", mec="k", ms=7, label=label)
        ax.set(xscale="log", yscale="log", xlabel="k [N/m]", ylabel="c [N s/m]", title=title)
        ax.set_xlim(np.min(p["k"]) / 1.2, np.max(p["k"]) * 1.2)
        ax.set_ylim(np.min(p["c"]) / 1.5, np.max(p["c"]) * 1.5)
        ax.legend(loc="upper right", fontsize=6)
        fig.colorbar(mesh, ax=ax, label="b [1/s] of E_pendulum")
    return save(fig, path)


def plot_decay_rate_cuts(
    k_values: np.ndarray,
    c_values: np.ndarray,
    b_suspension: np.ndarray,
    c_fine: np.ndarray,
    b_linear_fine: np.ndarray,
    b_quasi_static_fine: np.ndarray,
    target: float,
    path: str | Path,
) -> Path:
    """The suspension's share -(b - b0) [1/s] over c at fixed k: FMU (markers), linear response (lines),
    stiff limit c <|dF/dt|^2> / (k^2 E) (dashed), and the share the measurement needs (black)."""
    fig, ax = plt.subplots(figsize=(9, 6))
    colours = plt.cm.plasma(np.linspace(0.0, 0.9, len(k_values)))
    for i, (k, col) in enumerate(zip(k_values, colours)):
        ax.loglog(c_values, -b_suspension[i], "o", color=col, label=f"k = {k:.3g} N/m")
        ax.loglog(c_fine, -b_linear_fine[i], "-", color=col, lw=1.0)
        ax.loglog(c_fine, -b_quasi_static_fine[i], "--", color=col, lw=0.7)
    ax.axhline(-target, color="k", lw=1.2, label=f"needed: {-target:.4f} 1/s")
    finite = -b_suspension[np.isfinite(b_suspension) & (b_suspension < 0)]
    if finite.size:
        ax.set_ylim(max(finite.min() / 3.0, 1e-6), finite.max() * 3.0)
    ax.set(xlabel="c [N s/m]", ylabel="-(b - b0) [1/s]", title="suspension share of the decay rate (FMU: markers; "
           "linear response: lines; stiff limit: dashed)")
    ax.legend(fontsize=7, ncols=2)
    ax.grid(alpha=0.3, which="both")
    return save(fig, path)


def plot_force_spectrum(
    omega: np.ndarray, spectra: Mapping[str, np.ndarray], marks: Mapping[str, float], path: str | Path
) -> Path:
    """Power spectral densities S(omega) [N^2 s/rad] of the pivot force and omega^2 S (its rate), log-log,
    with vertical lines at ``marks`` (e.g. suspension natural frequencies [rad/s])."""
    fig, axes = plt.subplots(1, 2, figsize=(13, 4.8))
    for label, s in spectra.items():
        axes[0].loglog(omega, s, lw=0.8, label=label)
        axes[1].loglog(omega, omega**2 * s, lw=0.8, label=label)
    for ax in axes:
        for (label, w), ls in zip(marks.items(), ("--", ":", "-.", "-")):
            ax.axvline(w, color="k", ls=ls, lw=0.8, label=label)
        ax.set_xlabel("omega [rad/s]")
        ax.grid(alpha=0.3, which="both")
        ax.legend(fontsize=7)
    axes[0].set(ylabel="S_F [N^2 s/rad]", title="pivot force spectrum (fixed pivot)")
    axes[1].set(ylabel="omega^2 S_F [N^2/(s rad)]", title="spectrum of dF/dt (what a stiff damper sees)")
    for ax in axes:
        top = max(float(np.max(line.get_ydata())) for line in ax.get_lines() if len(line.get_ydata()) > 2)
        ax.set_ylim(top * 1e-8, top * 3.0)
    return save(fig, path)


def plot_energy_flow(
    runs: Mapping[str, np.ndarray], path: str | Path, *, smooth_s: float = 1.0, zoom_s: float = 0.5
) -> Path:
    """How the pendulum's energy reaches the suspension: P_to_suspension [W] averaged over ``smooth_s``
    and unaveraged over the first ``zoom_s`` seconds, E_suspension [J], and the cumulative budget:
    pendulum energy lost, W_suspension, W_air + W_bearing and E_suspension + W_suspension [J]."""
    fig, axes = plt.subplots(4, 1, figsize=(11, 13))
    colours = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    for (label, r), col in zip(runs.items(), colours):
        t = r["time"]
        dt = float(t[1] - t[0])
        p = r["P_to_suspension"]
        mean = running_mean(p, round(smooth_s / dt))
        axes[0].plot(t, mean, color=col, lw=1.5, label=f"{label} ({smooth_s:g} s mean)")
        z = t <= t[0] + zoom_s
        axes[1].plot(t[z], p[z], color=col, lw=1.0, label=label)
        e_s = np.asarray(r["E_suspension"])
        axes[2].semilogy(t, np.maximum(e_s, 1e-4 * e_s.max()), color=col, lw=0.5, label=label)
        axes[3].plot(t, r["E_pendulum"][0] - r["E_pendulum"], color=col, lw=1.5, label=f"{label}: pendulum energy lost")
        axes[3].plot(t, r["W_suspension"], color=col, ls="--", label=f"{label}: W_suspension")
        axes[3].plot(t, r["W_air"] + r["W_bearing"], color=col, ls=":", label=f"{label}: W_air + W_bearing")
        axes[3].plot(t, r["E_suspension"] + r["W_suspension"], color=col, lw=0.6, alpha=0.6)
    axes[0].set(ylabel="P_to_suspension [W]", title=f"power from the pendulum into the suspension, {smooth_s:g} s mean")
    axes[1].set(ylabel="P_to_suspension [W]", title=f"first {zoom_s:g} s, unaveraged: energy pumped in and taken back")
    axes[2].set(ylabel="E_suspension [J]", title="energy stored in the suspension")
    axes[3].set(xlabel="t [s]", ylabel="energy [J]", title="cumulative: lost by the pendulum, dissipated "
                "(thin: E_suspension + W_suspension = integral of P_to_suspension)")
    for ax in axes:
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7, loc="upper left")
    return save(fig, path)
