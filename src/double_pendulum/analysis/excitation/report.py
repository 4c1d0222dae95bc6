"""Summary (key figures with units in their names) and Markdown report of ``base_excitation``."""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any

from ...model.parameters import PendulumParameters
from ...runs.results_io import report_opening
from .drive import FLOQUET_TOLERANCE
from .study import KapitzaResult, distance_to_bound, normal_modes, wedge_tip_frequency
from .summary_types import AchesonSummary, ExcitationSummary, KapitzaSummary
from .theory import equivalent_lengths

UNIT_SUFFIXES = (("_rad_per_s", "rad/s"), ("_rad", "rad"), ("_m", "m"), ("_s", "s"))


def unit_headers(rows: Sequence[Mapping[str, Any]]) -> list[dict[str, Any]]:
    """Rows with the unit suffix of each key written as a CSV header: ``amplitude_m`` -> ``amplitude [m]``."""

    def header(key: str) -> str:
        for suffix, unit in UNIT_SUFFIXES:
            if key.endswith(suffix):
                return f"{key[: -len(suffix)]} [{unit}]"
        return key

    return [{header(k): v for k, v in row.items()} for row in rows]


def kapitza_summary(k: KapitzaResult) -> KapitzaSummary:
    """The simulated threshold [m] (Floquet multipliers) against the exact bounds of the held input and of the
    continuous sinusoid and against ``sqrt(2 g l1)/omega``."""
    b = k.bisection
    return {
        "kapitza_frequency_rad_per_s": k.setup.omega,
        "kapitza_steps_per_period": k.setup.steps_per_period,
        "kapitza_mass_ratio_m2_over_m1": k.setup.mass_ratio,
        "kapitza_rod_length_m": k.params.l1,
        "kapitza_criterion": "Floquet: largest |multiplier| of the simulated monodromy matrix of one period"
                             f" <= 1 + {FLOQUET_TOLERANCE:g}",
        "kapitza_threshold_amplitude_m": b.threshold,
        "kapitza_threshold_uncertainty_m": 0.5 * (b.stable_at - b.unstable_at),
        "kapitza_held_exact_amplitude_m": k.held_exact,
        "kapitza_relative_error_vs_held_exact": b.threshold / k.held_exact - 1.0,
        "kapitza_mathieu_exact_amplitude_m": k.mathieu_exact,
        "kapitza_held_over_continuous": k.held_exact / k.mathieu_exact - 1.0,
        "kapitza_theory_amplitude_m": k.theory_point_mass,
        "kapitza_relative_error": b.threshold / k.theory_point_mass - 1.0,
        "kapitza_effective_length_m": k.effective_length,
        "kapitza_single_pendulum_limit_length_error": k.effective_length / k.params.l1 - 1.0,
        "kapitza_theory_effective_length_amplitude_m": k.theory_effective,
        "kapitza_probes": len(b.probes),
    }


def acheson_summary(rows: Sequence[Mapping[str, Any]], bands: Sequence[Mapping[str, Any]]) -> AchesonSummary:
    """The map's agreement with the linear theory (held input as simulated, and the continuous sinusoid) and
    where the measured stable band begins."""
    agree = sum(r["stable"] == r["theory_stable"] for r in rows)
    agree_continuous = sum(r["stable"] == r["theory_continuous_stable"] for r in rows)
    stable_w = [b["omega_rad_per_s"] for b in bands if math.isfinite(b["lowest_stable_m"])]
    l_slow, l_fast = equivalent_lengths(PendulumParameters())
    off = [distance_to_bound(r["amplitude_m"], r["omega_rad_per_s"]) for r in rows
           if r["stable"] != r["theory_continuous_stable"]]
    return {
        "acheson_map_points": len(rows),
        "acheson_criterion": "Floquet: largest |multiplier| of the simulated monodromy matrix of one period"
                             f" <= 1 + {FLOQUET_TOLERANCE:g}",
        "acheson_stable_points": sum(bool(r["stable"]) for r in rows),
        "acheson_theory_stable_points": sum(bool(r["theory_stable"]) for r in rows),
        "acheson_agreement_fraction": agree / len(rows),
        "acheson_theory_continuous_stable_points": sum(bool(r["theory_continuous_stable"]) for r in rows),
        "acheson_agreement_fraction_continuous": agree_continuous / len(rows),
        "acheson_continuous_disagreements_max_relative_distance_to_bound": max(off, default=0.0),
        "acheson_equivalent_length_slow_mode_m": l_slow,
        "acheson_equivalent_length_fast_mode_m": l_fast,
        "acheson_theory_lowest_stable_frequency_rad_per_s": wedge_tip_frequency(),
        "acheson_measured_lowest_stable_frequency_rad_per_s": min(stable_w, default=math.nan),
        "acheson_theory_flutter_amplitude_high_frequency_m": 0.454 * l_fast,
    }


