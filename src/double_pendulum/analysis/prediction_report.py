r"""The Markdown report of the ``measured_vs_sim`` scenario: every figure from its summary.

Start states, prediction horizons (first time after t0 at which the position error [m] exceeds
1 cm and 5 cm, :mod:`.track_comparison`), the two floors of the horizon (the track's rod-length error
and the spread from the start's uncertainty) and whether model error or the start's uncertainty limits the
prediction. The measured motion is regular (below the lower rod's flip energy), so no horizon is a chaos limit.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from .measurement import SEED_TOTAL_MASS_KG

LABELS = {
    "seed_start_frictionless": "seed start (reconstruction at t0), frictionless",
    "seed_start_identified": "seed start, identified losses",
    "lsq_start_identified": "least-squares start, identified losses",
}
"""Names of the runs in the report, by run label."""

HORIZON_HEADER = (
    "| run | lower bob 1 cm [s] | lower bob 5 cm [s] | both bobs 1 cm [s] | both bobs 5 cm [s] "
    "| rms error of the lower bob in the first second [mm] |\n|---|---|---|---|---|---|"
)
"""Header of the horizon table (:func:`horizon_rows`)."""

HORIZON_KEYS = ("lower_bob_1cm_s", "lower_bob_5cm_s", "both_bobs_1cm_s", "both_bobs_5cm_s")
"""Horizon columns of :data:`HORIZON_HEADER`, in order."""


def fmt_horizon(value: float | None, span: float) -> str:
    """A horizon [s] for the report ('> span' if never exceeded within the prediction)."""
    return f"> {span:.1f}" if value is None else f"{value:.2f}"


def horizon_rows(s: Mapping[str, Any]) -> str:
    """Rows of :data:`HORIZON_HEADER`: horizons [s] and rms error [mm] of the lower bob per run."""
    span = s["prediction_s"]
    rows = []
    for label, h in s["horizons_s"].items():
        rms_mm = 1e3 * s["rms_error_first_second_m"][label]["lower_bob"]
        cells = [LABELS.get(label, label), *(fmt_horizon(h[key], span) for key in HORIZON_KEYS), f"{rms_mm:.0f}"]
        rows.append("| " + " | ".join(cells) + " |")
    return "\n".join(rows)


def sensitivity_rows(s: Mapping[str, Any]) -> str:
    """Markdown table of the horizons [s] per fit window of the least-squares start (full run only)."""
    span = s["prediction_s"]
    rows = [
        f"| {r['fit_frames']} | {r['chi2_red']:.0f} | {1e3 * r['rms_residual_m']:.1f} "
        f"| {fmt_horizon(r['lower_bob_1cm_s'], span)} "
        f"| {fmt_horizon(r['lower_bob_5cm_s'], span)} | {fmt_horizon(r['both_bobs_5cm_s'], span)} |"
        for r in s.get("fit_window_sensitivity", [])
    ]
    if not rows:
        return "(full run only)"
    head = "| frames fitted | chi2_red | rms residual [mm] | lower bob 1 cm [s] | lower bob 5 cm [s] | both 5 cm [s] |"
    return "\n".join([head, "|---|---|---|---|---|---|", *rows])


def state_rows(s: Mapping[str, Any]) -> str:
    """Rows comparing the seed's start state with the least-squares one (value +- standard error)."""
    seed = s["starts"]["seed_reconstruction"]
    lsq = s["starts"]["least_squares"]
    units = {"phi1_0": "rad", "phi2_0": "rad", "omega1_0": "rad/s", "omega2_0": "rad/s"}
    return "\n".join(
        f"| {n} [{u}] | {seed[n]:.4f} | {lsq['state'][n]:.4f} +- {lsq['stderr'][n]:.4f} |" for n, u in units.items()
    )


def cause_text(s: Mapping[str, Any]) -> str:
    """Model error or chaos? Compare the observed 5 cm horizon with the ensemble's, and the two seed runs."""
    span = s["prediction_s"]
    observed = s["horizons_s"]["lsq_start_identified"]["lower_bob_5cm_s"]
    chaos = s["chaos_horizons_s"]["lower_bob_5cm_s"]
    seed = s["horizons_s"]
    d_friction = max(
        abs((seed["seed_start_identified"][k] or span) - (seed["seed_start_frictionless"][k] or span))
        for k in seed["seed_start_identified"]
    )
    chaos_bound = span if chaos is None else chaos  # None: beyond the prediction
    if observed is not None and chaos_bound > 2.0 * observed:
        cause = (
            "The observed 5 cm horizon is less than half the start-uncertainty horizon: the prediction fails "
            "through model "
            f"error (point masses on massless rods, where the real pendulum moves about "
            f"{SEED_TOTAL_MASS_KG - s['model']['masses_kg']:.1f} kg of acrylic rods as well, and the track's "
            "systematic errors), not through the uncertainty of the start."
        )
    else:
        cause = (
            "The observed 5 cm horizon is comparable with the start-uncertainty horizon: the start's uncertainty "
            "limits it."
        )
    if d_friction < 0.005:
        return f"{cause} The identified losses leave the seed-start horizons unchanged (to the frame)."
    return f"{cause} The identified losses change the seed-start horizons by at most {d_friction:.2f} s."


