"""The suspension study's analysis without the FMU: energy flow, summary entries, tables, figure inputs.

Synthetic runs, maps and force spectra with known answers: the energy budget closes, the natural
frequencies are sqrt(k/M), the limits of the linear response take their closed forms.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from double_pendulum.analysis.decay.fit import fit_model
from double_pendulum.analysis.suspension import decay_map
from double_pendulum.analysis.suspension import transfer as study
from double_pendulum.analysis.suspension.decay_map import MAP_UNITS, DecayMap, decay_maps
from double_pendulum.analysis.suspension.energy_flow import ENERGY_FLOW_OUTPUTS, energy_flow_summary, peak_frequency
from double_pendulum.analysis.suspension.identification import FitFrames, MeasuredDecay
from double_pendulum.analysis.suspension.response import ForceSpectrum
from double_pendulum.analysis.track.measurement import FRAME_INTERVAL

M12 = 0.6  # m1 + m2 [kg]


def _structured(columns: dict[str, np.ndarray]) -> np.ndarray:
    return np.rec.fromarrays(list(columns.values()), names=list(columns)).view(np.ndarray)


def _flat_spectrum(s0: float = 2.0, w_max: float = 100.0, mean_energy: float = 0.5) -> ForceSpectrum:
    """White force spectrum S0 [N^2 s/rad] on both axes up to w_max [rad/s], <|dF/dt|^2> = 40 N^2/s^2."""
    omega = np.linspace(0.0, w_max, 10001)
    s = np.full_like(omega, s0)
    return ForceSpectrum(omega, s, s.copy(), mean_energy, 40.0, M12, result=np.zeros(0))


def _decay_map(b: np.ndarray, m_s: float = 2.0) -> DecayMap:
    k = np.array([1e4, 4e4, 1.6e5])[: b.shape[0]]
    c = np.array([1.0, 10.0, 100.0])[: b.shape[1]]
    zeros = np.zeros_like(b)
    return DecayMap(m_s, k, c, b, b + 1e-7, zeros, zeros, b_base=-0.005)


def _measured(t: np.ndarray, energy: np.ndarray, sigma: np.ndarray, i0: int = 100) -> MeasuredDecay:
    frames = FitFrames(float(t[0]), np.arange(len(t)), t, sigma)
    return MeasuredDecay(None, i0, frames, energy, fit_model("exponential", t, energy, sigma), factor=4.0)


# --- energy flow ---------------------------------------------------------------------------------


def test_peak_frequency_finds_a_sinusoid_on_its_bin():
    dt, n = 0.005, 2000  # 10 s: bins every 2 pi / 10 rad/s
    t = np.arange(n) * dt
    w = 2.0 * math.pi * 37 / (n * dt)
    signal = 0.3 + np.sin(w * t) + 0.2 * np.sin(3.1 * w * t)
    assert peak_frequency(signal, dt) == pytest.approx(w, rel=1e-12)


def test_energy_flow_summary_splits_the_loss_and_closes_the_suspension_balance():
    dt = 0.005
    t = np.arange(0.0, 10.0 + dt / 2, dt)
    w_n = 2.0 * math.pi * 4.0  # the pivot rings at 4 Hz (40 cycles in the record)
    w_air, w_bearing, w_susp = 0.02 * t, 0.001 * t, 0.01 * t
    e_s = 1e-3 * np.sin(w_n * t) ** 2  # stored in the suspension, zero at both ends
    p_to_s = 0.01 + 1e-3 * w_n * np.sin(2.0 * w_n * t)  # d(E_s + W_s)/dt
    e_p = 1.0 - (w_air + w_bearing + w_susp + e_s)
    xs, ys = 2e-3 * np.sin(w_n * t), 1e-3 * np.cos(0.5 * w_n * t)
    result = _structured(
        {
            "time": t,
            "E_pendulum": e_p,
            "E_suspension": e_s,
            "E_total": e_p + e_s,
            "W_air": w_air,
            "W_bearing": w_bearing,
            "W_suspension": w_susp,
            "P_to_suspension": p_to_s,
            "xs": xs,
            "ys": ys,
            "energy_residual": np.full_like(t, -1e-9),
        }
    )
    assert set(ENERGY_FLOW_OUTPUTS) <= set(result.dtype.names)
    f = energy_flow_summary(result)
    assert f["pendulum_energy_lost_J"] == pytest.approx(0.31, rel=1e-9)
    assert f["share_W_air"] == pytest.approx(0.2 / 0.31, rel=1e-9)
    assert f["share_W_bearing"] == pytest.approx(0.01 / 0.31, rel=1e-9)
    assert f["share_W_suspension"] == pytest.approx(0.1 / 0.31, rel=1e-9)
    shares = ("share_W_suspension", "share_W_air", "share_W_bearing", "share_still_in_suspension")
    assert sum(f[k] for k in shares) == pytest.approx(1.0, abs=1e-12)
    assert f["integral_P_dt_J"] == pytest.approx(f["E_suspension_gain_plus_W_suspension_J"], rel=1e-6)
    assert f["max_E_suspension_J"] == pytest.approx(1e-3, rel=1e-2)  # sampled peak of sin^2
    assert f["mean_E_suspension_J"] == pytest.approx(0.5e-3, rel=1e-3)  # <sin^2> = 1/2
    assert f["mean_P_to_suspension_W"] == pytest.approx(0.01, rel=1e-3)
    assert f["peak_frequency_xs_rad_s"] == pytest.approx(w_n, rel=1e-3)
    assert f["peak_frequency_ys_rad_s"] == pytest.approx(0.5 * w_n, rel=1e-3)
    assert f["rms_xs_m"] == pytest.approx(2e-3 / math.sqrt(2.0), rel=1e-3)
    assert f["max_abs_energy_residual_J"] == pytest.approx(1e-9)


# --- summary entries -----------------------------------------------------------------------------


def test_spectrum_summary_of_a_white_force_spectrum():
    spectrum = _flat_spectrum(s0=2.0, w_max=100.0, mean_energy=0.5)
    ident = type("Ident", (), {"k": 2e4, "c": 30.0, "m_s": 2.0})()
    s = study.spectrum_summary(spectrum, ident)
    assert s["rms_F_x_N"] == pytest.approx(math.sqrt(200.0), rel=1e-12)  # <F^2> = S0 * w_max
    assert s["rms_frequency_rad_s"] == pytest.approx(math.sqrt(40.0 / 400.0), rel=1e-12)
    assert s["identified_omega_n_x_rad_s"] == pytest.approx(100.0)  # sqrt(2e4 / 2)
    assert s["identified_omega_n_y_rad_s"] == pytest.approx(math.sqrt(2e4 / 2.6))
    # stiff limit -c <|dF/dt|^2> / (k^2 E); resonant limit -sum pi S0 / (2 M) / E
    assert s["quasi_static_share_at_identified_per_s"] == pytest.approx(-30.0 * 40.0 / (4e8 * 0.5))
    resonant = -(math.pi * 2.0 / (2.0 * 2.0) + math.pi * 2.0 / (2.0 * 2.6)) / 0.5
    assert s["resonant_limit_share_at_identified_per_s"] == pytest.approx(resonant, rel=1e-9)


def test_resonant_point_is_where_the_lightest_damped_column_crosses_the_level():
    b = np.array([[-0.01, -0.02], [-0.03, -0.04], [-0.02, -0.05]])
    dmap = _decay_map(b)
    k, c = study.resonant_point(dmap, -0.02)
    assert c == 1.0
    assert k == pytest.approx(math.sqrt(1e4 * 4e4), rel=1e-12)  # halfway in ln k between the first two rows
    assert study.resonant_point(dmap, -0.5) is None
    r = study.resonant_summary((k, c), 2.0, _flat_spectrum())
    assert r["omega_n_x_rad_s"] == pytest.approx(math.sqrt(k / 2.0))
    assert r["omega_n_y_rad_s"] == pytest.approx(math.sqrt(k / (2.0 + M12)))
    assert r["resonant_limit_share_per_s"] < 0.0


def test_run_summary_recovers_the_rate_and_the_exponential_shape_of_a_run():
    t = 1.0 + np.arange(300) * FRAME_INTERVAL
    sigma = np.full_like(t, 2e-3)
    measured = 0.8 * np.exp(-0.025 * t)
    md = _measured(t, measured, sigma)
    assert md.b == pytest.approx(-0.025, rel=1e-9)
    simulated = 0.8 * np.exp(-0.02 * t)
    run = _structured({"E_pendulum": simulated, "E_total": simulated + 1e-4})
    s = study.run_summary(md, run, reference_chi2=10.0, total_b_err=0.002)
    assert s["b_E_pendulum_per_s"] == pytest.approx(-0.02, rel=1e-6)
    assert s["b_E_total_per_s"] == pytest.approx(-0.02, rel=0.01)
    assert s["relative_difference_to_measured"] == pytest.approx(-0.2, rel=1e-5)
    assert s["difference_in_total_sigma"] == pytest.approx(0.005 / 0.002, rel=1e-5)  # against the total error
    assert s["p"] == pytest.approx(1.0, abs=1e-3)  # exponential decay: dE/dt = -k E^1
    chi2 = float(np.sum(((simulated - measured) / sigma) ** 2))
    assert s["chi2"] == pytest.approx(chi2, rel=1e-12)
    assert s["delta_chi2"] == pytest.approx(chi2 - 10.0, rel=1e-12)
    m = study.measured_summary(md, seed_b=-0.024, total_b_err=0.002)
    assert m["n_frames"] == 300 and m["release_frame"] == 100
    assert m["a_J"] == pytest.approx(0.8, rel=1e-9)
    assert m["b_per_s_stderr_autocorr"] == pytest.approx(2.0 * m["b_per_s_stderr"])  # sqrt(factor 4)


# --- tables and figure inputs --------------------------------------------------------------------


def test_map_table_has_one_row_per_grid_point_with_the_natural_frequencies():
    maps = [_decay_map(np.full((3, 2), -0.02)), _decay_map(np.full((2, 2), -0.03), m_s=8.0)]
    table = study.map_table(maps, M12)
    assert list(table.dtype.names) == list(MAP_UNITS)
    assert len(table) == 6 + 4
    assert np.all(table["M_s"][6:] == 8.0)
    assert table["omega_n_x"] == pytest.approx(np.sqrt(table["k"] / table["M_s"]))
    assert table["omega_n_y"] == pytest.approx(np.sqrt(table["k"] / (table["M_s"] + M12)))
    assert table["b_suspension"] == pytest.approx(table["b_E_pendulum"] + 0.005)


def test_frames_table_takes_the_runs_on_the_fitted_frames():
    n = 10  # the runs have rows every frame from t0; the fitted frames are every second one
    offsets = np.arange(0, n, 2)
    t, sigma = offsets * FRAME_INTERVAL, np.full(5, 1e-3)
    energy = 0.8 * np.exp(-0.025 * t)
    fit = fit_model("exponential", t, energy, sigma)
    md = MeasuredDecay(None, 7, FitFrames(0.0, offsets, t, sigma), energy, fit, factor=1.0)
    runs = {
        "identified": _structured({"E_pendulum": np.arange(n, dtype=float), "E_total": np.arange(n) + 0.5}),
        "no suspension": _structured({"E_pendulum": 10.0 + np.arange(n), "E_total": 10.0 + np.arange(n)}),
    }
    table = study.frames_table(md, runs, np.ones(5))
    assert "E_pendulum_resonant" not in table.dtype.names
    assert list(table["frame"]) == [7.0, 9.0, 11.0, 13.0, 15.0]
    assert list(table["E_pendulum_identified"]) == [0.0, 2.0, 4.0, 6.0, 8.0]
    assert list(table["E_total_identified"]) == [0.5, 2.5, 4.5, 6.5, 8.5]
    runs["resonant"] = runs["no suspension"]
    assert list(study.frames_table(md, runs, np.ones(5))["E_pendulum_resonant"]) == [10.0, 12.0, 14.0, 16.0, 18.0]
    assert set(study.FRAME_UNITS) <= set(table.dtype.names) | {"E_pendulum_resonant"}


def test_predicted_cuts_follow_the_stiff_limit_c_over_k_squared():
    spectrum = _flat_spectrum()
    dmap = _decay_map(np.full((3, 3), -0.02))
    c_fine, lr, qs = study.predicted_cuts(dmap, spectrum, n_c=11)
    assert c_fine[0] == pytest.approx(1.0) and c_fine[-1] == pytest.approx(100.0)
    assert lr.shape == qs.shape == (3, 11)
    assert qs[0] == pytest.approx(-c_fine * 40.0 / (1e4**2 * 0.5))
    assert qs[0] / qs[1] == pytest.approx(np.full(11, 16.0))  # k four times stiffer: share / 16
    assert np.all(lr < 0.0)


def test_natural_frequency_marks_and_shown_spectrum():
    spectrum = _flat_spectrum()
    ident = type("Ident", (), {"k": 2e4, "c": 30.0, "m_s": 2.0})()
    marks = study.natural_frequency_marks(spectrum, ident)
    assert list(marks.values()) == pytest.approx([100.0, math.sqrt(2e4 / 2.6)])
    assert "= 100 rad/s" in next(iter(marks)) and all("assumed" in label for label in marks)  # k, M_s: not measured
    omega, spectra = study.shown_force_spectra(spectrum)
    assert omega[0] >= study.SPECTRUM_SHOWN_FROM and [len(s) for s in spectra.values()] == [len(omega)] * 2
    assert [label.split()[-1] for label in spectra] == ["F_x", "F_y"]


def test_decay_maps_sweeps_the_main_grid_then_coarser_ones_per_extra_mass(monkeypatch):
    calls = []

    def fake_sweep(fmu_path, base, frames, cases, max_workers=None):
        calls.append((list(cases), max_workers))
        return [{"b_E_pendulum": -float(i), "b_E_total": -float(i)} for i in range(len(cases))]

    class Spectrum:
        def linear_response_rate(self, k, c, m_s):
            return 0.0

        def quasi_static_rate(self, k, c):
            return 0.0

    monkeypatch.setattr(decay_map, "decay_rate_sweep", fake_sweep)
    k, c = (1.0, 2.0, 3.0, 4.0, 5.0), (10.0, 20.0, 30.0)
    maps = decay_maps("x.fmu", {}, None, Spectrum(), k, c, 2.0, m_s_extra=(0.5, 8.0), extra_stride=2, max_workers=3)
    assert len(calls) == 1 and calls[0][1] == 3  # one sweep for every grid
    cases = calls[0][0]
    assert len(cases) == 1 + 15 + 6 + 6 and cases[0]["suspension"] is False  # one run without suspension, shared
    assert [m.m_s for m in maps] == [2.0, 0.5, 8.0]
    assert tuple(maps[0].k) == k and tuple(maps[0].c) == c
    assert tuple(maps[1].k) == (1.0, 3.0, 5.0) and tuple(maps[1].c) == (10.0, 30.0)
    assert tuple(maps[2].k) == tuple(maps[1].k) and tuple(maps[2].c) == tuple(maps[1].c)
    assert all(m.b_base == 0.0 for m in maps)
    assert maps[0].b[0, 0] == -1.0 and maps[1].b[0, 0] == -16.0 and maps[2].b[-1, -1] == -27.0
    assert cases[16]["k_x"] == 1.0 and cases[16]["M_s"] == 0.5 and cases[16]["c_x"] == 10.0
