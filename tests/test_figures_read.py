"""The figures as a reader sees them (issue 27's list): legends off the data or under the axes, axes labelled, nothing
clipped, numbers on log axes, names in words. Synthetic data, no scenario runs; each figure is drawn and measured."""

from __future__ import annotations

import matplotlib.pyplot as plt
import numpy as np
import pytest
from matplotlib.transforms import Bbox

from double_pendulum.plots import case, coupling, excitation, losses, prediction, style, suspension, trajectories

MODULES = (case, coupling, excitation, losses, prediction, suspension, trajectories)


@pytest.fixture
def drawn(monkeypatch):
    """Keep each figure open and drawn: ``save`` records it instead of closing it."""
    figures = []

    def keep(fig, path):
        fig.canvas.draw()
        figures.append(fig)
        return path

    for module in MODULES:
        monkeypatch.setattr(module, "save", keep)
    yield figures
    plt.close("all")


def _data_axes(fig) -> list:
    """The axes that hold data (not colour bars)."""
    return [ax for ax in fig.axes if ax.get_label() != "<colorbar>"]


def _inside(inner: Bbox, outer: Bbox, slack: float = 1.0) -> bool:
    return (inner.x0 >= outer.x0 - slack and inner.y0 >= outer.y0 - slack and inner.x1 <= outer.x1 + slack
            and inner.y1 <= outer.y1 + slack)


def _data_points(ax) -> np.ndarray:
    """Display coordinates of every plotted point of ``ax``'s lines (markers and line vertices)."""
    points = [line.get_transform().transform(np.column_stack(line.get_data())) for line in ax.get_lines()
              if len(line.get_xdata()) and not line.get_label().startswith("_child")]
    return np.concatenate(points) if points else np.empty((0, 2))


def _check_labels_and_legends(fig) -> None:
    """Every data axes says what its axes are; every legend lies in the figure and covers no plotted point."""
    renderer = fig.canvas.get_renderer()
    figure = fig.bbox
    for ax in _data_axes(fig):
        assert ax.get_xlabel() or ax.get_shared_x_axes().get_siblings(ax) != [ax], "an x axis without a label"
        assert ax.get_ylabel() or fig.get_supylabel() or ax.get_shared_y_axes().get_siblings(ax) != [ax]
    legends = [*fig.legends, *(ax.get_legend() for ax in fig.axes if ax.get_legend())]
    for legend in legends:
        box = legend.get_window_extent(renderer)
        assert box.x0 >= figure.x0 - 1 and box.x1 <= figure.x1 + 1  # within the figure's width (the saved figure
        # is cropped to its content, bbox_inches="tight", so a legend under the axes is kept)
        for ax in _data_axes(fig):
            points = _data_points(ax)
            inside = (points[:, 0] > box.x0) & (points[:, 0] < box.x1) & (points[:, 1] > box.y0) & \
                (points[:, 1] < box.y1) if len(points) else np.array([])
            assert not inside.any(), f"the legend covers {int(inside.sum())} plotted points"


def _tick_labels(ax, axis: str = "y") -> list[str]:
    lo, hi = sorted(ax.get_ylim() if axis == "y" else ax.get_xlim())
    ticks = ax.get_yticklabels() if axis == "y" else ax.get_xticklabels()
    return [t.get_text() for t in ticks if lo <= t.get_position()[1 if axis == "y" else 0] <= hi and t.get_text()]


def _errors(n: int = 120) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    t = np.linspace(0.0, 20.0, n)
    return {f"run {i}": (t, 0.01 * (i + 1) * (1.0 + 0.5 * np.sin(t))) for i in range(6)}


