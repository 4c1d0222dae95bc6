r"""The Markdown report of the ``loss_identification`` scenario, built from its summary.

Every number comes from the summary of :func:`double_pendulum.analysis.losses.identification.identify_losses`:
the model comparison (AIC/BIC with the residual correlation), the models the record supports about as
well and the range of the air share across them, the top model's parameters with errors, correlations
and profiles, its loss shares, b and p measured against simulated, the residuals of the two halves of the
record, and the answer to the seed's question.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any


def _pm(value: float, err: float) -> str:
    return f"{value:.3g} +- {err:.2g}"


def _unit(unit: str) -> str:
    """A unit after a value (nothing for the dimensionless '1')."""
    return "" if unit == "1" else f" {unit}"


def model_table(rows: list[Mapping[str, Any]]) -> str:
    """Markdown table: model, parameters with errors, chi2_red, dAIC, dBIC, Akaike weight, shares."""
    lines = ["| model | parameters | chi2_red | dAIC | dBIC | Akaike weight | b_sim [1/s] | p_sim | loss shares |",
             "|---|---|---|---|---|---|---|---|---|"]  # fmt: skip
    for r in rows:
        params = ", ".join(f"{n} = {_pm(p['value'], p['stderr'])}{_unit(p['unit'])}"
                           for n, p in r["parameters"].items())
        shares = ", ".join(f"{k} {v:.0%}" for k, v in r["shares"].items())
        if r.get("fit_stopped", "converged") != "converged":
            shares += f" (fit stopped: {r['fit_stopped']}, its chi2 may lie above the model's minimum)"
        if not r.get("converged", True):
            shares += f" (not ranked: {r['not_ranked_because']})"
        lines.append(f"| {r['model']} | {params} | {r['chi2_red']:.3f} | {r['delta_aic']:.1f} | {r['delta_bic']:.1f} "
                     f"| {r['akaike_weight']:.3f} | {r.get('b_sim_per_s', float('nan')):.5f} "
                     f"| {r.get('p_sim', float('nan')):.2f} | {shares} |")  # fmt: skip
    return "\n".join(lines)


def parameter_lines(s: Mapping[str, Any]) -> str:
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
        verdict = "identified" if ident[name] else "NOT identified (relative error above 50 %)"
        partners = s["identifiability"].get("strongly_correlated", {}).get(name)
        if partners:
            verdict += f"; strongly correlated with {', '.join(partners)}: the energy fixes their combination"
        out.append(f"- {name} = {_pm(p['value'], p['stderr'])}{_unit(p['unit'])} ({p['description']}; "
                   f"{p['relative_error']:.0%} relative{interval}) -- {verdict}")  # fmt: skip
    return "\n".join(out)


def correlation_text(s: Mapping[str, Any]) -> str:
    """The best model's parameter correlation matrix as text."""
    ident = s["identifiability"]
    names, corr = ident["parameters"], ident["correlation"]
    if len(names) < 2:
        return "one parameter: no correlations."
    pairs = [f"{names[i]}-{names[j]}: {corr[i][j]:+.3f}" for i in range(len(names)) for j in range(i + 1, len(names))]
    return ", ".join(pairs)


def goal_text(s: Mapping[str, Any]) -> str:
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


def seed_friction_text(s: Mapping[str, Any]) -> str:
    """The fitted drag torque against the seed's rolling-friction estimate, as a torque at the pivot."""
    d = s.get("drag_torque_against_seed_rolling_friction")
    if not d:
        return ""
    lo, hi = sorted(d["fitted_over_seed"])
    return (f"The fitted drag torque, {1e3 * d['fitted_tau_b_N_m']:.2f} mN.m per joint, is {lo:.0f} to {hi:.0f} times"
            f" the seed's own rolling-friction estimate as a torque (c_R = {d['c_R'][0]:g} to {d['c_R'][1]:g} times"
            f" r_b = {1e3 * d['r_b_m']:g} mm times the pivot's load {d['pivot_load_N']:.2f} N:"
            f" {1e6 * d['torque_N_m'][0]:.0f} to {1e6 * d['torque_N_m'][1]:.0f} uN.m). Such a torque is plausible"
            " for sealed ball bearings (seals and grease, of the order of 1 N.mm); the seed names its bearings'"
            " maker, not their type or seals, so this stays an assumption.")


