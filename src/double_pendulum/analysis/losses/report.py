r"""The Markdown report of the ``loss_identification`` scenario, built from its summary.

Every number comes from the summary of :func:`double_pendulum.analysis.losses.identification.identify_losses`:
the model comparison (AIC/BIC with the residual correlation), the models the record supports about as
well and the range of the air share across them, the top model's parameters with errors, correlations
and profiles, its loss shares, b and p measured against simulated, the residuals of the two halves of the
record, and the answer to the seed's question.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

from ...runs.results_io import report_opening
from .air_profile import air_share_text
from .holdout import holdout_section
from .mechanisms import model_title
from .summary_types import LossesSummary


def _pm(value: float, err: float | None) -> str:
    """``value +- err``; a value without an error (a fit that stopped short of an optimum): "stopped at value"."""
    return f"stopped at {value:.3g}" if err is None else f"{value:.3g} +- {err:.2g}"


def _unit(unit: str) -> str:
    """A unit after a value (nothing for the dimensionless '1')."""
    return "" if unit == "1" else f" {unit}"


def model_table(rows: list[Mapping[str, Any]]) -> str:
    """Markdown table, one model a row in words: parameters with errors, dAIC, Akaike weight, p_sim, shares."""
    lines = ["| model | parameters | dAIC | Akaike weight | p_sim | loss shares |", "|---|---|---|---|---|---|"]
    for r in rows:
        params = ", ".join(f"{n} = {_pm(p['value'], p['stderr'])}{_unit(p['unit'])}"
                           for n, p in r["parameters"].items())
        shares = ", ".join(f"{k} {v:.0%}" for k, v in r["shares"].items())
        daic = f"{r['delta_aic']:.1f}"
        if "delta_aic_at_best" in r:  # its optimum is its nested limit: a bound, not a fit
            daic = f"at best {r['delta_aic_at_best']:.0f}"
            shares = f"no finite fit: its best is {model_title(r['best_is_limit_model'])} (see below)"
        elif not r.get("converged", True):
            daic, shares = "not ranked", f"{shares} (not ranked: {r['not_ranked_because']})"
        elif r.get("fit_stopped", "converged") != "converged":
            shares += f" (fit stopped: {r['fit_stopped']}, its chi2 may lie a little above the model's minimum)"
        if r.get("reduces_to"):
            shares += f" (no better than {model_title(r['reduces_to'])}, which it contains)"
        lines.append(f"| {model_title(r['model'])} (`{r['model']}`) | {params} | {daic} | {r['akaike_weight']:.2f} "
                     f"| {r.get('p_sim', float('nan')):.2f} | {shares} |")  # fmt: skip
    return "\n".join(lines)


def parameter_lines(s: LossesSummary) -> str:
    """The best model's parameters: value, error (with the correlation factor), profile interval, verdict."""
    out = []
    ident = s["identifiability"]["identified"]
    for name, p in s["parameters"].items():
        prof = s["profile_likelihood"].get(name)
        interval = ""
        if prof:
            lo, hi = prof["interval_1sigma"]
            fmt = lambda v: "beyond the profiled range" if v is None else f"{v:.3g}"  # noqa: E731
            interval = f"; profile (delta chi2/F = 1): {fmt(lo)} .. {fmt(hi)}"
        partners = s["identifiability"].get("strongly_correlated", {}).get(name)
        if partners:
            verdict = (f"not identified on its own: it correlates with {', '.join(partners)} beyond 0.95, so the "
                       "energy fixes their combination, not each")
        elif ident[name]:
            verdict = "identified (in this model: its value assumes this model's mechanisms)"
        else:
            verdict = "NOT identified (relative error above 50 %)"
        out.append(f"- {name} = {_pm(p['value'], p['stderr'])}{_unit(p['unit'])} ({p['description']}; "
                   f"{p['relative_error']:.0%} relative{interval}) -- {verdict}")  # fmt: skip
    return "\n".join(out)