def test_the_prediction_errors_put_the_legend_under_the_axes_and_keep_each_run_s_colour(drawn):
    curves = _errors()
    colours = prediction.run_colours(list(curves))
    t = curves["run 5"][0]
    per_frame = ("run 5", t, 2 * curves["run 5"][1])
    prediction.plot_prediction_errors(curves, [0.02, 0.05], "unused.png", per_frame=per_frame,
                                      spread=(t, np.full_like(t, 1e-3)), floor=(t, np.full_like(t, 3e-3)),
                                      colours=colours, dashed=["run 4"])
    fig = drawn[0]
    ax = fig.axes[0]
    assert ax.get_legend() is None and len(fig.legends) == 1
    assert fig.legends[0].get_window_extent().y1 <= ax.get_window_extent().y0  # under the axes, over no data
    _check_labels_and_legends(fig)
    lines = {line.get_label(): line for line in ax.get_lines()}
    assert lines["run 5, per frame"].get_color() == lines["run 5, smoothed"].get_color() == colours["run 5"]
    assert lines["run 5, per frame"].get_alpha() < 1 and lines["run 4, smoothed"].get_linestyle() == "--"
    # the uncertainty is a band, the track's own error dots: they no longer look alike
    assert ax.collections and lines["track's own error: | |r2 - r1| - l2 | (a rigid rod has none)"].get_marker() == "."


def test_the_coordinates_show_the_whole_comparison_in_the_colours_of_the_error_plot(drawn):
    t = np.linspace(0.8, 20.8, 600)
    measured = {name: np.sin(t + i) for i, name in enumerate(("x1", "y1", "x2", "y2"))}
    runs = {"run 0": (t, measured), "run 3": (t, measured)}
    colours = prediction.run_colours(["run 0", "run 1", "run 2", "run 3"])
    prediction.plot_track_comparison(t, measured, runs, "unused.png", colours=colours, title="the whole 20 s")
    fig = drawn[0]
    lo, hi = fig.axes[-1].get_xlim()
    assert lo <= t[0] and hi >= t[-1]  # to the end of the comparison
    simulated = [line for line in fig.axes[0].get_lines() if line.get_label() == "simulated: run 3"]
    assert simulated[0].get_color() == colours["run 3"]  # as in the error plot, not the next in the cycle
    _check_labels_and_legends(fig)


def _paths(n: int = 600) -> np.ndarray:
    """A stand-in for ``paths.csv``: the measured and the simulated lower bob on ellipses, 30 frames a second."""
    t = np.arange(n) / 30.0
    columns = {"time": t + 0.8, "t_since_t0": t, "pivot_x_simulated": np.full(n, 0.002),
               "pivot_y_simulated": np.full(n, -0.001)}
    for kind, lag in (("measured", 0.0), ("simulated", 0.05)):
        for bob, r in (("1", 0.3), ("2", 0.45)):
            columns[f"x{bob}_{kind}"] = 0.1 * np.sin(4 * (t - lag)) * r
            columns[f"y{bob}_{kind}"] = -r + 0.05 * np.cos(3 * (t - lag))
    return np.rec.fromarrays(list(columns.values()), names=list(columns)).view(np.ndarray)


def test_the_lower_bob_paths_show_three_windows_with_the_legend_under_them(drawn):
    prediction.plot_lower_bob_paths(_paths(), "unused.png", run="a fitted run", colour="C5")
    fig = drawn[0]
    titles = [ax.get_title() for ax in fig.axes]
    assert titles[0] == "t - t0 = 0.00 to 2.00 s" and titles[2] == "t - t0 = 17.97 to 19.97 s"  # start and end
    assert titles[1].startswith("t - t0 = 9.00 to ")  # and the middle, 2 s each
    assert len(fig.legends) == 1 and all(ax.get_legend() is None for ax in fig.axes)
    assert all(ax.get_aspect() == 1.0 for ax in fig.axes)  # a path in the plane is not stretched
    _check_labels_and_legends(fig)


