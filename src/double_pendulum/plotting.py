"""Matplotlib figures for scenario results (headless Agg backend, PNG files)."""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402


def _save(fig: plt.Figure, path: str | Path) -> Path:
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path


def plot_angles(runs: Mapping[str, np.ndarray], path: str | Path) -> Path:
    """Angles phi1, phi2 [rad] over time, one panel per run."""
    fig, axes = plt.subplots(len(runs), 1, figsize=(9, 3 * len(runs)), squeeze=False)
    for ax, (label, r) in zip(axes[:, 0], runs.items()):
        ax.plot(r["time"], r["phi1"], label="phi1")
        ax.plot(r["time"], r["phi2"], label="phi2")
        ax.set(title=label, xlabel="t [s]", ylabel="angle [rad]")
        ax.legend(loc="upper right")
        ax.grid(alpha=0.3)
    return _save(fig, path)


def plot_traces(runs: Mapping[str, np.ndarray], path: str | Path) -> Path:
    """Paths of both bobs in the x-y plane (like the seed's long-exposure photographs)."""
    fig, axes = plt.subplots(1, len(runs), figsize=(5 * len(runs), 5), squeeze=False)
    for ax, (label, r) in zip(axes[0], runs.items()):
        ax.plot(r["x2"], r["y2"], lw=0.6, label="lower bob")
        ax.plot(r["x1"], r["y1"], lw=0.8, label="upper bob")
        ax.plot([0], [0], "k+", ms=10)
        ax.set(title=label, xlabel="x [m]", ylabel="y [m]", aspect="equal")
        ax.legend(loc="lower right", fontsize=8)
        ax.grid(alpha=0.3)
    return _save(fig, path)


def plot_energy(runs: Mapping[str, np.ndarray], path: str | Path) -> Path:
    """Energies [J] over time and the relative drift of the total energy."""
    fig, axes = plt.subplots(len(runs), 2, figsize=(12, 3 * len(runs)), squeeze=False)
    for (ax_e, ax_d), (label, r) in zip(axes, runs.items()):
        for name in ("E_kin", "E_pot", "E_total"):
            ax_e.plot(r["time"], r[name], label=name)
        ax_e.set(title=label, xlabel="t [s]", ylabel="energy [J]")
        ax_e.legend(loc="upper right", fontsize=8)
        ax_e.grid(alpha=0.3)
        e0 = r["E_total"][0]
        ax_d.plot(r["time"], (r["E_total"] - e0) / abs(e0))
        ax_d.set(title=f"{label}: (E_total - E0) / E0", xlabel="t [s]", ylabel="relative drift")
        ax_d.grid(alpha=0.3)
    return _save(fig, path)


def plot_phase_portraits(runs: Mapping[str, np.ndarray], path: str | Path) -> Path:
    """Phase portraits omega over phi for both rods (the seed's figs. 15/16)."""
    fig, axes = plt.subplots(len(runs), 2, figsize=(11, 4 * len(runs)), squeeze=False)
    for (ax1, ax2), (label, r) in zip(axes, runs.items()):
        for ax, k in ((ax1, "1"), (ax2, "2")):
            phi = np.angle(np.exp(1j * r[f"phi{k}"]))  # wrapped to (-pi, pi]
            ax.plot(phi, r[f"omega{k}"], ",", alpha=0.6)
            ax.set(title=f"{label}: rod {k}", xlabel=f"phi{k} [rad] (wrapped)", ylabel=f"omega{k} [rad/s]")
            ax.grid(alpha=0.3)
    return _save(fig, path)


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
    return _save(fig, path)


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
    return _save(fig, path)


def plot_energy_per_mechanism(runs: Mapping[str, np.ndarray], path: str | Path) -> Path:
    """E_total [J] over time [s] for each run, log scale (straight lines mean exponential decay)."""
    fig, ax = plt.subplots(figsize=(9, 5))
    for label, r in runs.items():
        ax.semilogy(r["time"], r["E_total"], label=label)
    ax.set(xlabel="t [s]", ylabel="E_total [J]", title="Energy of the pendulum and its suspension")
    ax.legend()
    ax.grid(alpha=0.3, which="both")
    return _save(fig, path)


