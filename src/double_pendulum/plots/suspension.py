"""The pivot suspension: decay-rate maps and cuts, the pendulum's force spectrum, the energy flow."""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
from matplotlib import patheffects
from matplotlib.colors import Normalize
from matplotlib.ticker import FuncFormatter, LogLocator

from .style import legend_below, legend_outside, running_mean, save

MAP_CMAP = "viridis"
DISPLAY_POINTS = 160  # display grid per axis of the interpolated decay-rate field
_OUTLINE = [patheffects.withStroke(linewidth=3.2, foreground="k")]  # white contour lines, visible on any colour


def smooth_log_field(
    k: np.ndarray, c: np.ndarray, b: np.ndarray, n: int = DISPLAY_POINTS
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``b`` (shape (len(k), len(c))) interpolated on an ``n`` x ``n`` grid, logarithmic in k and c, for display.

    The interpolation runs over (log k, log c), on log(-b) where every b is negative (decay), else on b:
    piecewise cubic monotone (PCHIP, no overshoots) along log k, then along log c (a tensor product,
    vectorised); linear along an axis with fewer than 3 points. Returns the display k, c (1-D) and the
    field (n, n).
    """
    lk, lc, b = np.log(np.asarray(k, float)), np.log(np.asarray(c, float)), np.asarray(b, float)
    decaying = bool(np.all(b < 0.0))
    values = np.log(-b) if decaying else b
    gk, gc = np.linspace(lk[0], lk[-1], n), np.linspace(lc[0], lc[-1], n)
    field = _interp_axis(_interp_axis(values, lk, gk, axis=0), lc, gc, axis=1)
    return np.exp(gk), np.exp(gc), -np.exp(field) if decaying else field


def _interp_axis(values: np.ndarray, x: np.ndarray, x_new: np.ndarray, axis: int) -> np.ndarray:
    """``values`` interpolated along ``axis`` from ``x`` to ``x_new``: PCHIP with 3 or more points, else linear."""
    from scipy.interpolate import PchipInterpolator, interp1d  # noqa: PLC0415 - only the decay-rate map needs it

    if x.size >= 3:
        return PchipInterpolator(x, values, axis=axis)(x_new)
    return interp1d(x, values, axis=axis)(x_new)


def _panel_order(panels: Mapping[str, Mapping[str, np.ndarray]]) -> list[str]:
    """Panel titles ordered by the suspension mass ``m_s`` [kg] where the panels give it, else as given."""
    return sorted(panels, key=lambda title: float(panels[title].get("m_s", 0.0)))


MAP_MARGIN = 1.35
"""Factor by which a map's axes reach beyond its grid in k and c (log axes): markers on the grid's edge (the
resonant end of the iso-b curve lies on the lightest damping mapped) stay inside the axes; the margin shows
the axes' grey background, labelled "not mapped"."""
NOT_MAPPED = "0.88"
"""Axes background of a map outside the mapped (k, c) range."""
PIECE_FRACTION = 0.25
"""Pieces of the linear-response contour shorter than this fraction of its longest piece are not drawn."""


def _iso_b(ax: plt.Axes, k: np.ndarray, c: np.ndarray, b: np.ndarray, level: float, **style) -> bool:
    """Draw the iso-line b = ``level`` of ``b`` (shape (len(k), len(c))) if it crosses the panel."""
    if not np.nanmin(b) < level < np.nanmax(b):
        return False
    ax.contour(k, c, np.asarray(b).T, levels=[level], **style)
    return True


def contour_pieces(k: np.ndarray, c: np.ndarray, b: np.ndarray, level: float,
                   fraction: float = PIECE_FRACTION) -> list[np.ndarray]:
    """The pieces (arrays of (k, c) points) of the iso-line b = ``level`` of ``b`` (shape (len(k), len(c))) whose
    length in (log k, log c) is at least ``fraction`` of the longest piece's; none if the level is not crossed.

    For the linear-response prediction: at light damping its suspension resonance picks out single lines of the
    finite (Welch) force spectrum, and the iso-line breaks into short islands around them that belong to the
    spectrum's resolution, not to the prediction's curve."""
    if not np.nanmin(b) < level < np.nanmax(b):
        return []
    fig = plt.figure()  # a scratch figure: only the contour's paths are wanted
    try:
        cs = fig.add_subplot().contour(np.log(k), np.log(c), np.asarray(b).T, levels=[level])
        pieces = [seg for seg in cs.allsegs[0] if len(seg) > 1]
    finally:
        plt.close(fig)
    lengths = [float(np.sum(np.hypot(*np.diff(seg, axis=0).T))) for seg in pieces]
    longest = max(lengths, default=0.0)
    return [np.exp(seg) for seg, n in zip(pieces, lengths) if n >= fraction * longest]


def _decay_panel(ax: plt.Axes, p: Mapping[str, np.ndarray], levels: Mapping[str, float], norm: Normalize):
    """One mass: the interpolated field, the simulated grid, the iso-b contours and the linear response."""
    kd, cd, bd = smooth_log_field(p["k"], p["c"], p["b"])
    mesh = ax.pcolormesh(kd, cd, bd.T, shading="gouraud", cmap=MAP_CMAP, norm=norm, rasterized=True)
    kk, cc = np.meshgrid(p["k"], p["c"], indexing="ij")
    ax.plot(kk.ravel(), cc.ravel(), ".", color="0.85", ms=2.5, label="simulated (k, c) (FMU runs)")
    for (label, level), ls in zip(levels.items(), ("-", "--", "-.")):
        if _iso_b(ax, kd, cd, bd, level, colors="w", linestyles=ls, linewidths=1.6):
            ax.collections[-1].set_path_effects(_OUTLINE)
        ax.plot([], [], color="w", ls=ls, lw=1.6, path_effects=_OUTLINE, label=f"{label}: b = {level:.4f} 1/s")
    if "b_fine" in p and levels:
        first = next(iter(levels))
        for piece in contour_pieces(p["k_fine"], p["c_fine"], p["b_fine"], levels[first]):
            ax.plot(piece[:, 0], piece[:, 1], "r:", lw=1.4)
        ax.plot([], [], "r:", lw=1.4, label=f"{first}, linear-response prediction (fixed-pivot force spectrum)")
    ax.set(xscale="log", yscale="log", xlabel="suspension stiffness k [N/m]", facecolor=NOT_MAPPED)
    ax.set_xlim(kd[0] / MAP_MARGIN, kd[-1] * MAP_MARGIN)
    ax.set_ylim(cd[0] / MAP_MARGIN, cd[-1] * MAP_MARGIN)
    ax.fill([], [], color=NOT_MAPPED, label="not mapped")
    for axis in (ax.xaxis, ax.yaxis):  # numbers at 1, 2 and 5 per decade: a map within one decade has some too
        axis.set_major_locator(LogLocator(base=10.0, subs=(1.0, 2.0, 5.0)))
        axis.set_major_formatter(FuncFormatter(lambda value, _: f"{value:g}"))
    return mesh


def _mark_points(
    ax: plt.Axes, k_range: np.ndarray, points: Mapping[str, tuple[float, float]] | None,
    slope_through: tuple[float, float] | None,
) -> None:
    """The stiff-limit line c ~ k^2 through ``slope_through`` and the labelled (k, c) ``points``."""
    if slope_through is not None:
        k0, c0 = slope_through
        ks = np.geomspace(np.min(k_range), np.max(k_range), 50)
        ax.plot(ks, c0 * (ks / k0) ** 2, color="orange", lw=1.4, label="c ~ k^2 through the fitted point "
                "(stiff limit)")
    for (label, (k, c)), marker in zip((points or {}).items(), "o^sDv"):
        ax.plot([k], [c], marker, color="r", mec="k", ms=8, label=label, clip_on=False, zorder=5)


def _unique_handles(axes) -> tuple[list, list[str]]:
    """Legend handles and labels of all ``axes``, each label once."""
    seen: dict[str, object] = {}
    for ax in axes:
        for handle, label in zip(*ax.get_legend_handles_labels()):
            seen.setdefault(label, handle)
    return list(seen.values()), list(seen)


def plot_decay_rate_map(
    panels: Mapping[str, Mapping[str, np.ndarray]],
    levels: Mapping[str, float],
    path: str | Path,
    *,
    points: Mapping[str, tuple[float, float]] | None = None,
    slope_through: tuple[float, float] | None = None,
) -> Path:
    """Decay rate b [1/s] over suspension stiffness k [N/m] and damping c [N s/m], one panel per mass.

    Each panel maps ``k``, ``c`` (1-D), ``b`` (shape (len(k), len(c))) and optionally the suspension
    mass ``m_s`` [kg] (panels are ordered by it) and a finer linear-response prediction ``k_fine``,
    ``c_fine``, ``b_fine`` (its contour for the first of ``levels``, red dotted). The simulated b is shown
    interpolated smoothly in log b over log k, log c (:func:`smooth_log_field`) on one colour scale with
    a shared colour bar; the grey dots are the simulated grid. ``levels`` label the iso-b contours drawn
    on the interpolated field; ``points`` and ``slope_through`` (the c ~ k^2 stiff limit) belong to the
    first panel given. The legend sits under the panels.
    """
    main = next(iter(panels))
    order = _panel_order(panels)
    all_b = np.concatenate([np.ravel(p["b"]) for p in panels.values()])
    norm = Normalize(float(np.nanmin(all_b)), float(np.nanmax(all_b)))
    n = len(order)
    fig, axes = plt.subplots(1, n, figsize=(4.6 * n + 1.4, 5.0), squeeze=False, sharey=True, layout="constrained")
    for ax, title in zip(axes[0], order):
        mesh = _decay_panel(ax, panels[title], levels, norm)
        if title == main:
            _mark_points(ax, panels[title]["k"], points, slope_through)
            title += " (the assumed suspension mass)" if points else ""
        ax.set_title(title)
    axes[0, 0].set_ylabel("suspension damping c [N s/m]")
    fig.colorbar(mesh, ax=axes[0].tolist(), label="decay rate b of the pendulum energy, E ~ exp(b t) [1/s]",
                 shrink=0.95, pad=0.02)
    by_mass = ", by suspension mass" if len(panels) > 1 else ""
    fig.suptitle(f"decay rate of the pendulum energy over the suspension's stiffness and damping{by_mass}")
    legend_below(fig, *_unique_handles(axes[0]), ncols=2)
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
    ax.plot([], [], "-", color="0.4", lw=1.0, label="linear response (lines)")
    ax.plot([], [], "--", color="0.4", lw=0.7, label="stiff limit (dashed)")
    ax.set(xlabel="suspension damping c [N s/m]", ylabel="suspension share of the decay rate -(b - b0) [1/s]",
           title="suspension share of the decay rate at fixed stiffness k (FMU: markers)")
    legend_outside(ax)
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
        ax.set_xlabel("angular frequency omega [rad/s]")
        ax.grid(alpha=0.3, which="both")
    axes[0].set(ylabel="force power spectral density S_F [N^2 s/rad]", title="pivot force spectrum (fixed pivot)")
    axes[1].set(ylabel="spectral density of dF/dt, omega^2 S_F [N^2/(s rad)]",
                title="spectrum of dF/dt (what a stiff damper sees)")
    legend_below(fig, *axes[0].get_legend_handles_labels(), ncols=2)
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
    fig, axes = plt.subplots(4, 1, figsize=(12, 13))
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
    axes[0].set(ylabel="power into the suspension [W]",
                title=f"power from the pendulum into the suspension (P_to_suspension), {smooth_s:g} s mean")
    axes[1].set(ylabel="power into the suspension [W]",
                title=f"first {zoom_s:g} s, unaveraged: energy pumped in and taken back")
    axes[2].set(ylabel="stored energy E_suspension [J]", title="energy stored in the suspension")
    axes[3].set(xlabel="t [s]", ylabel="energy [J]", title="cumulative: lost by the pendulum, dissipated "
                "(thin: E_suspension + W_suspension = integral of P_to_suspension)")
    for ax in axes:
        ax.grid(alpha=0.3)
        legend_outside(ax, fontsize=7)
    return save(fig, path)
