"""The measured track: loading and flagging, circle fit, angles, derivative filters, energy and its errors."""

from __future__ import annotations

import numpy as np
import pytest
from conftest import DATA
from scipy.integrate import solve_ivp
from scipy.signal import savgol_filter

from double_pendulum.analysis.track import measurement as ms
from double_pendulum.model.dynamics import fixed_pivot_vector_field
from double_pendulum.model.energy import total_energy
from double_pendulum.model.kinematics import positions
from double_pendulum.model.parameters import PendulumParameters

TRUE = PendulumParameters(l1=0.2965, l2=0.1971)
PIVOT = (0.0035, -0.0029)  # where the pivot sits in the synthetic track's coordinates [m]


def _motion(n_frames: int = 300, start=(0.6, -1.0, 0.0, 0.0)) -> np.ndarray:
    """Frictionless motion of the seed pendulum sampled at the camera rate: rows phi1, phi2, w1, w2."""
    t = np.arange(n_frames) * ms.FRAME_INTERVAL
    sol = solve_ivp(
        fixed_pivot_vector_field(TRUE),
        (0.0, t[-1]),
        list(start),
        method="DOP853",
        t_eval=t,
        rtol=1e-11,
        atol=1e-12,
    )
    return sol.y


def _synthetic_track(rng: np.random.Generator, sigma1: float, sigma2: float, n_frames: int = 300) -> ms.Track:
    """Track of simulated motion with the pivot at PIVOT and white position noise [m] on each bob."""
    phi1, phi2, *_ = _motion(n_frames)
    x1, y1, x2, y2 = positions(phi1, phi2, TRUE.l1, TRUE.l2, np.sin, np.cos)
    x1, x2 = x1 + PIVOT[0] + rng.normal(0, sigma1, n_frames), x2 + PIVOT[0] + rng.normal(0, sigma2, n_frames)
    y1, y2 = y1 + PIVOT[1] + rng.normal(0, sigma1, n_frames), y2 + PIVOT[1] + rng.normal(0, sigma2, n_frames)
    frame = np.arange(n_frames)
    valid = ms.flag_bad_frames(x1, y1, x2, y2)
    return ms.Track(frame, frame / ms.FPS, x1, y1, x2, y2, valid)


# --- loading and flagging ------------------------------------------------------------------------


def test_loader_returns_634_evenly_spaced_frames_close_to_the_printed_times():
    track = ms.load_track()
    assert len(track) == 634
    np.testing.assert_array_equal(track.frame, np.arange(634))
    np.testing.assert_allclose(np.diff(track.t), 1.0 / 29.97, rtol=1e-12)
    printed = np.loadtxt(DATA / "seed_table1.csv", delimiter=",", skiprows=1, usecols=1)
    lag = track.t - printed
    assert np.all((lag > -1e-9) & (lag < 0.01))  # printed time: cut to 3, later 2 decimals
    assert track.valid.all()  # the seed's table has no tracker jump


def test_missing_table_raises_file_not_found_naming_the_path(tmp_path):
    with pytest.raises(FileNotFoundError, match="nope.csv"):
        ms.load_track(tmp_path / "nope.csv")


def test_table_with_other_columns_is_rejected(tmp_path):
    path = tmp_path / "t.csv"
    path.write_text("frame,t,x1,y1,x2,y2\n0,0,0,0,0,0\n")
    with pytest.raises(ValueError, match="columns"):
        ms.load_track(path)


def test_tracker_jump_is_flagged_kept_and_fenced_off_in_the_energy(tmp_path):
    lines = (DATA / "seed_table1.csv").read_text().splitlines()
    cells = lines[1 + 300].split(",")
    cells[4] = repr(float(cells[4]) + 0.06)  # the lower bob jumps 6 cm sideways in frame 300
    lines[1 + 300] = ",".join(cells)
    path = tmp_path / "jump.csv"
    path.write_text("\n".join(lines) + "\n")
    track = ms.load_track(path)
    assert len(track) == 634
    assert np.flatnonzero(~track.valid).tolist() == [300]
    rec = ms.reconstruct(track)
    half = ms.SG_WINDOW // 2
    assert not rec.energy_valid[300 - half : 300 + half + 1].any()
    assert rec.energy_valid[300 - half - 1] and rec.energy_valid[300 + half + 1]
    clean = ms.fit_geometry(ms.load_track())
    assert rec.geometry.l2 == pytest.approx(clean.l2, abs=1e-4)  # the jump does not enter l2


