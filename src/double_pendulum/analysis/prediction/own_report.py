"""The ``measured_vs_sim`` report of a user's own record (:mod:`~double_pendulum.analysis.track.user_track`): the
FMU's prediction of the user's camera track, every figure from that record and none of the seed's (its start time,
rods, camera and the seed's own comparison by eye are not the user's)."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from ...runs.results_io import report_opening
from ..losses.mechanisms import model_title
from .report import (
    HORIZON_HEADER,
    MAIN_RUN,
    budget_text,
    geometry_text,
    horizon_claims_text,
    horizon_rows,
    loss_models_text,
    loss_text,
    regime_text,
)

OWN_LABELS = {
    "seed_start_frictionless": "reconstructed start (angles and rates of the frame at t0), no friction, point masses",
    "seed_start_identified": "reconstructed start, fitted losses",
    "lsq_start_identified": "least-squares start (state only), fitted losses",
    "lsq_fixed_geometry_identified": "least-squares start over the geometry's frames, geometry fixed",
    "lsq_pivot_shift_identified": "least-squares start, pivot offset and l2 (no rotation)",
    "lsq_geometry_identified": "least-squares start and geometry (rotation, pivot offset, l2), fitted losses",
}
"""Names of the runs in a user's report, by run label (the ``seed_start`` runs start the way the seed started: from
the reconstruction of the frame at t0)."""


def _rods(rods: Mapping[str, float]) -> str:
    """The rods of the model in words."""
    if not any(rods.values()):
        return "point masses on massless rods (your pendulum file gives no rods)"
    return (f"rods of {rods['m_rod1']:g} kg and {rods['m_rod2']:g} kg, {rods['L_rod1']:g} m and {rods['L_rod2']:g} m "
            "long (your pendulum file)")


def _damping_text(s: Mapping[str, Any]) -> str:
    """How much 1 % more damping moves the main start's 5 cm horizon, per loss model (the default run's central
    difference, :func:`~.loss_uncertainty.damping_sensitivity`)."""
    sens = s["loss_uncertainty"]["damping_sensitivity"]
    if not sens:
        return ""
    rows = "; ".join(f"{model_title(m)}: {d['smoothed_s_per_percent']:+.1f} s"
                     f"{' or more (a censored end)' if d['slope_is_lower_bound'] else ''}"
                     for m, d in sens.items())  # fmt: skip
    return ("**The damping level.** Every fitted loss coefficient times 1.01 against times 0.99 (central difference): "
            f"the smoothed 5 cm horizon changes by {rows} per 1 % more damping.")


def own_report_text(s: Mapping[str, Any]) -> str:
    """The Markdown report of ``measured_vs_sim`` on a user's record (``s``: its summary)."""
    r, m = s["record"], s["model"]
    geo = s["starts"]["least_squares_geometry"]
    lsq = s["starts"]["least_squares"]
    d = s["horizon_5cm_details"][MAIN_RUN]
    span = s["prediction_s"]
    window_s = geo["n_frames"] * r["frame_interval_s"]
    held = (f"all {span:.1f} s compared (censored: the horizon is longer)" if s["horizon_5cm_censored"]
            else f"{s['horizon_5cm_s']:.1f} s")
    raw = "never" if d["raw_horizon_s"] is None else f"first after {d['raw_horizon_s']:.1f} s"
    reconstructed = s["horizons_smoothed_s"]["seed_start_frictionless"]["lower_bob_5cm_s"]
    quick = " (quick run)" if s["quick"] else ""
    sentences = [
        f"The FMU is started from your pendulum's state at t0 = {s['t0_s']:.2f} s, the end of the release in your "
        f"camera track {r['file']}, and its bob positions are compared with your track frame by frame for "
        f"{span:.1f} s.",
        f"With the start and the camera's geometry fitted to the first {window_s:.1f} s after t0, the lower bob stays "
        f"within 5 cm of your track (smoothed over {s['smoothing']['window_s']:g} s) for {held}; frame by frame the "
        f"error exceeds 5 cm {raw}"
        + (" (a quick run: a smoke test of 3 s with one assumed loss model)." if s["quick"] else "."),
        "Started from the angles and rates reconstructed at t0, without friction, it stays within 5 cm for "
        + ("the whole comparison." if reconstructed is None else f"{reconstructed:.1f} s."),
        "How sure: the losses were fitted to this same record, so this is no test on new data.",
    ]
    return report_opening(f"FMU prediction of your pendulum's track ({r['file']}){quick}", sentences, {
        "smoothed error": f"the distance between simulated and measured bob, smoothed by a moving median over "
                          f"{s['smoothing']['window_s']:g} s, which removes the track's frame-to-frame jitter",
        "horizon": "the first time after t0 at which the error exceeds a threshold (2 cm, 5 cm)",
        "censored": "a horizon that reaches the end of the record: only known not to lie within it",
        "in-sample": "judged on the data the model was fitted to: agreement there is expected, not a test",
    }) + f"""## Your record and the model

- Track `{r['file']}`: {r['frames']} frames at {r['fps']:.4g} fps ({r['frame_interval_from']}); the prediction
  starts at frame {s['start_frame']} (t0 = {s['t0_s']:.3f} s, where the loss fits start) and runs {span:.2f} s.
- Pendulum (`{r['pendulum']['file']}`): m1 = {r['pendulum']['m1_kg']:g} kg, m2 = {r['pendulum']['m2_kg']:g} kg,
  l1 = {1e3 * m['lengths_m']['l1']:.1f} mm, l2 = {1e3 * m['lengths_m']['l2']:.1f} mm; {_rods(m['rods'])}.
- Losses: ``{m['loss_model']}`` (air drag and a constant friction torque in the joints) fitted to
  {m['loss_fit_record_s']:.1f} s of your record's energy as ``loss_identification`` fits it
  ({m['loss_fit_runs']} runs): {loss_text(s)}.

## Start states and geometry

The state alone fitted to {lsq['n_frames']} frames: rms residual {1e3 * lsq['rms_residual']:.1f} mm. Fitted with
the geometry over {geo['n_frames']} frames ({window_s:.2f} s): {geometry_text(geo['geometry'], geo['geometry_stderr'])};
rms residual {1e3 * geo['rms_residual']:.1f} mm.

## Prediction horizons

Lower bob; "none in {span:.2f}": not exceeded in the {span:.2f} s compared (``prediction_error.png``,
``coordinates.png``):

{HORIZON_HEADER}
{horizon_rows(s, OWN_LABELS)}

{horizon_claims_text(s)}

{loss_models_text(s)}

{_damping_text(s)}

{budget_text(s)}

{regime_text(s)}
"""
