r"""The Markdown report of the ``energy_decay`` scenario: figures from its summary and the discussion.

Every number comes from the summary (:mod:`.decay_summary`); the sections explain the geometry, the
energy's errors, the exponential fit E = a exp(b t) [J], the comparison of decay models and why a and
b differ from the seed's a = 0.813 J, b = -0.024 1/s.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

from ...runs.results_io import report_opening
from ..track.measurement import FPS, SEED_TOTAL_MASS_KG, SG_POLYORDER, SG_WINDOW
from .error_budget import budget_table
from .fit import AUTOCORRELATION_LAG_S
from .summary_types import DecaySummary


def plus_minus(value: float, err: float, scale: float = 1.0, digits: int = 4) -> str:
    """``value +- err``, both multiplied by ``scale`` (e.g. 1e3 for m -> mm), with ``digits`` decimals."""
    return f"{value * scale:.{digits}f} +- {err * scale:.{digits}f}"


def comparison_rows(summary: DecaySummary) -> str:
    """Markdown table of the decay models: parameters with errors, chi2_red, dAIC, dBIC, Akaike weight."""
    lines = ["| model | parameters | chi2_red | dAIC | dBIC | Akaike weight |", "|---|---|---|---|---|---|"]
    for row in summary["model_comparison"]:
        units = row["units"]
        params = ", ".join(
            f"{n} = {v:.4g} +- {row['stderr'][n]:.2g} {units[n] if units[n] != '1' else ''}".rstrip()
            for n, v in row["params"].items()
        )
        lines.append(
            f"| {row['model']} | {params} | {row['chi2_red']:.3f} | {row['delta_aic']:.1f} | "
            f"{row['delta_bic']:.1f} | {row['akaike_weight']:.3f} |"
        )
    return "\n".join(lines)


def variant_rows(summary: DecaySummary) -> str:
    """Markdown table of the exponential fit a [J], b [1/s] (errors inflated for correlation) per energy, weights."""
    labels = {
        "equal_weights": "Savitzky-Golay energy, equal weights",
        "cd_equal_weights": "central-difference energy, equal weights",
        "position_noise_relative": "Savitzky-Golay energy, propagated noise as relative weights",
        "seed_eq25": "Savitzky-Golay energy, seed's eq. 25",
        "seed_recipe_cd_eq25": "central-difference energy, seed's eq. 25 (the seed's recipe)",
        "equal_weights_with_release": "Savitzky-Golay energy, equal weights, hand release included",
    }
    lines = ["| energy, weights | a [J] | b [1/s] | chi2_red | n |", "|---|---|---|---|---|"]
    rows = {"Savitzky-Golay energy, calibrated errors (main result)": summary}
    rows.update({labels[k]: v for k, v in summary["weighting_variants"].items()})
    for label, v in rows.items():
        chi2 = "-" if v["chi2_red"] is None else f"{v['chi2_red']:.2f}"
        a = plus_minus(v["a_J"], v["a_J_stderr_autocorr"])
        b = plus_minus(v["b_per_s"], v["b_per_s_stderr_autocorr"], digits=5)
        lines.append(f"| {label} | {a} | {b} | {chi2} | {v['n_points']} |")
    return "\n".join(lines)


def _geometry_section(s: DecaySummary) -> str:
    """Frames, pivot, rod lengths [mm] and position noise."""
    pivot = s["pivot_origin_m"]
    noise = s["position_noise_m"]
    return f"""## Geometry

- Frames: {s["n_frames"]} at {FPS} fps; flagged as tracker jumps: {s["n_flagged"]}; hand release over at
  frame {s["release_frame"]} (t = {s["release_time_s"]:.3f} s); frames in the fits: {s["n_fit"]}.
