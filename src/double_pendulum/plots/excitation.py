"""The pendulum driven through its inputs: Kapitza's threshold, Acheson's stability map, resonance curves."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import matplotlib.pyplot as plt
import numpy as np

from .style import legend_below, save


def _deviation(phi: np.ndarray) -> np.ndarray:
    """Angle from upright [rad], wrapped into [-pi, pi)."""
    return np.mod(phi, 2.0 * np.pi) - np.pi


def plot_kapitza_threshold(
    probes: Sequence[Mapping[str, Any]],
    theory: tuple[np.ndarray, np.ndarray],
    lines: Mapping[str, float],
    runs: Mapping[str, np.ndarray],
    theta0: float,
    path: str | Path,
) -> Path:
    """Left: the Floquet exponent [1/s] of each bisection probe (from the simulated monodromy matrix) against
    the amplitude [mm], the linear theory's exponent (``theory``: amplitudes [m], exponents [1/s]) and the
    threshold lines (``lines``: label -> amplitude [m]). Right: the upper rod's tilt over its start tilt
    against time [s] for the example runs (``runs``: label -> result)."""
    fig, (ax, bx) = plt.subplots(1, 2, figsize=(12.5, 5.2))
    a = np.array([p["amplitude_m"] for p in probes]) * 1e3
    exponent = np.array([p["floquet_exponent_per_s"] for p in probes])
    stable = np.array([p["stable"] for p in probes])
    ax.plot(theory[0] * 1e3, theory[1], color="0.6", lw=2.5, label="linear theory, input held over each step")
    ax.plot(a[stable], exponent[stable], "o", color="tab:green",
            label="simulated: stable (multipliers on the unit circle)")
    ax.plot(a[~stable], exponent[~stable], "x", color="tab:red", ms=8, label="simulated: unstable")
    for (label, value), style in zip(lines.items(), (":", "-.", "--", "-")):
        ax.axvline(value * 1e3, color="k", ls=style, lw=1.0, label=f"{label}: {value * 1e3:.3f} mm")
    ax.set_xlim(theory[0][0] * 1e3, theory[0][-1] * 1e3)
    ax.set_xlabel("vibration amplitude a [mm]")
    ax.set_ylabel("Floquet exponent ln(largest |multiplier|) / period [1/s]")
    ax.set_title("Growth rate of the upright position (monodromy matrix through the FMU)", fontsize=10)
    ax.legend(fontsize=7.5, loc="upper right", framealpha=0.95)
    for label, result in runs.items():
        bx.plot(result["time"], _deviation(result["phi1"]) / theta0, lw=0.8, label=label)
    bx.set_xlabel("time [s]")
    bx.set_ylabel("upper rod tilt from upright / start tilt")
    bx.set_ylim(-6.0, 12.0)
    bx.set_title("Upper rod just below and above the threshold", fontsize=10)
    bx.legend(fontsize=8, loc="upper left")
    fig.suptitle("Kapitza's inverted pendulum (single-pendulum limit, omega = 50 rad/s): threshold of the upright"
                 " position")
    return save(fig, path)


def plot_stability_map(
    rows: Sequence[Mapping[str, Any]],
    omega_curve: np.ndarray,
    boundaries: Mapping[str, np.ndarray],
    path: str | Path,
) -> Path:
    """Upright-stable (green) and unstable (red) grid points over frequency [rad/s] and amplitude [mm],
    with the theoretical boundaries (``boundaries``: label -> amplitude [m] on ``omega_curve``)."""
    fig, ax = plt.subplots(figsize=(10, 7))
    w = np.array([r["omega_rad_per_s"] for r in rows])
    a = np.array([r["amplitude_m"] for r in rows]) * 1e3
    ok = np.array([r["stable"] for r in rows])
    ax.scatter(w[ok], a[ok], s=60, marker="s", color="tab:green",
               label="simulated: upright stable (Floquet multipliers of one period)")
    ax.scatter(w[~ok], a[~ok], s=40, marker="x", color="tab:red", label="simulated: upright unstable")
    for (label, values), (color, style) in zip(boundaries.items(), (("k", "-"), ("tab:blue", "--"), ("k", ":"))):
        ax.plot(omega_curve, values * 1e3, color=color, ls=style, lw=1.6, label=label)
    ax.set_xlim(omega_curve[0], omega_curve[-1])
    ax.set_ylim(0, 1.08 * a.max())
    ax.set_xlabel("vibration angular frequency omega [rad/s]")
    ax.set_ylabel("vibration amplitude a [mm]")
    ax.set_title("Inverted double pendulum on a vertically vibrated pivot: is the upright position stable?")
    ax.legend(fontsize=8, loc="upper center", bbox_to_anchor=(0.5, -0.1), ncol=2)
    return save(fig, path)


def plot_upright_runs(runs: Mapping[str, np.ndarray], path: str | Path) -> Path:
    """Both rods' tilt from upright [rad] over time [s] for a few runs (``runs``: label -> result)."""
    fig, axes = plt.subplots(len(runs), 1, figsize=(10, 2.4 * len(runs)), sharex=True, squeeze=False)
    for ax, (label, result) in zip(axes[:, 0], runs.items()):
        ax.plot(result["time"], _deviation(result["phi1"]), lw=0.8, label="upper rod")
        ax.plot(result["time"], _deviation(result["phi2"]), lw=0.8, label="lower rod")
        ax.set_ylabel("tilt [rad]")
        ax.set_title(label, fontsize=9)
        ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    axes[-1, 0].set_xlabel("time [s]")
    fig.suptitle("Inverted double pendulum on a vibrated pivot: tilt from upright (through the FMU)")
    return save(fig, path)