def _factor_text(s: LossesSummary) -> str:
    """How far F is from changing which models tie (``supported_from_factor``)."""
    joins = {m: f for m, f in s.get("supported_from_factor", {}).items() if f is not None}
    if not joins:
        return ""
    parts = ", ".join(f"{model_title(m)} from F = {f:.1f}" for m, f in joins.items())
    return (f"With a larger F the chi2 differences shrink against the charge per fitted number and models with fewer "
            f"numbers join the tie: {parts} (F = {s['correlation_factor_F']:.2f} here).")


def _pair_text(s: LossesSummary, max_corr: float = 0.95) -> str:
    """Within each supported pair of losses, whether the record fixes each loss or only their combination."""
    parts = []
    for r in s["models"]:
        corr = r.get("parameter_correlation")
        if r["model"] not in s["supported_models"]["models"] or not corr or len(corr) != 2:
            continue
        a, b = list(r["parameters"])
        if abs(corr[0][1]) > max_corr:
            parts.append(f"in {model_title(r['model'])} {a} and {b} correlate at r = {corr[0][1]:+.3f}")
    if not parts:
        return ""
    return ("Within the pairs the record fixes only the combination, not each loss (neither is identified on its "
            "own, so the shares above are the total loss restated under the assumed pair): " + "; ".join(parts) + ".")


def _correlation_note(s: LossesSummary) -> str:
    """What a strong correlation of the parameters means for the shares."""
    if not any(s["identifiability"].get("strongly_correlated", {}).values()):
        return ""
    return (" Where two parameters correlate this strongly the energy fixes their combination, not each: the split "
            "below is the total loss restated under this one assumed pair of mechanisms.")


def _regularisation_text(s: LossesSummary) -> str:
    """What the width of the friction sign function changes (``regularisation``), or nothing in a quick run."""
    reg = s.get("regularisation")
    if not reg:
        return ""
    rows = reg["by_omega_reg_rad_per_s"]
    fit = rows[f"{reg['fits_omega_reg_rad_per_s']:g}"]
    fmu = rows[f"{reg['fmu_default_omega_reg_rad_per_s']:g}"]
    return f"""## The friction regularisation

The friction torques switch sign with the joint's rotation through tanh(omega / omega_reg) instead of a sharp
step. The fits run at omega_reg = {reg['fits_omega_reg_rad_per_s']:g} rad/s (the FMU's default is
{reg['fmu_default_omega_reg_rad_per_s']:g} rad/s). Against a near-sharp {reg['reference_omega_reg_rad_per_s']:g} rad/s,
{model_title(reg['model'])} at its fitted values over the record moves the angles by at most
{fit['max_angle_difference_rad']:.1e} rad at the fits' width ({fmu['max_angle_difference_rad']:.1e} rad at the
FMU's), its joint losses by {fit['joint_work_relative_change']:+.1e} (relative) and chi2 by
{fit['delta_chi2']:+.1e}: far below what separates the models."""


def correlation_text(s: LossesSummary) -> str:
    """The best model's parameter correlation matrix as text."""
    ident = s["identifiability"]
    names, corr = ident["parameters"], ident["correlation"]
    if len(names) < 2:
        return "none (one parameter)"
    pairs = [f"{names[i]}-{names[j]}: {corr[i][j]:+.3f}" for i in range(len(names)) for j in range(i + 1, len(names))]
    return ", ".join(pairs)