def plot_energy_budget_stacked(result: np.ndarray, path: str | Path) -> Path:
    """Where the energy went: stacked E_pendulum, E_suspension and each W_* [J] over time [s]."""
    names = ("E_pendulum", "E_suspension", "W_air", "W_bearing", "W_suspension")
    fig, ax = plt.subplots(figsize=(9, 5))
    ax.stackplot(result["time"], *(result[n] for n in names), labels=names, alpha=0.85)
    ax.axhline(result["E_total"][0], color="k", lw=0.8, ls="--", label="E_total(0)")
    ax.set(xlabel="t [s]", ylabel="energy [J]", title="Energy budget, all mechanisms on")
    ax.legend(loc="lower left", fontsize=8)
    ax.grid(alpha=0.3)
    return _save(fig, path)


# ---------------------------------------------------------------------------- chaos (issue 7)
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
    fig, axes = plt.subplots(1, n + 1, figsize=(4.2 * (n + 1), 4.4), squeeze=False)
    colours = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    for i, (label, (x, y)) in enumerate(traces.items()):
        for ax in (axes[0, i], axes[0, n]):
            ax.plot(x, y, lw=0.7, color=colours[i % len(colours)], label=label)
    for ax in axes[0]:
        ax.plot([0], [0], "k+", ms=10)
        if diverge is not None:
            ax.annotate(
                "",
                xy=diverge,
                xytext=(diverge[0] + 0.08, diverge[1] + 0.08),
                arrowprops={"color": "red", "width": 1.5, "headwidth": 7},
            )
        ax.set(xlabel="x2 [m]", ylabel="y2 [m]", aspect="equal")
        ax.grid(alpha=0.3)
    for i, label in enumerate(traces):
        axes[0, i].set_title(label)
    axes[0, n].set_title("overlaid")
    axes[0, n].legend(loc="lower right", fontsize=7)
    if title:
        fig.suptitle(title)
    return _save(fig, path)


def plot_ensemble_clouds(
    snapshots: Mapping[float, tuple[np.ndarray, np.ndarray]], path: str | Path, *, title: str = ""
) -> Path:
    """Positions of the lower bob [m] of every ensemble member at a few times: the cloud spreading."""
    n = len(snapshots)
    fig, axes = plt.subplots(1, n, figsize=(3.2 * n, 3.6), squeeze=False, sharex=True, sharey=True)
    for ax, (t, (x, y)) in zip(axes[0], snapshots.items()):
        ax.plot(x, y, ".", ms=2, alpha=0.6)
        ax.plot([0], [0], "k+", ms=8)
        ax.set(title=f"t = {t:g} s", xlabel="x2 [m]", aspect="equal")
        ax.grid(alpha=0.3)
    axes[0, 0].set_ylabel("y2 [m]")
    if title:
        fig.suptitle(title)
    return _save(fig, path)


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
    ax.set(xlabel="t [s]", ylabel="spread of the lower bob [m]", title="ensemble spread (start uncertainty)")
    ax.legend(fontsize=7, ncol=2, loc="lower right")
    ax.grid(alpha=0.3, which="both")
    return _save(fig, path)


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
        title=f"horizon vs uncertainty; dotted: slope -1/lambda, lambda = {lyapunov:.2f} 1/s",
    )
    ax.legend()
    ax.grid(alpha=0.3, which="both")
    return _save(fig, path)


def plot_lyapunov_convergence(
    curves: Mapping[str, tuple[np.ndarray, np.ndarray]], path: str | Path, *, title: str = ""
) -> Path:
    """Running Benettin estimates lambda(t) [1/s] against the averaging time t [s]."""
    fig, ax = plt.subplots(figsize=(8, 5))
    for label, (t, lam) in curves.items():
        ax.semilogx(t, lam, lw=1.0, label=label)
    ax.axhline(0.0, color="k", lw=0.6)
    ax.set(xlabel="averaging time t [s]", ylabel="lambda(t) [1/s]", title=title or "convergence of lambda")
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3, which="both")
    return _save(fig, path)


