"""The suspension scenario: identification reproduces the measured decay, the map obeys the physics."""

from __future__ import annotations

import numpy as np
import pytest
from conftest import quick_scenario
from double_pendulum.scenarios import suspension_transfer as st
from double_pendulum.scenarios.friction_budget import SEED_RELEASE

from double_pendulum.analysis.decay.fit import calibrate_error_model, fit_model
from double_pendulum.analysis.suspension.decay_map import BASE_SETTINGS, MAP_SETTINGS, decay_rate_sweep
from double_pendulum.analysis.suspension.identification import (
    FIT_SETTINGS,
    FitFrames,
    identify_suspension,
    suspension_values,
)
from double_pendulum.analysis.suspension.response import pivot_force_spectrum
from double_pendulum.analysis.track.measurement import FRAME_INTERVAL, load_track, reconstruct
from double_pendulum.analysis.track.tilt import seed_record_geometry
from double_pendulum.runs.results_io import read_results_csv


@pytest.fixture(scope="module")
def identified(runner):
    """The quick identification (first seconds of the track), shared by the tests of this module."""
    return identify_suspension(runner, quick=True)


def _measured_b(window_s: float) -> tuple[float, np.ndarray, np.ndarray, np.ndarray, int]:
    """b of the camera energy after the release over ``window_s`` s, straight from measurement + decay_fit."""
    rec = reconstruct(load_track(), seed_record_geometry().geometry)
    i0 = rec.release_frame
    idx = np.flatnonzero(rec.free_motion & (rec.t <= rec.t[i0] + window_s))
    t, e = rec.t[idx], rec.energy[idx]
    sigma = calibrate_error_model(t, e, rec.sigma_energy[idx], rec.momentum[idx]).sigma
    return fit_model("exponential", t, e, sigma).value("b"), t, sigma, idx - i0, i0


def test_identified_suspension_carries_most_of_the_measured_decay_rate(runner, identified):
    b_meas, t, sigma, offsets, i0 = _measured_b(st.QUICK.window_s)
    assert identified.measured.b == pytest.approx(b_meas, rel=1e-9)
    t0 = float(t[0])
    run = runner.simulate(
        {**FIT_SETTINGS, **identified.values},
        start_time=t0,
        stop_time=t0 + offsets[-1] * FRAME_INTERVAL,
        output_interval=FRAME_INTERVAL,
        outputs=("E_pendulum",),
    )
    b_sim = fit_model("exponential", t, run["E_pendulum"][offsets], sigma).value("b")
    # fitted to the energy itself, the suspension carries most of the decay but not all of its early part: on the
    # track turned back by the camera's tilt the decay is not exponential (dE/dt ~ -E^p, p about 1/2, energy_decay),
    # which a viscous-like suspension loss cannot follow (on the untilted track b agreed within 5 %)
    assert 0.7 < b_sim / b_meas < 0.95, (b_sim, b_meas)
    # the suspension carries the loss: without it the same start decays at less than a third of the rate
    no_suspension = {k: v for k, v in identified.values.items() if k != "suspension"}
    run0 = runner.simulate(
        {**FIT_SETTINGS, **no_suspension},
        start_time=t0,
        stop_time=t0 + offsets[-1] * FRAME_INTERVAL,
        output_interval=FRAME_INTERVAL,
        outputs=("E_pendulum",),
    )
    assert abs(fit_model("exponential", t, run0["E_pendulum"][offsets], sigma).value("b")) < abs(b_meas) / 3
    ident = identified.identification
    assert 0.0 < ident.c_stderr < ident.c
    # the calibrated errors nearly describe the scatter about the FMU's energy; what is left (chi2_red about 1.6 on
    # the first seconds; below 1.5 on the untilted track) is the non-exponential decay the suspension cannot follow
    assert 0.7 < ident.chi2_red < 2.0