def goal_text(s: LossesSummary) -> str:
    """The goal, met or not, in numbers."""
    g, h = s["goal"], s["residual_halves"]
    lines = [
        f"- b: measured {s['b_measured_per_s']:.5f} +- {s['b_measured_stderr']:.5f} 1/s, simulated "
        f"{s['b_sim_per_s']:.5f} 1/s: {g['b_relative_deviation']:+.2%} "
        f"({'within' if g['b_within_2_percent'] else 'NOT within'} 2 %)",
        f"- p (dE/dt ~ -E^p): measured {s['p_measured']:.3f} +- {s['p_measured_stderr']:.3f}, simulated "
        f"{s['p_sim']:.3f}: {g['p_deviation_in_stderr']:+.2f} standard errors "
        f"({'within' if g['p_within_2_stderr'] else 'NOT within'} 2)",
        f"- mean residual simulated - measured: first half "
        f"{h['first_half']['mean_J'] * 1e3:+.2f} +- {h['first_half']['stderr_J'] * 1e3:.2f} mJ, second half "
        f"{h['second_half']['mean_J'] * 1e3:+.2f} +- {h['second_half']['stderr_J'] * 1e3:.2f} mJ, difference "
        f"{h['difference_J'] * 1e3:+.2f} +- {h['difference_stderr_J'] * 1e3:.2f} mJ: "
        f"{'a trend' if h['trend'] else 'no trend'} (2 sigma)",
    ]
    verdict = "The goal is met." if g["met"] else "The goal is NOT met (see the numbers above)."
    return "\n".join(lines) + "\n\n" + verdict


def seed_friction_text(s: LossesSummary) -> str:
    """The fitted drag torque against the seed's rolling-friction estimate, as a torque at the pivot."""
    d = s.get("drag_torque_against_seed_rolling_friction")
    if not d:
        return ""
    lo, hi = sorted(d["fitted_over_seed"])
    c_r = "".join(f" In {model_title(m)} the load-proportional law needs c_R = {v['c_R']:.3f}, "
                  f"{min(v['over_seed']):.0f} to {max(v['over_seed']):.0f} times the seed's {d['c_R'][0]:g} to "
                  f"{d['c_R'][1]:g} for ball bearings."
                  for m, v in s.get("load_proportional_friction_against_seed", {}).items())
    return (f"in air drag + bearing drag torque the fitted drag torque, {1e3 * d['fitted_tau_b_N_m']:.2f} mN.m per "
            f"joint, is {lo:.0f} to {hi:.0f} times"
            f" the seed's own rolling-friction estimate as a torque (c_R = {d['c_R'][0]:g} to {d['c_R'][1]:g} times"
            f" r_b = {1e3 * d['r_b_m']:g} mm times the pivot's load {d['pivot_load_N']:.2f} N:"
            f" {1e6 * d['torque_N_m'][0]:.0f} to {1e6 * d['torque_N_m'][1]:.0f} uN.m). Such a torque is plausible"
            " for sealed ball bearings (seals and grease, of the order of 1 N.mm); the seed names its bearings'"
            " maker, not their type or seals, so this stays an assumption." + c_r)


def noise_section(s: LossesSummary) -> str:
    """AIC and BIC with F and with the AR(1) likelihood, side by side for every ranked model, and the ties."""
    nm = s.get("noise_model")
    if not nm:
        return ""
    refitted = bool(nm.get("refitted"))
    gain = " re-fit's gain in -2 ln L |" if refitted else ""
    lines = [f"| model | dAIC (F) | dBIC (F) | rho | dAIC (AR(1)) | dBIC (AR(1)) |{gain} innovations' "
             "autocorrelation, lags 1-3 |", "|---|---|---|---|---|---|" + ("---|" if refitted else "") + "---|"]
    for r in s["models"]:
        c = nm["criteria"].get(r["model"])
        if c is None:
            continue
        acf = ", ".join(f"{v:+.2f}" for v in c["innovation_autocorrelation"])
        g = f" {c['refit']['gain_neg2_log_likelihood']:.2f} |" if refitted else ""
        lines.append(f"| {model_title(r['model'])} | {r['delta_aic']:.1f} | {r['delta_bic']:.1f} | {c['rho']:.2f} "
                     f"| {c['delta_aic']:.1f} | {c['delta_bic']:.1f} |{g} {acf} |")
    n = next(iter(nm["criteria"].values()))["n_eff"]
    where = ("maximised by fitting every model again under it (its loss parameters, kappa and rho together)"
             if refitted else "evaluated at each least-squares optimum")
    return f"""## The noise model: AR(1) residuals, AIC and BIC from its likelihood

The fits' residuals are modelled as an AR(1) process, r_i = rho r_(i-1) + e_i, with rho and the variance fitted to
each model's residuals; its exact Gaussian likelihood, {where}, gives AIC =
-2 ln L + 2 k and BIC = -2 ln L + k ln n_eff (n_eff = n (1 - rho)/(1 + rho) = {n:.0f} frames; k counts the loss
parameters, kappa, rho and the variance). Beside them the criteria with the common factor F. All four are in-sample.

{chr(10).join(lines)}

{nm['text']} {_whiteness_text(nm, s['n_frames'])}"""


