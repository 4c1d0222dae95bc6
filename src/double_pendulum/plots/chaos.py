"""Chaos: ensembles, predictability, Lyapunov exponents, flip maps, Poincare sections."""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path

import matplotlib.colors
import matplotlib.pyplot as plt
import numpy as np

from .style import legend_below, legend_outside, save


def plot_lower_mass_traces(
    traces: Mapping[str, tuple[np.ndarray, np.ndarray]],
    path: str | Path,
    *,
    diverge: tuple[float, float] | None = None,
    title: str = "",
) -> Path:
    """Traces of the lower bob (x2, y2) [m], one panel per run and all overlaid (seed figs. 4-6).

    ``diverge`` marks the point (x2, y2) [m] where the runs part (the seed's red arrow).
    """
    n = len(traces)
    ncols = 2 if n + 1 <= 4 else 3
    nrows = -(-(n + 1) // ncols)
    fig, grid = plt.subplots(nrows, ncols, figsize=(4.6 * ncols, 2.7 * nrows + 0.7), squeeze=False, sharex=True,
                             sharey=True)
    axes = grid.ravel()
    colours = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    for i, (label, (x, y)) in enumerate(traces.items()):
        for ax in (axes[i], axes[n]):
            ax.plot(x, y, lw=0.7, color=colours[i % len(colours)], label=label)
        axes[i].set_title(label, fontsize=10)
    axes[n].set_title("all overlaid", fontsize=10)
    for ax in axes[: n + 1]:
        ax.plot([0], [0], "k+", ms=10)
        if diverge is not None:
            ax.annotate("", xy=diverge, xytext=(diverge[0] + 0.08, diverge[1] + 0.08),
                        arrowprops={"color": "red", "width": 1.5, "headwidth": 7})
        ax.set(aspect="equal")
        ax.grid(alpha=0.3)
    for ax in axes[n + 1:]:
        ax.set_visible(False)
    for ax in grid[-1]:
        ax.set_xlabel("lower bob x2 [m]")
    for ax in grid[:, 0]:
        ax.set_ylabel("lower bob y2 [m]")
    if title:
        fig.suptitle(f"paths of the lower bob: {title}")
    return save(fig, path)


def plot_ensemble_clouds(
    snapshots: Mapping[float, tuple[np.ndarray, np.ndarray]], path: str | Path, *, title: str = ""
) -> Path:
    """Positions of the lower bob [m] of every ensemble member at a few times: the cloud spreading."""
    n = len(snapshots)
    ncols = 3 if n > 4 else 2 if n > 1 else 1
    nrows = -(-n // ncols)
    fig, grid = plt.subplots(nrows, ncols, figsize=(3.6 * ncols, 2.5 * nrows + 0.7), squeeze=False, sharex=True,
                             sharey=True)
    axes = grid.ravel()
    for ax, (t, (x, y)) in zip(axes, snapshots.items()):
        ax.plot(x, y, ".", ms=2, alpha=0.6)
        ax.plot([0], [0], "k+", ms=8)
        ax.set(title=f"t = {t:g} s", aspect="equal")
        ax.grid(alpha=0.3)
    for ax in axes[n:]:
        ax.set_visible(False)
    for ax in grid[-1]:
        ax.set_xlabel("lower bob x2 [m]")
    for ax in grid[:, 0]:
        ax.set_ylabel("lower bob y2 [m]")
    fig.suptitle(f"lower bob of every ensemble member at a few times: {title}" if title
                 else "lower bob of every ensemble member at a few times")
    return save(fig, path)


def plot_ensemble_spread(
    times: np.ndarray,
    spreads: Mapping[str, np.ndarray],
    thresholds: list[float] | tuple[float, ...],
    path: str | Path,
) -> Path:
    """RMS spread [m] of the lower bob's position within each ensemble over time (log scale)."""
    fig, ax = plt.subplots(figsize=(9, 5))
    for label, s in spreads.items():
        ax.semilogy(times, np.maximum(s, 1e-12), lw=1.0, label=label)
    for d in thresholds:
        ax.axhline(d, color="k", ls="--", lw=0.8)
        ax.text(times[-1], d, f" {d * 100:g} cm", va="bottom", ha="right", fontsize=8)
    ax.set(xlabel="t [s]", ylabel="RMS spread of the lower bob's position [m]",
           title="spread of release ensembles over time, by start uncertainty sigma")
    legend_outside(ax)
    ax.grid(alpha=0.3, which="both")
    return save(fig, path)


def plot_predictability(
    sigmas: np.ndarray, horizons: Mapping[str, np.ndarray], lyapunov: float, path: str | Path
) -> Path:
    """Predictability horizon [s] against the start uncertainty [m], with the slope -1/lambda."""
    fig, ax = plt.subplots(figsize=(7, 5))
    for label, hz in horizons.items():
        line = ax.semilogx(sigmas, hz, "o-", label=label)[0]
        ok = np.isfinite(hz)
        if np.count_nonzero(ok) >= 2 and lyapunov > 0:
            anchor = np.argmax(ok)
            guide = hz[anchor] - np.log(sigmas / sigmas[anchor]) / lyapunov
            ax.semilogx(sigmas, guide, ":", color=line.get_color(), lw=1)
    ax.set(
        xlabel="start uncertainty sigma [m]",
        ylabel="predictability horizon [s]",
        title=f"predictability horizon vs start uncertainty\n(dotted: slope -1/lambda, lambda = {lyapunov:.2f} 1/s)",
    )
    legend_outside(ax)
    ax.grid(alpha=0.3, which="both")
    return save(fig, path)


def plot_lyapunov_convergence(
    curves: Mapping[str, tuple[np.ndarray, np.ndarray]], path: str | Path, *, title: str = ""
) -> Path:
    """Running Benettin estimates lambda(t) [1/s] against the averaging time t [s]."""
    fig, ax = plt.subplots(figsize=(8, 5))
    for label, (t, lam) in curves.items():
        ax.semilogx(t, lam, lw=1.0, label=label)
    ax.axhline(0.0, color="k", lw=0.6)
    ax.set(xlabel="averaging time t [s]", ylabel="largest Lyapunov exponent estimate lambda(t) [1/s]",
           title=f"convergence of the largest Lyapunov exponent: {title}" if title else "convergence of lambda")
    legend_below(fig, *ax.get_legend_handles_labels(), ncols=1)  # long labels: below, as wide as the axes
    ax.grid(alpha=0.3, which="both")
    return save(fig, path)


def plot_lyapunov_vs_energy(
    theta0: np.ndarray, energy_ratio: np.ndarray, lam: np.ndarray, path: str | Path
) -> Path:
    """Largest exponent [1/s] against the release angle theta0 [rad] (phi1 = phi2 = theta0, at rest)."""
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(12, 4.5))
    ax1.plot(theta0, lam, "o-")
    ax1.set(xlabel="release angle theta0 = phi1 = phi2 [rad]", ylabel="largest Lyapunov exponent lambda [1/s]",
            title="largest Lyapunov exponent, released from rest")
    ax2.plot(energy_ratio, lam, "o-")
    ax2.axvline(1.0, color="r", ls="--", lw=0.8, label="E = E_flip (a rod can flip)")
    ax2.set(xlabel="energy relative to the flip energy E / E_flip [-]", ylabel="largest Lyapunov exponent lambda [1/s]",
            title="against the energy")
    ax2.legend(fontsize=8, loc="upper left")
    for ax in (ax1, ax2):
        ax.grid(alpha=0.3)
    return save(fig, path)


def plot_lyapunov_spectrum(
    times: np.ndarray, running: np.ndarray, bound: np.ndarray, path: str | Path
) -> Path:
    """Running estimates of all four exponents [1/s] and of their sum, with the sum's bound."""
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(14, 4.8))
    for i in range(running.shape[1]):
        ax1.semilogx(times, running[:, i], label=f"lambda{i + 1}")
    ax1.axhline(0.0, color="k", lw=0.6)
    ax1.set(xlabel="averaging time t [s]", ylabel="Lyapunov exponent estimate [1/s]",
            title="running estimates of all four exponents (QR)")
    legend_outside(ax1)
    ax2.loglog(times, np.abs(running.sum(axis=1)), label="|sum of the exponents|")
    ax2.loglog(times, np.abs(running[:, 0] + running[:, -1]), label="|lambda1 + lambda4|")
    ax2.loglog(times, bound, "k--", label="bound ln((m1+m2)/m1) / t")
    ax2.set(xlabel="averaging time t [s]", ylabel="magnitude of the sum [1/s]",
            title="pairing check (lambda, 0, 0, -lambda): sums tend to 0")
    legend_outside(ax2)
    for ax in (ax1, ax2):
        ax.grid(alpha=0.3, which="both")
    return save(fig, path)