def test_upper_bob_jump_is_flagged():
    track = ms.load_track()
    y1 = track.y1.copy()
    y1[123] += 0.02
    valid = ms.flag_bad_frames(track.x1, y1, track.x2, track.y2)
    assert np.flatnonzero(~valid).tolist() == [123]


# --- circle fit and geometry --------------------------------------------------------------------


def test_circle_fit_recovers_centre_and_radius_within_its_stated_uncertainty():
    """60 noisy arcs like the seed's (+-0.7 rad, 0.5 mm noise): errors scale with the stated sigmas."""
    xc, yc, radius, noise = 0.0035, -0.0029, 0.2964, 5e-4
    z = []
    for seed in range(60):
        rng = np.random.default_rng(seed)
        ang = rng.uniform(-0.7, 0.7, 300)
        x = xc + radius * np.sin(ang) + rng.normal(0, noise, ang.size)
        y = yc - radius * np.cos(ang) + rng.normal(0, noise, ang.size)
        fit = ms.fit_circle(x, y)
        z.append(
            [
                (fit.xc - xc) / fit.sigma_xc,
                (fit.yc - yc) / fit.sigma_yc,
                (fit.radius - radius) / fit.sigma_radius,
            ]
        )
        assert fit.rms_residual == pytest.approx(noise, rel=0.15)
    z = np.array(z)
    assert np.mean(np.abs(z) < 3.0) >= 0.95
    rms = np.sqrt(np.mean(z**2, axis=0))
    assert np.all((rms > 0.7) & (rms < 1.3)), rms  # stated sigmas are neither too small nor too large


def test_geometry_of_a_simulated_track_recovers_pivot_and_rods():
    rec_geom = ms.fit_geometry(_synthetic_track(np.random.default_rng(1), 4e-4, 6e-4))
    p = rec_geom.pivot
    assert abs(p.xc - PIVOT[0]) < 3 * p.sigma_xc
    assert abs(p.yc - PIVOT[1]) < 3 * p.sigma_yc
    assert abs(rec_geom.l1 - TRUE.l1) < 3 * rec_geom.sigma_l1
    assert abs(rec_geom.l2 - TRUE.l2) < 3 * rec_geom.sigma_l2 + 2e-6  # + the small bias of |noisy vector|


def test_position_noise_estimate_recovers_the_injected_noise():
    track = _synthetic_track(np.random.default_rng(2), 5e-4, 1e-3, n_frames=600)
    s1, s2 = ms.estimate_position_noise(track, ms.fit_geometry(track))
    assert s1 == pytest.approx(5e-4, rel=0.2)
    assert s2 == pytest.approx(1e-3, rel=0.2)


# --- angles, derivatives, energy -----------------------------------------------------------------


def test_angles_invert_the_package_positions():
    phi1, phi2 = np.linspace(-3.0, 3.0, 50), np.linspace(3.0, -3.0, 50)
    got1, got2 = ms.angles(*positions(phi1, phi2, 0.3, 0.2, np.sin, np.cos))
    np.testing.assert_allclose(got1, phi1, atol=1e-12)
    np.testing.assert_allclose(got2, phi2, atol=1e-12)


def test_savgol_derivative_flattens_peaks_far_less_than_central_differences_at_modest_noise_cost():
    sg, cd = ms.savgol_derivative_coefficients(), ms.central_difference_coefficients()
    omega = np.array([10.0, 15.0, 20.0, 25.0, 30.0])  # the measured rates have their power up to ~25 rad/s
    g_sg, g_cd = ms.derivative_gain(sg, omega), ms.derivative_gain(cd, omega)
    assert np.all(np.abs(1 - g_sg) < 0.01)
    assert np.all(np.abs(1 - g_sg) < 0.1 * np.abs(1 - g_cd))
    assert g_cd[2] ** 2 < 0.87  # central differences: > 13 % of the kinetic energy lost at 20 rad/s
    assert np.sqrt(np.sum(sg**2)) < 1.6 * np.sqrt(np.sum(cd**2))  # white-noise gain 1.08 vs 0.71
    signal = np.sin(np.linspace(0, 7, 80)) + 0.01 * np.random.default_rng(0).normal(size=80)
    ref = savgol_filter(signal, ms.SG_WINDOW, ms.SG_POLYORDER, deriv=1, delta=ms.FRAME_INTERVAL)
    got = ms.savgol_derivative(signal)
    h = ms.SG_WINDOW // 2
    np.testing.assert_allclose(got[h:-h], ref[h:-h], rtol=1e-10, atol=1e-10)
    assert np.isnan(got[:h]).all() and np.isnan(got[-h:]).all()