def _whiteness_text(nm: Mapping[str, Any], n: int) -> str:
    """Whether AR(1) whitens the residuals: the innovations' largest autocorrelation against 2/sqrt(n)."""
    worst = max(abs(v) for c in nm["criteria"].values() for v in c["innovation_autocorrelation"])
    bound = 2.0 / math.sqrt(n)
    if worst <= bound:
        return (f"The innovations e_i are white within 2/sqrt(n) = {bound:.2f} at lags 1 to 3: AR(1) describes the "
                "residuals' correlation.")
    return (f"The innovations e_i are not white (autocorrelation up to {worst:.2f} at lags 1 to 3 against "
            f"2/sqrt(n) = {bound:.2f} for independent frames): AR(1) captures the main correlation, not all of it, "
            "so its likelihood differences are approximate too.")


def _opening(s: LossesSummary) -> str:
    """Title, plain summary and the words used."""
    title = "Loss identification: which mechanisms drain the seed's pendulum?"
    lost = (f"The camera track shows the pendulum losing {s['measured_loss_J']:.2f} J of energy over "
            f"{s['record_s']:.0f} s. ")
    if s["quick"]:
        return report_opening(title, [
            lost + "This quick run (a smoke test) fits one assumed pair of losses, air drag and a constant friction "
            "torque in the joints, with one step of the fit, and compares nothing.",
            "Its numbers only show that the scenario runs; the default run compares the candidate losses.",
            "Nothing here is a result about the pendulum.",
        ], _terms(s))
    sup = s["supported_models"]
    air = sup["air_share_range"]
    names = "; ".join(model_title(m) for m in sup["models"])
    sentences = [
        lost + "Simulating the pendulum with different assumed losses (air drag, friction torques in the joints, a "
        "damped springy pivot) and adjusting each loss's strength until the simulated energy follows the measured "
        "one, this report asks which losses can explain it.",
        (f"{len(sup['models'])} of the {len(s['models'])} candidates follow the measurement about equally well "
         f"({names}), so the record shows how fast the energy falls but not which losses cause it"
         + (f": air drag's share of the loss can be anything from {air[0]:.0%} to {air[1]:.0%}." if air else "."))
        if len(sup["models"]) > 1 else
        (f"One of the {len(s['models'])} candidates follows the measurement best, by a margin the usual criterion "
         f"(AIC, 2) counts: {names}" + (f", with air drag taking {air[0]:.0%} of the loss." if air else ".")),
    ]
    profile = s.get("air_share_profile")
    if profile and profile["share_interval"]:
        lo, hi = profile["share_interval"]
        if lo is not None and hi is not None:
            sentences.append(f"Asked which shares of air drag the record allows at all (any model within a likelihood "
                             f"margin of 4 of the best fit), it answers {lo:.0%} to {hi:.0%}.")
    nm = s.get("noise_model")
    if nm and sorted(nm["ties"]["bic_ar1"]) != sorted(sup["models"]):
        bic, air_bic = nm["ties"]["bic_ar1"], nm["air_share_range"]["bic_ar1"]
        sentences.append(f"A stricter criterion that charges more for each fitted number (BIC, with a model of the "
                         f"correlated noise) keeps {len(bic)} of them ({'; '.join(model_title(m) for m in bic)})"
                         + (", none with air drag" if air_bic is None else "")
                         + ": how many candidates tie depends on the criterion, and so does air drag's share.")
    bound = s.get("suspension_as_main_loss")
    if bound:
        sentences.append(f"A damped springy pivot as the main loss, the seed's explanation, fits clearly worse at the "
                         f"stiffness and mass assumed here ({s['suspension_fixed']['k_N_per_m']:g} N/m, "
                         f"{s['suspension_fixed']['M_s_kg']:g} kg): no damping makes it fit better than a rigid pivot.")
    verdict = "the candidates tie" if len(sup["models"]) > 1 else "one leads"
    sentences.append("How sure: every fit is judged on the same record it was fitted to, and the verdict "
                     f"that {verdict} holds unless the frames' errors are far more correlated than the "
                     f"data indicate (neighbouring frames' errors are alike, so n frames count as "
                     f"n / {s['correlation_factor_F']:.2f} independent ones).")
    return report_opening(title, sentences, _terms(s))