def report_text(summary: Mapping[str, Any]) -> str:
    """The Markdown report: every figure from ``summary``."""
    s = summary
    quick = " (quick run)" if s["quick"] else ""
    sus = s["model"]["suspension"]
    lsq = s["starts"]["least_squares"]
    floor = s["track_rod_length_floor"]
    chaos = s["chaos_horizons_s"]
    span = s["prediction_s"]
    change = lsq["change_from_reconstruction"]
    return f"""# FMU prediction of the measured track{quick}

Start at the frame nearest the seed's t0 = 0.8 s (t0 = {s["t0_s"]:.4f} s, frame {s["start_frame"]}), predict
{span:.1f} s, compare the bob positions with the track frame by frame. Positions relative to the pivot
fitted by the measurement (the FMU's origin is the pivot's rest position; the track's pivot sits at
x = {1e3 * s["pivot_origin_m"]["x"]:.2f} mm, y = {1e3 * s["pivot_origin_m"]["y"]:.2f} mm in its own coordinates).
Model: rod lengths l1 = {s["model"]["lengths_m"]["l1"]:.4f} m, l2 = {s["model"]["lengths_m"]["l2"]:.4f} m from the
track; identified losses = air drag (bobs, rods) and bearing friction at the defaults plus the suspension
identified by ``suspension_transfer`` (k = {sus["k_N_per_m"]:g} N/m, M_s = {sus["M_s_kg"]:g} kg,
c = {sus["c_N_s_per_m"]:.1f} +- {sus["c_stderr"]:.1f} N s/m).

## Start states

| start value | seed start (angles, Savitzky-Golay rates of frame t0) | least squares over {lsq["n_frames"]} frames |
|---|---|---|
{state_rows(s)}

The least-squares start reproduces its {lsq["n_frames"]} frames with an rms position residual of
{1e3 * lsq["rms_residual"]:.1f} mm (chi2_red = {lsq["chi2_red"]:.0f} with the rod-jitter noise as errors: the track
has errors the jitter does not show; the standard errors are scaled by chi2_red). The rates differ from the
reconstruction's by {change["omega1_0"]:+.2f} and {change["omega2_0"]:+.2f} rad/s.

## Prediction horizons

Time after t0 at which the position error first exceeds 1 cm and 5 cm (``prediction_error.png``,
``coordinates.png``; "> {span:.1f}": not within the prediction):

{HORIZON_HEADER}
{horizon_rows(s)}

**Two floors.** (1) The track: the distance between the bobs varies where a rigid rod allows none,
by {1e3 * floor["rms_m"]:.1f} mm rms and up to {1e3 * floor["max_m"]:.1f} mm in this window (correlation of the
signed deviation with omega2^2: {floor["correlation_with_omega2_squared"]:+.2f}), so an error of 1 cm is at the
data's own resolution. (2) The start's uncertainty: {s["ensemble_size"]} runs from start states drawn from the
least-squares covariance part from the central run by 1 cm after {fmt_horizon(chaos["lower_bob_1cm_s"], span)} s
and by 5 cm after {fmt_horizon(chaos["lower_bob_5cm_s"], span)} s (median distance of the lower bob). {cause_text(s)}

**Regime: regular, not chaotic.** The measured motion has E of about 0.8 J (point masses; 0.92 J with the
acrylic members), below the 1.15 J (1.28 J with the members) the lower rod needs to flip over. At that
energy the motion is regular: the finite-time Lyapunov exponent of the measured start falls like 1/T
(0.26, 0.10, 0.07 1/s after 20, 50, 100 s; docs/data-analysis.md), so it tends to 0 and the runs from
the uncertain start separate slowly (about linearly), not exponentially. Neither horizon is a chaos
limit: it is where model error and the start's uncertainty have grown to the threshold.

Fit window of the least-squares start (more frames: a better average over the track's errors, but more
model error inside the window):

{sensitivity_rows(s)}

The seed saw agreement until about 2 s (about {2.0 - s["t0_s"]:.1f} s after t0) by eye, on plots whose scale
is the whole swing; in numbers the lower bob leaves the 5 cm band after the horizons above.
"""