def report_text(s: Mapping[str, Any]) -> str:
    """The whole report."""
    from .claims import SEPARATING_MEASUREMENTS, per_joint_text

    air = s["air_drag_at_defaults"]
    err = s.get("top_model_shares_stderr", {})
    shares = ", ".join(f"{k} {v:.0%} +- {err.get(k, 0.0):.0%}" for k, v in s["top_model_shares"].items())
    b_range = s.get("b_sim_range_all_models_per_s")
    b_text = (f" Every converged model, air drag alone included, gives b_sim from {b_range[0]:.4f} to"
              f" {b_range[1]:.4f} 1/s: b is what the fit matches, so agreement in b discriminates nothing, and the"
              " agreement in p is in-sample (p was fitted on the same record)." if b_range else "")
    mode = (" (quick mode, a smoke run: air+drag alone, one Gauss-Newton step at rtol 1e-5, no comparison, no"
            " profiles; its errors are the curvature errors of that step)" if s["quick"] else
            " (thorough: with air+drag2, the three-mechanism models and the profile likelihood)"
            if s.get("thorough") else
            " (default run: one and two mechanisms; `--thorough` adds air+drag2, the three-mechanism models"
            " air+drag+bearing, air+drag+viscous and air+drag+suspension and the best model's profile likelihood,"
            " about 2.5 min more CPU)")
    return f"""# Loss identification: which mechanisms drain the seed's pendulum?

The measured energy of the seed's pendulum (camera track, Table 1; rigid links with 70 g acrylic
members, `SEED_RIGID_LINKS`) over the whole record ({s['record_s']:.1f} s, {s['n_frames']} frames
from t0 = {s['t0_s']:.3f} s) is fitted by the simulated energy of the pendulum, started in the
measured state, for combinations of loss mechanisms{mode}. The fit scales the simulated energy by a
calibration kappa = {s['energy_scale_kappa']:.4f} (camera energy against model energy; it changes
neither b nor p). The residuals are correlated over about a swing: variance factor
F = {s['correlation_factor_F']:.2f} (n_eff = n/F); AIC = chi2/F + 2k, BIC = chi2/F + k ln(n/F), errors
multiplied by sqrt(F).

## Models

{model_table(s['models'])}

![loss shares](loss_shares.png)

## Which models the record supports

{s['supported_models']['text']}

{SEPARATING_MEASUREMENTS}

{per_joint_text(s['models'])}

## The top model by AIC: {s['top_model']} (not a verdict)

{parameter_lines(s)}

Correlations: {correlation_text(s)}. Where two parameters correlate this strongly the energy fixes their
combination, not each: the split below is the total loss restated under this one assumed pair of mechanisms.

{seed_friction_text(s)}

Shares of the dissipated work over the record, in this model: {shares}. The model dissipates
{s['simulated_loss_J']:.3f} J; the measured exponential fit loses {s['measured_loss_J']:.3f} J over the same frames.

![measured and simulated energy](energy_fit.png)

{"![profile likelihood](profiles.png)" if s['profile_likelihood'] else ""}

## Does the top model follow the measured energy over all 21 s?

Exponential and power-law fits to the measured and to the simulated energy (FMU run of the top model) on the
same frames with the same errors:

{goal_text(s)}
{b_text}

## Does the suspension dominate the loss (the seed's question)?

{s['answer']}

## Air drag

With the default drag coefficients (bobs cw = 1, rods cw_rod = {air['cw_rod']:g}, edge-on) on the
seed's pendulum, air drag dissipates {air['W_air_J']:.3f} J over the record, {air['share_of_measured_loss']:.0%}
of the measured loss. The seed itself calls air drag and rolling friction negligible and holds the
suspension mainly responsible (its section 4.2.5).
"""
