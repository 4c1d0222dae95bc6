"""The measured energy decay: decay fits and the circle fit of the pivot."""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

from .style import legend_below, legend_outside, save


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
    fig, axes = plt.subplots(rows, 1, figsize=(11, 4 + 2.5 * (rows - 1)), squeeze=False, sharex=True)
    ax = axes[0, 0]
    ax.errorbar(t[used], energy[used], yerr=sigma[used], fmt=".", ms=2, lw=0.5, alpha=0.6, label="measured")
    skip = ~used & np.isfinite(energy)
    if skip.any():
        ax.plot(t[skip], energy[skip], "x", color="0.5", ms=4, label="not fitted")
    for label, values in curves.items():
        ax.plot(t_curve, values, lw=1.5, label=label)
    ax.set(ylabel="energy E [J]", title="energy of the measured pendulum with fitted decay curves")
    legend_outside(ax)
    ax.grid(alpha=0.3)
    if residual_curve:
        ax_r = axes[1, 0]
        model = np.interp(t[used], t_curve, curves[residual_curve])
        ax_r.plot(t[used], (energy[used] - model) / sigma[used], ".", ms=2)
        ax_r.axhline(0.0, color="k", lw=0.8)
        ax_r.set(ylabel="(E - fit) / sigma [-]",
                 title=f"normalised residuals against {residual_curve}")
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
    for x, y, label, alpha in ((x2, y2, "lower bob", 0.5), (x1, y1, "upper bob", 1.0)):
        dots = ax.plot(x[valid], y[valid], ".", ms=1.5, alpha=alpha)[0]
        ax.plot([], [], ".", ms=7, color=dots.get_color(), label=label)  # a legend marker large enough to see
    ax.plot(l1 * np.sin(ang), -l1 * np.cos(ang), "k-", lw=0.6, label=f"fit, l1 = {1e3 * l1:.1f} mm")
    if not valid.all():
        ax.plot(x1[~valid], y1[~valid], "rx", ms=5, label=f"flagged frames ({np.count_nonzero(~valid)})")
    ax.plot([0.0], [0.0], "k+", ms=12, mew=1.5, label="fitted pivot")
    ax.set(xlabel="x [m]", ylabel="y [m]", aspect="equal", title="track relative to the fitted pivot")
    ax.grid(alpha=0.3)
    legend_below(fig, *ax.get_legend_handles_labels(), ncols=5)
    for ax, r, length, name in (
        (axes[1], np.hypot(x1, y1), l1, "r1 - l1 (upper bob to pivot)"),
        (axes[2], np.hypot(x2 - x1, y2 - y1), l2, "|r2 - r1| - l2 (between the bobs)"),
    ):
        ax.plot(t[valid], 1e3 * (r[valid] - length), ".", ms=2)
        ax.plot(t[~valid], 1e3 * (r[~valid] - length), "rx", ms=5)
        ax.axhline(0.0, color="k", lw=0.8)
        ax.set(xlabel="t [s]", ylabel="rod-length residual [mm]", title=name)
        ax.grid(alpha=0.3)
    return save(fig, path)