def test_the_figure_of_a_case_of_one_s_own_labels_every_panel_and_keeps_legends_off_the_data(drawn):
    t = np.linspace(0.0, 10.0, 1001)
    names = ("phi1", "phi2", "E_total", "E_kin", "E_pot", "W_air", "W_bearing", "W_bearing_drag", "W_suspension",
             "W_input", "energy_residual", "x1", "y1", "x2", "y2")
    columns = {"time": t, **{name: np.sin(t + k) for k, name in enumerate(names)}}
    columns["W_bearing"] = columns["W_input"] = np.zeros_like(t)  # switched off: not drawn
    result = np.rec.fromarrays(list(columns.values()), names=list(columns)).view(np.ndarray)
    case.plot_case(result, "unused.png", title="your case: phi1_0 = 2; 10 s")
    fig = drawn[0]
    assert fig.get_suptitle() == "your case: phi1_0 = 2; 10 s"
    energy = fig.axes[1]
    labels = [line.get_label() for line in energy.get_lines()]
    assert "dissipated by air drag (W_air)" in labels and not any("W_bearing)" in label for label in labels)
    assert not any("W_input" in label for label in labels)
    _check_labels_and_legends(fig)


def test_loss_shares_name_models_in_words_and_show_a_bound_without_a_bar(drawn):
    rows = [
        {"model": "viscous", "model_in_words": "viscous joint damping alone", "delta_aic": 0.0, "converged": True,
         "shares": {"viscous joint damping": 1.0}},
        {"model": "air+drag", "model_in_words": "air drag + bearing drag torque", "delta_aic": 0.7,
         "converged": True, "shares": {"air drag": 0.37, "bearing drag torque": 0.63}},
        {"model": "air", "model_in_words": "air drag alone", "delta_aic": 23.8, "converged": True,
         "shares": {"air drag": 1.0}},
        {"model": "air+suspension", "model_in_words": "air drag + damped suspension", "delta_aic": 176.0,
         "converged": False, "delta_aic_at_best": 25.8, "best_is_limit_model_in_words": "air drag alone",
         "shares": {"air drag": 0.04, "damped suspension": 0.96}},
    ]
    losses.plot_loss_shares(rows, "unused.png")
    fig = drawn[0]
    ax = fig.axes[0]
    ticks = [t.get_text() for t in ax.get_yticklabels()]
    assert any(t.startswith("air drag + bearing drag torque  (dAIC 0.7)") for t in ticks)
    assert any("dAIC at best 26" in t for t in ticks) and not any("+drag" in t for t in ticks)
    legend = [t.get_text() for t in fig.axes[0].get_legend().get_texts()]
    assert "damped suspension" not in legend  # no bar drawn for a fit that is a bound
    assert any(line.get_linestyle() == "--" for line in ax.get_lines())  # the tie's boundary


def test_the_stacked_budget_draws_no_empty_band_and_says_the_coefficients_are_the_defaults(drawn):
    t = np.linspace(0.0, 60.0, 600)
    names = ("time", "E_total", "E_pendulum", "E_suspension", "W_air", "W_bearing", "W_bearing_drag", "W_suspension")
    r = np.zeros(len(t), dtype=[(n, float) for n in names])
    r["time"] = t
    r["W_air"], r["W_bearing"], r["W_suspension"] = 0.1 * t / 60, 0.02 * t / 60, 0.2 * t / 60
    r["E_suspension"] = 1e-3 * np.abs(np.sin(100 * t))  # fast exchange with the pendulum: the old sawtooth
    r["E_pendulum"] = 0.65 - r["W_air"] - r["W_bearing"] - r["W_suspension"] - r["E_suspension"]
    r["E_total"] = r["E_pendulum"] + r["E_suspension"]
    trajectories.plot_energy_budget_stacked(r, "unused.png", note="default, illustrative coefficients")
    fig = drawn[0]
    ax = fig.axes[0]
    labels = [t.get_text() for t in fig.legends[0].get_texts()]
    assert not any("W_bearing_drag" in s for s in labels)  # zero all along: named in the title instead
    assert "W_bearing_drag" in ax.get_title() and "default, illustrative" in ax.get_title()
    assert sum("stored" in s for s in labels) == 1  # pendulum and suspension in one band: no sawtooth between them
    _check_labels_and_legends(fig)