def plot_flip_map(
    phi1: np.ndarray,
    phi2: np.ndarray,
    flip_time: np.ndarray,
    energy: np.ndarray,
    threshold: float,
    path: str | Path,
    *,
    t_max: float,
) -> Path:
    """Time to the first flip [s] over the release angles (log colour), no flip in white.

    The black curve is V(phi1, phi2) = E_flip: inside it flipping is energetically impossible.
    """
    fig, ax = plt.subplots(figsize=(7.5, 6.5))
    extent = (phi1[0], phi1[-1], phi2[0], phi2[-1])
    masked = np.ma.masked_invalid(flip_time)
    image = ax.imshow(
        masked,
        origin="lower",
        extent=extent,
        cmap="viridis",
        norm=matplotlib.colors.LogNorm(vmin=max(np.nanmin(flip_time), 1e-2), vmax=t_max),
        interpolation="nearest",
        aspect="equal",
    )
    ax.contour(phi1, phi2, energy, levels=[threshold], colors="k", linewidths=1.2)
    ax.contourf(phi1, phi2, energy, levels=[energy.min() - 1.0, threshold], colors="none", hatches=["//"])
    fig.colorbar(image, ax=ax, label="time to the first flip [s]")
    ax.set(
        xlabel="phi1 at release [rad]",
        ylabel="phi2 at release [rad]",
        title=f"flip-time map (white: no flip in {t_max:g} s; hatched: E < E_flip)",
    )
    return save(fig, path)