def plot_lyapunov_vs_energy(
    theta0: np.ndarray, energy_ratio: np.ndarray, lam: np.ndarray, path: str | Path
) -> Path:
    """Largest exponent [1/s] against the release angle theta0 [rad] (phi1 = phi2 = theta0, at rest)."""
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(12, 4.5))
    ax1.plot(theta0, lam, "o-")
    ax1.set(xlabel="theta0 [rad]", ylabel="lambda [1/s]", title="largest Lyapunov exponent, from rest")
    ax2.plot(energy_ratio, lam, "o-")
    ax2.axvline(1.0, color="r", ls="--", lw=0.8, label="E = E_flip (a rod can flip)")
    ax2.set(xlabel="E / E_flip", ylabel="lambda [1/s]", title="against energy")
    ax2.legend(fontsize=8)
    for ax in (ax1, ax2):
        ax.grid(alpha=0.3)
    return _save(fig, path)


def plot_lyapunov_spectrum(
    times: np.ndarray, running: np.ndarray, bound: np.ndarray, path: str | Path
) -> Path:
    """Running estimates of all four exponents [1/s] and of their sum, with the sum's bound."""
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(12, 4.5))
    for i in range(running.shape[1]):
        ax1.semilogx(times, running[:, i], label=f"lambda{i + 1}")
    ax1.axhline(0.0, color="k", lw=0.6)
    ax1.set(xlabel="t [s]", ylabel="[1/s]", title="Lyapunov spectrum (QR)")
    ax1.legend(fontsize=8)
    ax2.loglog(times, np.abs(running.sum(axis=1)), label="|sum of the exponents|")
    ax2.loglog(times, np.abs(running[:, 0] + running[:, -1]), label="|lambda1 + lambda4|")
    ax2.loglog(times, bound, "k--", label="bound ln((m1+m2)/m1) / t")
    ax2.set(xlabel="t [s]", ylabel="[1/s]", title="pairing (lambda, 0, 0, -lambda)")
    ax2.legend(fontsize=8)
    for ax in (ax1, ax2):
        ax.grid(alpha=0.3, which="both")
    return _save(fig, path)


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
    return _save(fig, path)


def plot_poincare_sections(
    sections: Mapping[str, tuple[np.ndarray, np.ndarray, np.ndarray]], path: str | Path
) -> Path:
    """Poincare sections phi1 = 0, omega1 > 0: points (phi2 [rad], omega2 [rad/s]) per start."""
    n = len(sections)
    fig, axes = plt.subplots(1, n, figsize=(6 * n, 5), squeeze=False)
    for ax, (label, (phi2, omega2, owner)) in zip(axes[0], sections.items()):
        wrapped = np.angle(np.exp(1j * phi2))
        ax.scatter(wrapped, omega2, c=owner, s=2.0, cmap="tab20", linewidths=0)
        ax.set(title=label, xlabel="phi2 [rad] (wrapped)", ylabel="omega2 [rad/s]")
        ax.grid(alpha=0.3)
    return _save(fig, path)


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
    ax.set(xlabel="t [s]", ylabel="lambda [1/s]", title=title or "Lyapunov exponent as the motion decays")
    ax.grid(alpha=0.3)
    twin = ax.twinx()
    twin.plot(times, energy_ratio, color="C3", lw=1.0, label="E / E_flip")
    twin.axhline(1.0, color="C3", ls="--", lw=0.8)
    twin.set_ylabel("E / E_flip", color="C3")
    lines = ax.get_legend_handles_labels()
    lines2 = twin.get_legend_handles_labels()
    ax.legend(lines[0] + lines2[0], lines[1] + lines2[1], loc="upper right", fontsize=8)
    return _save(fig, path)


def plot_residuals(runs: Mapping[str, np.ndarray], path: str | Path) -> Path:
    """|energy_residual| / E_total(0) over time [s], log scale, one line per run."""
    fig, ax = plt.subplots(figsize=(9, 5))
    for label, r in runs.items():
        e0 = abs(r["E_total"][0]) or 1.0
        ax.semilogy(r["time"], np.abs(r["energy_residual"]) / e0 + 1e-18, label=label)
    ax.set(xlabel="t [s]", ylabel="|energy_residual| / E_total(0)", title="Energy residual of the worst cases")
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3, which="both")
    return _save(fig, path)