def test_a_log_axis_within_a_decade_is_numbered_in_plain_decimals_to_its_lowest_part(drawn):
    t = np.linspace(0.0, 60.0, 100)
    runs = {name: np.rec.fromarrays([t, e0 * np.exp(-rate * t)], names=["time", "E_total"])
            for name, e0, rate in (("frictionless", 0.65, 0.0), ("all", 0.65, 0.012))}
    trajectories.plot_energy_per_mechanism(runs, "unused.png", note="defaults")
    ax = drawn[0].axes[0]
    labels = _tick_labels(ax)
    assert labels and not any("times" in s or "^" in s or "10" in s for s in labels)  # no "6x10^-1"
    lo, hi = ax.get_ylim()
    lowest = min(float(s) for s in labels)
    assert lowest <= lo * (hi / lo) ** 0.2  # a number in the lowest fifth of the axis
    assert style._digit_below(0.31) == pytest.approx(0.3) and style._digit_above(0.66) == pytest.approx(0.7)


def test_panels_of_a_coupling_figure_each_label_their_axes_and_share_one_legend_under_them(drawn):
    rows = [{"start": s, "suspension": m, "method": method, "macro_step_s": h, "stable": True,
             "coupling_energy_J": h * (1 + i)}
            for s in ("chaotic", "regular") for m in ("default", "light stiff")
            for i, method in enumerate(("jacobi", "iterative")) for h in (1e-3, 2e-3, 5e-3)]
    coupling.plot_against(rows, "macro_step_s", "coupling_energy_J", "unused.png", xlabel="macro step h [s]",
                          ylabel="energy made by the coupling [J]", title="energy the coupling makes")
    fig = drawn[0]
    assert all(ax.get_ylabel() == "energy made by the coupling [J]" for ax in fig.axes)  # the right column too
    assert len(fig.legends) == 1 and all(ax.get_legend() is None for ax in fig.axes)
    _check_labels_and_legends(fig)


def test_the_stability_map_numbers_its_log_axes_plainly(drawn):
    points = [{"scheme": s, "h_omega": hw, "mass_ratio": mu, "stable": mu < 1.0}
              for s in ("jacobi", "jacobi_sequential") for hw in (0.1, 0.5, 1.0, 2.0)
              for mu in (0.25, 0.6, 0.9, 1.1, 2.0)]
    curves = {s: (np.geomspace(0.03, 3.0, 20), np.linspace(1.0, 0.2, 20)) for s in ("jacobi", "jacobi_sequential")}
    coupling.plot_stability_map(points, curves, "unused.png")
    fig = drawn[0]
    for ax in fig.axes:
        for axis in ("x", "y"):
            labels = _tick_labels(ax, axis)
            assert not any("times" in s or "^" in s for s in labels)
    assert _tick_labels(fig.axes[0], "y")  # the shared mass-ratio axis is numbered
    _check_labels_and_legends(fig)