- Pivot (circle fit of the upper bob, in the table's coordinates):
  x = {plus_minus(pivot["x"], pivot["sigma_x"], 1e3, 2)} mm, y = {plus_minus(pivot["y"], pivot["sigma_y"], 1e3, 2)} mm;
  rms distance of the upper bob from the circle {1e3 * s["circle_rms_residual_m"]:.2f} mm.
- l1 = {plus_minus(s["l1_m"], s["l1_stderr_m"], 1e3, 2)} mm (circle radius);
  l2 = {plus_minus(s["l2_m"], s["l2_stderr_m"], 1e3, 2)} mm (mean bob distance, std {1e3 * s["l2_std_m"]:.1f} mm).
  Both errors treat the frames as independent; the radii wander slowly, so they are lower bounds: the
  upper bob's distance from the pivot drifts by {1e3 * s["r1_drift_m_per_s"] * s["n_frames"] / FPS:+.1f} mm
  over the run (camera or mount moving). The energy uses the angles, which a radial shift leaves unchanged.
- Position noise (frame-to-frame jitter of the rod lengths): upper bob {1e3 * noise["upper_bob"]:.2f} mm,
  lower bob {1e3 * noise["lower_bob"]:.2f} mm.
"""


def _energy_section(s: DecaySummary) -> str:
    """The energy, the derivative filters' gains and the calibrated error model."""
    em, sc = s["error_model"], s["scatter"]
    sg = s["derivative_filters"]["savgol"]["gain"]
    cd = s["derivative_filters"]["central_difference"]["gain"]
    return f"""## Energy and its errors

The energy is `double_pendulum.model.energy.total_energy` for point masses m1 = {s["masses_kg"]["m1"]} kg,
m2 = {s["masses_kg"]["m2"]} kg on the measured rods (potential zero with both bobs at rest below the
fitted pivot). The angular velocities come from a Savitzky-Golay derivative ({SG_WINDOW} frames, order
{SG_POLYORDER}): on a harmonic motion at 10 / 20 / 25 rad/s it returns {sg["10_rad_s"]:.3f} /
{sg["20_rad_s"]:.3f} / {sg["25_rad_s"]:.3f} of the true rate, the seed's central differences
{cd["10_rad_s"]:.3f} / {cd["20_rad_s"]:.3f} / {cd["25_rad_s"]:.3f} (kinetic energy: the square).

The propagated position noise gives energy errors of only {1e3 * em["median_sigma_noise_J"]:.1f} mJ
(median); the exponential fit with them has chi2_red = {em["chi2_red_with_noise_only"]:.0f}, so the
scatter of the energy is not white position noise. It grows with speed: the rms residual is
{1e3 * sc["rms_residual_slowest_quarter_J"]:.0f} mJ in the slowest quarter of the frames and
{1e3 * sc["rms_residual_fastest_quarter_J"]:.0f} mJ in the fastest, single frames are off by up to
{sc["max_abs_residual_J"]:.2f} J, and the distance between the bobs changes by up to
{1e3 * sc["max_bob_distance_change_in_two_frames_m"]:.0f} mm within two frames (a rigid rod would not).
The fits therefore use errors calibrated on the data by maximum likelihood, alternating with the
exponential fit: sigma^2 = sigma_noise^2 + s0^2 + dv^2 (m1^2 v1^2 + m2^2 v2^2) with
s0 = {1e3 * em["floor_J"]:.1f} mJ and dv = {em["dv_m_per_s"]:.3f} m/s (the seed's eq. 25 has
dv = {em["seed_dv_m_per_s"]} m/s and no floor).
"""


def _fit_section(s: DecaySummary) -> str:
    """The exponential fit, its correlation-inflated errors and the difference to the seed."""
    seed = s["seed"]
    return f"""## Exponential fit E = a exp(b t)

a = {plus_minus(s["a_J"], s["a_J_stderr"])} J, b = {plus_minus(s["b_per_s"], s["b_per_s_stderr"], digits=5)} 1/s
(standard errors of the fit). The residuals are correlated over a swing: the record's correlation factor
F = 1 + 2 sum(rho_k) over {AUTOCORRELATION_LAG_S} s of lags of the residuals about the free-exponent law (the most
flexible decay law here, so that its residuals hold the scatter, not a misfit of the decay's shape) is
{s["autocorrelation_factor"]:.2f}, which makes the errors a +- {s["a_J_stderr_autocorr"]:.4f} J,
b +- {s["b_per_s_stderr_autocorr"]:.5f} 1/s. The same F enters every error and every comparison of this report.

The seed: a = {seed["a_J"]} J +- {100 * seed["a_rel_err"]:.2f} %, b = {seed["b_per_s"]} 1/s
+- {100 * seed["b_rel_err"]:.2f} %. Difference in b: {seed["b_difference_per_s"]:+.5f} 1/s, that is
{seed["b_difference_in_seed_sigma"]:+.2f} times the seed's error and
{seed["b_difference_in_combined_sigma"]:+.2f} times the combined error; in a: {seed["a_difference_J"]:+.4f} J,
{seed["a_difference_in_combined_sigma"]:+.2f} times the combined error.

The same fit with other energies and weights (errors inflated for the correlation):

{variant_rows(s)}
"""


def _comparison_section(s: DecaySummary) -> str:
    """The decay models compared; the free exponent p of dE/dt = -k E^p against 1/2, 1, 3/2."""
    rows = {r["model"]: r for r in s["model_comparison"]}
    power = rows["power"]
    p, sp = power["params"]["p"], power["stderr"]["p"]
    sp_corr = sp * math.sqrt(s["autocorrelation_factor"])
    return f"""## Model comparison (same frames, calibrated errors)

{comparison_rows(s)}

Lowest AIC: {s["model_comparison"][0]["model"]}{_tie_text(s)}. The criteria divide chi2 by F =
{s["autocorrelation_factor"]:.2f} (the frames count as n / F independent ones). The free exponent of
dE/dt = -k E^p is p = {p:.2f} +- {sp:.2f} (+- {sp_corr:.2f} with
the correlation): Coulomb friction has p = 1/2 ({(p - 0.5) / sp_corr:+.1f} sigma), losses proportional
to the energy p = 1 ({(p - 1.0) / sp_corr:+.1f} sigma), quadratic drag (E ~ 1/(1 + t/tau)^2, the seed's
alternative "inverse square of time") p = 3/2 ({(p - 1.5) / sp_corr:+.1f} sigma, dAIC =
{rows["quadratic_drag"]["delta_aic"]:.0f}).
"""


def _tie_text(s: DecaySummary) -> str:
    """Which decay laws lie within dAIC 2 of the lowest (the record does not rank them)."""
    tied = [r["model"] for r in s["model_comparison"][1:] if r["delta_aic"] < 2.0]
    return f" ({', '.join(tied)} within dAIC 2 of it: the record does not rank them)" if tied else ""


def _discussion_section(s: DecaySummary) -> str:
    """Why a and b differ from the seed's: origin, velocity smoothing, energy model, weights, frames."""
    m1, m2 = s["masses_kg"]["m1"], s["masses_kg"]["m2"]
    cd20 = s["derivative_filters"]["central_difference"]["gain"]["20_rad_s"]
    sg20 = s["derivative_filters"]["savgol"]["gain"]["20_rad_s"]
    var = s["weighting_variants"]
    return f"""## Why a and b differ from the seed's

- **Origin and rod lengths.** The seed put the pivot at the grid point of least variance of the
  distance; here it is a geometric circle fit. The potential energy is measured from the pivot, and
  1 mm of height is (m1 + m2) g * 1 mm = {1e3 * (m1 + m2) * 9.81e-3:.1f} mJ; the seed does not say where
  its potential is zero.
- **Velocity smoothing at 30 fps.** As the seed explains (4.2.2, fig. 8), the frames before and after
  the lowest point cut the corner and flatten the speed peaks: central differences return
  {100 * cd20:.1f} % of the rate of a 20 rad/s motion ({100 * cd20**2:.0f} % of its kinetic energy), the
  Savitzky-Golay derivative {100 * sg20:.1f} %. Larger kinetic energies mean a larger a: with equal
  weights a = {var["cd_equal_weights"]["a_J"]:.4f} J from central differences,
  {var["equal_weights"]["a_J"]:.4f} J from the Savitzky-Golay derivative.
- **Energy model.** Point masses on massless rods: the seed's pendulum moves
  {SEED_TOTAL_MASS_KG} kg in total (4.2.3) against m1 + m2 = {m1 + m2:.3f} kg, so about
  {SEED_TOTAL_MASS_KG - m1 - m2:.1f} kg of acrylic rods are missing from the energy and make the
  computed energy depend on the configuration: one source of the floor s0.
- **Weights.** The seed weighted with eq. 25, whose errors nearly vanish at the turning points although
  the energy scatters there too: the slowest tenth of the frames carries
  {100 * s["scatter"]["seed_weight_share_of_slowest_tenth"]:.0f} % of the total weight. With eq. 25 weights
  b = {var["seed_eq25"]["b_per_s"]:.4f} 1/s, with equal weights {var["equal_weights"]["b_per_s"]:.4f} 1/s:
  the weights move b by more than its statistical error, a sign that the exponential is only an
  approximation to the decay.
- **Frames.** The energy rises during the first frames while the hand lets go; those frames are left
  out. Table 1 covers {s["n_frames"] / FPS:.1f} s (the seed speaks of a 30 s measurement).
- **Rounding.** The seed prints b = -0.024 with two digits: every value from -0.0245 to -0.0235 is
  printed so, a range as wide as the seed's own error of b.
"""


def _budget_section(s: DecaySummary) -> str:
    """The error budget's rows, then b as it is: statistical error, the range over named variants, the halves."""
    if "error_budget" not in s:
        return ""
    bud = s["error_budget"]
    st, nm = bud["b_statement"], bud["noise_model"]
    h = st["halves"]
    ratio = [e / st["statistical_per_s"] for e in h["b_per_s_stderr_ar1"]]
    stat3 = [st["statistical"][k] for k in ("ar1_per_s", "bootstrap_per_s", "correlation_factor_per_s")]
    variants = "\n".join(f"| {group} | {name} | {b:.5f} | {1e4 * (b - st['b_per_s']):+.2f} |"
                         for group, vs in st["variants_per_s"].items() for name, b in vs.items())  # fmt: skip
    return f"""## Error budget of a and b

The errors quoted above are statistical only. Re-doing the fit with one choice changed at a time
(`src/double_pendulum/analysis/decay/error_budget.py`):

{budget_table(bud)}

The quadrature total is no confidence interval: it counts the noise twice (the statistical row and the halves'
row, whose halves each carry {min(ratio):.1f} to {max(ratio):.1f} times the whole record's statistical error)
and adds shifts of choices as if they were independent errors. The rod-mass row is a bias of the point-mass
energy (the acrylic members carry energy too); the seed's 1.26 % and 4.89 % are statistical errors of its fit alone.

### b as it is

{st["text"]}.

**Statistical error** (`analysis/decay/noise.py`). The normalised residuals of the fit have a lag-one
autocorrelation rho = {nm["rho"]:.2f}. With AR(1) residuals of that rho the fit's b has the standard error
{st["statistical"]["ar1_per_s"]:.5f} 1/s (sandwich); the AR(1) likelihood's own optimum (generalised least
squares) is b = {nm["gls"]["b_per_s"]:.5f} +- {nm["gls"]["b_per_s_stderr"]:.5f} 1/s. A moving-block bootstrap
({nm["bootstrap"]["resamples"]} resamples of blocks of {nm["bootstrap"]["block_frames"]} frames =
{nm["bootstrap"]["block_s"]:.1f} s, one slow swing of 1.31 s, so that a swing's pattern of residuals stays
inside a block) gives {st["statistical"]["bootstrap_per_s"]:.5f} 1/s, and the correlation factor F of the
sections above {st["statistical"]["correlation_factor_per_s"]:.5f} 1/s. The residuals' autocorrelation is not AR(1)'s
geometric decay: at lags of 1, 2 and 3 frames it is {" / ".join(f"{x:.2f}" for x in nm["autocorrelation_lags_1_to_3"])}
and it turns negative at {_lag_text(nm["first_negative_lag_s"])}, which AR(1) does not describe; the three
estimates, {min(stat3):.5f} to {max(stat3):.5f} 1/s, are the statistical error's range.

**Systematic range** (b of the main fit with one choice changed; not added in quadrature):

| group | variant | b [1/s] | shift [1e-4 1/s] |
|---|---|---|---|
{variants}

b lies between {st["systematic_range_per_s"][0]:.4f} and {st["systematic_range_per_s"][1]:.4f} 1/s over these;
the widest is {st["systematic_widest_variant"]} ({1e4 * st["systematic_max_shift_per_s"]:.1f}e-4 1/s), which
puts most weight on the slowest frames; without it the variants move b by up to
{1e4 * st["systematic_max_shift_without_seed_weights_per_s"]:.1f}e-4 1/s.

**The halves.** First half b = {plus_minus(h["b_per_s"][0], h["b_per_s_stderr_ar1"][0], digits=5)} 1/s, second half
b = {plus_minus(h["b_per_s"][1], h["b_per_s_stderr_ar1"][1], digits=5)} 1/s (AR(1) errors; rho
{h["rho"][0]:.2f} and {h["rho"][1]:.2f}): they differ by {abs(h["difference_in_sigma_ar1"]):.1f} sigma
({abs(h["difference_in_sigma_bootstrap"]):.1f} sigma with the block bootstrap's errors). {_halves_words(h)}
"""


def _halves_words(h: dict[str, Any]) -> str:
    """What the halves' difference in sigma says, in words that follow the numbers."""
    z = max(abs(h["difference_in_sigma_ar1"]), abs(h["difference_in_sigma_bootstrap"]))
    faster = "second" if h["b_per_s"][1] < h["b_per_s"][0] else "first"
    if z < 2.0:
        return f"Under 2 sigma with either error: a hint that the {faster} half decays faster, not a detection."
    if z < 3.0:
        return f"Between 2 and 3 sigma: the {faster} half decays faster, at a significance that needs confirming."
    return f"Over 3 sigma: the {faster} half decays faster; the decay is not stationary."


def _slope_words(amp: dict[str, Any], p_minus_1: float) -> str:
    """Whether the windows' slope tells a constant b (slope 0) from the free-exponent law (slope p - 1)."""
    slope, err = amp["slope_dlnb_dlnE"], amp["slope_stderr"]
    zero, law = abs(slope) / err < 2.0, abs(slope - p_minus_1) / err < 2.0
    if zero and law:
        return ("The windows agree with a constant b and with that law alike (both within 2 sigma of the slope): "
                "they cannot tell the friction laws apart by their amplitude dependence.")
    if law:
        return "The windows reject a constant b (over 2 sigma) and agree with that law."
    return "The slope agrees with a constant b, not with that law (over 2 sigma)." if zero else (
        "The slope agrees with neither (over 2 sigma from both).")


def _lag_text(lag: float | None) -> str:
    """A lag [s] in words (None: beyond the block)."""
    return "no lag within the block" if lag is None else f"{lag:.2f} s"


def _stationarity_section(s: DecaySummary) -> str:
    """The non-stationarity study: calibration drift, the energy's biases, b against the energy."""
    if "error_budget" not in s:
        return ""
    st = s["error_budget"]["stationarity"]
    dr, l2, amp = st["calibration_drift"], st["l2"], st["amplitude"]
    rods = st["rod_mass"]["rod mass (point masses vs rigid links)"]
    stat = s["error_budget"]["b_statement"]["statistical_per_s"]
    p_row = next(r for r in s["model_comparison"] if r["model"] == "power")
    p, sp = p_row["params"]["p"], p_row["stderr"]["p"] * math.sqrt(s["autocorrelation_factor"])
    rows = "\n".join(f"| {w['t_start_s']:.1f}-{w['t_end_s']:.1f} | {w['mean_energy_J']:.3f} | "
                     f"{plus_minus(w['b_per_s'], w['b_per_s_stderr'], digits=4)} | {w['rho']:.2f} |"
                     for w in amp["windows"])  # fmt: skip
    settle = "\n".join(f"- {x}" for x in st["what_would_settle_it"])
    return f"""## Is the decay stationary?

(`src/double_pendulum/analysis/decay/stationarity.py`; every shift is the main recipe re-done.)

- **Calibration drift.** The upper bob's distance from the pivot changes by {1e3 * dr["r1_change_m"]:+.2f} mm over
  the record. If the camera's scale drifted, the angles and the energy are unchanged. If the pivot moved toward
  the bob, its height changed by up to that, which is {1e3 * dr["potential_energy_change_J"]:.1f} mJ of potential
  energy; the track corrected for such a pivot gives a shift of {1e3 * dr["a_shift_J"]:+.2f} mJ in a and
  {1e4 * dr["b_shift_per_s"]:+.2f}e-4 1/s in b ({abs(dr["b_shift_per_s"]) / stat:.2f} times b's statistical error).
- **The energy's biases.** The acrylic members (point masses against rigid links) raise a by
  {1e3 * rods["a_shift_J"]:.0f} mJ and move b by {1e4 * rods["b_shift_per_s"]:+.2f}e-4 1/s; l2 moved by
  {1e3 * l2["shift_m"]:.0f} mm (the table's resolution) moves a by {1e3 * l2["a_shift_J"]:.1f} mJ and b by
  {1e4 * l2["b_shift_per_s"]:+.2f}e-4 1/s. Both are biases of the energy's scale, nearly constant over the
  record, so b, a relative rate, barely feels them.
- **Does b depend on the energy?** Exponential fits in {len(amp["windows"])} consecutive windows (AR(1) errors):

| window [s] | mean energy [J] | b [1/s] | rho |
|---|---|---|---|
{rows}

  A weighted line through (ln E, ln|b|) has the slope {amp["slope_dlnb_dlnE"]:+.2f} +- {amp["slope_stderr"]:.2f}:
  0 for losses proportional to the energy, p - 1 for dE/dt = -k E^p, whose fit to the whole record gives
  p - 1 = {p - 1:+.2f} +- {sp:.2f}. {_slope_words(amp, p - 1)} The record spans only a factor
  {amp["windows"][0]["mean_energy_J"] / amp["windows"][-1]["mean_energy_J"]:.1f} in energy.

What would settle it, and the record cannot:

{settle}
"""


def tilt_section(s: DecaySummary) -> str:
    """The camera's tilt against gravity and what removing it changes (``tilt`` of the summary)."""
    tilt = s["tilt"]
    rows = ["| track | b [1/s] | halves apart [sigma, AR(1) / bootstrap] | p (AR(1)) | p's 95 % interval | "
            "exponential's dAIC (AR(1)) |", "|---|---|---|---|---|---|"]
    for name in ("tilted", "untilted"):
        t = tilt[name]
        h, x = t["halves"], t["exponent"]
        lo, hi = (f"{v:.2f}" if v is not None else "beyond" for v in x["interval_95"])
        rows.append(f"| {name} | {t['b_per_s']:.4f} | {abs(h['difference_in_sigma_ar1']):.1f} / "
                    f"{abs(h['difference_in_sigma_bootstrap']):.1f} | {x['p']:.2f} +- {x['p_stderr']:.2f} | "
                    f"{lo} to {hi} | "
                    f"{t['ar1_models']['models']['exponential']['delta_aic']:.1f} |")
    return f"""## The camera's tilt

{tilt['text']}

{chr(10).join(rows)}

The tilted track is the main analysis; the untilted one is the track as the camera saw it. p is the exponent of
dE/dt = -k E^p fitted under an AR(1) noise model (p = 1: the exponential); its interval is where the profile
likelihood stays within Delta(-2 ln L) = 4.
{_rods_text(tilt.get("rods_from_energy"))}"""


def _rods_text(r: Mapping[str, Any] | None) -> str:
    """The rods' member mass read from the energy with the tilt, and what the noise model carries into it."""
    if not r:
        return ""
    ns = r["noise_sensitivity"]
    lo, hi = ns["range_g"]
    h1, h2 = ns["halves"]["first"], ns["halves"]["second"]
    return (f"\nRead from the energy together with the tilt (their correlation {r['correlation']:.2f}), each rod "
            f"member weighs {r['rod_member_g']:.0f} +- {r['rod_member_stderr_g']:.0f} g (the seed states 70 +- 30 g). "
            f"That error takes the tracking noise's model as right; with the noise 20 % lower or higher, or its "
            f"lag-one correlation at 0 to 0.7, the mass runs from {lo:.0f} to {hi:.0f} g, and the record's halves give "
            f"{h1['rod_member_g']:.0f} +- {h1['rod_member_stderr_g']:.0f} and {h2['rod_member_g']:.0f} +- "
            f"{h2['rod_member_stderr_g']:.0f} g.\n")


def report_text(summary: DecaySummary) -> str:
    """The Markdown report: figures from ``summary`` and the discussion of the differences to the seed."""
    sections = (_geometry_section, tilt_section, _energy_section, _fit_section, _budget_section, _stationarity_section,
                _comparison_section, _discussion_section)
    body = "\n".join(section(summary) for section in sections)
    return _opening(summary) + body


def _opening(s: DecaySummary) -> str:
    """Title, plain summary and the words used."""
    st = s["error_budget"]["b_statement"]
    rows = {r["model"]: r for r in s["model_comparison"]}
    p = rows["power"]["params"]["p"]
    sp = rows["power"]["stderr"]["p"] * math.sqrt(s["autocorrelation_factor"])
    tied = [r["model"] for r in s["model_comparison"] if r["delta_aic"] < 2.0]
    return report_opening("Energy decay of the seed pendulum (Table 1)", [
        f"From the seed's camera track ({s['n_fit']} frames after the hand release) this report computes the "
        "pendulum's energy frame by frame and fits how it decays.",
        f"Fitted as E = a exp(b t) it decays at b = {s['b_per_s']:.4f} 1/s (the energy falls by about "
        f"{100 * (1 - math.exp(s['b_per_s'])):.1f} % a second), close to the seed's -0.024 1/s.",
        f"b's statistical error is {st['statistical_per_s']:.4f} 1/s (residuals correlated as AR(1); a block "
        f"bootstrap gives {st['statistical']['bootstrap_per_s']:.5f}); the choice of weights, window and energy "
        f"moves b by up to {st['systematic_max_shift_per_s']:.4f} 1/s ({st['systematic_widest_variant']}), a range "
        "of choices reported apart, not added to it.",
        f"The decay is not exactly exponential: laws with a loss that grows less steeply with the energy fit as well "
        f"or better ({', '.join(tied)} tie), and the free loss exponent is p = {p:.2f} +- {sp:.2f} (1 would be "
        "exponential).",
    ], {
        "b": "the decay rate [1/s] of E = a exp(b t); a [J] the energy at t = 0",
        "p": "the loss exponent of dE/dt = -k E^p: 0.5 for a constant friction torque (coulomb), 1 for an exponential "
             "decay, 1.5 for air drag (quadratic_drag)",
        "Savitzky-Golay": "a smoothing derivative: a local polynomial fitted over a few frames, for the rates",
        "chi2": "the sum over the frames of ((fitted - measured energy) / the energy's error)^2",
        "chi2_red": "the sum of squared residuals over their errors per degree of freedom; about 1 when the errors "
                    "match the scatter",
        "F": "the correlation factor: neighbouring frames' residuals are alike over about a swing, so the frames count "
             "as n / F independent ones and statistical errors grow by sqrt(F)",
        "AIC": "Akaike's information criterion chi2 / F + 2 k (k fitted numbers): lower is better; a difference dAIC "
               "below 2 means the record does not tell two laws apart",
        "BIC": "the Bayesian information criterion chi2 / F + k ln(n / F), which charges extra numbers more",
        "Akaike weight": "exp(-dAIC / 2) over the sum of that for all laws: each law's relative support among these",
    })