HEADROOM = 6.0
"""The resonance curve's log axis reaches this factor above the largest amplitude: the band above the data holds the
mode labels and the theory's crosses, clear of the curves."""


def plot_resonance_curve(
    rows: Sequence[Mapping[str, Any]],
    modes: Sequence[float],
    peaks: Sequence[Mapping[str, Any]],
    torque: float,
    path: str | Path,
) -> Path:
    """Steady-state amplitudes of both angles [rad] against the drive frequency [rad/s], the undamped
    small-angle normal modes (dashed, labelled), the fitted peaks (dotted) and the damped linear response's peaks
    (crosses), the labels and crosses in a band above the data (:data:`HEADROOM`); the legend under the axes."""
    fig, ax = plt.subplots(figsize=(10.5, 5.2))
    rows = sorted(rows, key=lambda r: r["omega_rad_per_s"])
    w = np.array([r["omega_rad_per_s"] for r in rows])
    top = 0.0
    for angle, color, label in (("phi1", "tab:blue", "upper rod phi1"), ("phi2", "tab:orange", "lower rod phi2")):
        amplitude = np.array([r[f"{angle}_amplitude_rad"] for r in rows])
        ax.semilogy(w, amplitude, "o-", ms=3, color=color, label=f"{label}: simulated amplitude")
        top = max(top, float(np.nanmax(amplitude)))
    low = ax.get_ylim()[0]
    ax.set_ylim(low, top * HEADROOM)
    for mode, name in zip(modes, ("slow", "fast")):
        ax.axvline(mode, color="k", ls="--", lw=0.8)
        ax.annotate(f"{name} normal mode {mode:.3f} rad/s", (mode, 0.985), xycoords=("data", "axes fraction"),
                    xytext=(6, 0), textcoords="offset points", fontsize=8, va="top")
    for p in peaks:
        color = "tab:blue" if p["angle"] == "phi1" else "tab:orange"
        if np.isfinite(p["peak_rad_per_s"]):
            ax.axvline(p["peak_rad_per_s"], color=color, ls=":", lw=0.8)
        ax.plot(p["damped_linear_peak_rad_per_s"], 0.84, "x", color=color, ms=7, transform=ax.get_xaxis_transform())
    ax.plot([], [], "k--", lw=0.8, label="undamped normal mode")
    ax.plot([], [], ":", color="0.3", lw=0.8, label="fitted peak of the simulated curve (rod's colour)")
    ax.plot([], [], "x", color="0.3", ms=7, label="peak of the damped linear theory (rod's colour)")
    ax.set_xlabel("drive angular frequency omega [rad/s]")
    ax.set_ylabel("steady-state amplitude [rad]")
    ax.set_title(f"Resonance under a pivot torque {torque * 1e3:g} mN m x sin(omega t), viscous pivot bearing",
                 fontsize=10)
    legend_below(fig, *ax.get_legend_handles_labels(), ncols=2, fontsize=8)
    return save(fig, path)