def _terms(s: LossesSummary) -> dict[str, str]:
    """The words the report uses, explained."""
    return {
        "chi2": "the sum over the frames of ((simulated - measured energy) / the energy's error)^2; smaller fits "
                "better",
        "F": f"the correlation factor, here {s['correlation_factor_F']:.2f}: the errors of neighbouring frames are "
             "alike over about one swing, so the frames count as n / F independent ones (F from the measured energy's "
             "scatter about a smooth decay law, the same F for every model)",
        "AIC": "Akaike's information criterion, chi2 / F + 2 k for a model with k fitted numbers: lower is better, and "
               "every extra fitted number costs 2",
        "dAIC": "a model's AIC minus the lowest AIC; below 2 the record does not tell two models apart",
        "BIC": "the Bayesian information criterion chi2 / F + k ln(n / F), which charges extra numbers more",
        "Akaike weight": "exp(-dAIC / 2) over the sum of that for all models fitted: each model's relative support "
                         "among these candidates, not the probability that it is true",
        "kappa": "one scale factor on the simulated energy, fitted with every model (the camera's energy calibration); "
                 "it changes neither b nor p",
        "b": "the decay rate [1/s] of the energy fitted as E = a exp(b t)",
        "p": "the loss exponent of dE/dt = -k E^p: 0.5 for a constant friction torque, 1 for viscous damping, 1.5 for "
             "air drag; p_sim is a simulated model's",
        "in-sample": "judged on the same data the model was fitted to, so agreement there is expected, not a test",
        "Gauss-Newton": "the fitting method: from a start, repeated linearised least-squares steps",
        "rtol": "the integrator's relative error tolerance per step",
    }


def _air_on_decay_text(air: Mapping[str, Any]) -> str:
    """The air drag at the default coefficients along the measured decay (empty without a model that has air)."""
    if air.get("W_air_on_measured_decay_J") is None:
        return ""
    return (f"Along a motion that decays as measured (the fitted {air['measured_decay_model']}, its air work divided "
            f"by its fitted air factor) the same coefficients dissipate {air['W_air_on_measured_decay_J']:.3f} J, "
            f"{air['share_on_measured_decay']:.0%} of the measured loss. ")


def untilted_text(u: Mapping[str, Any] | None) -> str:
    """What the camera's tilt changes in the comparison (the thorough run's untilted identification); "" without."""
    if not u:
        return ("The energy is that of the track turned back by the camera's tilt against gravity (`energy_decay`'s "
                "`tilt`); `--thorough` repeats the comparison on the untilted track.")
    ties = "; ".join(f"{k}: {', '.join(v)}" for k, v in u["ties"].items())
    return (f"On the untilted track (the camera's tilt not removed) the models within 2 of the lowest were: {ties} "
            "(the criteria as in the noise-model section below).")