def test_reconstructed_energy_is_the_package_total_energy_with_measured_rods_and_seed_masses():
    rec = ms.reconstruct(ms.load_track())
    assert (rec.params.m1, rec.params.m2) == (0.301, 0.297)
    assert (rec.params.l1, rec.params.l2) == (rec.geometry.l1, rec.geometry.l2)
    expected = total_energy(rec.phi1, rec.phi2, rec.omega1, rec.omega2, rec.params, np.cos)
    np.testing.assert_array_equal(rec.energy, expected)
    expected_cd = total_energy(rec.phi1, rec.phi2, rec.omega1_cd, rec.omega2_cd, rec.params, np.cos)
    np.testing.assert_array_equal(rec.energy_cd, expected_cd)
    np.testing.assert_allclose(rec.e_kin + rec.e_pot, rec.energy, rtol=1e-12)
    assert np.isfinite(rec.energy[rec.energy_valid]).all()


def test_reconstruction_of_frictionless_motion_keeps_the_energy_better_than_central_differences():
    """Simulated frictionless swing through the whole chain: SG errs less per frame and on average."""
    track = _synthetic_track(np.random.default_rng(3), 3e-4, 5e-4)
    phi1, phi2, w1, w2 = _motion()
    e_true = float(total_energy(phi1[0], phi2[0], w1[0], w2[0], TRUE))
    rec = ms.reconstruct(track)
    v = rec.energy_valid
    err_sg, err_cd = rec.energy[v] - e_true, rec.energy_cd[v] - e_true
    assert abs(np.mean(err_sg)) < 0.001 * e_true
    assert np.mean(err_cd) < -0.003 * e_true  # the seed's flattened speed peaks (4.2.2)
    assert np.sqrt(np.mean(err_sg**2)) < 0.6 * np.sqrt(np.mean(err_cd**2))


def test_measured_energy_scatters_less_with_the_savgol_derivative():
    """The docstring's evidence for the filter choice: scatter of E about its exponential fit, Table 1."""
    from double_pendulum.analysis.decay.fit import exponential, fit_model

    rec = ms.reconstruct(ms.load_track())
    m = rec.free_motion
    rms = []
    for energy in (rec.energy, rec.energy_cd):
        fit = fit_model("exponential", rec.t[m], energy[m])
        rms.append(np.sqrt(np.mean((energy[m] - exponential(rec.t[m], *fit.params)) ** 2)))
    assert rms[0] < 0.8 * rms[1]


def test_propagated_energy_error_matches_monte_carlo():
    phi1, phi2, *_ = _motion(120)
    x1, y1, x2, y2 = positions(phi1, phi2, TRUE.l1, TRUE.l2, np.sin, np.cos)
    s1, s2 = 1e-3, 2e-4  # upper-bob noise dominates: the shared term of phi1 and phi2 matters
    rng = np.random.default_rng(4)
    sg = ms.savgol_derivative_coefficients()
    energies = []
    for _ in range(400):
        n = [rng.normal(0, s, x1.size) for s in (s1, s1, s2, s2)]
        p1, p2 = ms.angles(x1 + n[0], y1 + n[1], x2 + n[2], y2 + n[3])
        energies.append(
            total_energy(p1, p2, ms.apply_stencil(p1, sg), ms.apply_stencil(p2, sg), TRUE, np.cos)
        )
    w1, w2 = ms.apply_stencil(phi1, sg), ms.apply_stencil(phi2, sg)
    predicted = ms.sigma_energy_propagated(phi1, phi2, w1, w2, TRUE, s1, s2, sg)
    h = ms.SG_WINDOW // 2
    ratio = (np.std(np.array(energies), axis=0) / predicted)[h:-h]
    assert np.median(ratio) == pytest.approx(1.0, abs=0.07)
    assert np.all((ratio > 0.75) & (ratio < 1.3))


def test_seed_error_formula_is_eq_25():
    assert ms.sigma_energy_seed(np.array(2.0), np.array(1.0), 0.3, 0.3) == pytest.approx(
        0.1 * np.hypot(0.6, 0.3)
    )


def test_release_ends_at_the_first_energy_maximum():
    energy = np.array([np.nan, 0.70, 0.72, 0.75, 0.74, 0.80, 0.73])
    assert ms.find_release_frame(energy) == 3
    rec = ms.reconstruct(ms.load_track())
    e = rec.energy_cd[1 : rec.release_frame + 1]
    assert np.all(np.diff(e) > 0)  # the hand still adds energy up to the release frame
    assert rec.release_frame < 15  # ... and lets go within half a second
    assert not rec.free_motion[: rec.release_frame].any()
