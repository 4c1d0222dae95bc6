r"""The Markdown report of the ``measured_vs_sim`` scenario: every figure from its summary.

Model and fitted losses, start states (state-only and with geometry), prediction horizons (first
time after t0 at which the smoothed and the raw position error [m] exceed 2 cm and 5 cm,
:mod:`.comparison`), the goal of at least 3 s at 5 cm, the two floors of the horizon (the track's
rod-length error and the spread from the fit's uncertainty), whether model error or the fit's
uncertainty limits the prediction, and the regime at the measured energy from the largest Lyapunov
exponent (regular or chaotic, as the number says).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

from ...runs.results_io import report_opening
from ..losses.mechanisms import model_title
from ..track.measurement import FPS
from .summary_types import PredictionSummary

LABELS = {
    "seed_start_frictionless": "seed start (reconstruction at t0), frictionless point masses",
    "seed_start_identified": "seed start, fitted losses",
    "lsq_start_identified": "least-squares start (state only), fitted losses",
    "lsq_fixed_geometry_identified": "least-squares start over the geometry's frames, geometry fixed (circle-fit"
                                     " pivot, track's l1 and l2, no rotation)",
    "lsq_pivot_shift_identified": "least-squares start, pivot offset and l2 (no rotation)",
    "lsq_geometry_identified": "least-squares start and geometry (rotation, pivot offset, l2), fitted losses",
}
"""Names of the runs in the report, by run label."""

MAIN_RUN = "lsq_geometry_identified"
"""The run the goal, the cause and the ensemble refer to."""

HORIZON_HEADER = (
    "| run | smoothed 2 cm [s] | smoothed 5 cm [s] | per frame 5 cm [s] | rms error in the first second [mm] |\n"
    "|---|---|---|---|---|"
)
"""Header of the horizon table (:func:`horizon_rows`): the lower bob's horizons; both bobs' are in the summary."""


def fmt_horizon(value: float | None, span: float) -> str:
    """A horizon [s] for the report ('none in SPAN' if never exceeded within the ``span`` [s] compared)."""
    return f"none in {span:.2f}" if value is None else f"{value:.2f}"


def horizon_rows(s: PredictionSummary, labels: Mapping[str, str] = LABELS) -> str:
    """Rows of :data:`HORIZON_HEADER`: the lower bob's smoothed and per-frame horizons [s] and rms error [mm], each
    run named by ``labels``."""
    span = s["prediction_s"]
    rows = []
    for label, h in s["horizons_smoothed_s"].items():
        raw = s["horizons_raw_s"][label]
        rms_mm = 1e3 * s["rms_error_first_second_m"][label]["lower_bob"]
        cells = [labels.get(label, label), fmt_horizon(h["lower_bob_2cm_s"], span),
                 fmt_horizon(h["lower_bob_5cm_s"], span), fmt_horizon(raw["lower_bob_5cm_s"], span), f"{rms_mm:.0f}"]
        rows.append("| " + " | ".join(cells) + " |")
    return "\n".join(rows)


def geometry_text(geometry: Mapping[str, float], stderr: Mapping[str, float]) -> str:
    """'view_rotation = 2.58 +- 0.15 deg, pivot_offset_x = 0.4 +- 0.9 mm, ...' for the fitted geometry
    (angles [rad] in degrees, lengths [m] in mm)."""
    parts = []
    for k, v in geometry.items():
        if k == "view_rotation":
            parts.append(f"{k} = {math.degrees(v):.2f} +- {math.degrees(stderr[k]):.2f} deg")
        else:
            parts.append(f"{k} = {1e3 * v:.1f} +- {1e3 * stderr[k]:.1f} mm")
    return ", ".join(parts)


def sensitivity_rows(s: PredictionSummary) -> str:
    """Markdown table of the smoothed horizons [s] per fit window of the start and geometry (``--thorough`` only;
    otherwise a sentence saying so and that the table's other windows come with ``--thorough``)."""
    span = s["prediction_s"]
    main = s["starts"]["least_squares_geometry"]
    main_row = {
        "fit_frames": main["n_frames"], "chi2_red": main["chi2_red"], "rms_residual_m": main["rms_residual"],
        "geometry": main["geometry"], **s["horizons_smoothed_s"][MAIN_RUN], "main": True,
    }
    table = sorted([*s.get("fit_window_sensitivity", []), main_row], key=lambda r: r["fit_frames"])
    if len(table) == 1:
        return (f"Only the {main['n_frames']}-frame window is fitted in this run; the other windows "
                "(0.5 s, 1 s, 2 s) are fitted with ``--thorough``.")
    rows = [
        f"| {r['fit_frames']}{' (used)' if r.get('main') else ''} | {r['fit_frames'] / FPS:.2f} "
        f"| {r['chi2_red']:.0f} | {1e3 * r['rms_residual_m']:.1f} "
        f"| {math.degrees(r['geometry']['view_rotation']):.2f} "
        f"| {1e3 * r['geometry']['pivot_offset_x']:.1f}, {1e3 * r['geometry']['pivot_offset_y']:.1f} "
        f"| {1e3 * r['geometry']['l2']:.1f} "
        f"| {fmt_horizon(r['lower_bob_2cm_s'], span)} | {fmt_horizon(r['lower_bob_5cm_s'], span)} "
        f"| {fmt_horizon(r['both_bobs_5cm_s'], span)} |"
        for r in table
    ]
    head = ("| frames fitted | window [s] | chi2_red | rms residual [mm] | camera rotation [deg] "
            "| pivot offset x, y [mm] | l2 [mm] | lower bob 2 cm [s] | lower bob 5 cm [s] | both 5 cm [s] |")
    return "\n".join([head, "|---|---|---|---|---|---|---|---|---|---|", *rows])


def state_rows(s: PredictionSummary) -> str:
    """Rows comparing the seed's start state with the least-squares ones (value +- standard error)."""
    seed = s["starts"]["seed_reconstruction"]
    lsq = s["starts"]["least_squares"]
    geo = s["starts"]["least_squares_geometry"]
    units = {"phi1_0": "rad", "phi2_0": "rad", "omega1_0": "rad/s", "omega2_0": "rad/s"}
    return "\n".join(
        f"| {n} [{u}] | {seed[n]:.4f} | {lsq['state'][n]:.4f} +- {lsq['stderr'][n]:.4f} "
        f"| {geo['state'][n]:.4f} +- {geo['stderr'][n]:.4f} |"
        for n, u in units.items()
    )


def correlation_text(fit: Mapping[str, Any], threshold: float = 0.9) -> str:
    """The pairs of fitted parameters whose correlation exceeds ``threshold`` in size (or 'none')."""
    names, corr = fit["parameters"], fit["correlation"]
    pairs = [f"{names[i]}/{names[j]} {corr[i][j]:+.2f}" for i in range(len(names)) for j in range(i + 1, len(names))
             if abs(corr[i][j]) > threshold]  # fmt: skip
    return ", ".join(pairs) if pairs else "none"


def claim_horizon(value: float, censored: bool) -> str:
    """A 5 cm horizon [s] as it may be claimed: 'not reached in the 19.99 s compared (censored)' when it reaches the
    end of the record, where it is only known not to lie within the record."""
    return f"not reached in the {value:.2f} s compared (censored)" if censored else f"{value:.2f} s"


def horizon_claims_text(s: PredictionSummary) -> str:
    """What the 5 cm horizons support: the three geometries side by side, the margin, in-sample, regime."""
    d = s["horizon_5cm_details"]
    main, fixed, shift = (d[k] for k in ("lsq_geometry_identified", "lsq_fixed_geometry_identified",
                                         "lsq_pivot_shift_identified"))
    pivot = s["starts"]["least_squares_pivot_shift"]["geometry"]
    raw = "never" if main["raw_horizon_s"] is None else f"after {main['raw_horizon_s']:.2f} s"
    return (
        "**What the 5 cm horizons support.** Over the same frames, with the geometry fitted (rotation, pivot"
        f" offset, l2): {claim_horizon(s['horizon_5cm_s'], s['horizon_5cm_censored'])}; with the pivot offset and"
        f" l2 but no rotation (the pivot moves {1e3 * pivot['pivot_offset_x']:+.1f} mm sideways instead):"
        f" {claim_horizon(s['horizon_5cm_s_pivot_shift'], s['horizon_5cm_censored_pivot_shift'])}; with the"
        " geometry fixed (circle-fit pivot, the track's l1 and l2, no rotation):"
        f" {claim_horizon(s['horizon_5cm_s_fixed_geometry'], s['horizon_5cm_censored_fixed_geometry'])} (largest"
        f" smoothed errors {1e3 * main['smoothed_error_peak_m']:.1f}, {1e3 * shift['smoothed_error_peak_m']:.1f} and"
        f" {1e3 * fixed['smoothed_error_peak_m']:.1f} mm). The fitted-geometry run's smoothed error comes within"
        f" {1e3 * main['margin_below_threshold_m']:.1f} mm of 5 cm ({main['smoothed_error_peak_at_s']:.1f} s after"
        f" t0); its raw per-frame error crosses 5 cm {raw}. A censored horizon is only known not to lie within the"
        " record: nothing is known beyond it."
        " The losses were fitted to this same record, so every horizon is in-sample; and at this energy the motion"
        " is regular (below), so a horizon measures how well the model's frequencies and damping match the"
        " pendulum's, not how predictable it is."
    )


def cause_text(s: PredictionSummary) -> str:
    """Model error or the fit's uncertainty? Compare the observed 5 cm horizon with the ensemble's."""
    span = s["prediction_s"]
    observed = s["horizons_smoothed_s"][MAIN_RUN]["lower_bob_5cm_s"]
    chaos = s["chaos_horizons_s"]["lower_bob_5cm_s"]
    chaos_bound = span if chaos is None else chaos  # None: beyond the prediction
    if observed is None:
        return (f"The lower bob stays within 5 cm (smoothed) for the whole {span:.1f} s prediction; the horizon is "
                "longer than the prediction.")
    if chaos_bound > 2.0 * observed:
        return (
            "The observed 5 cm horizon is less than half the horizon of the fit's own uncertainty: the prediction "
            "fails through model error (the rigid-plate rods, the loss laws, the track's systematic errors), not "
            "through the uncertainty of the start."
        )
    return ("The observed 5 cm horizon is comparable with that of the fit's own uncertainty: the start's "
            "uncertainty limits it.")


def regime_text(s: PredictionSummary) -> str:
    """The regime paragraph: the exponent, its decay, the energy against the flip energy, what limits the horizon."""
    r = s["regime"]
    checkpoints = ", ".join(f"{v:.3f} 1/s after {k.split('_after_')[1].replace('_s', '')} s"
                            for k, v in r["checkpoints"].items())  # fmt: skip
    below = "below" if r["energy_over_flip_energy"] < 1 else "above"
    head = (
        f"**Regime: {r['verdict']}.** The fitted start has E = {r['energy_J']:.3f} J (rods included), "
        f"{below} the {r['lower_rod_flip_energy_J']:.3f} J the lower rod needs to flip "
        f"(E/E_flip = {r['energy_over_flip_energy']:.2f}). Its largest Lyapunov exponent (frictionless, "
        f"{r['averaging_time_s']:.0f} s) is {r['largest_lyapunov_exponent_per_s']:.3f} 1/s; running estimate: "
        f"{checkpoints} (at T/4: {r['exponent_at_quarter_time_per_s']:.3f} 1/s)."
    )
    if r["verdict"] == "regular":
        return (f"{head} It keeps falling towards 0 (lambda T grows only about like ln T, as for a separation "
                "that grows linearly): the motion is regular, nearby runs separate about linearly, and no horizon "
                "here is a chaos limit; it is a model and measurement limit.")
    return (f"{head} It does not fall towards 0 (lambda T grows like T): the motion is chaotic, with an e-folding "
            f"time of about {1 / r['largest_lyapunov_exponent_per_s']:.1f} s.")


def loss_models_text(s: PredictionSummary) -> str:
    """The main start under every loss model the record supports equally: each model's 5 cm horizons, the ranges."""
    sens = s["loss_model_sensitivity"]
    span = s["prediction_s"]
    if sens["n_models"] < 2 and s.get("quick"):
        return ("**Under the other loss models.** Not run: this mode fits one loss model, so the horizons' spread over "
                "the models the record supports equally is unknown here.")
    if sens["n_models"] < 2:
        return ("**Under the other loss models.** None is run: of the loss models ``loss_identification`` fits, only "
                "this one lies within dAIC 2 of the best on this record, so there is no spread over equally supported "
                "models to show. The others are not ruled out for the motion: their energy fits lie 2 or more behind.")
    rows = "; ".join(f"{model_title(m)}: {claim_horizon(h['horizon_s'], h['censored'])} smoothed, "
                     f"{fmt_horizon(h['raw_horizon_s'], span)} s per frame" for m, h in sens["models"].items())
    return (f"**Under the other loss models.** The energy record supports {sens['n_models']} loss models equally "
            "(``loss_identification``), and the horizons depend on which one the prediction uses. The same start and "
            f"geometry with each ({rows}) keep the smoothed error within 5 cm for {smoothed_range_text(sens)} and the "
            f"per-frame error for {raw_range_text(sens)}. That range, not one run's figure, is what the record "
            "supports; the table above is the run with one of them.")


def loss_uncertainty_text(s: PredictionSummary) -> str:
    """The horizon's sensitivity to the damping level per model and, with ``--thorough``, the ensemble over the
    losses' and the start's covariance (median and 16-84 % range)."""
    u = s.get("loss_uncertainty")
    if not u or not u["damping_sensitivity"]:
        return ""
    rows = "; ".join(f"{model_title(m)}: {d['smoothed_s_per_percent']:+.1f} s smoothed"
                     f"{' or more' if d['slope_is_lower_bound'] else ''}, {d['raw_s_per_percent']:+.1f} s per frame"
                     for m, d in u["damping_sensitivity"].items())  # fmt: skip
    censored = all(all(level["censored"] for level in d["levels"].values()) for d in u["damping_sensitivity"].values())
    if censored:
        text = ("**The losses' uncertainty.** The horizons above take each model's fitted losses as exact. With 1 % "
                "less and 1 % more damping (every loss coefficient times 0.99 and 1.01) the 5 cm horizon still reaches "
                f"the end of the record ({', '.join(map(model_title, u['damping_sensitivity']))}): censored at every "
                "level, so how far 1 % of damping moves it is not known from this record.")
    else:
        text = ("**The losses' uncertainty.** The horizons above take each model's fitted losses as exact, and the "
                "horizon is very sensitive to the damping level: 1 % more damping (every loss coefficient times "
                f"1.01; central difference of +-1 %) changes the 5 cm horizon by about ({rows}; \"or more\": a "
                "censored end, the size is a lower bound), so an uncertainty of the fitted damping of a few tenths "
                "of a per cent already moves it by a second.")
    if "ensemble" not in u:
        return text + " The ensemble over the losses' covariance runs with ``--thorough``."
    ens = "; ".join(f"{model_title(m)}: {_stats_text(e['smoothed_5cm'])} smoothed, {_stats_text(e['raw_5cm'])} "
                    "per frame" for m, e in u["ensemble"].items())  # fmt: skip
    return text + f" Drawn from the losses' and the start's covariance ({u['ensemble_definition']}): {ens}."


def _end(value: float, span: float) -> str:
    """A horizon [s] as text, 'beyond the record' at the record's end ``span`` [s] (censored)."""
    return "beyond the record" if value >= span else f"{value:.1f} s"


def budget_text(s: Mapping[str, Any]) -> str:
    """The horizon over every uncertain input (:mod:`.horizon_budget`): the one-at-a-time changes, the rods'
    profile and the distribution's median and ranges."""
    b = s["horizon_budget"]
    span, d = b["span_s"], b["distribution"]
    lo, hi = d["range_16_84_s"]
    lo2, hi2 = d["range_2_97_s"]
    names = [f"the {n}" if n != "l1" else n for n in b["inputs_drawn"]]
    drawn = ", ".join(names[:-1]) + f" and {names[-1]}"
    text = (f"**The horizon over every uncertain input.** {d['n']} runs, each drawing {drawn} from their covariance "
            f"at once: the 5 cm horizon (smoothed) has the median {_end(d['median_s'], span)}, 16-84 % from "
            f"{_end(lo, span)} to {_end(hi, span)}, 2.5-97.5 % from {_end(lo2, span)} to {_end(hi2, span)} "
            f"({d['censored_fraction']:.0%} of the runs never leave 5 cm within the record).")
    if b["rod_profile"] is None and b["dominant_input"] is None:
        return text + (" (A quick run: a smoke test of the ensemble and of the losses one at a time; the other "
                       "inputs run by default.)")
    rows = "\n".join(f"| {r['input']} | {r['kind']} | {r['low']}: {_end(r['low_s'], span)} | "
                     f"{r['high']}: {_end(r['high_s'], span)} |" for r in b["one_at_a_time"])  # fmt: skip
    text += (f" What moves it (``horizon_budget.png``; the main run: {_end(b['main_horizon_s'], span)}), each input "
             "at two values with the others held, the start and geometry fitted again where the input is part of "
             f"the model (rods, l1, window); largest change first:\n\n| input | values | low | high |\n"
             f"|---|---|---|---|\n{rows}\n\nThe uncertain input that moves it most: {b['dominant_input']}.")
    prof = b["rod_profile"]
    if prof:
        steps = ", ".join(f"{1e3 * r['member_kg']:.0f} g: {dc:+.1f}" for r, dc in
                          zip(prof["rows"], prof["delta_chi2_over_chi2_red"]))  # fmt: skip
        rms = ", ".join(f"{1e3 * r['member_kg']:.0f} g: {1e3 * r['rms_error_m']:.0f} mm" for r in prof["rows"])
        window = ("lowest at the edge of the masses tried, so it bounds the mass on one side only" if prof["at_edge"]
                  else f"lowest at {1e3 * prof['best']:.0f} +- {1e3 * prof['stderr']:.0f} g")
        text += (f"\n\n**The rods' inertia.** The start and geometry fitted again with each member's mass: the "
                 f"fit's chi2 over the start-fit window rises by (chi2 - chi2_min) / chi2_red = {steps} "
                 f"({window}); the lower bob's RMS error over the whole prediction is {rms} (lowest of these at "
                 f"{1e3 * prof['record_rms_lowest_at_kg']:.0f} g, with the losses fitted for the seed's 70 g). "
                 f"The drawn rods take +-{1e3 * b['rods_stderr_kg']:.0f} g: {b['rods_stderr_from']}.")
    return text


def _short_horizon(score: Mapping[str, Any]) -> str:
    """'12.34 s', or '> 19.99 s' for a censored horizon (never crossed in the record)."""
    return f"{'> ' if score['horizon_5cm_censored'] else ''}{score['horizon_5cm_s']:.2f} s"


def motion_out_of_sample_text(s: PredictionSummary) -> str:
    """The out-of-sample test of the motion (``--thorough``): per direction a table of every model's held-out RMS
    error, median smoothed error and horizon, half-fitted against whole-record-fitted, and what it says."""
    o = s.get("out_of_sample_motion")
    if not o:
        return ("**Out of sample.** Every horizon above is in-sample. The test that fits each loss model to one half "
                "of the energy record and predicts the other half's motion runs with ``--thorough``.")
    span = s["prediction_s"]
    tables = []
    for name, d in o["directions"].items():
        fitted, predicts = name.split("_predicts_")
        rows = []
        for m in d["order"]:
            x, w = d["scores"][m], d["whole_record_scores"][m]
            tie = " (tie)" if m in d["tie"] else ""
            rows.append(f"| {model_title(m)}{tie} | {100 * x['rms_error_m']:.1f} ({100 * w['rms_error_m']:.1f}) | "
                        f"{100 * x['median_smoothed_error_m']:.1f} ({100 * w['median_smoothed_error_m']:.1f}) | "
                        f"{_short_horizon(x)} ({_short_horizon(w)}) |")
        tables.append(f"Losses fitted to the {fitted} half, scored on the {predicts} half "
                      f"({next(iter(d['scores'].values()))['n_frames']} frames); in brackets the same model fitted to "
                      "the whole record (in-sample):\n\n| loss model | RMS error of the lower bob [cm] | median "
                      "smoothed error [cm] | 5 cm horizon, smoothed |\n|---|---|---|---|\n" + "\n".join(rows))
    return (f"**Out of sample: the motion.** Each supported loss model fitted to one half of the energy record alone "
            f"(the split {o['split_after_t0_s']:.1f} s after t0, the energy test's), the main start run with it "
            f"through the FMU for the whole {span:.1f} s, the lower bob compared on the half the fit never saw "
            "(``out_of_sample_motion.png``).\n\n" + "\n\n".join(tables) + f"\n\n{o['text']}\n\n"
            "![out of sample: the motion](out_of_sample_motion.png)")


def _stats_text(stats: Mapping[str, Any]) -> str:
    """'median 13.3 s (16-84 %: 9.5 s to beyond the record)' of :func:`~.loss_uncertainty.horizon_stats`."""
    med = "beyond the record" if stats["median_censored"] else f"{stats['median_s']:.1f} s"
    lo, hi = stats["range_16_84_s"]
    top = "beyond the record" if stats["top_censored"] else f"{hi:.1f} s"
    return f"median {med} (16-84 %: {lo:.1f} s to {top})"


def smoothed_range_text(sens: Mapping[str, Any]) -> str:
    """The smoothed 5 cm horizons' range over the loss models (``loss_model_sensitivity``), its top said as the
    end of the record where a model's horizon is censored."""
    lo, hi = sens["smoothed_5cm_range_s"]
    top = f"the end of the {hi:.1f} s compared (censored)" if sens["smoothed_censored_models"] else f"{hi:.1f} s"
    return f"{lo:.1f} s to {top}"


def raw_range_text(sens: Mapping[str, Any]) -> str:
    """The per-frame 5 cm horizons' range over the loss models [s]."""
    lo, hi = sens["raw_5cm_range_s"]
    return f"{lo:.1f} to {hi:.1f} s"


def loss_text(s: PredictionSummary) -> str:
    """The identified loss parameters: value +- standard error with units."""
    return ", ".join(f"{k} = {p['value']:.4g} +- {p['stderr']:.2g} {p['unit']}"
                     for k, p in s["model"]["loss_parameters"].items())  # fmt: skip


def _loss_models_sentence(s: PredictionSummary) -> str:
    """The opening's sentence on the loss models the record cannot tell apart (empty with one model)."""
    sens = s["loss_model_sensitivity"]
    if sens["n_models"] < 2:
        return ""
    return (f"These losses are one of {sens['n_models']} loss models that fit the measured energy equally well; with "
            f"each of them the same start stays within 5 cm for {smoothed_range_text(sens)} smoothed and "
            f"{raw_range_text(sens)} frame by frame, so the record supports that range, not one figure.")


def _opening(s: PredictionSummary, quick: str) -> str:
    """Title, plain summary and the words used; horizons to 0.1 s, as the page's table gives them (the smoothing
    window is 0.25 s, and a first crossing of the per-frame error moves by a few 30 fps frames)."""
    d = s["horizon_5cm_details"][MAIN_RUN]
    span = s["prediction_s"]
    held = (f"stays within 5 cm of the track for all {span:.1f} s compared" if s["horizon_5cm_censored"]
            else f"stays within 5 cm of the track for {s['horizon_5cm_s']:.1f} s")
    raw = ("never" if d["raw_horizon_s"] is None else f"first after {d['raw_horizon_s']:.1f} s")
    seed = s["horizons_smoothed_s"]["seed_start_frictionless"]["lower_bob_5cm_s"]
    seed_text = "the whole comparison" if seed is None else f"{seed:.1f} s"
    return report_opening(f"FMU prediction of the measured track{quick}", [
        f"The FMU is started from the pendulum's state at t0 = {s['t0_s']:.2f} s, as the seed did, and the "
        f"simulated bob positions are compared with the camera track frame by frame for {span:.1f} s.",
        f"With the start and the camera's geometry fitted to the first "
        f"{s['starts']['least_squares_geometry']['n_frames'] / FPS:.1f} s, the lower bob {held} when the error is "
        f"smoothed over {s['smoothing']['window_s']:g} s"
        + (f" (it comes within {1e3 * d['margin_below_threshold_m']:.1f} mm of 5 cm, "
           f"{d['smoothed_error_peak_at_s']:.1f} s after t0)" if s["horizon_5cm_censored"] else "")
        + f"; frame by frame the error exceeds 5 cm {raw}"
        + (" (a quick run: a smoke test of 3 s, not the default run's numbers)." if s["quick"] else "."),
        _loss_models_sentence(s),
        f"Started the seed's way (its own reconstruction of the state, no friction) it stays within 5 cm for "
        f"{seed_text}, with the start fitted but the geometry fixed for {s['horizon_5cm_s_fixed_geometry']:.1f} s.",
        "How sure: the friction losses were fitted to this same record, so this is no test on new data; another "
        "camera geometry fits as well, and the motion is regular, not chaotic, so this measures how well the "
        "model's swing frequencies and damping match the pendulum's, not how predictable it is.",
    ], {
        "smoothed error": f"the distance between simulated and measured bob, smoothed by a moving median over "
                          f"{s['smoothing']['window_s']:g} s (about 7 frames), which removes the track's frame-to-frame"
                          " jitter; the per-frame error keeps it",
        "horizon": "the first time after t0 at which the error exceeds a threshold (2 cm, 5 cm)",
        "censored": "a horizon that reaches the end of the record: only known not to lie within it",
        "in-sample": "judged on the data the model was fitted to: agreement there is expected, not a test",
        "Savitzky-Golay": "a smoothing derivative (a local polynomial fit over a few frames) for the rates",
        "chi2_red": "the fit's sum of squared residuals over their errors per degree of freedom; about 1 if the "
                    "model misses the track by its noise; the standard errors are scaled by its square root",
        "Lyapunov exponent": "the rate [1/s] at which nearby runs separate exponentially; tending to 0 with the "
                             "averaging time T (like ln T / T: the separation grows linearly) means regular motion",
    })


def report_text(summary: PredictionSummary) -> str:
    """The Markdown report: every figure from ``summary``."""
    s = summary
    quick = " (quick run)" if s["quick"] else ""
    m = s["model"]
    lsq = s["starts"]["least_squares"]
    geo = s["starts"]["least_squares_geometry"]
    floor = s["track_rod_length_floor"]
    chaos = s["chaos_horizons_s"]
    span = s["prediction_s"]
    goal = s["goal"]
    reached = (f"for the whole {goal['reached_s']:.2f} s compared (censored)" if goal["reached_is_lower_bound"]
               else f"for {goal['reached_s']:.2f} s")
    change = lsq["change_from_reconstruction"]
    smooth = s["smoothing"]
    return _opening(s, quick) + f"""## Method

Start at the frame nearest the seed's t0 = 0.8 s (t0 = {s["t0_s"]:.4f} s, frame {s["start_frame"]}), predict
{span:.1f} s, compare the bob positions with the track frame by frame. Positions relative to the pivot
fitted by the measurement (circle fit of the upper bob, at x = {1e3 * s["pivot_origin_m"]["x"]:.2f} mm,
y = {1e3 * s["pivot_origin_m"]["y"]:.2f} mm in the track's coordinates); the FMU's origin is the pivot at rest,
its positions turned and shifted by the fitted camera rotation and pivot offset where these are fitted.

Model: the seed's pendulum with its acrylic rods ({m["rods"]["m_rod1"]:.3f} kg and {m["rods"]["m_rod2"]:.3f} kg
plates of {m["rods"]["L_rod1"]:.2f} m and {m["rods"]["L_rod2"]:.2f} m), l1 = {m["lengths_m"]["l1"]:.4f} m,
l2 = {m["lengths_m"]["l2"]:.4f} m from the track, and the losses ``{m["loss_model"]}`` (air drag and a bearing drag
torque), one of the models ``loss_identification`` finds the record cannot tell apart (the main start with each
of the others: under the horizons), fitted to {m["loss_fit_record_s"]:.1f} s of the measured energy decay as that
scenario's {"quick" if s["quick"] else "default"} run fits it (same start and run budget, so either scenario reads
the other's cached fit; {m["loss_fit_runs"]} in-process runs): {loss_text(s)}. The seed-start frictionless
run uses point masses on massless rods, as the seed did.

## Start states and geometry

| start value | seed start (angles, Savitzky-Golay rates of frame t0) \
| least squares, state only, {lsq["n_frames"]} frames | least squares with geometry, {geo["n_frames"]} frames |
|---|---|---|---|
{state_rows(s)}

The state-only start reproduces its {lsq["n_frames"]} frames with an rms position residual of
{1e3 * lsq["rms_residual"]:.1f} mm (chi2_red = {lsq["chi2_red"]:.0f} with the rod-jitter noise as errors; the
standard errors are scaled by chi2_red); its rates differ from the reconstruction's by {change["omega1_0"]:+.2f} and
{change["omega2_0"]:+.2f} rad/s. Fitted together with the geometry over {geo["n_frames"]} frames
({geo["n_frames"] / FPS:.2f} s after t0): {geometry_text(geo["geometry"], geo["geometry_stderr"])}
(view_rotation: the FMU's positions turned counter-clockwise about the pivot, a camera whose vertical is
not along gravity; pivot offset from the circle-fit pivot; standard errors scaled by
chi2_red = {geo["chi2_red"]:.0f}); rms residual {1e3 * geo["rms_residual"]:.1f} mm.
Correlations above 0.9 in size: {correlation_text(geo)}. l1 is left at the
track's value: fitted as well it trades off against the pivot's height.

## Prediction horizons

Time after t0 at which the position error first exceeds 2 cm and 5 cm. The per-frame error carries the
track's jitter, so the horizons are taken on the error smoothed by a {smooth["method"]} over
{smooth["window_s"]:.2f} s; the per-frame 5 cm horizon is given beside them; lower bob
(``prediction_error.png``, ``coordinates.png``; "none in {span:.2f}": not exceeded in the {span:.2f} s compared,
censored):

{HORIZON_HEADER}
{horizon_rows(s)}

{horizon_claims_text(s)}

{loss_models_text(s)}

{loss_uncertainty_text(s)}

{budget_text(s)}

{motion_out_of_sample_text(s)}

**Goal**: {goal["statement"]}. Held {reached}, **{"met" if goal["met"] else "not met"}** (in-sample).
The seed saw agreement until about 2 s, i.e. about {2.0 - s["t0_s"]:.1f} s after t0, by eye.

**Two floors.** (1) The track: the distance between the bobs varies where a rigid rod allows none,
by {1e3 * floor["rms_m"]:.1f} mm rms and up to {1e3 * floor["max_m"]:.1f} mm in this window (correlation of the
signed deviation with omega2^2: {floor["correlation_with_omega2_squared"]:+.2f}). (2) The start's own
uncertainty (losses held at their fit): {s["ensemble_size"]} runs drawn from the covariance of the start and geometry
part from the central run by 2 cm after {fmt_horizon(chaos["lower_bob_2cm_s"], span)} s and by 5 cm after
{fmt_horizon(chaos["lower_bob_5cm_s"], span)} s (median distance of the lower bob). {cause_text(s)}

{regime_text(s)}

Fit window of the start and geometry (more frames: a better average over the track's errors, but more
model error inside the window):

{sensitivity_rows(s)}
"""
