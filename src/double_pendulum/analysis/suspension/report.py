r"""The Markdown report of the suspension study (scenario ``suspension_transfer``), from its summary.

:func:`report_text` writes every figure of the report from the summary dict the scenario builds
(:mod:`~double_pendulum.analysis.suspension.transfer`, :mod:`~double_pendulum.analysis.suspension.decay_map`,
:mod:`~double_pendulum.analysis.suspension.identification`, :mod:`~double_pendulum.analysis.suspension.energy_flow`);
nothing is computed here but ratios and differences of summary values. Sections: the measured
decay and start state, the map b(k, c) and its iso-b curve, the identification and its valley, the
refit (rate and shape of the decay), and the energy flow into the suspension.

Units as in the summary's keys: k in N/m, c in N s/m, M_s in kg, b in 1/s, energies in J (shown in
mJ where noted), powers in W (shown in mW), omega in rad/s.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

from ...runs.results_io import report_opening
from .decay_map import k_of_key
from .summary_types import SuspensionSummary


def _format_or_dash(value: float | None, fmt: str = ".4g") -> str:
    """``value`` formatted with ``fmt``, "-" for None (a quantity that does not exist on this grid)."""
    return "-" if value is None else format(value, fmt)


def _measured_section(s: SuspensionSummary) -> str:
    """Section "Measured decay and start": the measured b and p, the fitted start state."""
    m, st = s["measured"], s["start_state"]
    shape = m["decay_shape"]
    return f"""## Measured decay and start