def test_stiff_suspension_loss_scales_as_c_over_k_squared_and_follows_linear_response(runner):
    n = 151  # 5 s of frames from the seed's release, suspension the only loss
    frames = FitFrames(0.0, np.arange(n), np.arange(n) * FRAME_INTERVAL, None)
    base = dict(SEED_RELEASE)
    points = [(1e5, 30.0), (1e5, 90.0), (1e5, 270.0), (2e5, 270.0)]
    cases = [{**BASE_SETTINGS, "suspension": False}]
    cases += [{**MAP_SETTINGS, **suspension_values(k, c, 2.0)} for k, c in points]
    rates = [r["b_E_pendulum"] for r in decay_rate_sweep(runner.fmu_path, base, frames, cases, max_workers=1)]
    assert abs(rates[0]) < 1e-5  # no loss mechanism, no decay
    b = dict(zip(points, rates[1:]))
    assert b[(1e5, 30.0)] > b[(1e5, 90.0)] > b[(1e5, 270.0)]  # more damping, faster decay (stiff range)
    assert b[(1e5, 90.0)] / b[(1e5, 30.0)] == pytest.approx(3.0, rel=0.15)  # ~ c
    assert b[(1e5, 270.0)] / b[(1e5, 90.0)] == pytest.approx(3.0, rel=0.15)
    assert b[(1e5, 270.0)] / b[(2e5, 270.0)] == pytest.approx(4.0, rel=0.15)  # ~ 1/k^2
    spectrum = pivot_force_spectrum(runner, base, 0.0, frames.duration, 0.301 + 0.297, 9.81)
    for (k, c), rate in b.items():
        assert rate == pytest.approx(spectrum.linear_response_rate(k, c, 2.0), rel=0.1)


def test_quick_run_writes_its_files_and_closes_the_energy_budget(quick_results):
    tmp_path, summary = quick_scenario(quick_results, "suspension_transfer")
    table = read_results_csv(tmp_path / "decay_rate_map.csv")
    assert len(table) == len(st.QUICK.k_grid) * len(st.QUICK.c_grid)
    assert np.all(table["b_suspension"] < 0)  # a damper only takes energy
    frames = read_results_csv(tmp_path / "frames.csv")
    assert np.all(np.diff(frames["E_total_identified"]) <= 1e-8)  # no input: the total energy never rises
    flow = summary["energy_flow"]["identified"]
    shares = ("share_W_suspension", "share_W_air", "share_W_bearing", "share_still_in_suspension")
    # closed to the integration's error: 1.0e-6 of the loss with the quick identification on the tilt-corrected track
    assert sum(flow[k] for k in shares) == pytest.approx(1.0, abs=3e-6)
    assert flow["integral_P_dt_J"] == pytest.approx(flow["E_suspension_gain_plus_W_suspension_J"], rel=0.01)
    for name in ("decay_rate_map", "decay_rate_cuts", "force_spectrum", "energy_flow", "energy_fit"):
        assert (tmp_path / f"{name}.png").stat().st_size > 10_000
    for name in ("identified", "fixed_pivot_force"):
        assert len(read_results_csv(tmp_path / f"{name}.csv")) > 100
    report = (tmp_path / "report.md").read_text()
    assert "curve, not a point" in report
    ident = summary["identified"]
    assert f"c = {ident['c_N_s_per_m']:.1f} +- {ident['c_stderr']:.1f} N s/m" in report
    # c is stated as conditional, and the valley beside the point: c along it rises with k at the fitted slope
    assert set(ident["conditional_on"]) == {"k", "M_s", "losses", "model", "valley"} and "is conditional" in report
    valley, slope = summary["valley"]["linearised"], summary["valley"]["fisher"]["valley_slope_dlnc_dlnk"]
    ratio = valley[-1]["c_N_s_per_m"] / valley[0]["c_N_s_per_m"]
    assert ratio == pytest.approx((valley[-1]["k_N_per_m"] / valley[0]["k_N_per_m"]) ** slope)
    assert f"b = {summary['measured']['b_per_s']:.5f} +- " in report
