"""The ``energy_decay`` report of a user's own record (:mod:`~double_pendulum.analysis.track.user_track`): the same
figures as the seed's report (:mod:`.report`), every one from the user's record, and no comparison with the seed."""

from __future__ import annotations

import math
from typing import Any

from ...runs.results_io import report_opening
from ..track.measurement import SG_POLYORDER, SG_WINDOW
from .error_budget import budget_table
from .report import comparison_rows, plus_minus, tilt_section, variant_rows


def _lengths(s: dict[str, Any]) -> str:
    """Where l1 and l2 come from: the pendulum file or the track."""
    given = s["record"]["pendulum"]["lengths_given_m"]
    fitted = s["lengths_fitted_m"]
    parts = []
    for k in ("l1", "l2"):
        fit = plus_minus(fitted[k], fitted[f"{k}_stderr"], 1e3, 1)
        parts.append(f"{k} = {1e3 * given[k]:.1f} mm (from the pendulum file; the track gives {fit} mm)" if k in given
                     else f"{k} = {fit} mm (fitted from the track)")
    return "; ".join(parts)


def own_report_text(s: dict[str, Any]) -> str:
    """The Markdown report of ``energy_decay`` on a user's record (``s``: its summary)."""
    r = s["record"]
    st = s["error_budget"]["b_statement"]
    pivot, noise = s["pivot_origin_m"], s["position_noise_m"]
    tied = [row["model"] for row in s["model_comparison"] if row["delta_aic"] < 2.0]
    pend = r["pendulum"]
    rods = pend["other_given"]
    opening = report_opening(f"Energy decay of your pendulum ({r['file']})", [
        f"This report analyses your own camera track {r['file']} ({r['frames']} frames at {r['fps']:.4g} fps, "
        f"{r['duration_s']:.1f} s) with the pendulum of {pend['file']}: the pendulum's energy frame by frame and "
        "how it decays.",
        f"Fitted as E = a exp(b t) it decays at b = {s['b_per_s']:.4f} 1/s (the energy falls by about "
        f"{100 * (1 - math.exp(s['b_per_s'])):.1f} % a second), with a statistical error of "
        f"{st['statistical_per_s']:.4f} 1/s.",
        f"The choice of weights, window and energy moves b by up to {st['systematic_max_shift_per_s']:.4f} 1/s "
        f"({st['systematic_widest_variant']}), a range of choices reported apart.",
        f"Decay laws that fit about equally well (within dAIC 2): {', '.join(tied)}.",
    ], {
        "b": "the decay rate [1/s] of E = a exp(b t); a [J] the energy at t = 0 of the record",
        "dAIC": "the difference of Akaike's information criterion from the lowest: below 2 the record does not tell "
                "two laws apart",
        "F": "the correlation factor: neighbouring frames' residuals are alike over about a swing, so the frames count "
             "as n / F independent ones and statistical errors grow by sqrt(F)",
    })
    return opening + f"""## Your record

- Track: `{r['file']}`, columns {', '.join(f"{k} = `{v}`" for k, v in r['columns'].items())}, positions times
  {r['scale_to_m']:g} to metres; frame interval {1e3 * r['frame_interval_s']:.3f} ms ({r['frame_interval_from']}).
- Frames: {r['frames']}; missing in the file (empty cells or rows): {r['frames_missing_in_file']}; flagged as tracker
  jumps: {r['frames_flagged']}; free motion from frame {s['release_frame']} (t = {s['release_time_s']:.3f} s: the
  first maximum of the energy, where a hand release ends, at the earliest the first frame with rates); frames in
  the fits: {s['n_fit']}.
- Pendulum (`{pend['file']}`): m1 = {pend['m1_kg']:g} kg, m2 = {pend['m2_kg']:g} kg;
  {', '.join(f'{k} = {v:g}' for k, v in rods.items()) or 'point masses on massless rods'}.
- Pivot (circle fit of the upper bob, in the file's coordinates): x = {plus_minus(pivot['x'], pivot['sigma_x'], 1e3, 2)}
  mm, y = {plus_minus(pivot['y'], pivot['sigma_y'], 1e3, 2)} mm; rms distance of the upper bob from the circle
  {1e3 * s['circle_rms_residual_m']:.2f} mm.
- Lengths: {_lengths(s)}.
- Position noise (frame-to-frame jitter of the rod lengths): upper bob {1e3 * noise['upper_bob']:.2f} mm, lower bob
  {1e3 * noise['lower_bob']:.2f} mm.

## Energy and its fit

The energy is the package's `total_energy` of this pendulum, the rates from a Savitzky-Golay derivative
({SG_WINDOW} frames, order {SG_POLYORDER}) at the record's frame interval; the errors are calibrated on the record
(sigma^2 = sigma_noise^2 + s0^2 + dv^2 (m1^2 v1^2 + m2^2 v2^2), s0 = {1e3 * s['error_model']['floor_J']:.1f} mJ,
dv = {s['error_model']['dv_m_per_s']:.3f} m/s).

a = {plus_minus(s['a_J'], s['a_J_stderr_autocorr'])} J,
b = {plus_minus(s['b_per_s'], s['b_per_s_stderr_autocorr'], digits=5)} 1/s
(errors inflated for the residuals' correlation, F = {s['autocorrelation_factor']:.2f}).

{st['text']}.

The same fit with other energies and weights:

{variant_rows(s)}

## Decay laws compared

{comparison_rows(s)}

{tilt_section(s)}
## Error budget of a and b

{budget_table(s['error_budget'])}

The quadrature total is no confidence interval: it adds shifts of choices as if they were independent errors.
"""