def plot_work_precision(rows: list[dict], path: str | Path, *, title: str = "") -> Path:
    """Max error over the horizon against CPU time [s], log-log, one line per method (ok runs only)."""
    fig, ax = plt.subplots(figsize=(8, 6))
    for solver in sorted({r["solver"] for r in rows}):
        pts = sorted((r["cpu_time_s"], r["max_error"]) for r in rows if r["solver"] == solver and r["status"] == "ok")
        if pts:
            ax.loglog(*zip(*pts), "o-", label=solver)
        failed = [r for r in rows if r["solver"] == solver and r["status"] != "ok"]
        if failed:
            ax.plot([], [], "x", label=f"{solver}: {len(failed)} failed/unstable")
    ax.set(xlabel="CPU time [s]", ylabel="max error over the horizon [rad, rad/s]", title=title)
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3, which="both")
    return _save(fig, path)


# ---------------------------------------------------------------------------- suspension, measured vs sim (issue 4)
def _running_mean(values: np.ndarray, width: int) -> np.ndarray:
    """Centered moving average over ``width`` samples (shorter at the ends)."""
    width = max(1, int(width))
    kernel = np.ones(width)
    return np.convolve(values, kernel, mode="same") / np.convolve(np.ones_like(values), kernel, mode="same")


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
    return _save(fig, path)


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
    return _save(fig, path)


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
    return _save(fig, path)


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
        mean = _running_mean(p, round(smooth_s / dt))
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
    return _save(fig, path)


def plot_track_comparison(
    t: np.ndarray,
    measured: Mapping[str, np.ndarray],
    runs: Mapping[str, tuple[np.ndarray, Mapping[str, np.ndarray]]],
    path: str | Path,
    *,
    starts: Mapping[str, float] | None = None,
) -> Path:
    """Measured coordinates (dots) and simulated ones (lines) over time [s], one panel per coordinate [m]
    (the seed's figs. 11-14); ``starts`` marks start times [s]."""
    names = list(measured)
    fig, axes = plt.subplots(len(names), 1, figsize=(11, 2.6 * len(names)), sharex=True, squeeze=False)
    for ax, name in zip(axes[:, 0], names):
        ax.plot(t, measured[name], ".", color="k", ms=3, label="track")
        for label, (ts, coords) in runs.items():
            ax.plot(ts, coords[name], lw=1.2, label=label)
        for t0 in (starts or {}).values():
            ax.axvline(t0, color="0.5", ls=":", lw=0.8)
        ax.set(ylabel=f"{name} [m]")
        ax.grid(alpha=0.3)
    axes[0, 0].legend(fontsize=7, ncols=2, loc="upper right")
    axes[-1, 0].set_xlabel("t [s]")
    return _save(fig, path)


def plot_prediction_errors(
    curves: Mapping[str, tuple[np.ndarray, np.ndarray]],
    thresholds: tuple[float, ...] | list[float],
    path: str | Path,
    *,
    floor: tuple[np.ndarray, np.ndarray] | None = None,
) -> Path:
    """Position error [m] over time since the start [s], log scale, with horizontal ``thresholds`` [m];
    ``floor`` (t, error) is drawn grey (e.g. the track's own deviation from a rigid rod)."""
    fig, ax = plt.subplots(figsize=(11, 5.5))
    for label, (t, err) in curves.items():
        ax.semilogy(t, np.maximum(err, 1e-5), lw=1.1, label=label)
    if floor is not None:
        label = "track: | |r2 - r1| - l2 | (rod-length error)"
        ax.semilogy(floor[0], np.maximum(floor[1], 1e-5), ".", color="0.6", ms=2, label=label)
    for th, ls in zip(thresholds, ("--", "-.", ":")):
        ax.axhline(th, color="k", ls=ls, lw=0.9, label=f"{100 * th:g} cm")
    ax.set(xlabel="t - t0 [s]", ylabel="position error [m]", title="simulated minus measured bob position")
    ax.legend(fontsize=7, ncols=2)
    ax.grid(alpha=0.3, which="both")
    return _save(fig, path)