def resonance_summary(rows: Sequence[Mapping[str, Any]], peaks: Sequence[Mapping[str, Any]]) -> dict[str, Any]:
    """Peak frequencies [rad/s] against the damped linear response's peaks (``relative_error``), the undamped
    normal modes, the largest relative error and damping shift, and the steady-state drift."""
    out: dict[str, Any] = {"resonance_drive_frequencies": len(rows)}
    slow, fast = normal_modes()
    out["resonance_normal_mode_slow_rad_per_s"], out["resonance_normal_mode_fast_rad_per_s"] = slow, fast
    for p in peaks:
        out[f"resonance_peak_{p['mode']}_{p['angle']}_rad_per_s"] = p["peak_rad_per_s"]
        out[f"resonance_damped_linear_peak_{p['mode']}_{p['angle']}_rad_per_s"] = p["damped_linear_peak_rad_per_s"]
        out[f"resonance_peak_{p['mode']}_{p['angle']}_relative_error"] = p["relative_error"]
    out["resonance_max_abs_relative_error"] = max(abs(p["relative_error"]) for p in peaks)
    out["resonance_max_abs_damping_shift"] = max(abs(p["damping_shift"]) for p in peaks)
    out["resonance_max_steady_state_drift"] = max(r["drift"] for r in rows)
    out["resonance_max_amplitude_rad"] = max(max(r["phi1_amplitude_rad"], r["phi2_amplitude_rad"]) for r in rows)
    return out


def _opening(s: ExcitationSummary, quick: bool) -> str:
    """Title, plain summary and the words used."""
    title = "Base excitation: the pendulum driven through its inputs" + (" (quick run)" if quick else "")
    return report_opening(title, [
        "The FMU's pivot was shaken up and down, or its upper rod driven by a motor torque, through its inputs, and "
        "the simulated motion was compared with the linear theory of each effect.",
        f"A single pendulum shaken at {s['kapitza_frequency_rad_per_s']:g} rad/s stays upright above an amplitude of "
        f"{1e3 * s['kapitza_threshold_amplitude_m']:.3f} mm (Kapitza's pendulum), which the exact theory of the motion "
        f"as simulated matches to {abs(100 * s['kapitza_relative_error_vs_held_exact']):.4f} %.",
        f"For the double pendulum, {s['acheson_stable_points']} of {s['acheson_map_points']} combinations of shaking "
        f"frequency and amplitude hold it upright, and the theory agrees on "
        f"{100 * s['acheson_agreement_fraction']:.0f} % of them (Acheson's inverted double pendulum).",
        f"Driven by a small torque, both rods resonate at the damped linear theory's peaks to within "
        f"{100 * s['resonance_max_abs_relative_error']:.2f} %, the resolution of the frequencies tried.",
    ], {
        "Floquet multipliers": "the eigenvalues of the monodromy matrix; upright is stable while none exceeds 1 in "
                               "size",
        "monodromy matrix": "the map of small deviations from upright over one shaking period, here from five "
                            "one-period runs through the FMU",
        "Mathieu equation": "the linear equation of a pendulum on a sinusoidally moving pivot; its stability bounds "
                            "are the continuous-sinusoid theory",
        "held input": "the FMU holds the pivot acceleration constant over each communication step, so the system "
                      "simulated has its own exact bounds, slightly off the continuous sinusoid's",
        "normal modes": "the hanging pendulum's two ways of swinging at one frequency each (slow and fast)",
    })


