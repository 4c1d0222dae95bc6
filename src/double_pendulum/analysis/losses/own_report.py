"""The ``loss_identification`` report of a user's own record (:mod:`~double_pendulum.analysis.track.user_track`):
the models fitted to the user's measured energy, every figure from that record, and none of the seed's friction
estimates (its bearings are not the user's)."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from ...runs.results_io import report_opening
from .mechanisms import model_title
from .report import model_table, parameter_lines


def _origin(given: Mapping[str, float]) -> str:
    """Which lengths the pendulum file gave and which the track."""
    from_file = [k for k in ("l1", "l2") if k in given]
    fitted = [k for k in ("l1", "l2") if k not in given]
    parts = ([f"{' and '.join(from_file)} from the pendulum file"] if from_file else []) + (
        [f"{' and '.join(fitted)} fitted from the track"] if fitted else [])
    return ", ".join(parts)


def own_report_text(s: Mapping[str, Any]) -> str:
    """The Markdown report of ``loss_identification`` on a user's record (``s``: its summary)."""
    r = s["record"]
    sup = s["supported_models"]
    p = r["pendulum"]
    lost = (f"Your camera track {r['file']} shows the pendulum losing {s['measured_loss_J']:.3f} J of energy over "
            f"{s['record_s']:.1f} s after the release.")
    if s["quick"]:
        sentences = [lost, "This quick run fits one assumed pair of losses, air drag and a constant friction torque in "
                     "the joints (air+drag), with one step of the fit, and compares nothing: run without --quick to "
                     "compare the candidate losses."]  # fmt: skip
    else:
        air = sup["air_share_range"]
        names = "; ".join(model_title(m) for m in sup["models"])
        many = len(sup["models"]) > 1
        sentences = [lost, (f"{len(sup['models'])} of the {len(s['models'])} candidate loss models follow the measured "
                            f"energy about equally well (within delta AIC 2): {names}" if many else
                            f"One of the {len(s['models'])} candidate loss models follows the measured energy best, by "
                            f"more than delta AIC 2: {names}")
                     + (f"; air drag's share of the loss {'among them ' if many else ''}{air[0]:.0%} to {air[1]:.0%}."
                        if air else ".")]  # fmt: skip
        profile = s.get("air_share_profile")
        if profile and profile["share_interval"] and None not in profile["share_interval"]:
            lo, hi = profile["share_interval"]
            sentences.append(f"The shares of air drag the record allows (any model within Delta(-2 ln L) <= 4 of the "
                             f"best fit): {lo:.0%} to {hi:.0%}.")
    sentences.append(f"The model with the lowest AIC, {model_title(s['top_model'])}, decays at b = "
                     f"{s['b_sim_per_s']:.4f} 1/s against the measured {s['b_measured_per_s']:.4f} +- "
                     f"{s['b_measured_stderr']:.4f} 1/s.")
    rods = ", ".join(f"{k} = {v:g}" for k, v in p["other_given"].items()) or "point masses on massless rods"
    return report_opening(f"Loss identification of your pendulum ({r['file']})", sentences, {
        "AIC": "Akaike's information criterion chi2 / F + 2 k (k fitted numbers): lower is better; models within "
               "delta AIC 2 of the lowest fit about equally well",
        "F": "the correlation factor: n frames count as n / F independent ones",
        "b": "the decay rate [1/s] of E = a exp(b t) fitted to the energy",
    }) + f"""## Your record

- Track `{r['file']}`: {r['frames']} frames at {r['fps']:.4g} fps ({r['frame_interval_from']}); the fits start at
  t0 = {s['t0_s']:.3f} s (the end of the release: the first maximum of the energy) and cover {s['n_frames']} frames.
- Pendulum (`{p['file']}`): m1 = {p['m1_kg']:g} kg, m2 = {p['m2_kg']:g} kg, l1 = {1e3 * s['pendulum']['l1']:.1f} mm,
  l2 = {1e3 * s['pendulum']['l2']:.1f} mm ({_origin(p['lengths_given_m'])}); {rods}.
- The start state is fitted to the first frames after t0. Air drag acts on the model's default bobs and rods
  (their sizes are not in your pendulum file), scaled by the fitted air factor; the suspension has the assumed
  k = {s['suspension_fixed']['k_N_per_m']:g} N/m and M_s = {s['suspension_fixed']['M_s_kg']:g} kg.

## Models fitted ({'quick run' if s['quick'] else 'thorough run' if s['thorough'] else 'default run'})

{model_table(s['models'])}

Parameters of the model with the lowest AIC ({model_title(s['top_model'])}):

{parameter_lines(s)}

Correlation factor F = {s['correlation_factor_F']:.2f}. Measured b = {s['b_measured_per_s']:.5f} 1/s, simulated
(lowest AIC) b = {s['b_sim_per_s']:.5f} 1/s; loss exponent p measured {s['p_measured']:.2f} +-
{s['p_measured_stderr']:.2f}, simulated {s['p_sim']:.2f}.

## A damped springy pivot?

{s['answer']}
"""