The camera energy (``double_pendulum.analysis.track.measurement``, calibrated errors, {m["n_frames"]} frames from the
end of the hand release at t = {m["window_s"][0]:.2f} s to t = {m["window_s"][1]:.2f} s): E = a exp(b t) with
a = {m["a_J"]:.4f} J, **b = {m["b_per_s"]:.5f} +- {m["b_per_s_stderr_autocorr"]:.5f} 1/s** (statistical: the fit
error inflated by the residual correlation, factor F = {m["autocorrelation_factor"]:.2f}; total with the systematic
errors of ``energy_decay``'s error budget: +- {m["b_per_s_total_error"]:.4f} 1/s); the seed printed
b = {m["seed_b_per_s"]} 1/s.
The free exponent of dE/dt = -k E^p is p = {shape["p"]:.2f} +- {shape["p_stderr"]:.2f}.

Every run starts at t0 = {m["t0_s"]:.3f} s from the state fitted to the positions of the first
{st["n_frames"]} frames (rms residual {1e3 * st["rms_residual"]:.1f} mm, chi2_red {st["chi2_red"]:.0f}: the track's
own systematic errors, see ``measured_vs_sim``): phi1 = {st["state"]["phi1_0"]:.4f} rad,
phi2 = {st["state"]["phi2_0"]:.4f} rad, omega1 = {st["state"]["omega1_0"]:.3f} rad/s,
omega2 = {st["state"]["omega2_0"]:.3f} rad/s. Air drag (bobs and rods) and bearing friction are on at the
defaults. b is fitted to E_pendulum, the bobs' energy: the camera sees the bobs, not the suspension.
"""


def _contour_text(points: Sequence[Mapping[str, Any]]) -> str:
    """The iso-b crossings (k [N/m], c [N s/m], branch) as one line of text."""
    if not points:
        return "none on this grid"
    return "; ".join(f"k = {p['k']:.3g} N/m, c = {p['c']:.3g} N s/m ({p['branch']})" for p in points)


def _map_section(s: SuspensionSummary) -> str:
    """Section "The map b(k, c)": grid, table per M_s, iso-b branches, the law checks, monotonicity in c."""
    main = s["maps"][0]
    lines = []
    for m in s["maps"]:
        lines.append(
            f"| {m['M_s_kg']:g} | {len(m['k_N_per_m'])} x {len(m['c_N_s_per_m'])} "
            f"| {m['b_base_no_suspension_per_s']:.5f} "
            f"| {_format_or_dash(m['reach_measured_b']['stiffest_k_reaching_N_per_m'], '.3g')} "
            f"| {_contour_text(m['iso_b_measured'])} |"
        )
    lr, qs, stiff = main["linear_response"], main["quasi_static_c_over_k2"], main["stiff_region"]
    needed = s["measured"]["b_per_s"] - main["b_base_no_suspension_per_s"]
    mono = main["monotonic_in_c"]
    mono_rows = "\n".join(
        f"| {k_of_key(k):.3g} | {'yes' if v['monotonic_below_it'] else 'no'} | {v['c_at_largest_loss']:.3g} |"
        for k, v in mono.items()
    )
    qs_share = _format_or_dash(qs["largest_share_within_per_s"], ".2g")
    largest = qs["largest_share_within_per_s"]
    verdict = (
        ": a suspension stiff enough for the law cannot explain the measurement"
        if largest is not None and largest < -needed
        else ""
    )
    fisher, settings = s["valley"]["fisher"], s["settings"]
    return f"""## The map b(k, c)

{s["map_runs"]} FMU runs (``decay_rate_map.csv``, ``decay_rate_map.png``), k = k_x = k_y from
{main["k_N_per_m"][0]:.3g} to {main["k_N_per_m"][-1]:.3g} N/m, c = c_x = c_y from {main["c_N_s_per_m"][0]:.3g} to
{main["c_N_s_per_m"][-1]:.3g} N s/m, swept in {s["map_wall_time_s"]:.0f} s by ``analysis.sweep.run_sweep``
at rtol {settings["map"]["rtol"]:g} (b to about 1e-4 relative; the run without suspension at rtol
{settings["map_without_suspension"]["rtol"]:g}).
b of E_pendulum and of E_total differ by at most {main["max_abs_b_E_pendulum_minus_b_E_total"]:.1e} 1/s.

| M_s [kg] | grid | b without suspension [1/s] | stiffest k reaching the measured b [N/m] | iso-b points (measured b) |
|---|---|---|---|---|
{chr(10).join(lines)}
{_other_masses_text(s)}

**The suspensions that explain the measured b form a curve, not a point.** The suspension has to add
{needed:.4f} 1/s. {_branches_text(s)}

**Shape check.** The stiff-suspension law (dissipated power c <|dF/dt|^2> / k^2, so b - b0 ~ c/k^2 and
iso-b curves c ~ k^2) is checked where the suspension is much stiffer than the pendulum (natural
frequencies and k/c at least {stiff["natural_frequency_over_force_frequency"]:g} times the force's rms
frequency, {stiff["n_cells"]} cells): it holds within {100 * qs["tolerance"]:.0f} % in {qs["n_cells_within"]} of them:

{_c_table(qs["rows_within"], f"the law holds within {100 * qs['tolerance']:.0f} %")}

Elsewhere in that region the c-independent resonant loss
still adds (small c). The largest suspension share where the law holds is {qs_share} 1/s, against the
{-needed:.4f} 1/s needed{verdict}. Along the measured curve the local slope of the valley is
d ln c / d ln k = {fisher["valley_slope_dlnc_dlnk"]:.1f} (c ~ k^2 would be 2). The full linear response
(``double_pendulum.analysis.suspension.response``, from one fixed-pivot run's force spectrum; dotted in the map)
agrees with the FMU within
{100 * lr["tolerance"]:.0f} % in {lr["n_cells_within"]} of {lr["n_cells"]} cells:

{_c_table(lr["rows_within"], f"the linear response agrees within {100 * lr['tolerance']:.0f} %")}

It fails where the suspension drains the pendulum so fast that its motion (and force spectrum) changes,
i.e. at soft, lightly damped suspensions, and in the chaotic resonance floor. See ``decay_rate_cuts.png``.

**Monotonic in c?** Per k: whether |b| grows monotonically with c up to its largest loss, and the c of
that largest loss:

| k [N/m] | monotonic up to the peak | c at the largest loss [N s/m] |
|---|---|---|
{mono_rows}

Where it does not, the lightly damped end wiggles: the resonant loss depends on the chaotic
trajectory's spectrum near omega_n, which changes from run to run.
"""


def _other_masses_text(s: SuspensionSummary) -> str:
    """Where the maps at other suspension masses are: here, or with ``--thorough``."""
    if len(s["maps"]) > 1:
        return "\nThe other masses are mapped on every second k and c of the main grid."
    if s.get("quick"):
        return ""
    return ("\nThe default run maps the identified mass only, on 7 values of c; ``--thorough`` maps it on 9 "
            "and adds coarser maps at M_s = 0.5 and 8 kg (68 more runs, about 2.5 times the map's CPU time).")


def _branches_text(s: SuspensionSummary) -> str:
    """The three branches of the measured iso-b curve on the main map, in numbers."""
    main = s["maps"][0]
    pts = main["iso_b_measured"]
    rising = [p for p in pts if p["branch"] == "rising"]
    falling = [p for p in pts if p["branch"] == "falling"]
    res = s["valley"]["resonant_end"]
    reach = main["reach_measured_b"]
    out = [f"On the map at M_s = {main['M_s_kg']:g} kg the measured b is crossed at: {_contour_text(pts)}."]
    if res is not None:
        out.append(
            f"Lightly damped branch: at c = {res['c_N_s_per_m']:g} N s/m the crossing lies at "
            f"k = {res['k_N_per_m']:.3g} N/m, "
            f"where the suspension's natural frequencies ({res['omega_n_x_rad_s']:.0f} rad/s horizontally, "
            f"{res['omega_n_y_rad_s']:.0f} rad/s vertically) lie in the pendulum's force spectrum and the loss hardly "
            f"depends on c (resonant limit pi S(omega_n)/(2M): {res['resonant_limit_share_per_s']:.4f} 1/s; the "
            f"linear response overestimates here, the FMU run at that point gives "
            f"b = {s['refit']['resonant']['b_E_pendulum_per_s']:.4f} 1/s: along c = {res['c_N_s_per_m']:g} the map "
            "is rough, the resonant loss follows the chaotic trajectory)."
        )
    if rising:
        out.append(f"Rising branch ({len(rising)} crossings): c grows steeply with k.")
    if falling:
        out.append(f"Overdamped branch ({len(falling)} crossings): the damper clamps the pivot, b ~ 1/c.")
    stiffest = reach["stiffest_k_reaching_N_per_m"]
    out.append(
        f"No c on the grid reaches the measured b above k = {_format_or_dash(stiffest, '.3g')} N/m: "
        "at fixed k the loss peaks at "
        "c ~ k/omega (the c of the largest loss per k is in the table *Monotonic in c?* below) and that peak falls "
        "with k. The stiffest k that still "
        f"reaches it per suspension mass: "
        + ", ".join(
            f"{m['M_s_kg']:g} kg: {_format_or_dash(m['reach_measured_b']['stiffest_k_reaching_N_per_m'], '.3g')} N/m"
            for m in s["maps"]
        )
        + " (a heavier suspension has lower natural frequencies at the same k)."
    )
    return " ".join(out)


def _c_table(rows: Mapping[str, Sequence[float]], what: str) -> str:
    """Markdown table of the c values [N s/m] per k [N/m] where ``what`` is true; a sentence if there are none."""
    lines = [f"| {k_of_key(k):.3g} | {', '.join(f'{c:.3g}' for c in cs)} |" for k, cs in rows.items() if cs]
    if not lines:
        return f"(no cell where {what})"
    return "\n".join([f"| k [N/m] | c [N s/m] where {what} |", "|---|---|", *lines])


def _identification_section(s: SuspensionSummary) -> str:
    """Section "Identification": c at the default k and M_s, the Fisher valley, c refitted along it."""
    i, v = s["identified"], s["valley"]
    f = v["fisher"]
    trace = [i, *v["trace"]]
    rows = "\n".join(
        f"| {t['k_N_per_m']:.3g} | {t['c_N_s_per_m']:.4g} +- {t['c_stderr']:.2g} | {t['chi2']:.1f} "
        f"| {t['delta_chi2']:+.1f} "
        f"| {t['delta_chi2_over_factor']:+.1f} | {t['b_per_s']:.5f} | {t['p']:.2f} |"
        for t in trace
    )
    res = v["resonant_end"]
    res_text = (
        ""
        if res is None
        else (
            f"The resonant end of the curve (k = {res['k_N_per_m']:.3g} N/m, c = {res['c_N_s_per_m']:g} N s/m) fits "
            f"worse: chi2 = {s['refit']['resonant']['chi2']:.0f} "
            f"({s['refit']['resonant']['delta_chi2']:+.0f}); its loss depends even more steeply on the amplitude "
            f"(p = {s['refit']['resonant']['p']:.2f})."
        )
    )
    valley = " | ".join(f"{p['k_N_per_m']:.3g} N/m: {p['c_N_s_per_m']:.3g}" for p in v["linearised"])
    refit = s["refit"]["identified"]
    return f"""## Identification

Least squares of the simulated E_pendulum against the measured energy per frame (calibrated errors),
k = {i["fixed"]["k"]:g} N/m and M_s = {i["fixed"]["M_s"]:g} kg fixed (the parameter defaults), c free:
c = {i["c_N_s_per_m"]:.1f} +- {i["c_stderr"]:.1f} N s/m (+- {i["c_stderr_uncorrelated"]:.1f} from the Jacobian,
inflated by sqrt({i["autocorrelation_factor"]:.1f}) for the correlated residuals), chi2 = {i["chi2"]:.1f} for
{i["n_frames"]} frames (chi2_red {i["chi2_red"]:.2f}), {i["n_fmu_runs"]} FMU runs.

**What this c is.** It is conditional: on the assumed k and M_s (not measured), on the default air drag and
rolling friction beside it (not fitted), and on this suspension model at these k and M_s: refitted, it gives
b = {refit["b_E_pendulum_per_s"]:.4f} 1/s against the measured {s["measured"]["b_per_s"]:.4f} 1/s
({refit["difference_in_total_sigma"]:+.1f} times the total error of the measured b, statistical and systematic;
{refit["difference_in_measured_sigma"]:+.1f} times its statistical error alone), which b alone does not reject,
and a loss exponent p = {refit["p"]:.2f}
against the measured {s["measured"]["decay_shape"]["p"]:.2f} +- {s["measured"]["decay_shape"]["p_stderr"]:.2f}.
Equally good fits lie along a valley (below), so c is not an identified property of the stand. Along the
linearised valley through the fitted point (d ln c / d ln k = {f["valley_slope_dlnc_dlnk"]:.1f}; not refitted):
k: c [N s/m] = {valley}.

**The degenerate direction.** The energy fixes one combination of (k, c, M_s). The Jacobian in
(ln k, ln c, ln M_s) at the identified point has Fisher eigenvalues {", ".join(f"{e:.3g}" for e in f["eigenvalues"])};
the weakest direction is {", ".join(f"{n} {x:+.2f}" for n, x in f["weakest_direction"].items())}. Fitting k too would
give sigma(ln k) = {f["stderr_ln_k_with_k_free"]:.3f}, sigma(ln c) = {f["stderr_ln_c_with_k_free"]:.2f} with correlation
{f["correlation_ln_k_ln_c"]:.3f}: a long narrow valley along d ln c / d ln k = {f["valley_slope_dlnc_dlnk"]:.1f}.
M_s moves the residuals {f["sensitivity_ratio_M_s_to_c"]:.1f} times as much as ln c does per unit of its logarithm,
nearly as the opposite of k does (the residual changes of ln M_s and ln k have a cosine of
{f["cos_angle_ln_k_ln_M_s"]:+.2f}): M_s enters mainly through the natural frequencies sqrt(k/M).

{_valley_heading(trace)}

| k [N/m] | c [N s/m] | chi2 | delta chi2 | delta chi2 / factor | b [1/s] | p |
|---|---|---|---|---|---|---|
{rows}

{" ".join(text for text in (res_text, _valley_text(trace)) if text)}
"""


def _valley_heading(trace: Sequence[Mapping[str, Any]]) -> str:
    """The line above the valley table: c refitted along the valley, or the identified point alone."""
    if len(trace) < 2:
        return "The identified point (c is refitted along the valley with `--thorough`):"
    return "Following the valley (c refitted at fixed k):"


def _valley_text(trace: Sequence[Mapping[str, Any]]) -> str:
    """Which way chi2 runs along the valley, and what that means."""
    if len(trace) < 2:
        return ""
    last = trace[-1]
    direction = "falls" if last["delta_chi2"] < 0 else "rises"
    return (
        f"Along the valley chi2 {direction} by {abs(last['delta_chi2']):.0f} "
        f"({abs(last['delta_chi2_over_factor']):.1f} after dividing by the correlation factor) from "
        f"k = {trace[0]['k_N_per_m']:.3g} to {last['k_N_per_m']:.3g} N/m, while p goes from {trace[0]['p']:.2f} "
        f"to {last['p']:.2f}: the valley is not flat, chi2 follows how closely the "
        "shape of the simulated decay (its amplitude dependence p) matches the measured one. No suspension reproduces "
        "that shape (next section), so this preference does not identify k: the result is the iso-b curve of the map "
        "and this valley, with c quoted at the default k."
    )


def _refit_section(s: SuspensionSummary) -> str:
    """Section "Refit": b and p of the FMU runs against the measured ones, the window checks."""
    m = s["measured"]
    rows = "\n".join(
        f"| {label} | {r['b_E_pendulum_per_s']:.5f} | {r['b_E_total_per_s']:.5f} "
        f"| {100 * r['relative_difference_to_measured']:+.1f} % "
        f"| {r['difference_in_total_sigma']:+.1f} | {r['p']:.2f} | {r['chi2']:.0f} |"
        for label, r in s["refit"].items()
    )
    windows = "\n".join(
        f"| first {w['window_s']:g} s | {w['measured_b_per_s']:.5f} +- {w['measured_b_stderr']:.5f} "
        f"| {w['c_N_s_per_m']:.1f} +- "
        f"{w['c_stderr']:.1f} | {w['b_per_s']:.5f} | {100 * w['b_relative_to_measured']:+.1f} % |"
        for w in s["window_checks"]
    )
    i = s["identified"]
    whole = (
        f"| whole record | {m['b_per_s']:.5f} +- {m['b_per_s_stderr_autocorr']:.5f} | {i['c_N_s_per_m']:.1f} +- "
        f"{i['c_stderr']:.1f} | {i['b_per_s']:.5f} | {100 * i['b_relative_to_measured']:+.1f} % |"
    )
    return f"""## Refit: does the identified suspension reproduce b?

The identified parameters run again through the FMU and b fitted on the same frames with the same
errors (measured: b = {m["b_per_s"]:.5f} +- {m["b_per_s_stderr_autocorr"]:.5f} 1/s, p = {m["decay_shape"]["p"]:.2f}):

| run | b of E_pendulum [1/s] | b of E_total [1/s] | vs measured | in total errors | p | chi2 |
|---|---|---|---|---|---|---|
{rows}

The same fit on the first 7 and 14 s only (same start, same k, M_s; run with ``--thorough``):

| frames | measured b [1/s] | c [N s/m] | refit b [1/s] | vs measured |
|---|---|---|---|---|
{windows}{chr(10) if windows else ""}{whole}

**Rate yes, shape no.** Least squares of the energy matches the energy level, not the exponential rate,
so where the simulated decay has another shape the two rates differ. The exponent of dE/dt = -k E^p is
{i["p"]:.2f} for the identified suspension against the measured {m["decay_shape"]["p"]:.2f} +-
{m["decay_shape"]["p_stderr"]:.2f} (1/2: Coulomb friction, 1: viscous losses, 3/2: quadratic drag): the
suspension's loss grows steeply with the amplitude, because the force rate |dF/dt|^2 comes from the lower
bob's whips, which fade as the energy falls. One c fitted to a longer record has to make up for the fading
loss late in the record{_window_trend(s["window_checks"], i)}. The suspension can supply the measured rate,
but the measured shape points to a loss that depends weakly on the amplitude (Coulomb-like friction).
"""


def _window_trend(windows: Sequence[Mapping[str, Any]], whole: Mapping[str, Any]) -> str:
    """The c [N s/m] fitted to the first seconds and to the whole record, as a clause ("" without windows)."""
    if not windows:
        return ""
    cs = ", ".join(f"{w['c_N_s_per_m']:.1f}" for w in windows)
    spans = ", ".join(f"{w['window_s']:g}" for w in windows)
    return f": c = {cs} and {whole['c_N_s_per_m']:.1f} N s/m for the first {spans} s and the whole record"


FLOW_HEADER = (
    "| run | pendulum lost [J] | to the dampers | to air | to the bearings | max E_suspension [mJ] "
    "| P mean / rms [mW] | spectral peak of xs / ys [rad/s] | integral of P / E_s gain + W_s [J] |\n"
    "|---|---|---|---|---|---|---|---|---|"
)
"""Header of the energy-flow table (one row per run of :func:`_flow_section`)."""


def _flow_section(s: SuspensionSummary) -> str:
    """Section "How the energy flows into the suspension": the energy-flow table and the force spectrum."""
    sp = s["spectrum"]
    fmu_share = s["refit"]["identified"]["b_E_pendulum_per_s"] - s["refit"]["no suspension"]["b_E_pendulum_per_s"]
    parts = []
    for label, f in s["energy_flow"].items():
        parts.append(
            f"| {label} | {f['pendulum_energy_lost_J']:.3f} | {100 * f['share_W_suspension']:.0f} % | "
            f"{100 * f['share_W_air']:.0f} % | {100 * f['share_W_bearing']:.1f} % "
            f"| {1e3 * f['max_E_suspension_J']:.2f} | "
            f"{1e3 * f['mean_P_to_suspension_W']:.2f} / {1e3 * f['rms_P_to_suspension_W']:.0f} | "
            f"{f['peak_frequency_xs_rad_s']:.1f} / {f['peak_frequency_ys_rad_s']:.1f} | "
            f"{f['integral_P_dt_J']:.5f} / {f['E_suspension_gain_plus_W_suspension_J']:.5f} |"
        )
    return f"""## How the energy flows into the suspension

``energy_flow.png``, ``identified.csv`` (and ``resonant.csv``): P_to_suspension, E_suspension and the works
at 5 ms resolution.

{FLOW_HEADER}
{chr(10).join(parts)}

{_flow_text(s)}

Pivot force of the fixed-pivot pendulum (``force_spectrum.png``): rms {sp["rms_F_x_N"]:.2f} N horizontally,
{sp["rms_F_y_N"]:.2f} N vertically, rms frequency sqrt(<|dF/dt|^2>/<F^2>) = {sp["rms_frequency_rad_s"]:.1f} rad/s.
The identified suspension's natural frequencies, {sp["identified_omega_n_x_rad_s"]:.0f} rad/s (x) and
{sp["identified_omega_n_y_rad_s"]:.0f} rad/s (y), are only a few times that. Its share of b is
{fmu_share:.4f} 1/s in the FMU; linear response predicts {sp["linear_response_share_at_identified_per_s"]:.4f} 1/s,
the stiff limit {sp["quasi_static_share_at_identified_per_s"]:.4f} 1/s, the resonant limit alone
{sp["resonant_limit_share_at_identified_per_s"]:.4f} 1/s: neither limit applies, the suspension sits between them.
"""


def _flow_text(s: SuspensionSummary) -> str:
    """What the energy-flow numbers of the identified (and the resonant) suspension say."""
    f = s["energy_flow"]["identified"]
    text = (
        f"P_to_suspension swings both ways, its rms {f['rms_P_to_suspension_W'] / f['mean_P_to_suspension_W']:.0f} "
        "times its mean: the pivot force pumps energy into the springs and takes most of it back within each "
        "swing; what the dampers keep is the loss. The suspension holds on average "
        f"{1e3 * f['mean_E_suspension_J']:.2f} mJ, at most {1e3 * f['max_E_suspension_J']:.1f} mJ: it passes the "
        "energy on about as fast as it arrives. The power balance closes (last column). At the identified "
        f"point the pivot moves at {f['peak_frequency_xs_rad_s']:.1f} rad/s (x) and {f['peak_frequency_ys_rad_s']:.1f} "
        "rad/s (y): it follows the pendulum's own force"
    )
    r = s["energy_flow"].get("resonant")
    if r is not None:
        text += (
            f"; at the resonant end at {r['peak_frequency_xs_rad_s']:.0f} and "
            f"{r['peak_frequency_ys_rad_s']:.0f} rad/s, "
            f"its natural frequencies, holding {1e3 * r['mean_E_suspension_J']:.1f} mJ on average"
        )
    return text + "."


def _opening(s: SuspensionSummary, quick: str) -> str:
    """Title, plain summary and the words used."""
    m, i, refit = s["measured"], s["identified"], s["refit"]["identified"]
    b0 = s["refit"]["no suspension"]["b_E_pendulum_per_s"]
    return report_opening(f"Can the pivot's suspension explain the measured energy decay?{quick}", [
        f"The camera shows the pendulum's energy decaying at b = {m['b_per_s']:.4f} 1/s; air drag and bearing friction "
        f"at the seed's own estimates account for only {abs(b0):.4f} 1/s of it, so this report asks whether a springy, "
        "damped mount of the pivot could take the rest.",
        "Maps of the decay rate over the mount's stiffness k and damping c show that many mounts reproduce the "
        "measured rate, along a curve in (k, c), not one.",
        f"Fitting c at an assumed k = {i['fixed']['k']:g} N/m and mass M_s = {i['fixed']['M_s']:g} kg gives "
        f"c = {i['c_N_s_per_m']:.0f} N s/m, but that suspension makes the loss depend on the swing's size far more "
        f"steeply than measured (loss exponent {refit['p']:.1f} against {m['decay_shape']['p']:.1f}), so it is a "
        "point on a curve of a model the data do not support at these k and M_s (others were not fitted), not a "
        "property of the stand.",
        "How sure: k and M_s are assumed, not measured, and every fit is judged on the record it was fitted to.",
    ], {
        "b": "the decay rate [1/s] of the energy fitted as E = a exp(b t)",
        "p": "the loss exponent of dE/dt = -k E^p: how steeply the loss grows with the energy",
        "F": "the correlation factor: the errors of neighbouring frames are alike over about a swing, so the frames "
             "count as n / F independent ones and every statistical error is multiplied by sqrt(F)",
        "total error": "the statistical error of b and its systematic errors (velocity estimator, weights, halves of "
                       "the record, rod mass, pivot) added in quadrature, from the energy_decay scenario",
        "iso-b curve": "the (k, c) where the simulated decay rate equals the measured one",
        "chi2": "the sum over the frames of ((simulated - measured energy) / the energy's error)^2",
        "chi2_red": "chi2 per degree of freedom; about 1 when a model misses the data by their errors",
        "linear response": "the suspension's loss predicted from the spectrum of the force the pendulum exerts on a "
                           "fixed pivot, without simulating the coupled motion",
        "rtol": "the integrator's relative error tolerance per step",
        "Jacobian": "the derivatives of the fit's residuals with respect to its parameters",
        "Fisher matrix": "J^T J of the fit's Jacobian: its eigenvalues say which combinations of (k, c, M_s) the "
                         "energy fixes (large) and which it leaves free (small)",
    })


def report_text(summary: SuspensionSummary) -> str:
    """The Markdown report: every figure from ``summary``."""
    quick = " (quick run: small grid, first seconds only)" if summary["quick"] else ""
    b0 = summary["refit"]["no suspension"]["b_E_pendulum_per_s"]
    head = _opening(summary, quick) + f"""## Question

Air drag and bearing friction at the seed's estimates take b = {b0:.4f} 1/s
of the measured {summary["measured"]["b_per_s"]:.4f} 1/s. How much can a damped suspension of the pivot add, which
suspensions reproduce the measurement, and is that the explanation? Run time {summary["wall_time_s"]:.0f} s.
The fitted c is a fit parameter, not a measured property: conditional on an assumed k and M_s and on the
default losses, of a model that reproduces neither b nor the decay's shape, along a valley of equally good
fits (Identification), it drifts with the fit window (below), and
``loss_identification`` finds that, at these k and M_s, a suspension with air drag fits the decay's shape no
better than a rigid pivot, where friction in the joints fits it well (see its report).

"""
    sections = (_measured_section, _map_section, _identification_section, _refit_section, _flow_section)
    return head + "\n".join(section(summary) for section in sections)