def test_the_resonance_curve_keeps_its_labels_and_crosses_above_the_data(drawn):
    w = np.linspace(2.4, 19.0, 40)
    rows = [{"omega_rad_per_s": x, "phi1_amplitude_rad": 0.02 / (1 + (x - 4.8) ** 2),
             "phi2_amplitude_rad": 0.027 / (1 + (x - 4.8) ** 2) + 0.02 / (1 + (x - 11.9) ** 2)} for x in w]
    peaks = [{"angle": a, "peak_rad_per_s": p, "damped_linear_peak_rad_per_s": p}
             for a, p in (("phi1", 4.79), ("phi2", 4.84), ("phi1", 11.85), ("phi2", 11.80))]
    excitation.plot_resonance_curve(rows, [4.809, 11.896], peaks, 5e-3, "unused.png")
    fig = drawn[0]
    ax = fig.axes[0]
    renderer = fig.canvas.get_renderer()
    curves = [line for line in ax.get_lines() if line.get_marker() == "o"]
    top_of_data = max(ax.transData.transform(np.column_stack(c.get_data()))[:, 1].max() for c in curves)
    axes_box = ax.get_window_extent(renderer)
    for text in ax.texts:
        box = text.get_window_extent(renderer)
        assert box.y0 > top_of_data and _inside(box, axes_box)  # above the curves, inside the axes
    crosses = [line for line in ax.get_lines() if line.get_marker() == "x" and len(line.get_xdata())]
    for cross in crosses:  # whole markers: inside the axes with room for their size
        y = cross.get_transform().transform(np.column_stack(cross.get_data()))[:, 1]
        assert (y + cross.get_markersize() < axes_box.y1).all() and (y > top_of_data).all()
    _check_labels_and_legends(fig)


def test_the_worst_residuals_keep_the_figure_title_clear_of_the_first_case(drawn):
    t = np.linspace(0.0, 1.0, 11)
    runs = {f"case {i}": {"time": t, "energy_residual": 1e-10 * (1 + t), "E_total": np.ones_like(t)} for i in range(3)}
    trajectories.plot_residuals(runs, "unused.png")
    fig = drawn[0]
    renderer = fig.canvas.get_renderer()
    first = fig.axes[0].title.get_window_extent(renderer)
    assert fig._suptitle.get_window_extent(renderer).y0 > first.y1 + 5  # a gap, not touching
    assert fig.axes[0].get_title(loc="left").startswith("case: ")


def test_the_decay_rate_map_keeps_an_edge_marker_inside_and_drops_islands_of_the_prediction(drawn):
    k, c = np.geomspace(5e3, 2e5, 9), np.geomspace(1.0, 3e3, 7)
    kk, cc = np.meshgrid(k, c, indexing="ij")
    panel = {"k": k, "c": c, "b": -0.005 - 0.03 * np.exp(-np.log(kk / 2e4) ** 2) * (1 + 0 * cc), "m_s": 2.0}
    kf, cf = np.geomspace(5e3, 2e5, 120), np.geomspace(1.0, 3e3, 120)
    kkf, ccf = np.meshgrid(kf, cf, indexing="ij")
    main = -0.005 - 0.03 * np.exp(-np.log(kkf / 2e4) ** 2)  # two long iso-lines either side of k = 2e4
    spot = -0.04 * np.exp(-(np.log(kkf / 1e5) ** 2 + np.log(ccf / 2.0) ** 2) / 0.01)  # an island at (1e5, 2)
    panel.update(k_fine=kf, c_fine=cf, b_fine=main + spot)
    suspension.plot_decay_rate_map({"M_s = 2 kg": panel}, {"measured": -0.025}, "unused.png",
                                   points={"resonant end": (8e3, 1.0)})
    fig = drawn[0]
    ax = next(a for a in fig.axes if a.get_title().startswith("M_s"))
    renderer = fig.canvas.get_renderer()
    marker = next(line for line in ax.get_lines() if line.get_label() == "resonant end")
    y = marker.get_transform().transform(np.column_stack(marker.get_data()))[0, 1]
    assert y - marker.get_markersize() > ax.get_window_extent(renderer).y0  # the whole triangle inside the axes
    pieces = suspension.contour_pieces(kf, cf, panel["b_fine"], -0.025)
    assert len(pieces) == 2 and all(p[:, 1].max() / p[:, 1].min() > 100 for p in pieces)  # the island is gone
    assert len(suspension.contour_pieces(kf, cf, panel["b_fine"], -0.025, fraction=0.0)) == 3  # it was there
    red = [line for line in ax.get_lines() if line.get_linestyle() == ":" and len(line.get_xdata())]
    assert len(red) == 2
    assert "not mapped" in [t.get_text() for t in fig.legends[0].get_texts()]