def report_text(s: LossesSummary) -> str:
    """The whole report."""
    from .claims import SEPARATING_MEASUREMENTS, per_joint_text

    air = s["air_drag_at_defaults"]
    err = s.get("top_model_shares_stderr", {})
    shares = ", ".join(f"{k} {v:.0%} +- {err.get(k, 0.0):.0%}" for k, v in s["top_model_shares"].items())
    b_range = s.get("b_sim_range_all_models_per_s")
    b_text = (f"Every converged model, air drag alone included, gives b_sim from {b_range[0]:.4f} to"
              f" {b_range[1]:.4f} 1/s: b is what the fit matches, so agreement in b discriminates nothing, and the"
              " agreement in p is in-sample (p was fitted on the same record)." if b_range else "")
    mode = (" (quick mode, a smoke run: air drag + bearing drag torque alone, one Gauss-Newton step at rtol 1e-5, no"
            " comparison, no"
            " profiles; its errors are the curvature errors of that step)" if s["quick"] else
            " (thorough: with air+drag2, the three-mechanism models and the profile likelihood)"
            if s.get("thorough") else
            " (default run: one and two mechanisms; `--thorough` adds air+drag2, the three-mechanism models"
            " air+drag+bearing, air+drag+viscous and air+drag+suspension and the best model's profile likelihood,"
            " about 2.5 min more CPU)")
    return _opening(s) + f"""## Method

The measured energy of the seed's pendulum (camera track, Table 1; rigid links with 70 g acrylic
members, `SEED_RIGID_LINKS`) over the whole record ({s['record_s']:.1f} s, {s['n_frames']} frames
from t0 = {s['t0_s']:.3f} s) is fitted by the simulated energy of the pendulum, started in the
measured state, for combinations of loss mechanisms{mode}. The fit scales the simulated energy by a
calibration kappa = {s['energy_scale_kappa']:.4f} (camera energy against model energy; it changes
neither b nor p). Errors of fitted numbers are multiplied by sqrt(F). {_factor_text(s)}

## Models

{model_table(s['models'])}

![loss shares](loss_shares.png)

## Which models the record supports

{s['supported_models']['text']}

{_pair_text(s)}

{air_share_text(s.get('air_share_profile'), s.get('untilted_track'))}

{untilted_text(s.get('untilted_track'))}

{noise_section(s)}

{holdout_section(s)}

How plausible the fitted friction is, against the seed's own estimate: {seed_friction_text(s)}

{SEPARATING_MEASUREMENTS}

{per_joint_text(s['models'])}

## The lowest AIC: {model_title(s['top_model'])} (not a verdict: see above)

{parameter_lines(s)}

Correlations: {correlation_text(s)}.{_correlation_note(s)}

Shares of the dissipated work over the record, in this model: {shares}. The model dissipates
{s['simulated_loss_J']:.3f} J; the measured exponential fit loses {s['measured_loss_J']:.3f} J over the same frames.

![measured and simulated energy](energy_fit.png)

{"![profile likelihood](profiles.png)" if s['profile_likelihood'] else ""}

## Does the model with the lowest AIC follow the measured energy over all {s['record_s']:.0f} s?

Exponential and power-law fits to the measured and to the simulated energy (FMU run of that model) on the
same frames with the same errors (in-sample: the model was fitted to these frames):

{goal_text(s)}

{b_text}

## Does the suspension dominate the loss (the seed's question)?

{s['answer']}

{_regularisation_text(s)}

## Air drag

With the default drag coefficients (bobs cw = 1, rods cw_rod = {air['cw_rod']:g}, edge-on) on the
seed's pendulum, air drag alone (no other loss) dissipates {air['W_air_J']:.3f} J over the record,
{air['share_of_measured_loss']:.0%} of the measured loss; it overstates air drag's part, since a pendulum that loses
only that much keeps a larger amplitude than the real one and drag grows like v^2.
{_air_on_decay_text(air)}The seed itself calls air drag and rolling friction negligible and holds the
suspension mainly responsible (its section 4.2.5).
"""