def report(summary: ExcitationSummary, peaks: Sequence[Mapping[str, Any]], quick: bool) -> str:
    """The findings in words and tables (Markdown)."""
    s = summary
    lines = [
        _opening(s, quick).rstrip("\n"),
        "",
        "Generated by `double-pendulum run base_excitation`" + (" --quick (coarse, shortened runs)" if quick else "")
        + ". Every run goes through the FMU with fmpy (`simulate_fmu(input=...)`): the pivot moves as",
        "y = a sin(omega t) with consistent `pivot_y`, `pivot_vy`, `pivot_ay`, or `tau1` = T0 sin(omega t).",
        "",
        "## Kapitza's inverted pendulum (single-pendulum limit)",
        "",
        f"m2 = {s['kapitza_mass_ratio_m2_over_m1']:g} m1: the upper rod is a point mass on a massless rod of"
        f" l1 = {s['kapitza_rod_length_m']} m; the lower test mass changes the slow mode's equivalent length"
        f" g/omega_slow^2 by {s['kapitza_single_pendulum_limit_length_error']:.1e} (relative).",
        f"At omega = {s['kapitza_frequency_rad_per_s']:g} rad/s, with the pivot acceleration held over each of"
        f" {s['kapitza_steps_per_period']} communication steps a period as the FMU holds its inputs, the"
        f" threshold is bisected over {s['kapitza_probes']} amplitudes on the Floquet multipliers of the"
        " system as simulated: the monodromy matrix of one period through the FMU (finite differences about"
        " upright), stable while its largest |multiplier| stays within 1e-6 of 1. A run that merely has not"
        " yet fallen over decides nothing: just below the threshold the growth is slow (about 4 % a period"
        " 0.1 % below it).",
        "",
        "| quantity | amplitude [mm] |",
        "|---|---|",
        f"| simulated threshold (Floquet multipliers) | {1e3 * s['kapitza_threshold_amplitude_m']:.4f} +- "
        f"{1e3 * s['kapitza_threshold_uncertainty_m']:.4f} |",
        "| exact linear bound, input held over each step (as simulated) |"
        f" {1e3 * s['kapitza_held_exact_amplitude_m']:.4f} |",
        "| exact linear bound, continuous sinusoid (Mathieu a_0) |"
        f" {1e3 * s['kapitza_mathieu_exact_amplitude_m']:.4f} |",
        f"| averaged a^2 omega^2 = 2 g l1 | {1e3 * s['kapitza_theory_amplitude_m']:.4f} |",
        f"| same with the effective length | {1e3 * s['kapitza_theory_effective_length_amplitude_m']:.4f} |",
        "",
        f"The simulated threshold lies {100 * s['kapitza_relative_error_vs_held_exact']:+.4f} % from the exact bound"
        " of the system simulated; the held input raises the bound by"
        f" {100 * s['kapitza_held_over_continuous']:+.2f} % over the continuous sinusoid's, and the averaged formula"
        f" lies {100 * s['kapitza_relative_error']:+.2f} % below the simulated threshold (it is the leading order"
        " in a/l; the next term raises the threshold by about 7 a^2/(32 l^2)).",
        "",
        "## Acheson: the inverted double pendulum held upright",
        "",
        f"{s['acheson_map_points']} grid points, each judged by the Floquet multipliers of its simulated"
        f" monodromy matrix: {s['acheson_stable_points']} upright-stable; the linear theory with the input held as"
        f" simulated gives {s['acheson_theory_stable_points']} and agrees on"
        f" {100 * s['acheson_agreement_fraction']:.1f} % of the points (`acheson_map.csv`: `stable` simulated,"
        " `theory_stable` held input, `theory_continuous_stable` continuous sinusoid); the continuous sinusoid's"
        f" theory gives {s['acheson_theory_continuous_stable_points']} and agrees on"
        f" {100 * s['acheson_agreement_fraction_continuous']:.1f} % (its disagreements lie within"
        f" {100 * s['acheson_continuous_disagreements_max_relative_distance_to_bound']:.1f} % of one of its bounds).",
        f"Theory: each normal mode is an inverted simple pendulum of length L_i = g/omega_i^2"
        f" ({s['acheson_equivalent_length_slow_mode_m']:.4f} m, {s['acheson_equivalent_length_fast_mode_m']:.4f} m);"
        " stable if both Mathieu equations are: a^2 omega^2 > 2 g L_slow (averaged; exact: a_0(q) < delta)"
        f" and a < 0.454 L_fast = {1e3 * s['acheson_theory_flutter_amplitude_high_frequency_m']:.1f} mm at high"
        " frequency (flutter, b_1(q) > delta).",
        "Lowest frequency with an upright-stable band: theory"
        f" {s['acheson_theory_lowest_stable_frequency_rad_per_s']:.1f} rad/s, map"
        f" {s['acheson_measured_lowest_stable_frequency_rad_per_s']:.1f} rad/s (grid resolution).",
        "",
        "## Resonance under a pivot torque",
        "",
        "The peaks are compared with the damped linear response (the hanging pendulum's M0, K and the viscous"
        " pivot bearing of the runs): damping moves each peak away from the undamped normal mode, differently"
        " for the two rods, so the normal modes are no reference for a damped peak.",
        "",
        "| mode | angle | undamped mode [rad/s] | damped linear peak [rad/s] | simulated peak [rad/s] | simulated"
        " against damped linear |",
        "|---|---|---|---|---|---|",
    ]
    lines += [f"| {p['mode']} | {p['angle']} | {p['normal_mode_rad_per_s']:.4f} | "
              f"{p['damped_linear_peak_rad_per_s']:.4f} | {p['peak_rad_per_s']:.4f} | "
              f"{100 * p['relative_error']:+.2f} % |" for p in peaks]
    lines += ["", f"Largest shift of a damped peak from its undamped mode:"
              f" {100 * s['resonance_max_abs_damping_shift']:.2f} %; largest steady-state drift of an amplitude over"
              f" the window: {100 * s['resonance_max_steady_state_drift']:.1f} %.", ""]
    return "\n".join(lines)