def plot_poincare_sections(
    sections: Mapping[str, tuple[np.ndarray, np.ndarray, np.ndarray]], path: str | Path
) -> Path:
    """Poincare sections phi1 = 0, omega1 > 0: points (phi2 [rad], omega2 [rad/s]) per start, coloured by start.

    The section is stated in the figure's title; each panel's title names its energy.
    """
    n = len(sections)
    fig, axes = plt.subplots(1, n, figsize=(5.6 * n, 5.4), squeeze=False)
    for ax, (label, (phi2, omega2, owner)) in zip(axes[0], sections.items()):
        wrapped = np.angle(np.exp(1j * phi2))
        ax.scatter(wrapped, omega2, c=owner, s=3.0, cmap="tab20", linewidths=0)
        ax.set(title=label, xlabel="lower-rod angle phi2 [rad] (wrapped)",
               ylabel="lower-rod angular velocity omega2 [rad/s]")
        ax.grid(alpha=0.3)
    fig.suptitle("Poincare sections at fixed energy: the lower rod's state each time the upper rod passes\n"
                 "straight down (phi1 = 0 mod 2 pi) with omega1 > 0; one colour per start")
    return save(fig, path)


def plot_lyapunov_with_friction(
    centres: np.ndarray,
    local: np.ndarray,
    times: np.ndarray,
    energy_ratio: np.ndarray,
    path: str | Path,
    *,
    title: str = "",
) -> Path:
    """Finite-time largest exponent [1/s] per window and the energy E/E_flip as friction drains it."""
    fig, ax = plt.subplots(figsize=(9, 5))
    ax.step(centres, local, where="mid", color="C0", label="largest exponent in the window")
    ax.axhline(0.0, color="k", lw=0.6)
    ax.set(xlabel="t [s]", ylabel="largest Lyapunov exponent lambda [1/s]",
           title=title or "Lyapunov exponent as the motion decays")
    ax.grid(alpha=0.3)
    twin = ax.twinx()
    twin.plot(times, energy_ratio, color="C3", lw=1.0, label="E / E_flip")
    twin.axhline(1.0, color="C3", ls="--", lw=0.8)
    twin.set_ylabel("energy relative to the flip energy E / E_flip [-]", color="C3")
    lines = ax.get_legend_handles_labels()
    lines2 = twin.get_legend_handles_labels()
    legend_below(fig, lines[0] + lines2[0], lines[1] + lines2[1], ncols=2)
    return save(fig, path)
